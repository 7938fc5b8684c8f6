#!/usr/bin/env bash
# Quick start, command 1: install, build, and run the main job on the shipped scenario:
# validate it, summarize it, draw its map, and generate a fresh batch of all three classes.
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
echo "== generating 30 scenarios (all classes, seed 1) -> $OUT/generated"
rosrun hameritt hameritt_generate --class all --count 30 --seed 1 --out "$OUT/generated" --quiet
rosrun hameritt hameritt_validate "$OUT"/generated/*/mission.json "$OUT"/generated/*/sim_config.json >/dev/null
echo "hameritt: main job done; outputs in $OUT"
