#!/usr/bin/python3
"""The city mission's own cars never overlap the ambient cars, judged from outside on the files
that hameritt_generate --world city writes (numpy; nothing of hameritt's own readers):

  * 20 city scenarios of the five classes with moving cars (route search, pursuit, avoid,
    follow, track), two seeds: every mission car (role other than traffic) against every
    ambient car of the scenario's traffic episode that its sim_config.json does not withhold
    ("traffic": {"withheld": [ids]}), separating-axis test every 0.1 s over the duration: no
    overlapping sample;
  * every withheld car comes within the clearance (0.5 m, plus 1 cm of rounding) of a mission
    car: the generator withholds no car it need not;
  * the ambient traffic that remains keeps >= 100 moving cars per km^2 inside the tile in every
    scenario (the mean over its 0.1 s samples; each scenario's is printed);
  * hameritt_validate accepts the scenarios and refuses (exit 2, naming the field) a withheld
    id that is not one of the episode's cars, and a withheld list with an overlapping car taken
    out of it.
Negative control, run here: the same check ignoring the withheld list finds overlapping samples.
Prints one line per scenario and a "N passed, N failed" summary; exits 1 on any failure.
"""

import glob
import json
import math
import os
import sys
import tempfile

try:
    import numpy as np
except ImportError as e:  # Debian: python3-numpy
    print("test_city_withheld: %s" % e, file=sys.stderr)
    sys.exit(1)

from tool_checks import check, counts, run  # noqa: E402
from test_city_traffic import DT, car_states, corners, episode_cars, sat_overlap  # noqa: E402

CLASSES = "route_search,pursuit,avoid,follow,track"
SEEDS = (7, 31)  # ten scenarios each: two of every class
MARGIN = 0.5


def load(d):
    """(path, sim, mission cars, ambient cars) of each scenario of batch d, the ambient cars
    being every car of the episode window, each with a "withheld" flag."""
    out = []
    for path in sorted(glob.glob(os.path.join(d, "*", "sim_config.json"))):
        with open(path) as f:
            sim = json.load(f)
        check("traffic" in sim, os.path.relpath(path, d) + " references its traffic episode")
        ref = sim["traffic"]
        _, cars = episode_cars(ref, sim, path)
        withheld = set(ref.get("withheld", []))
        for c in cars:
            c["withheld"] = c["id"] in withheld
        check(len(withheld) == len(ref.get("withheld", [])) and
              withheld <= {c["id"] for c in cars}, "withheld ids are distinct episode cars")
        mission = []
        for e in sim["entities"]:
            if e["class"] != "car" or e["role"] == "traffic":
                continue
            traj = e.get("trajectory") or [[0.0, e["pose"]["x"], e["pose"]["y"], 0.0,
                                            e["pose"]["yaw"]]]
            mission.append({"id": e["id"], "size": e["size"], "trajectory": traj})
        out.append((path, sim, mission, cars))
    return out


def overlaps(mission, ambient, times, margin=0.0):
    """{ambient index: overlapping samples} of the mission cars against the ambient cars, each
    footprint grown by `margin` on every side."""
    if not mission or not ambient:
        return {}
    ax, ay, ayaw, al, aw = car_states(ambient, times)
    al, aw = al + 2 * margin, aw + 2 * margin
    mx, my, myaw, ml, mw = car_states(mission, times)
    ml, mw = ml + 2 * margin, mw + 2 * margin
    reach = 0.5 * np.hypot(al, aw)
    found = {}
    for m in range(len(mission)):
        d = np.hypot(ax - mx[m][None, :], ay - my[m][None, :])
        n, k = np.nonzero(d < reach[:, None] + 0.5 * math.hypot(ml[m], mw[m]))
        if len(k) == 0:
            continue
        ca = corners(mx[m, k], my[m, k], myaw[m, k], ml[m], mw[m])
        cb = corners(ax[n, k], ay[n, k], ayaw[n, k], al[n], aw[n])
        hit = sat_overlap(ca, cb, myaw[m, k], ayaw[n, k])
        for i in n[hit]:
            found[int(i)] = found.get(int(i), 0) + 1
    return found


def moving_density(cars, times, bounds):
    """Moving cars (> 0.5 m in 1 s) inside the tile per km^2 at each sample."""
    lo, hi = bounds
    km2 = (hi[0] - lo[0]) * (hi[1] - lo[1]) / 1e6
    xs, ys = car_states(cars, times)[:2]
    inside = (xs >= lo[0]) & (xs <= hi[0]) & (ys >= lo[1]) & (ys <= hi[1])
    step = int(round(1.0 / DT))
    moved = np.hypot(xs[:, step:] - xs[:, :-step], ys[:, step:] - ys[:, :-step]) > 0.5
    return np.sum(inside[:, :-step] & moved, axis=0) / km2


