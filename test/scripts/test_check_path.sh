#!/usr/bin/env bash
# hameritt_check_path judged from outside: exit codes (0 clean, 3 violation, 2 bad input),
# violation times against an independent line-intersection computation in Python, the report
# on stdout equal to --out, and errors that name the file, line and column with nothing
# written.
source "$(dirname "$0")/cli_lib.sh" check_path

C="$BIN/hameritt_check_path"
M="$SRC/scenarios/default/mission.json"
MW="$SRC/test/data/adk_windows_mission.json"

# A clean flight far from every keep-out zone: climb at the start, fly east.
cat >"$T/clean.csv" <<'CSV'
t,x,y,z,yaw
0,-279.147,-258.585,0,0
10,-279.147,-258.585,40,0
40,-150,-258.585,40,0
CSV
"$C" --mission "$M" --path "$T/clean.csv" --out "$T/clean.json" >"$T/clean.out"
rc=$?
[[ $rc -eq 0 ]] && ok || bad "clean path exited $rc, expected 0"
cmp -s "$T/clean.out" "$T/clean.json" && ok || bad "stdout and --out differ"
/usr/bin/python3 - "$T/clean.json" <<'PY' && ok || bad "clean report"
import json, sys
r = json.load(open(sys.argv[1]))
assert list(r) == ["mission", "mission_file", "path_file", "samples", "t_start", "t_end",
                   "duration", "violations", "violation_count", "violation_duration",
                   "aoi_time"], list(r)
assert r["mission"] == "area_search-00000000000007fc", r["mission"]
assert r["samples"] == 3 and r["duration"] == 40 and r["violation_count"] == 0
assert r["violations"] == [] and r["violation_duration"] == 0
assert [a["id"] for a in r["aoi_time"]] == ["aoi_1", "aoi_2"]
PY

# Through koz_1 at 50 m (above koz_2's 36 m ceiling) along y = 250, x = -320 + t: both samples
# outside, so entry and exit come from the segment's intersections with the zone's edges.
printf 't,x,y,z\n0,-320,250,50\n100,-220,250,50\n' >"$T/cross.csv"
"$C" --mission "$M" --path "$T/cross.csv" >"$T/cross.json"
rc=$?
[[ $rc -eq 3 ]] && ok || bad "violating path exited $rc, expected 3"
"$C" --mission "$MW" --path "$T/cross.csv" >"$T/cross_windows.json"
rc=$?
[[ $rc -eq 3 ]] && ok || bad "violating path (windows) exited $rc, expected 3"
/usr/bin/python3 - "$M" "$T/cross.json" "$T/cross_windows.json" <<'PY' && ok || bad "violation times"
import json, sys
mission = json.load(open(sys.argv[1]))
koz = next(k for k in mission["keep_out_zones"] if k["id"] == "koz_1")
poly = koz["polygon"]
# Crossings of the line y = 250 with the polygon's edges, as x; t = x + 320.
xs = []
for i in range(len(poly)):
    (x0, y0), (x1, y1) = poly[i], poly[(i + 1) % len(poly)]
    if (y0 - 250) * (y1 - 250) < 0:
        xs.append(x0 + (250 - y0) / (y1 - y0) * (x1 - x0))
assert len(xs) == 2, xs
t_in, t_out = min(xs) + 320, max(xs) + 320
r = json.load(open(sys.argv[2]))
assert r["violation_count"] == 1, r
v = r["violations"][0]
assert v["zone"] == "koz_1" and v["purpose"] == "vantage_denial", v
assert abs(v["t_enter"] - t_in) < 1e-9 and abs(v["t_exit"] - t_out) < 1e-9, (v, t_in, t_out)
assert abs(v["duration"] - (t_out - t_in)) < 1e-9 and abs(r["violation_duration"] - v["duration"]) < 1e-9
aoi1 = next(a for a in r["aoi_time"] if a["id"] == "aoi_1")
assert aoi1["time_inside"] > 0 and aoi1["entries"] == 1, aoi1
# With koz_1 active only in [20, 60] (test/data/adk_windows_mission.json) the violation ends at 60.
w = json.load(open(sys.argv[3]))
assert w["violation_count"] == 1, w
v = w["violations"][0]
assert abs(v["t_enter"] - t_in) < 1e-9 and v["t_exit"] == 60, v
PY

# Through koz_2 only while its window is closed (net 1000 in the windows mission): clean there,
# a violation in the shipped mission.
printf 't,x,y,z\n0,-200,230,20\n10,-200,260,20\n' >"$T/koz2.csv"
"$C" --mission "$MW" --path "$T/koz2.csv" >/dev/null
rc=$?
[[ $rc -eq 0 ]] && ok || bad "inactive zone: exited $rc, expected 0"
"$C" --mission "$M" --path "$T/koz2.csv" >/dev/null
rc=$?
[[ $rc -eq 3 ]] && ok || bad "active zone: exited $rc, expected 3"

# --- bad input: exit 2, file/line/column in the message, --out not written
printf 't,x,y,z\n0,1,2,3\n1,1,abc,3\n' >"$T/malformed.csv"
expect 2 "$T/malformed.csv:3: column 3 \(y\): expected a finite number, got 'abc'" \
  "$C" --mission "$M" --path "$T/malformed.csv" --out "$T/no1.json"
printf 't,x,y\n0,1,2\n' >"$T/missing_column.csv"
expect 2 "$T/missing_column.csv:1: header: expected the columns t,x,y,z first" \
  "$C" --mission "$M" --path "$T/missing_column.csv" --out "$T/no2.json"
printf 't,x,y,z\n0,1,2,3\n5,1,2,3\n4,1,2,3\n' >"$T/decreasing.csv"
expect 2 "$T/decreasing.csv:4: column 1 \(t\): expected a time after the previous sample's 5" \
  "$C" --mission "$M" --path "$T/decreasing.csv" --out "$T/no3.json"
printf 't,x,y,z\n0,1,2\n' >"$T/short_row.csv"
expect 2 "$T/short_row.csv:2: expected 4 fields as in the header, got 3" \
  "$C" --mission "$M" --path "$T/short_row.csv"
expect 2 "$T/nonexistent.csv: cannot read" "$C" --mission "$M" --path "$T/nonexistent.csv"
sed 's/"time_limit": 472/"time_limit": "long"/' "$M" >"$T/bad_mission.json"
expect 2 "$T/bad_mission.json: time_limit: expected a number" \
  "$C" --mission "$T/bad_mission.json" --path "$T/clean.csv" --out "$T/no4.json"
printf '{"schema": "hameritt/mission", ' >"$T/truncated.json"
expect 2 "$T/truncated.json" "$C" --mission "$T/truncated.json" --path "$T/clean.csv"
expect 2 "--path is required" "$C" --mission "$M"
expect 2 "--mission is required" "$C" --path "$T/clean.csv"
expect 2 "unknown argument '--paht'" "$C" --mission "$M" --paht "$T/clean.csv"
expect 2 "--out: expected a value" "$C" --mission "$M" --path "$T/clean.csv" --out
expect 2 "$T/nodir/report.json: cannot write" \
  "$C" --mission "$M" --path "$T/cross.csv" --out "$T/nodir/report.json"
for f in no1 no2 no3 no4; do
  [[ ! -e "$T/$f.json" ]] && ok || bad "bad input wrote $T/$f.json"
done
[[ -z "$(find "$T" -name '*.tmp.*')" ]] && ok || bad "temporary files left behind"

echo "test_check_path: $pass passed, $fail failed"
[[ $fail -eq 0 ]]
