#!/usr/bin/env bash
# Redraws the renderer pictures (docs/images/render_*.png, shown in docs/explanation/renderer.md)
# with hameritt_render from the shipped scenario: the front camera of a UAV hovering 22 m above
# the street east of the target car (car_706), looking west along it; clear, in snow, in fog and
# at dusk, plus the depth, segmentation and boxes images of the clear view and the down camera
# over the target.
# Camera noise is off so that the pictures compress well (and show the scene, not the sensor).
source "$(dirname "$0")/common.sh"
build >/dev/null
source_devel
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
cfg="$HAMERITT_ROOT/scenarios/default/sim_config.json"
out="$HAMERITT_ROOT/docs/images"
mkdir -p "$out"
view=(--sim-config "$cfg" --time 60 --pose -228,252,22,3.1416 --set noise=off --set rain=0
      --set foliage=0.9)
render() {  # NAME ARGS...: renders into $tmp/NAME
  local name="$1"
  shift
  rosrun hameritt hameritt_render "${view[@]}" --out "$tmp/$name" "$@"
}
render clear --camera front --set time_of_day=10.5
render snow --camera front --set time_of_day=11 --set snow=0.8
render fog --camera front --set time_of_day=11 --set fog=0.45
render dusk --camera front --set time_of_day=18.35
render down --camera down --pose -271,249,35,1.5708 --set time_of_day=10.5
cp "$tmp/clear/front_rgb.png" "$out/render_clear.png"
cp "$tmp/snow/front_rgb.png" "$out/render_snow.png"
cp "$tmp/fog/front_rgb.png" "$out/render_fog.png"
cp "$tmp/dusk/front_rgb.png" "$out/render_dusk.png"
cp "$tmp/clear/front_depth.png" "$out/render_depth.png"
cp "$tmp/clear/front_segmentation.png" "$out/render_segmentation.png"
cp "$tmp/clear/front_boxes.png" "$out/render_boxes.png"
cp "$tmp/down/down_boxes.png" "$out/render_down_boxes.png"
ls -l "$out"/render_*.png
