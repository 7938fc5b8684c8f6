#!/usr/bin/python3
"""The city world type judged from outside, through the command-line tools:

  * hameritt_generate --world city writes a batch of every class that python3-jsonschema
    (Draft 7) and hameritt_validate accept, byte-identical for --jobs 1 and --jobs 2;
  * hameritt_world --world city --metrics: Shapely's union of the building footprints of the
    written world.json gives the same plan fraction, and the written entities give the same
    building count, as the tool's own measurement; the figures meet the city's targets and the
    suburb's do not (the negative control);
  * a city parameter out of range, or an unknown world type, exits 2 naming the key and its
    allowed range, and nothing is written;
  * the default world (suburb) writes no "type" key.
Prints one line per failure and a "N passed, N failed" summary; exits 1 on any failure.
"""

import filecmp
import glob
import json
import os
import subprocess
import sys
import tempfile

try:
    from jsonschema import Draft7Validator
    from shapely.geometry import Polygon
    from shapely.ops import unary_union
except ImportError as e:  # Debian: python3-jsonschema, python3-shapely
    print("test_city_world: %s" % e, file=sys.stderr)
    sys.exit(1)

from tool_checks import BIN, ENV, SRC, check, counts, run  # noqa: E402


def footprint(e):
    import math
    p, s = e["pose"], e["size"]
    c, si = math.cos(p["yaw"]), math.sin(p["yaw"])
    hx, hy = 0.5 * s[0], 0.5 * s[1]
    return Polygon([(p["x"] + c * dx - si * dy, p["y"] + si * dx + c * dy)
                    for dx, dy in ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy))])


def measure(tmp, world_type):
    out = os.path.join(tmp, world_type + "_world.json")
    metrics = os.path.join(tmp, world_type + "_metrics.json")
    r = run("hameritt_world", "--world", world_type, "--out", out, "--metrics", metrics)
    check(r.returncode == 0, "hameritt_world --world " + world_type, r.stderr)
    with open(out) as f:
        world = json.load(f)
    with open(metrics) as f:
        m = json.load(f)
    return world, m


def judge_plan(world, m, name):
    lo, hi = world["bounds"]["min"], world["bounds"]["max"]
    area = (hi[0] - lo[0]) * (hi[1] - lo[1])
    solid = [footprint(e) for e in world["entities"]
             if e["class"] in ("building", "parking_garage", "house", "garage")]
    plan = unary_union(solid).area / area
    check(abs(plan - m["plan_fraction"]) < 0.005, name + " plan fraction (Shapely)",
          "%.4f vs %.4f" % (plan, m["plan_fraction"]))
    n = sum(1 for e in world["entities"] if e["class"] in ("building", "parking_garage", "house"))
    check(n == m["buildings"], name + " building count", "%d vs %d" % (n, m["buildings"]))
    towers = sum(1 for e in world["entities"]
                 if e["class"] in ("building", "parking_garage", "house") and e["size"][2] >= 60)
    check(abs(towers / max(n, 1) - m["tower_share"]) < 1e-3, name + " tower share")
    return plan


def city_targets(m):
    los50 = [p["probability"] for p in m["p_los"] if p["height_m"] == 50][0]
    return (m["blocks_per_km2"] >= 40 and 0.40 <= m["plan_fraction"] <= 0.60 and
            6 <= m["median_storeys"] <= 8 and 0.05 <= m["tower_share"] <= 0.10 and
            m["buildings_per_km2"] >= 600 and los50 <= 0.5 and 0.2 <= m["svf_median"] <= 0.45)


