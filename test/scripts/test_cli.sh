#!/usr/bin/env bash
# Command-line behaviour of the tools, judged from outside: exit codes, error messages that
# name the file and field, no partial output, determinism across --jobs, and the shipped
# scenario regenerating byte for byte from its class and seed.
source "$(dirname "$0")/cli_lib.sh" cli

G="$BIN/hameritt_generate"
V="$BIN/hameritt_validate"

# --- bad arguments
expect 2 "--class is required" "$G" --count 1 --seed 1 --out "$T/a"
expect 2 "--count: expected a positive integer, got '-3'" "$G" --class all --count -3 --seed 1 --out "$T/a"
expect 2 "--count: expected 1 to" "$G" --class all --count 0 --seed 1 --out "$T/a"
expect 2 "got 'boat'" "$G" --class boat --count 1 --seed 1 --out "$T/a"
expect 2 "--seed: expected a non-negative integer" "$G" --class all --count 1 --seed x1 --out "$T/a"
expect 2 "unknown argument '--colour'" "$G" --class all --count 1 --seed 1 --out "$T/a" --colour red
[[ ! -e "$T/a" ]] && ok || bad "bad arguments created $T/a"

# --- bad configuration files: the message names the file and the JSON field
printf '{ "seed": 1,\n  "extent_x": 1000.0,\n  oops }\n' >"$T/broken.json"
expect 2 "$T/broken.json: malformed JSON.*line 3" "$G" --class all --count 1 --seed 1 --out "$T/b" --world-config "$T/broken.json"
sed 's/"street_width": 10.0/"street_width": "wide"/' "$SRC/config/world.json" >"$T/wrongtype.json"
expect 2 "$T/wrongtype.json: world.street_width: expected a number, got string" "$G" --class all --count 1 --seed 1 --out "$T/b" --world-config "$T/wrongtype.json"
sed 's/"confuser_count_min": 1/"confuser_count_min": -2/' "$SRC/config/generator.json" >"$T/neg.json"
expect 2 "$T/neg.json: generator.confuser_count_min" "$G" --class all --count 1 --seed 1 --out "$T/b" --generator-config "$T/neg.json"
[[ ! -e "$T/b" ]] && ok || bad "bad configuration created output"
# a command-line mistake is shown with the usage; a bad file is not (the usage would bury the
# message naming the file and field)
expect 2 "unknown argument.*usage: hameritt_generate" "$G" --class all --count 1 --seed 1 --out "$T/a" --colour red
err="$("$G" --class all --count 1 --seed 1 --out "$T/b" --world-config "$T/wrongtype.json" 2>&1 >/dev/null)"
[[ "$err" != *usage:* ]] && ok || bad "a configuration-file error printed the usage: $err"

# --- unwritable output: clear error, nothing written
touch "$T/file"
expect 2 "cannot create output directory" "$G" --class all --count 3 --seed 1 --out "$T/file/sub"
expect 2 "readonly_proc.*cannot create|cannot create.*readonly_proc" "$G" --class all --count 3 --seed 1 --out /proc/hameritt/"$(basename "$T")"/readonly_proc

# --- determinism across --jobs, and validity of everything generated
"$G" --class all --count 45 --seed 5 --out "$T/j1" --jobs 1 --quiet && ok || bad "generate --jobs 1"
"$G" --class all --count 45 --seed 5 --out "$T/j2" --jobs 2 --quiet && ok || bad "generate --jobs 2"
"$G" --class all --count 45 --seed 5 --out "$T/j7" --jobs 7 --quiet && ok || bad "generate --jobs 7"
diff -r "$T/j1" "$T/j2" >/dev/null && ok || bad "--jobs 1 and --jobs 2 outputs differ"
diff -r "$T/j1" "$T/j7" >/dev/null && ok || bad "--jobs 1 and --jobs 7 outputs differ"
n=$(find "$T/j1" -mindepth 1 -maxdepth 1 -type d | wc -l)
[[ $n -eq 45 ]] && ok || bad "expected 45 scenario directories, got $n"
[[ -z "$(find "$T/j1" -name '.tmp-*' -o -name '*.tmp.*')" ]] && ok || bad "temporary files left behind"
"$V" "$T"/j1/*/mission.json "$T"/j1/*/sim_config.json "$T/j1/manifest.json" "$T/j1/world.json" >/dev/null && ok || bad "generated files do not validate"

# --- hameritt_validate rejects edited files with file, JSON path and rule
m="$(ls -d "$T"/j1/area_search-* | head -1)/mission.json"
/usr/bin/python3 - "$m" "$T/edited.json" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
d["area_priors"][0]["cells"][0]["probability"] += 0.25
json.dump(d, open(sys.argv[2], "w"))
PY
expect 2 "$T/edited.json: /area_priors/0" "$V" "$T/edited.json"
printf '{"schema": "hameritt/mission", ' >"$T/truncated.json"
expect 2 "$T/truncated.json" "$V" "$T/truncated.json"

# --- the shipped scenario validates and regenerates byte for byte from its class and seed
D="$SRC/scenarios/default"
"$V" "$D/mission.json" "$D/sim_config.json" >/dev/null && ok || bad "shipped scenario does not validate"
cls="$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["class"])' "$D/mission.json")"
seed="$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["seed"])' "$D/mission.json")"
id="$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["scenario_id"])' "$D/mission.json")"
"$G" --class "$cls" --scenario-seed "$seed" --out "$T/regen" --quiet && ok || bad "regenerate shipped scenario"
cmp -s "$D/mission.json" "$T/regen/$id/mission.json" && ok || bad "shipped mission.json differs from a regeneration (re-run scripts/make_default_scenario.sh?)"
cmp -s "$D/sim_config.json" "$T/regen/$id/sim_config.json" && ok || bad "shipped sim_config.json differs from a regeneration"

# --- summary and map tools on it
"$BIN/hameritt_summary" "$D" | grep -q "^objective" && ok || bad "hameritt_summary"
"$BIN/hameritt_map" "$D" --out "$T/map.png" && ok || bad "hameritt_map"
[[ "$(head -c 8 "$T/map.png" | od -An -tx1 | tr -d ' \n')" == "89504e470d0a1a0a" ]] && ok || bad "map is not a PNG"
expect 2 "" "$BIN/hameritt_map" "$T/does_not_exist" --out "$T/x.png"

echo "$pass passed, $fail failed"
[[ $fail -eq 0 ]]
