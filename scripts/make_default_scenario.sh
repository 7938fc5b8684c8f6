#!/usr/bin/env bash
# Regenerates the shipped scenario (scenarios/default) and the maps in docs/images/ with the
# project's own tools. Run after a change that alters generator output on purpose.
source "$(dirname "$0")/common.sh"
build >/dev/null
source_devel
SEED=2044
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
rosrun hameritt hameritt_generate --class area_search --scenario-seed "$SEED" --out "$tmp" --quiet
rm -rf "$HAMERITT_ROOT/scenarios/default"
mv "$tmp"/area_search-* "$HAMERITT_ROOT/scenarios/default"
mkdir -p "$HAMERITT_ROOT/docs/images"
for spec in area_search:2044 route_search:14 pursuit:11; do
  cls="${spec%%:*}"
  rosrun hameritt hameritt_generate --class "$cls" --scenario-seed "${spec##*:}" --out "$tmp/$cls" --quiet
  rosrun hameritt hameritt_map "$tmp/$cls"/"$cls"-* --out "$HAMERITT_ROOT/docs/images/map_$cls.png"
done
echo "scenarios/default and docs/images regenerated"