def main():
    with tempfile.TemporaryDirectory(prefix="hameritt_city_") as tmp:
        # Metrics, cross-checked with Shapely.
        city, cm = measure(tmp, "city")
        suburb, sm = measure(tmp, "suburb")
        judge_plan(city, cm, "city")
        judge_plan(suburb, sm, "suburb")
        check(city_targets(cm), "city meets its targets", json.dumps(cm))
        check(not city_targets(sm), "suburb misses the city targets (negative control)")
        check(city["params"].get("type") == "city", "city params carry the type")
        check("type" not in suburb["params"] and "city" not in suburb["params"],
              "suburb params carry no type")
        classes = {e["class"] for e in city["entities"]}
        for c in ("building", "parking_garage", "parking_lot", "alley", "lamp_post",
                  "traffic_light", "bus_stop", "bench", "street_tree", "car", "street"):
            check(c in classes, "city has " + c)

        # A batch of every class, judged by jsonschema and hameritt_validate; --jobs invariant.
        validators = {}
        for kind in ("mission", "sim_config", "world", "manifest", "traffic_episode"):
            with open(os.path.join(SRC, "config", "schema", kind + ".schema.json")) as f:
                validators[kind] = Draft7Validator(json.load(f))
        dirs = []
        for jobs in ("1", "2"):
            d = os.path.join(tmp, "batch" + jobs)
            r = run("hameritt_generate", "--world", "city", "--class", "all", "--count", "6",
                    "--seed", "5", "--jobs", jobs, "--out", d, "--quiet")
            check(r.returncode == 0, "generate --world city --jobs " + jobs, r.stderr)
            dirs.append(d)
        docs = 0
        for path in sorted(glob.glob(os.path.join(dirs[0], "**", "*.json"), recursive=True)):
            kind = os.path.basename(path)[:-5]
            if kind.startswith("traffic_episode_"):
                kind = "traffic_episode"
            if kind not in validators:
                continue
            with open(path) as f:
                doc = json.load(f)
            errors = list(validators[kind].iter_errors(doc))
            check(not errors, "jsonschema " + path, errors[0].message if errors else "")
            docs += 1
            other = path.replace(dirs[0], dirs[1])
            check(filecmp.cmp(path, other, shallow=False), "byte-identical across --jobs " + path)
        episodes = glob.glob(os.path.join(dirs[0], "traffic_episode_*.json"))
        check(1 <= len(episodes) <= 6, "traffic episode files beside world.json", str(episodes))
        # Negative controls: the schemas refuse a crowd pedestrian with an unknown activity or
        # an odd keyframe field, and a reference without its pedestrian ids.
        with open(sorted(episodes)[0]) as f:
            ep = json.load(f)
        check(len(ep["pedestrians"]) >= 300, "episode pedestrians", str(len(ep["pedestrians"])))
        ep["pedestrians"][0]["activity"] = "flying"
        check(list(validators["traffic_episode"].iter_errors(ep)),
              "control: jsonschema refuses an unknown pedestrian activity")
        ep["pedestrians"][0] = dict(ep["pedestrians"][0], activity="walking", speed=1.2)
        check(list(validators["traffic_episode"].iter_errors(ep)),
              "control: jsonschema refuses an unknown pedestrian key")
        sim_path = sorted(glob.glob(os.path.join(dirs[0], "*", "sim_config.json")))[0]
        with open(sim_path) as f:
            sim = json.load(f)
        check("pedestrians" in sim["traffic"], "a reference names its pedestrians")
        del sim["traffic"]["pedestrians"]
        check(list(validators["sim_config"].iter_errors(sim)),
              "control: jsonschema refuses a reference without its pedestrian ids")
        check(docs == 2 * 6 + 2 + len(episodes), "documents in the batch", str(docs))
        files = sorted(f for f in glob.glob(os.path.join(dirs[0], "**", "*.json"), recursive=True)
                       if f not in episodes)
        check(len(files) == docs - len(episodes), "files for hameritt_validate", str(len(files)))
        r = run("hameritt_validate", *files)
        check(r.returncode == 0, "hameritt_validate accepts the city batch", r.stdout + r.stderr)

        # Bad input: exit 2, the key and its range named, nothing written.
        with open(os.path.join(SRC, "config", "world.json")) as f:
            base = json.load(f)
        bad = dict(base, type="city", city={"arterial_width": 35.0})
        bad_path = os.path.join(tmp, "bad_world.json")
        with open(bad_path, "w") as f:
            json.dump(bad, f)
        out = os.path.join(tmp, "never")
        r = run("hameritt_generate", "--world-config", bad_path, "--class", "all", "--count", "1",
                "--seed", "1", "--out", out)
        check(r.returncode == 2, "out-of-range city key exits 2", str(r.returncode))
        check("world.city.arterial_width: expected 20 to 30, got 35" in r.stderr,
              "message names the key and range", r.stderr)
        check(not os.path.exists(out), "nothing written for a bad key")
        r = run("hameritt_generate", "--world", "metropolis", "--class", "all", "--count", "1",
                "--seed", "1", "--out", out)
        check(r.returncode == 2 and "--world: expected suburb or city" in r.stderr,
              "unknown world type exits 2", r.stderr)
        big = dict(base, extent_x=2500.0)
        with open(bad_path, "w") as f:
            json.dump(big, f)
        r = run("hameritt_world", "--world-config", bad_path, "--world", "city", "--out", out)
        check(r.returncode == 2 and "world.extent_x: expected 500 to 2000" in r.stderr,
              "tile beyond 2 km exits 2", r.stderr)
        check(not os.path.exists(out), "nothing written for a bad tile")
    print(counts.summary())
    return 1 if counts.failed else 0


if __name__ == "__main__":
    sys.exit(main())