def main():
    with tempfile.TemporaryDirectory(prefix="hameritt_withheld_") as tmp:
        world_path = os.path.join(tmp, "world.json")
        r = run("hameritt_world", "--world", "city", "--out", world_path)
        check(r.returncode == 0, "hameritt_world --world city", r.stderr)
        with open(world_path) as f:
            world = json.load(f)
        bounds = (world["bounds"]["min"], world["bounds"]["max"])
        scenarios = []
        for seed in SEEDS:
            d = os.path.join(tmp, "seed%d" % seed)
            r = run("hameritt_generate", "--world", "city", "--class", CLASSES, "--count", "10",
                    "--seed", str(seed), "--out", d, "--quiet")
            check(r.returncode == 0, "generate --world city --seed %d" % seed, r.stderr)
            scenarios += load(d)
        check(len(scenarios) == 20, "scenarios written", str(len(scenarios)))

        before = after = mission_total = 0
        withheld_counts, densities = [], []
        needless = []
        victim = None  # (path, withheld id whose removal leaves an overlap, its samples)
        for path, sim, mission, cars in scenarios:
            name = os.path.basename(os.path.dirname(path))
            times = np.arange(0.0, sim["duration"] + 1e-9, DT)
            kept = [c for c in cars if not c["withheld"]]
            held = [c for c in cars if c["withheld"]]
            every = overlaps(mission, cars, times)
            left = overlaps(mission, kept, times)
            near = overlaps(mission, held, times, MARGIN + 0.01)
            needless += [c["id"] for i, c in enumerate(held) if i not in near]
            n_before, n_after = sum(every.values()), sum(left.values())
            density = moving_density(kept, times, bounds)
            print("%s: %d mission cars, %d ambient, %d withheld, %d overlapping samples without "
                  "the list, %d with it, %.1f moving cars/km^2 (mean, min %.1f)"
                  % (name, len(mission), len(cars), len(held), n_before, n_after,
                     density.mean(), density.min()))
            check(n_after == 0, name + ": no mission car overlaps an ambient car",
                  "%d samples" % n_after)
            before += n_before
            after += n_after
            mission_total += len(mission)
            withheld_counts.append(len(held))
            densities.append(density.mean())
            if every and (victim is None or max(every.values()) > victim[2]):
                i = max(every, key=every.get)
                victim = (path, cars[i]["id"], every[i])
        check(mission_total >= 20, "mission cars judged", str(mission_total))
        # The density of every scenario: a mission car that ends its route pulls over to the
        # kerb before the intersection, out of the lanes and boxes that the traffic drives.
        low = [(os.path.relpath(os.path.dirname(s[0]), tmp), d)
               for s, d in zip(scenarios, densities)
               if d < 100.0]
        check(not low, ">= 100 moving cars per km^2 remain in every scenario (mean over its "
              "samples)", " ".join("%s %.1f" % x for x in low))
        check(not needless, "every withheld car comes within %.1f m of a mission car" % MARGIN,
              " ".join(needless[:10]))
        # The negative control: the same check ignoring the withheld list.
        check(before > 0, "control: ignoring the withheld list finds overlaps", str(before))
        check(after == 0, "no overlapping sample in the 20 scenarios", str(after))
        print("%d scenarios, %d mission cars: %d overlapping samples ignoring the withheld list, "
              "%d with it; withheld cars per scenario median %.1f, max %d; moving cars/km^2 "
              "remaining: mean %.1f, per scenario %.1f to %.1f, %d below 100"
              % (len(scenarios), mission_total, before, after, float(np.median(withheld_counts)),
                 max(withheld_counts), float(np.mean(densities)), min(densities),
                 max(densities), sum(d < 100.0 for d in densities)))
        check(sum(withheld_counts) > 0 and max(withheld_counts) <= max(len(s[3]) for s in scenarios),
              "withheld counts", str(withheld_counts))

        if victim is None:
            check(False, "a scenario with a withheld overlapping car for the validator checks")
        else:
            path, vid, _ = victim
            r = run("hameritt_validate", path)
            check(r.returncode == 0, "hameritt_validate accepts the scenario", r.stderr)
            with open(path) as f:
                good = f.read()
            for label, edit, want in (
                    ("an unknown withheld id", lambda w: w + ["car_999999"],
                     "traffic.withheld[%d]"),
                    ("an overlapping car not withheld", lambda w: [i for i in w if i != vid],
                     "/traffic/withheld")):
                doc = json.loads(good)
                withheld = doc["traffic"].get("withheld", [])
                doc["traffic"]["withheld"] = edit(withheld)
                field = want % len(withheld) if "%d" in want else want
                with open(path, "w") as f:
                    json.dump(doc, f)
                r = run("hameritt_validate", path)
                check(r.returncode == 2 and field in r.stderr,
                      "hameritt_validate refuses %s (exit 2, naming %s)" % (label, field),
                      "exit %d: %s" % (r.returncode, r.stderr[-500:]))
            with open(path, "w") as f:
                f.write(good)
    print(counts.summary())
    return 1 if counts.failed else 0


if __name__ == "__main__":
    sys.exit(main())
