#!/usr/bin/env bash
# Keep-out zones over the target's street, its block and an AOI (scenarios/specs/
# street_closure.hspec): 100 scenarios pass hameritt_validate --spec (which recomputes each zone
# from the scene); Shapely measures the zones again from the files alone (the AOI zone is the
# AOI buffered by its margin with mitred corners, the street zone a band of the drawn length
# that holds the target, the block zone convex and beside it, bands and windows as drawn), and
# fails a wrong margin (negative control); a mission whose AOI or street zone is moved 1 m fails
# validation; bad zone settings exit 2 naming file:line:column, nothing written.
source "$(dirname "$0")/cli_lib.sh" specs_koz

G="$BIN/hameritt_generate"
V="$BIN/hameritt_validate"
spec="$SRC/scenarios/specs/street_closure.hspec"
N=100
"$G" --spec "$spec" --count $N --seed 11 --out "$T/s" --jobs 2 --quiet && ok || bad "generation failed"
"$V" --spec "$spec" "$T/s" >"$T/v.out" 2>"$T/v.err" && ok || bad "validation failed: $(head -3 "$T/v.err")"
grep -qx "$N scenarios, $N meet the spec, 0 fail" "$T/v.out" && ok || bad "$(tail -1 "$T/v.out")"

judged=$(/usr/bin/python3 - "$T/s" <<'EOF'
import glob, json, sys
from shapely.geometry import Point, Polygon

def aoi_zone_ok(zone, aoi, margin):
    want = Polygon(aoi).buffer(margin, join_style=2, mitre_limit=10.0)
    return Polygon(zone).hausdorff_distance(want) < 2e-3  # vertices rounded to the millimetre

n = off_centre = 0
for sdir in sorted(glob.glob(sys.argv[1] + "/*/")):
    m = json.load(open(sdir + "mission.json"))
    sim = json.load(open(sdir + "sim_config.json"))
    v = sim["spec"]["values"]
    street, block, aoi = m["keep_out_zones"][-3:]  # the koz statements' zones, in order
    assert (street["purpose"], block["purpose"], aoi["purpose"]) == (
        "restricted", "access_denial", "vantage_denial"), sdir
    a2 = m["areas_of_interest"][1]["polygon"]
    assert aoi_zone_ok(aoi["polygon"], a2, v["koz3.margin"]), (sdir, "aoi zone")
    # Negative control: the same zone is not the AOI grown by another margin.
    assert not aoi_zone_ok(aoi["polygon"], a2, v["koz3.margin"] - 1), (sdir, "control")
    t = next(e for e in sim["entities"] if e["role"] == "target")["pose"]
    p = Point(t["x"], t["y"])
    # The street band: the drawn length along the street, centred where the target is (its
    # projection on the band's axis falls on the band's centre).
    q = street["polygon"]
    sides = [Point(q[i]).distance(Point(q[i + 1])) for i in range(2)]
    k = 0 if sides[0] > sides[1] else 1
    ux, uy = (q[k + 1][0] - q[k][0]) / sides[k], (q[k + 1][1] - q[k][1]) / sides[k]
    cx, cy = sum(x for x, _ in q) / 4, sum(y for _, y in q) / 4
    along = (p.x - cx) * ux + (p.y - cy) * uy
    assert abs(sides[k] - v["koz1.length"]) < 2e-3, (sdir, "street zone length", sides)
    off_centre += abs(along) > 2e-3
    assert Polygon(q).distance(p) < 25.0, (sdir, "street zone far from the target")
    assert street["altitude"] == {"min": v["koz1.alt_min"], "max": v["koz1.alt_max"]}, sdir
    b = Polygon(block["polygon"])
    assert b.is_valid and abs(b.convex_hull.area - b.area) < 0.05 and b.area > 2000, sdir
    assert b.distance(p) < 10.0 and block["time_window"] == {"nlt": v["koz2.nlt"]}, sdir
    n += 1
# A target beyond the end of its street segment (at a corner) has its band at the segment's end.
assert off_centre <= n // 10, f"{off_centre} of {n} street zones not centred on the target"
print(n)
EOF
) && ok || bad "shapely judge: $judged"
[[ "$judged" == "$N" ]] && ok || bad "expected $N scenes judged, got $judged"

# Negative controls: the AOI zone, then the street zone, moved 1 m east in a copy of one scene.
one="$(ls -d "$T/s"/*/ | head -1)"
for k in 1 3; do
  rm -rf "$T/d$k" && cp -r "$one" "$T/d$k"
  /usr/bin/python3 - "$T/d$k/mission.json" "$k" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
for v in d["keep_out_zones"][-int(sys.argv[2])]["polygon"]:
    v[0] += 1.0
json.dump(d, open(sys.argv[1], "w"), indent=2)
EOF
done
expect 2 "koz vantage_denial over aoi 2: no such keep-out zone in the mission" "$V" --spec "$spec" "$T/d1"
expect 2 "koz restricted over street: no such keep-out zone in the mission" "$V" --spec "$spec" "$T/d3"

# Type errors: file:line:column, what was expected, nothing written.
k=0
for line in 'koz restricted over street { count: 2 }|3:30: error: unknown setting .count. of a zone over street; settings: alt, length, margin, net, nlt' \
  'koz restricted over street { length: 5 }|3:38: error: koz1.length: expected values within \[10, 400\], got 5' \
  'koz restricted over aoi 9|3:25: error: expected the AOI.s number \(1 to 5\) after .aoi., got .9.' \
  'koz restricted over aoi 3|3:25: error: aoi 3: a scenario of this spec may have 2 AOI\(s\)'; do
  k=$((k + 1))
  printf 'scenario area_search\naois { count: 2 }\n%s\n' "${line%%|*}" >"$T/bad$k.hspec"
  expect 2 "bad$k.hspec:${line#*|}" "$G" --spec "$T/bad$k.hspec" --count 2 --seed 1 --out "$T/x$k"
  [[ ! -e "$T/x$k" ]] && ok || bad "a refused run wrote $T/x$k"
done
printf 'scenario pursuit\ntarget car\nkoz restricted over aoi 1\n' >"$T/bad5.hspec"
expect 2 "bad5.hspec:3:1: error: a zone over an AOI applies to area_search only" "$G" --spec "$T/bad5.hspec" --count 2 --seed 1 --out "$T/x5"

echo "$pass passed, $fail failed"
[[ $fail -eq 0 ]]
