#!/usr/bin/env bash
# mission.launch spec:=FILE spec_seed:=S: roslaunch generates one scenario from a spec while it
# reads the launch file, then flies it. The flown scenario (output_dir/scenario) is byte for byte
# scenario 0 of `hameritt_generate --spec FILE --seed S`, carries the spec provenance block and
# passes `hameritt_validate --spec`; the ADK's metrics name its id. spec_params reach the
# scenario; a spec the generator refuses stops the launch before any node starts, with nothing
# written (negative controls: another spec's validator fails the scene; a bad param).
source "$(dirname "$0")/cli_lib.sh" mission_spec
export PATH="/usr/bin:/bin:$PATH"
S="$SRC/scenarios/specs"
red="$S/red_sedan_garage.hspec"
port=$((14000 + $$ % 2000))
export ROS_MASTER_URI="http://localhost:$port"

# --- the mission: a few sim seconds, as fast as possible
out="$T/out"
if timeout 300 roslaunch -p "$port" hameritt mission.launch spec:="$red" spec_seed:=7 \
     mode:=maneuver_only time_limit:=4 real_time_factor:=0 output_dir:="$out" \
     >"$T/launch.log" 2>&1; then
  ok
else
  bad "roslaunch exited non-zero or timed out"; tail -40 "$T/launch.log"
fi
scen="$out/scenario"
"$BIN/hameritt_generate" --spec "$red" --count 1 --seed 7 --out "$T/ref" --quiet && ok || bad "reference generation"
ref="$(ls -d "$T/ref"/*/ | head -1)"
for f in mission.json sim_config.json; do
  cmp -s "$scen/$f" "$ref/$f" && ok || bad "$f differs from hameritt_generate --spec --seed 7's"
done
/usr/bin/python3 - "$scen" "$out/metrics.json" <<'EOF' && ok || bad "provenance / metrics"
import json, sys
scen, metrics = sys.argv[1:]
sim = json.load(open(scen + "/sim_config.json"))
mission = json.load(open(scen + "/mission.json"))
spec = sim["spec"]
assert spec["file"].endswith("red_sedan_garage.hspec"), spec["file"]
assert len(spec["hash"]) == 16 and spec["sampler"] == "random", spec
m = json.load(open(metrics))
assert m["scenario_id"] == mission["scenario_id"], (m["scenario_id"], mission["scenario_id"])
assert m["outcome"] in ("success", "timeout"), m["outcome"]
print("flown", m["scenario_id"], m["outcome"], "end", m["end_time"])
EOF
o=$("$BIN/hameritt_validate" --spec "$red" "$scen" 2>"$T/v.err") && ok || bad "validate: $(cat "$T/v.err")"
[[ "$(tail -1 <<<"$o")" == "1 scenarios, 1 meet the spec, 0 fail" ]] && ok || bad "validate: $o"
# Negative control: the flown scene does not meet another spec.
expect 2 "does not hold|is not one of" "$BIN/hameritt_validate" --spec "$S/impala_lookalikes.hspec" "$scen"

# --- spec_params reach the scenario (roslaunch --dump-params loads the launch: the generator
# runs, no node starts)
p="$T/p"
roslaunch --dump-params hameritt mission.launch spec:="$S/snowy_dusk_search.hspec" spec_seed:=3 \
  spec_params:="snow=0.9 altitude=30" spec_out:="$p" >"$T/dump.log" 2>&1 && ok || bad "dump-params: $(tail -5 "$T/dump.log")"
grep -q '"snow": 0.9' "$p/sim_config.json" && ok || bad "spec_params snow=0.9 not in the scenario"
"$BIN/hameritt_validate" --spec "$S/snowy_dusk_search.hspec" --param snow=0.9 --param altitude=30 "$p" >/dev/null 2>&1 &&
  ok || bad "spec_params scenario fails its spec"
expect 2 "outside" "$BIN/hameritt_validate" --spec "$S/snowy_dusk_search.hspec" --param snow=0.6 "$p"

# --- a refused spec stops the launch (roslaunch exits 1 before any node starts); nothing is
# written
x="$T/x"
if timeout 120 roslaunch -p "$port" hameritt mission.launch spec:="$S/snowy_dusk_search.hspec" \
     spec_params:="snwo=1" spec_out:="$x" >"$T/bad.log" 2>&1; then
  bad "a bad spec_params launched"
else
  ok
fi
grep -q "unknown parameter 'snwo'" "$T/bad.log" && ok || bad "no message naming the parameter: $(tail -5 "$T/bad.log")"
[[ ! -e "$x" && -z "$(ls -d "$T"/x.tmp.* 2>/dev/null)" ]] && ok || bad "a refused spec wrote $x"

echo "$pass passed, $fail failed"
[[ $pass -eq 15 && $fail -eq 0 ]]
