#!/usr/bin/python3
"""Success rate of the baseline on seeded follow missions (maneuver-only mode).

Generates `hameritt_generate --class follow --count N --seed SEED` and flies each scenario in
mission.launch (mode maneuver_only, lock-step, as fast as it goes), then prints per scenario
the outcome and the follow phase's figures from metrics.json (the ADK's ground truth): the
find, the approach to the envelope, the inside fraction, the longest stretch outside and the
failure, the wall time, and the success count with the failures grouped by cause.

  /usr/bin/python3 bench/bench_follow.py [--count 10] [--seed 1] [--first 0] [--pursue true|false]
      [--out DIR] [--jobs 1]

--jobs runs that many missions at once, each on its own ROS master.
"""
import collections
import json
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mission_bench_util import (fly_all, fly_mission, generate,  # noqa: E402
                                pursuit_arguments)


def cause(r):
    """The failure's kind, for the summary."""
    text = r.get("failure") or r["outcome"]
    for key, name in (("search phase", "not found"), ("outside the envelope", "outside rule"),
                      ("inside the envelope", "inside fraction"), ("approach", "approach cut"),
                      ("keep-out", "keep-out"), ("collision", "collision")):
        if key in text:
            return name
    return text


def fly(scenario, out, pursue, port):
    rc, wall, m = fly_mission(scenario, out, port, ["pursue:=" + pursue])
    r = {"scenario": os.path.basename(scenario), "rc": rc, "wall_s": wall}
    if isinstance(m, str) or "follow" not in m:
        r["outcome"] = m if isinstance(m, str) else "no follow block"
        return r
    f = m["follow"]
    r.update({"outcome": m["outcome"], "success": f["success"], "failure": f["failure"],
              "find": f["start_time"], "approach": f["approach_time"],
              "duration": f["duration"], "elapsed": f["elapsed"],
              "inside_fraction": f["inside_fraction"], "longest_outside": f["longest_outside"],
              "rms_distance_error": f["rms_distance_error"]})
    return r


def main():
    ap = pursuit_arguments()
    a = ap.parse_args()
    out = a.out or tempfile.mkdtemp(prefix="hameritt_bench_follow.")
    dirs = generate("follow", a.count, a.seed, out, ["--first", str(a.first)])

    def report(r):
        find = r.get("find")
        print("%-24s %-8s find %s, approach %4.1f s, %5.1f of %3.0f s: inside %5.1f %%, "
              "longest outside %4.1f s, RMS %.1f m; %s; wall %.0f s"
              % (r["scenario"], r["outcome"], "%.1f s" % find if find is not None else "none",
                 r.get("approach", 0), r.get("elapsed", 0), r.get("duration", 0),
                 100 * r.get("inside_fraction", 0), r.get("longest_outside", 0),
                 r.get("rms_distance_error", 0), r.get("failure") or "-", r["wall_s"]),
              flush=True)

    results = fly_all(dirs, out, a.jobs, lambda d, o, port: fly(d, o, a.pursue, port), report)
    ok = sum(r["outcome"] == "success" for r in results)
    causes = collections.Counter(cause(r) for r in results if r["outcome"] != "success")
    print("pursue %s, seed %d: %d of %d succeeded; failures: %s" % (
        a.pursue, a.seed, ok, len(results),
        ", ".join("%s %d" % kv for kv in sorted(causes.items())) or "none"))
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump({"seed": a.seed, "pursue": a.pursue, "succeeded": ok,
                   "failures": dict(causes), "runs": results}, f, indent=1)
    print("results in", out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
