#!/usr/bin/env bash
# The scenario language end to end: every example spec in scenarios/specs/ generates 1,000
# scenarios, and hameritt_validate --spec re-checks every hard requirement from the scenes
# (relations recomputed by the relation code), with soft-requirement frequencies within 3 sigma
# of their probabilities; outputs pass the JSON schemas (python3-jsonschema); the same spec and
# seed give the same bytes on any --jobs; malformed, unsatisfiable and bad-parameter runs exit 2
# with nothing written; and the validator fails on scenes that do not meet a spec (negative
# controls).
source "$(dirname "$0")/cli_lib.sh" specs

G="$BIN/hameritt_generate"
V="$BIN/hameritt_validate"
S="$SRC/scenarios/specs"
N=1000
OUT="$T"
[[ -d /dev/shm && -w /dev/shm ]] && OUT="$(mktemp -d /dev/shm/hameritt_specs.XXXXXX)" && trap 'rm -rf "$T" "$OUT"' EXIT

# soft_ok VALIDATE_OUTPUT SPEC: every "soft 'R': held in K of N" line is within 3 sigma of the
# probability that SPEC gives R ("prefer P R"); prints how many were checked.
soft_check() {
  /usr/bin/python3 - "$1" "$2" <<'EOF'
import math, re, sys
out, spec = open(sys.argv[1]).read(), open(sys.argv[2]).read()
probs = {m.group(2).strip(): float(m.group(1))
         for m in re.finditer(r"^prefer\s+([0-9.]+)\s+(.*?)\s*(#.*)?$", spec, re.M)}
lines = re.findall(r"^soft '(.*)': held in (\d+) of (\d+) scenarios$", out, re.M)
if len(lines) != len(probs):
    print(f"expected {len(probs)} soft lines, got {len(lines)}"); sys.exit(1)
for req, k, n in lines:
    p, k, n = probs[req], int(k), int(n)
    sigma = math.sqrt(n * p * (1 - p))
    if abs(k - n * p) > 3 * sigma:
        print(f"soft '{req}': {k} of {n}, expected {n * p:.0f} +- {3 * sigma:.0f}"); sys.exit(1)
print(len(lines))
EOF
}

