#!/usr/bin/python3
"""Success rate of the baseline on seeded pursuit missions (maneuver-only mode).

Generates `hameritt_generate --class pursuit --count N --seed SEED` and flies each scenario in
mission.launch (mode maneuver_only, lock-step, as fast as it goes, the mission's own time limit
unless --time-limit), then prints per scenario the outcome, the target's in-view time and
fraction (from metrics.json, the ADK's ground truth) and the wall time, and the success count.

  /usr/bin/python3 bench/bench_pursuit.py [--count 10] [--seed 1] [--first 0] [--pursue true|false]
      [--time-limit 0] [--out DIR] [--jobs 1]

--jobs runs that many missions at once, each on its own ROS master.
"""
import json
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mission_bench_util import (fly_all, fly_mission, generate,  # noqa: E402
                                pursuit_arguments)


def fly(scenario, out, pursue, time_limit, port):
    rc, wall, m = fly_mission(scenario, out, port,
                              ["time_limit:=%g" % time_limit, "pursue:=" + pursue])
    if isinstance(m, str):
        return {"scenario": os.path.basename(scenario), "outcome": m, "rc": rc,
                "wall_s": wall}
    limit = m["time_limit"]
    in_view = m["targets"][0]["in_view_time"]
    return {"scenario": os.path.basename(scenario), "outcome": m["outcome"], "rc": rc,
            "time_limit": limit, "in_view_time": in_view,
            "in_view_fraction": in_view / limit if limit else 0.0,
            "first_seen": m["targets"][0].get("first_seen_time"), "wall_s": wall}


def main():
    ap = pursuit_arguments()
    ap.add_argument("--time-limit", type=float, default=0.0, help="0: the mission's")
    a = ap.parse_args()
    out = a.out or tempfile.mkdtemp(prefix="hameritt_bench_pursuit.")
    dirs = generate("pursuit", a.count, a.seed, out, ["--first", str(a.first)])

    def report(r):
        print("%-26s %-8s in view %6.1f s of %4.0f s (%3.0f %%), first seen %s, wall %.0f s"
              % (r["scenario"], r["outcome"], r.get("in_view_time", 0), r.get("time_limit", 0),
                 100 * r.get("in_view_fraction", 0), r.get("first_seen"), r["wall_s"]),
              flush=True)

    results = fly_all(dirs, out, a.jobs,
                      lambda d, o, port: fly(d, o, a.pursue, a.time_limit, port), report)
    ok = sum(r["outcome"] == "success" for r in results)
    print("pursue %s, seed %d: %d of %d succeeded" % (a.pursue, a.seed, ok, len(results)))
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump({"seed": a.seed, "pursue": a.pursue, "succeeded": ok, "runs": results}, f,
                  indent=1)
    print("results in", out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
