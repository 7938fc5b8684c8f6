#!/usr/bin/env bash
# Quick start, command 1: install, build, and run the main job on the shipped scenario:
# validate it, summarize it, draw its map, run the whole mission end to end with the baseline
# clients (headless, recording a bag), print its metrics, and generate a fresh batch of
# scenarios of all three classes.
source "$(dirname "$0")/common.sh"
install_deps
build
source_devel

SCENARIO="${1:-$HAMERITT_ROOT/scenarios/default}"
OUT="${HAMERITT_OUT:-$HAMERITT_ROOT/out}"
mkdir -p "$OUT"
echo "== validating $SCENARIO"
rosrun hameritt hameritt_validate "$SCENARIO/mission.json" "$SCENARIO/sim_config.json"
echo "== summary"
rosrun hameritt hameritt_summary "$SCENARIO"
echo "== map -> $OUT/default_map.png"
rosrun hameritt hameritt_map "$SCENARIO" --out "$OUT/default_map.png"
echo "== mission: roslaunch hameritt mission.launch mode:=${HAMERITT_MODE:-end_to_end} record:=true -> $OUT/mission"
rm -rf "$OUT/mission"
mkdir -p "$OUT/mission"
# A private ROS master port, so that a running roscore is left alone.
port=$((11400 + $$ % 500))
# The COP and the TAK bridge ride along (docs/tutorials/06-cop-tak.md):
# CoT events go to a local listener on 127.0.0.1 only.
tak_port=$((16000 + $$ % 2000))
/usr/bin/python3 "$HAMERITT_ROOT/scripts/cot_listen.py" --port "$tak_port" >"$OUT/mission/cot.log" 2>&1 &
cot_pid=$!
trap 'kill -INT $cot_pid 2>/dev/null || true' EXIT
ROS_MASTER_URI="http://localhost:$port" roslaunch -p "$port" hameritt mission.launch \
  scenario:="$SCENARIO" mode:="${HAMERITT_MODE:-end_to_end}" record:=true output_dir:="$OUT/mission" \
  real_time_factor:="${HAMERITT_REAL_TIME_FACTOR:-0}" cop:=true tak:="udp://127.0.0.1:$tak_port" \
  >"$OUT/mission/launch.log" 2>&1 ||
  { tail -40 "$OUT/mission/launch.log"; echo "hameritt: the mission launch failed (log: $OUT/mission/launch.log)"; exit 1; }
grep -E "simulator: sim .* wall" "$OUT/mission/launch.log" | tail -1 || true
echo "== COP and TAK bridge ($OUT/mission/cot.log)"
kill -INT "$cot_pid" && wait "$cot_pid" || true
grep -hE "(cop|tak_bridge): summary" "$OUT/mission/launch.log" | sed 's/^.*\]: //; s/\x1b\[[0-9;]*m//g' || true
grep -E "^cot_listen|^  [a-z]-|believed target" "$OUT/mission/cot.log" | head -12 || true
echo "== metrics ($OUT/mission/metrics.json)"
cat "$OUT/mission/metrics.json"
echo
echo "== bag ($OUT/mission/mission.bag)"
rosbag info "$OUT/mission/mission.bag" | head -60
# Dataset export (issue 11): the mission's bag as a small COCO dataset, and its summary.
echo "== dataset: hameritt_export $OUT/mission/mission.bag --format coco -> $OUT/dataset"
rosrun hameritt hameritt_export "$OUT/mission/mission.bag" --format coco --out "$OUT/dataset" \
  --every 4 --split train=0.8,val=0.2 --seed 1 --force --quiet
rosrun hameritt hameritt_export --preview "$OUT/dataset" --image-id most --out "$OUT/dataset_preview.png"
echo "== generating 30 scenarios (all classes, seed 1) -> $OUT/generated"
rosrun hameritt hameritt_generate --class all --count 30 --seed 1 --out "$OUT/generated" --quiet
rosrun hameritt hameritt_validate "$OUT"/generated/*/mission.json "$OUT"/generated/*/sim_config.json >/dev/null
echo "hameritt: main job done; outputs in $OUT"