specs=("$S"/*.hspec)
[[ ${#specs[@]} -ge 8 ]] && ok || bad "expected at least 8 example specs, got ${#specs[@]}"
soft_total=0
city_verified=0
for spec in "${specs[@]}"; do
  name="$(basename "$spec" .hspec)"
  if grep -q '^world city' "$spec"; then
    # A city scene carries the city's traffic (about 4.5 MB of JSON): every scenario is
    # re-checked in memory by --verify (the checker of hameritt_validate --spec, on the finished
    # scene) and the files of every tenth by hameritt_validate itself; made in 4 shards (--first)
    # so that /dev/shm holds one at a time.
    for ((k = 0; k < 4; k++)); do
      rm -rf "$OUT/$name"
      "$G" --spec "$spec" --count $((N / 4)) --first $((k * N / 4)) --seed 2026 --out "$OUT/$name" \
        --jobs 2 --quiet --verify >"$T/$name.gen" 2>&1 && ok || bad "$name: generation failed: $(tail -2 "$T/$name.gen")"
      grep -qx "$((N / 4)) scenarios verified against the spec" "$T/$name.gen" &&
        city_verified=$((city_verified + N / 4))
      mapfile -t tenth < <(ls -d "$OUT/$name"/*/ | awk 'NR % 10 == 1')
      [[ ${#tenth[@]} -eq $((N / 40)) ]] && ok || bad "$name: expected $((N / 40)) scenarios to validate, got ${#tenth[@]}"
      "$V" --spec "$spec" "${tenth[@]}" >"$T/$name.out" 2>"$T/$name.err" && ok ||
        bad "$name: validation failed: $(head -3 "$T/$name.err")"
      grep -qx "${#tenth[@]} scenarios, ${#tenth[@]} meet the spec, 0 fail" "$T/$name.out" && ok ||
        bad "$name: $(tail -1 "$T/$name.out")"
    done
    k=$(soft_check "$T/$name.gen" "$spec") && ok || bad "$name: $k"
    soft_total=$((soft_total + ${k:-0}))
    continue
  fi
  "$G" --spec "$spec" --count $N --seed 2026 --out "$OUT/$name" --jobs 2 --quiet &&
    ok || bad "$name: generation failed"
  n=$(find "$OUT/$name" -mindepth 1 -maxdepth 1 -type d | wc -l)
  [[ $n -eq $N ]] && ok || bad "$name: expected $N scenario directories, got $n"
  "$V" --spec "$spec" "$OUT/$name" >"$T/$name.out" 2>"$T/$name.err" && ok ||
    bad "$name: validation failed: $(head -3 "$T/$name.err")"
  grep -qx "$N scenarios, $N meet the spec, 0 fail" "$T/$name.out" && ok ||
    bad "$name: $(tail -1 "$T/$name.out")"
  k=$(soft_check "$T/$name.out" "$spec") && ok || bad "$name: $k"
  soft_total=$((soft_total + ${k:-0}))
done
[[ $city_verified -eq $N ]] && ok || bad "expected $N city scenarios verified, got $city_verified"
# Three examples carry a soft requirement: all were checked.
[[ $soft_total -eq 3 ]] && ok || bad "expected 3 soft requirements checked, got $soft_total"

# --- outside judge: the JSON schemas (sim_config's spec block included)
/usr/bin/python3 - "$SRC/config/schema" "$OUT" <<'EOF' && ok || bad "jsonschema"
import glob, json, sys
import jsonschema
schema_dir, out = sys.argv[1:]
checked = 0
for kind in ("mission", "sim_config"):
    schema = json.load(open(f"{schema_dir}/{kind}.schema.json"))
    for f in sorted(glob.glob(f"{out}/*/*/{kind}.json"))[::97]:
        doc = json.load(open(f))
        jsonschema.validate(doc, schema)
        if kind == "sim_config":
            assert "spec" in doc and len(doc["spec"]["hash"]) == 16, f
        checked += 1
# Negative control: a spec block with a bad hash fails the schema.
doc["spec"]["hash"] = "XYZ"
try:
    jsonschema.validate(doc, schema)
    sys.exit("a bad spec.hash passed the schema")
except jsonschema.ValidationError:
    pass
assert checked > 100, checked
EOF

# --- same spec and seed, same bytes on any --jobs; Halton too
red="$S/red_sedan_garage.hspec"
"$G" --spec "$red" --count 40 --seed 9 --out "$T/j1" --jobs 1 --quiet && ok || bad "jobs 1"
"$G" --spec "$red" --count 40 --seed 9 --out "$T/j3" --jobs 3 --quiet && ok || bad "jobs 3"
diff -r "$T/j1" "$T/j3" >/dev/null && ok || bad "--spec outputs differ between --jobs 1 and 3"
"$G" --spec "$S/halton_sweep.hspec" --sampler halton --count 40 --seed 9 --out "$T/h1" --jobs 1 --quiet && ok || bad "halton jobs 1"
"$G" --spec "$S/halton_sweep.hspec" --sampler halton --count 40 --seed 9 --out "$T/h2" --jobs 2 --quiet && ok || bad "halton jobs 2"
diff -r "$T/h1" "$T/h2" >/dev/null && ok || bad "halton outputs differ between --jobs 1 and 2"
"$V" --spec "$S/halton_sweep.hspec" "$T/h1" >/dev/null 2>&1 && ok || bad "halton outputs fail the spec"
grep -q '"sampler": "halton"' "$T/h1"/*/sim_config.json && ok || bad "no halton provenance"

# --- --param overrides reach the scenes
"$G" --spec "$S/snowy_dusk_search.hspec" --param snow=0.9 --count 20 --seed 4 --out "$T/p" --quiet && ok || bad "--param run"
n=$(grep -l '"snow": 0.9' "$T/p"/*/sim_config.json | wc -l)
[[ $n -eq 20 ]] && ok || bad "--param snow=0.9: $n of 20 scenarios have snow 0.9"
"$V" --spec "$S/snowy_dusk_search.hspec" --param snow=0.9 "$T/p" >/dev/null 2>&1 && ok || bad "--param outputs fail the spec"
# Negative control: the same scenes against the spec's own range(0.5, 1) pass, against 0.6 fail.
expect 2 "environment.snow: 0.9 is outside 0.6" "$V" --spec "$S/snowy_dusk_search.hspec" --param snow=0.6 "$T/p"

# --- bad input: exit 2, a message naming the place, nothing written
printf 'scenario area_search\ntarget car {colour: red}\n' >"$T/bad.hspec"
expect 2 "bad.hspec:2:13: error: unknown attribute 'colour' of car; did you mean 'color'" "$G" --spec "$T/bad.hspec" --count 3 --seed 1 --out "$T/x1"
printf 'scenario area_search\ntarget car {color: red}\nrequire street ON_TOP_OF target\nrequire driveway ON_TOP_OF target\n' >"$T/unsat.hspec"
expect 2 "unsat.hspec:4:1: error: unsatisfiable in this world: driveway ON_TOP_OF target: 0 of [0-9]+ candidates \(parking places x looks: [0-9]+ -> color red: [0-9]+ -> street ON_TOP_OF target: [0-9]+\)" "$G" --spec "$T/unsat.hspec" --count 3 --seed 1 --out "$T/x2"
expect 2 "--param: unknown parameter 'snwo'; did you mean 'snow'" "$G" --spec "$S/snowy_dusk_search.hspec" --param snwo=1 --count 3 --seed 1 --out "$T/x3"
expect 2 "--param: parameter 'snow' given more than once" "$G" --spec "$S/snowy_dusk_search.hspec" --param snow=1 --param snow=0.7 --count 3 --seed 1 --out "$T/x4"
expect 2 "--sampler: expected random or halton, got 'sobol'" "$G" --spec "$red" --sampler sobol --count 3 --seed 1 --out "$T/x5"
expect 2 "a spec names its class" "$G" --spec "$red" --class pursuit --count 3 --seed 1 --out "$T/x6"
expect 2 "cannot read spec file" "$G" --spec "$T/missing.hspec" --count 3 --seed 1 --out "$T/x7"
for x in x1 x2 x3 x4 x5 x6 x7; do
  [[ ! -e "$T/$x" ]] && ok || bad "a refused run wrote $T/$x"
done

# --- negative controls: the validator fails scenes that do not meet the spec
expect 2 "requirement 'garage LEFT_OF target \{color: white\}' does not hold|model 'Accord' is not one of Impala|make '.*' is not one of Chevrolet" "$V" --spec "$S/impala_lookalikes.hspec" "$T/j1"
out=$("$V" --spec "$S/impala_lookalikes.hspec" "$T/j1" 2>/dev/null | tail -1)
[[ "$out" == "40 scenarios, 0 meet the spec, 40 fail" ]] && ok || bad "impala spec on red-sedan scenes: $out"
one="$(ls -d "$T/j1"/*/ | head -1)"
sed -i 's/"color": "red"/"color": "green"/' "$one/sim_config.json"
out=$("$V" --spec "$red" "$T/j1" 2>"$T/neg.err" | tail -1)
[[ "$out" == "40 scenarios, 39 meet the spec, 1 fail" ]] && ok || bad "edited target colour: $out"
grep -q "color 'green' is not one of red" "$T/neg.err" && ok || bad "no colour message: $(cat "$T/neg.err")"

# The UAV start and the AOI around the target, recomputed from the scene: one kerbside scene
# with its UAV moved 1 km, one impala scene with its AOI moved 25 m, each fails (exit 2).
k1="$(ls -d "$OUT/kerbside_suv"/*/ | head -1)"
/usr/bin/python3 - "$k1/sim_config.json" <<'EOF2'
import json, sys
d = json.load(open(sys.argv[1]))
d["uav"]["start"]["x"] += 1000.0  # at least 700 m from the target
json.dump(d, open(sys.argv[1], "w"), indent=2)
EOF2
expect 2 "uav.start_within: the UAV starts" "$V" --spec "$S/kerbside_suv.hspec" "$k1"
i1="$(ls -d "$OUT/impala_lookalikes"/*/ | head -1)"
/usr/bin/python3 - "$i1/mission.json" <<'EOF2'
import json, sys
d = json.load(open(sys.argv[1]))
for v in d["areas_of_interest"][0]["polygon"]:
    v[1] += 25.0
json.dump(d, open(sys.argv[1], "w"), indent=2)
EOF2
expect 2 "aois.target_offset" "$V" --spec "$S/impala_lookalikes.hspec" "$i1"
printf 'scenario area_search\ntarget car parked\naois { target_offset: 100 }\n' >"$T/off.hspec"
expect 2 "aois.target_offset: up to 100 m" "$G" --spec "$T/off.hspec" --count 3 --seed 1 --out "$T/x8"
[[ ! -e "$T/x8" ]] && ok || bad "a refused run wrote $T/x8"

# The van placed beside the sedan, and the landmark distance, recomputed from the scene: one
# scene without its van fails (exit 2); a spec asking for the target within 0.5 m of an
# intersection is refused as unsatisfiable; scenes generated within 40 m of an intersection pass
# and fail a 10 m spec.
v1=$(/usr/bin/python3 - "$OUT/van_beside_sedan" <<'EOF2'
import glob, json, sys
for sdir in sorted(glob.glob(sys.argv[1] + "/*/")):
    d = json.load(open(sdir + "sim_config.json"))
    m = json.load(open(sdir + "mission.json"))
    ids = {r["related"]["id"] for r in m["scene_relations"] if r["related"]["class"] == "car"}
    kept = [e for e in d["entities"] if not (e["role"] == "traffic" and e["id"] in ids
                                             and e["trajectory"] == [])]
    if len(kept) == len(d["entities"]) - 1:
        d["entities"] = kept
        json.dump(d, open(sdir + "sim_config.json", "w"), indent=2)
        print(sdir)
        break
EOF2
)
[[ -n "$v1" ]] && ok || bad "no van_beside_sedan scene with a placed van"
expect 2 "requirement 'car NEXT_TO target \{vehicle_class: van, color: white\}' does not hold" "$V" --spec "$S/van_beside_sedan.hspec" "$v1"
# A look-alike of the Impala repainted red no longer shares the target's colour (exit 2).
c1="$(ls -d "$OUT/impala_lookalikes"/*/ | head -1)"
/usr/bin/python3 - "$c1/sim_config.json" <<'EOF2'
import json, sys
d = json.load(open(sys.argv[1]))
c = [e for e in d["entities"] if e["role"] == "confuser"]
assert c, "no confuser"
c[0]["attributes"]["color"] = "red"
json.dump(d, open(sys.argv[1], "w"), indent=2)
EOF2
expect 2 "confuser car_[0-9]+: color 'red' differs from the target's" "$V" --spec "$S/impala_lookalikes.hspec" "$c1"
# The city spec builds the city (its scenes say so); on suburb scenes it is refused (exit 2).
grep -q '"type": "city"' "$(ls -d "$OUT/city_bus_stop"/*/ | head -1)/sim_config.json" && ok || bad "city_bus_stop: scene not in the city"
expect 2 "city_bus_stop.hspec:3:7: error: this spec is written for the city world; the world here is suburb" "$V" --spec "$S/city_bus_stop.hspec" "$T/j1"
printf 'scenario area_search\ntarget car parked within 0.5 of intersection\n' >"$T/w0.hspec"
expect 2 "w0.hspec:2:19: error: unsatisfiable in this world: target within 0.5 of intersection: 0 of" "$G" --spec "$T/w0.hspec" --count 3 --seed 1 --out "$T/x9"
[[ ! -e "$T/x9" ]] && ok || bad "a refused run wrote $T/x9"
printf 'scenario area_search\ntarget car parked within 40 of intersection\n' >"$T/w40.hspec"
printf 'scenario area_search\ntarget car parked within 10 of intersection\n' >"$T/w10.hspec"
"$G" --spec "$T/w40.hspec" --count 30 --seed 3 --out "$T/w40" --quiet && ok || bad "within 40: generation failed"
"$V" --spec "$T/w40.hspec" "$T/w40" >/dev/null 2>&1 && ok || bad "within 40: scenes fail their spec"
out=$("$V" --spec "$T/w10.hspec" "$T/w40" 2>/dev/null | tail -1)
[[ "$out" =~ ^30\ scenarios,\ ([0-9]+)\ meet\ the\ spec,\ ([0-9]+)\ fail$ && ${BASH_REMATCH[2]} -gt 0 ]] && ok || bad "within 10 on within-40 scenes: $out"

# A moving target and keep-out zones: malformed statements exit 2 naming the place, nothing
# written; a route_landmarks scene whose mission drops the garage's EVENTUALLY_RIGHT_OF, and one
# whose restricted zone is raised 10 m, fail (exit 2).
printf 'scenario area_search\ntarget car parked\nrequire garage EVENTUALLY_RIGHT_OF target\n' >"$T/ev.hspec"
expect 2 "ev.hspec:3:1: error: EVENTUALLY_\* applies to a moving target" "$G" --spec "$T/ev.hspec" --count 3 --seed 1 --out "$T/x10"
printf 'scenario route_search\ntarget car moving\nkoz restricted over hosue\n' >"$T/koz.hspec"
expect 2 "koz.hspec:3:21: error: unknown zone cover 'hosue'; did you mean 'house'" "$G" --spec "$T/koz.hspec" --count 3 --seed 1 --out "$T/x11"
for x in x10 x11; do
  [[ ! -e "$T/$x" ]] && ok || bad "a refused run wrote $T/$x"
done
r1="$(ls -d "$OUT/route_landmarks"/*/ | head -1)"
cp -r "$r1" "$T/r2"
/usr/bin/python3 - "$r1/mission.json" "$T/r2/mission.json" <<'EOF2'
import json, sys
d = json.load(open(sys.argv[1]))
n = len(d["scene_relations"])
d["scene_relations"] = [r for r in d["scene_relations"] if r["operator"] != "EVENTUALLY_RIGHT_OF"
                        or r["related"]["class"] != "garage"]
assert len(d["scene_relations"]) < n, "no garage EVENTUALLY_RIGHT_OF listed"
json.dump(d, open(sys.argv[1], "w"), indent=2)
d = json.load(open(sys.argv[2]))
z = [k for k in d["keep_out_zones"] if k["purpose"] == "restricted"]
z[-1]["altitude"]["max"] += 10.0
json.dump(d, open(sys.argv[2], "w"), indent=2)
EOF2
expect 2 "requirement 'garage EVENTUALLY_RIGHT_OF target' holds but the mission does not list it" "$V" --spec "$S/route_landmarks.hspec" "$r1"
expect 2 "koz restricted over house: no such keep-out zone in the mission" "$V" --spec "$S/route_landmarks.hspec" "$T/r2"

echo "$pass passed, $fail failed"
[[ $fail -eq 0 ]]
