#!/usr/bin/python3
"""Success rate of the avoid baseline on seeded avoid missions (maneuver-only mode).

Generates `hameritt_generate --class avoid --count N --seed SEED [--world W]` and flies each
scenario in mission.launch (mode maneuver_only, lock-step, as fast as it goes), then prints per
scenario the outcome, the avoid score of metrics.json (the ADK's: reach time, SPL, minimum
separation, seconds below the minimum) and the wall time, and the success count.

  /usr/bin/python3 bench/bench_avoid.py [--count 10] [--seed 1] [--world suburb|city]
      [--traffic-rate 2] [--out DIR] [--jobs 1]

--traffic-rate 0 flies blind to the other aircraft (no /adk/traffic reports). --jobs runs that
many missions at once, each on its own ROS master.
"""
import argparse
import concurrent.futures
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mission_bench_util import fly_mission  # noqa: E402


def fly(scenario, out, rate, port):
    rc, wall, m = fly_mission(scenario, out, port, ["traffic_rate_hz:=%g" % rate])
    if isinstance(m, str):
        return {"scenario": os.path.basename(scenario), "outcome": m, "rc": rc,
                "wall_s": wall}
    a = m.get("avoid", {})
    return {"scenario": os.path.basename(scenario), "outcome": m["outcome"], "rc": rc,
            "end_time": m["end_time"], "time_limit": m["time_limit"],
            "reach_time": a.get("reach_time"), "spl": a.get("spl"),
            "min_separation": a.get("min_separation"),
            "seconds_below_minimum": a.get("seconds_below_minimum"),
            "failure": a.get("failure"), "wall_s": wall}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--count", type=int, default=10)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--world", default="suburb", choices=["suburb", "city"])
    ap.add_argument("--traffic-rate", type=float, default=2.0)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    out = a.out or tempfile.mkdtemp(prefix="hameritt_bench_avoid.")
    scen = os.path.join(out, "scenarios")
    subprocess.run(["rosrun", "hameritt", "hameritt_generate", "--class", "avoid", "--count",
                    str(a.count), "--seed", str(a.seed), "--world", a.world, "--out", scen],
                   check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(scen, "manifest.json")) as f:
        manifest = json.load(f)
    dirs = [os.path.join(scen, s["path"]) for s in manifest["scenarios"]]
    results = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=a.jobs) as pool:
        futures = [pool.submit(fly, d, os.path.join(out, "run_%02d" % i), a.traffic_rate,
                               22000 + 17 * i + os.getpid() % 1000)
                   for i, d in enumerate(dirs)]
        for fut in futures:
            r = fut.result()
            results.append(r)
            sep = r.get("min_separation")
            print("%-24s %-8s reach %s s of %s, SPL %s, min separation %s m, %s s below, %s, "
                  "wall %.0f s" % (r["scenario"], r["outcome"], r.get("reach_time"),
                                   r.get("time_limit"), r.get("spl"),
                                   "%.1f" % sep if sep is not None else None,
                                   r.get("seconds_below_minimum"), r.get("failure") or "-",
                                   r["wall_s"]), flush=True)
    ok = sum(r["outcome"] == "success" for r in results)
    print("avoid, %s, seed %d, traffic %g Hz: %d of %d succeeded" % (
        a.world, a.seed, a.traffic_rate, ok, len(results)))
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump({"seed": a.seed, "world": a.world, "traffic_rate_hz": a.traffic_rate,
                   "succeeded": ok, "runs": results}, f, indent=1)
    print("results in", out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
