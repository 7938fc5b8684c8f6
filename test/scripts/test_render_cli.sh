#!/usr/bin/env bash
# hameritt_render judged from outside: it writes every file for every camera, the PNGs decode
# to the camera's size, boxes.json and camera_info agree with the intrinsics, options select
# cameras, poses and weather, and bad input exits 2 with a message naming the flag, file or
# field and leaves nothing behind.
source "$(dirname "$0")/cli_lib.sh" render_cli

R="$BIN/hameritt_render"
CFG="$SRC/scenarios/default/sim_config.json"

# check_png FILE W H: a valid PNG (signature, chunk CRCs, zlib stream) of W x H RGB pixels.
check_png() {
  /usr/bin/python3 - "$@" <<'PY' && ok || bad "$1 is not a valid ${2}x${3} RGB PNG"
import struct, sys, zlib
path, w, h = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
data = open(path, "rb").read()
assert data[:8] == b"\x89PNG\r\n\x1a\n", "signature"
i, idat, size = 8, b"", None
while i < len(data):
    n, kind = struct.unpack(">I4s", data[i:i + 8])
    body = data[i + 8:i + 8 + n]
    assert zlib.crc32(kind + body) == struct.unpack(">I", data[i + 8 + n:i + 12 + n])[0], "crc"
    if kind == b"IHDR":
        size = struct.unpack(">IIBB", body[:10])
    elif kind == b"IDAT":
        idat += body
    i += 12 + n
assert size == (w, h, 8, 2), size
raw = zlib.decompress(idat)
assert len(raw) == h * (1 + 3 * w), len(raw)
PY
}

# --- everything, for both payload cameras
O="$T/all"
"$R" --sim-config "$CFG" --time 60 --out "$O" 2>"$T/log" && ok || bad "render all cameras: $(cat "$T/log")"
grep -q "2 camera(s) at t = 60 s (perception_path)" "$T/log" && ok || bad "summary line: $(cat "$T/log")"
for cam in front down; do
  for kind in rgb depth segmentation instances boxes; do
    check_png "$O/${cam}_${kind}.png" 640 480
  done
  grep -q "^camera_name: $cam$" "$O/${cam}_camera_info.yaml" && ok || bad "$cam camera_info name"
done
[[ -z "$(find "$O" -name '*.tmp.*')" ]] && ok || bad "temporary files left behind"
[[ $(find "$O" -type f | wc -l) -eq 13 ]] && ok || bad "expected 13 files, got $(find "$O" -type f | wc -l)"
/usr/bin/python3 - "$O" <<'PY' && ok || bad "boxes.json and camera_info disagree or are malformed"
import json, math, re, sys
d = sys.argv[1]
b = json.load(open(d + "/boxes.json"))
assert b["scenario_id"].startswith("area_search-"), b["scenario_id"]
assert b["time"] == 60 and b["uav_pose"]["source"] == "perception_path"
assert set(b["cameras"]) == {"front", "down"}
for name, cam in b["cameras"].items():
    y = open(f"{d}/{name}_camera_info.yaml").read()
    k = [float(v) for v in re.search(r"camera_matrix:\n  rows: 3\n  cols: 3\n  data: \[(.*)\]", y).group(1).split(",")]
    assert abs(k[0] - cam["fx"]) < 1e-6 and abs(k[2] - cam["cx"]) < 1e-6 and abs(k[5] - cam["cy"]) < 1e-6, (k, cam)
    assert cam["cx"] == (cam["width"] - 1) / 2 and cam["cy"] == (cam["height"] - 1) / 2
    assert "distortion_model: plumb_bob" in y and "projection_matrix" in y
    for box in cam["boxes"]:
        assert box["class"] in ("car", "pedestrian"), box
        assert 0 <= box["x_min"] <= box["x_max"] < cam["width"] and 0 <= box["y_min"] <= box["y_max"] < cam["height"]
        assert 0 < box["visible_pixels"] <= box["total_pixels"]
        assert math.isclose(box["occlusion"], 1 - box["visible_pixels"] / box["total_pixels"], abs_tol=1e-12)
