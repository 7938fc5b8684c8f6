#!/usr/bin/env bash
# Several cars and pedestrians placed by one spec: 200 scenarios of a spec with a white car
# NEXT_TO the target and a pedestrian LEFT_OF it are re-checked by hameritt_validate --spec
# (relations recomputed from the scene, not from the sampler's bookkeeping), the placed
# entities are measured again by Shapely (footprints apart, the car within NEXT_TO's distance),
# a scene without its placed pedestrian fails (negative control), the same bytes come on any
# --jobs, and a pair that no place can meet together is refused (exit 2, nothing written).
source "$(dirname "$0")/cli_lib.sh" specs_placed

G="$BIN/hameritt_generate"
V="$BIN/hameritt_validate"
N=200
cat >"$T/two.hspec" <<'EOF'
scenario area_search
target car {vehicle_class: sedan} parked
require car NEXT_TO target {color: white}
require pedestrian LEFT_OF target
require not car IN_FRONT_OF target
EOF
"$G" --spec "$T/two.hspec" --count $N --seed 2026 --out "$T/two" --jobs 2 --quiet &&
  ok || bad "generation failed"
"$V" --spec "$T/two.hspec" "$T/two" >"$T/two.out" 2>"$T/two.err" && ok ||
  bad "validation failed: $(head -3 "$T/two.err")"
grep -qx "$N scenarios, $N meet the spec, 0 fail" "$T/two.out" && ok || bad "$(tail -1 "$T/two.out")"

# Outside judge (Shapely): in each scene, the standing white car and pedestrian listed in the
# mission's relations do not overlap each other or the target, the car's footprint lies within
# NEXT_TO's distance of the target's and the pedestrian stands on the target's left half-plane.
# Prints how many scenes had both placed; one scene without its pedestrian is written for the
# negative control.
both=$(/usr/bin/python3 - "$T/two" "$SRC/config/generator.json" "$T/doctored" <<'EOF'
import glob, json, math, os, shutil, sys
from shapely.geometry import Polygon
out, cfg_path, doctored = sys.argv[1:]
next_to = json.load(open(cfg_path))["relations"]["next_to_distance"]

def footprint(e):
    p = e["pose"]
    cx, cy, yaw = p["x"], p["y"], p["yaw"]
    hx, hy = e["size"][0] / 2, e["size"][1] / 2
    c, s = math.cos(yaw), math.sin(yaw)
    return Polygon([(cx + c * x - s * y, cy + s * x + c * y)
                    for x, y in ((hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy))])

both = 0
for sdir in sorted(glob.glob(out + "/*/")):
    sim = json.load(open(sdir + "sim_config.json"))
    mission = json.load(open(sdir + "mission.json"))
    ents = {e["id"]: e for e in sim["entities"]}
    target = next(e for e in sim["entities"] if e["role"] == "target")
    rel = {(r["operator"], r["related"]["id"]) for r in mission["scene_relations"]}
    car = [ents[i] for op, i in rel if op == "NEXT_TO" and i in ents and ents[i]["role"] == "traffic"
           and not ents[i]["trajectory"] and ents[i]["attributes"]["color"] == "white"]
    ped = [ents[i] for op, i in rel if op == "LEFT_OF" and i in ents
           and ents[i]["role"] == "pedestrian" and not ents[i]["trajectory"]]
    if not car or not ped:
        continue  # the world's own entity meets one of them
    both += 1
    t, c, p = footprint(target), footprint(car[0]), footprint(ped[0])
    assert c.distance(t) <= next_to + 1e-3, (sdir, c.distance(t))
    assert min(c.distance(t), p.distance(t), c.distance(p)) >= 0.29, sdir
    tp = target["pose"]
    dx, dy = p.centroid.x - tp["x"], p.centroid.y - tp["y"]
    assert -math.sin(tp["yaw"]) * dx + math.cos(tp["yaw"]) * dy > 0, (sdir, "not on the left")
    if both == 1:
        shutil.copytree(sdir, doctored)
        sim["entities"] = [e for e in sim["entities"] if e["id"] != ped[0]["id"]]
        json.dump(sim, open(os.path.join(doctored, "sim_config.json"), "w"), indent=2)
print(both)
EOF
) && ok || bad "shapely judge: $both"
[[ "$both" =~ ^[0-9]+$ && $both -ge $((N * 3 / 4)) ]] && ok || bad "expected >= $((N * 3 / 4)) scenes with both placed, got $both"
# Negative control: the scene without its placed pedestrian fails, naming the requirement.
expect 2 "requirement 'pedestrian LEFT_OF target' does not hold" "$V" --spec "$T/two.hspec" "$T/doctored"

# Same bytes on --jobs 1 and 3.
"$G" --spec "$T/two.hspec" --count 20 --seed 5 --out "$T/j1" --jobs 1 --quiet && ok || bad "jobs 1"
"$G" --spec "$T/two.hspec" --count 20 --seed 5 --out "$T/j3" --jobs 3 --quiet && ok || bad "jobs 3"
diff -r "$T/j1" "$T/j3" >/dev/null && ok || bad "outputs differ between --jobs 1 and 3"

# A pair that no place meets together: refused naming the later requirement, nothing written.
# Two cars next to the target with none in front of it: only the place behind it is left.
cat >"$T/pair.hspec" <<'EOF'
scenario area_search
target car parked
require not car IN_FRONT_OF target
require car NEXT_TO target {color: white}
require car NEXT_TO target {color: black}
EOF
expect 2 "pair.hspec:5:1: error: unsatisfiable in this world: car NEXT_TO target \{color: black\}: 0 of [0-9]+ candidates \(.* -> car NEXT_TO target \{color: white\}: [0-9]+\)" "$G" --spec "$T/pair.hspec" --count 3 --seed 1 --out "$T/x1"
[[ ! -e "$T/x1" ]] && ok || bad "a refused run wrote $T/x1"
# Negative control: without the white car's line the black one compiles and generates.
sed -i '/color: white/d' "$T/pair.hspec"
"$G" --spec "$T/pair.hspec" --count 3 --seed 1 --out "$T/x2" --quiet && ok || bad "one car next to it: refused"

echo "$pass passed, $fail failed"
[[ $fail -eq 0 ]]
