#!/usr/bin/env bash
# Redraws the city pictures (docs/images/city_*.png, shown in docs/explanation/city.md) with the
# project's tools: a city scenario from hameritt_generate --world city, its map from hameritt_map,
# and hameritt_render's front and down cameras over a downtown street at dusk and in fog.
# Camera noise is off so that the pictures compress well.
source "$(dirname "$0")/common.sh"
if [ "${1:-}" != "--no-build" ]; then build >/dev/null; fi
source_devel
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
out="$HAMERITT_ROOT/docs/images"
mkdir -p "$out"
rosrun hameritt hameritt_generate --world city --class area_search --scenario-seed 1 \
  --out "$tmp/gen" --quiet
cfg="$(ls "$tmp"/gen/*/sim_config.json | head -1)"
rosrun hameritt hameritt_map "$(dirname "$cfg")" --full --px-per-m 0.8 --out "$out/city_map.png"
# A UAV 22 m up over a local street south of the downtown core, looking north; and the down
# camera 60 m up over the centre.
view=(--sim-config "$cfg" --time 30 --set noise=off --set rain=0 --set snow=0 --set foliage=0.9)
render() {  # NAME ARGS...: renders into $tmp/NAME
  local name="$1"
  shift
  rosrun hameritt hameritt_render "${view[@]}" --out "$tmp/$name" "$@"
}
render dusk --camera front --pose "${CITY_FRONT_POSE:--70,-330,22,1.5708}" --set time_of_day=18.35 --set fog=0
render fog --camera front --pose "${CITY_FRONT_POSE:--70,-330,22,1.5708}" --set time_of_day=11 --set fog=0.45
render down_dusk --camera down --pose "${CITY_DOWN_POSE:-0,0,160,0}" --set time_of_day=18.35 --set fog=0
render down_fog --camera down --pose "${CITY_DOWN_POSE:-0,0,160,0}" --set time_of_day=11 --set fog=0.45
cp "$tmp/dusk/front_rgb.png" "$out/city_front_dusk.png"
cp "$tmp/fog/front_rgb.png" "$out/city_front_fog.png"
cp "$tmp/down_dusk/down_rgb.png" "$out/city_down_dusk.png"
cp "$tmp/down_fog/down_rgb.png" "$out/city_down_fog.png"
ls -l "$out"/city_*.png