assert len(b["cameras"]["front"]["boxes"]) > 0
PY

# --- one camera, a pose of our own, other weather; the same input gives the same bytes
O2="$T/down"
"$R" --sim-config "$CFG" --time 30 --out "$O2" --camera down --pose -271,249,40,0 \
  --set snow=0.8 --set time_of_day=17.5 --set gaussian_std=0 --frame 3 2>/dev/null && ok || bad "down camera with options"
[[ -f "$O2/down_rgb.png" && ! -e "$O2/front_rgb.png" ]] && ok || bad "--camera down wrote other cameras"
grep -q '"source": "--pose"' "$O2/boxes.json" && ok || bad "--pose not used"
grep -q '"car_706"' "$O2/boxes.json" && ok || bad "the target car under the UAV has no box"
"$R" --sim-config "$CFG" --time 30 --out "$T/again" --camera down --pose -271,249,40,0 \
  --set snow=0.8 --set time_of_day=17.5 --set gaussian_std=0 --frame 3 2>/dev/null
cmp -s "$O2/down_rgb.png" "$T/again/down_rgb.png" && ok || bad "same input, different image"
cmp -s "$O2/boxes.json" "$T/again/boxes.json" && ok || bad "same input, different boxes"

# --- bad input: exit 2, a message naming the flag, file or field, nothing written
N="$T/never"
expect 2 "--sim-config is required" "$R" --time 1 --out "$N"
expect 2 "--time is required" "$R" --sim-config "$CFG" --out "$N"
expect 2 "--out is required" "$R" --sim-config "$CFG" --time 1
expect 2 "unknown argument '--colour'" "$R" --sim-config "$CFG" --time 1 --out "$N" --colour red
expect 2 "--time: expected a number, got 'soon'" "$R" --sim-config "$CFG" --time soon --out "$N"
expect 2 "--time: expected a time in \[0, 472\]" "$R" --sim-config "$CFG" --time 473 --out "$N"
expect 2 "--time: expected a time in" "$R" --sim-config "$CFG" --time -1 --out "$N"
expect 2 "$T/missing.json" "$R" --sim-config "$T/missing.json" --time 1 --out "$N"
printf '{"schema": "hameritt/sim_config", ' >"$T/truncated.json"
expect 2 "$T/truncated.json" "$R" --sim-config "$T/truncated.json" --time 1 --out "$N"
expect 2 "--camera: no camera 'rear'.*front, down" "$R" --sim-config "$CFG" --time 1 --out "$N" --camera rear
expect 2 "--set fog: expected a value in \[0, 1\], got 2" "$R" --sim-config "$CFG" --time 1 --out "$N" --set fog=2
expect 2 "--set: unknown key 'haze'" "$R" --sim-config "$CFG" --time 1 --out "$N" --set haze=1
expect 2 "--set: expected KEY=VALUE" "$R" --sim-config "$CFG" --time 1 --out "$N" --set fog
expect 2 "--pose: expected x,y,z,yaw" "$R" --sim-config "$CFG" --time 1 --out "$N" --pose 1,2,3
expect 2 "--frame: expected a non-negative integer" "$R" --sim-config "$CFG" --time 1 --out "$N" --frame -4
expect 2 "--models: /nonexistent/meshes is not a directory" "$R" --sim-config "$CFG" --time 1 --out "$N" --models /nonexistent
[[ ! -e "$N" ]] && ok || bad "bad input created $N"
touch "$T/file"
expect 2 "cannot create output directory" "$R" --sim-config "$CFG" --time 1 --out "$T/file/sub" --camera down
[[ -z "$(find "$T" -name '*.tmp.*')" ]] && ok || bad "temporary files left behind after failures"

echo "$pass passed, $fail failed"
[[ $fail -eq 0 ]]
