#!/usr/bin/python3
"""Success rate of the baseline on seeded track missions (maneuver-only mode).

For each seed S of --seeds, generates `hameritt_generate --class track --count 1 --seed S` (the
scenario test/scripts/test_mission_track.py flies for its seed) and flies it in mission.launch
(mode maneuver_only, lock-step, as fast as it goes, found_by_sighting:=false: the find, and so
the track phase's start, is the client's claim, as in the test), then prints per scenario the
outcome and the track phase's figures from metrics.json (the ADK's ground truth): its start,
the time flown, the tracked fraction (the lowest of the targets'), the breaks, the failure, the
wall time, and the success count with the failures grouped by cause.

  /usr/bin/python3 bench/bench_track.py [--seeds 1-10] [--pursue true|false]
      [--use-target-state true|false] [--track-boxes perfect_perception|detector]
      [--world suburb|city] [--out DIR] [--jobs 1]

--world city generates each seed's scenario in the generated city (`hameritt_generate --world
city`).

--track-boxes detector: the reported boxes come from the colour/shape detector's blobs in the
down camera's rendered frames instead of the perfect-perception report.

--jobs runs that many missions at once, each on its own ROS master.
"""
import argparse
import collections
import json
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mission_bench_util import fly_all, fly_mission, generate  # noqa: E402


def seed_list(text):
    """'1-10' or '1,4,8' (or both, comma-separated) as a list of seeds."""
    seeds = []
    for part in text.split(","):
        lo, _, hi = part.partition("-")
        seeds += range(int(lo), int(hi or lo) + 1)
    return seeds


def cause(r):
    """The failure's kind, for the summary."""
    text = r.get("failure") or r["outcome"]
    for key, name in (("lost for more than", "loss > limit"), ("tracked", "tracked fraction"),
                      ("search phase", "not found"), ("ended before", "mission ended"),
                      ("keep-out", "keep-out"),
                      ("collision", "collision")):
        if key in text:
            return name
    return text


def fly(scenario, seed, out, args, port):
    rc, wall, m = fly_mission(scenario, out, port, args)
    r = {"seed": seed, "scenario": os.path.basename(scenario), "rc": rc, "wall_s": wall}
    if isinstance(m, str) or "track" not in m:
        r["outcome"] = m if isinstance(m, str) else "no track block"
        return r
    t = m["track"]
    r.update({"outcome": m["outcome"], "success": t["success"], "failure": t.get("failure"),
              "start": t.get("start_time"), "elapsed": t.get("elapsed", 0),
              "duration": t.get("duration", 0), "tracked_fraction": t.get("tracked_fraction", 0),
              "targets": len(t.get("per_target", [])),
              "breaks": sum(p["breaks"] for p in t.get("per_target", [])),
              "precision": min((p.get("precision", 0) for p in t.get("per_target", [])),
                               default=0),
              "mota": t.get("clear_mot", {}).get("mota"),
              "tp": t.get("clear_mot", {}).get("tp"), "fn": t.get("clear_mot", {}).get("fn")})
    return r


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=seed_list, default=seed_list("1-10"))
    ap.add_argument("--pursue", default="true", choices=["true", "false"])
    ap.add_argument("--use-target-state", default="true", choices=["true", "false"])
    ap.add_argument("--track-boxes", default="perfect_perception",
                    choices=["perfect_perception", "detector"])
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--world", default="suburb", choices=["suburb", "city"])
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    out = a.out or tempfile.mkdtemp(prefix="hameritt_bench_track.")
    jobs = []
    for s in a.seeds:
        [d] = generate("track", 1, s, os.path.join(out, "seed_%02d" % s), ["--world", a.world])
        jobs.append((d, s))
    args = ["found_by_sighting:=false", "pursue:=" + a.pursue,
            "use_target_state:=" + a.use_target_state, "track_boxes:=" + a.track_boxes]

    def report(r):
        start = r.get("start")
        print("seed %2d %-24s %-8s %d target(s), start %s, %5.1f of %3.0f s: tracked %5.1f %%, "
              "%d breaks, reported boxes: precision %.3f, CLEAR-MOT TP %s FN %s; %s; wall %.0f s"
              % (r["seed"], r["scenario"], r["outcome"], r.get("targets", 0),
                 "%.1f s" % start if start is not None else "none", r.get("elapsed", 0),
                 r.get("duration", 0), 100 * r.get("tracked_fraction", 0), r.get("breaks", 0),
                 r.get("precision", 0), r.get("tp"), r.get("fn"),
                 r.get("failure") or "-", r["wall_s"]), flush=True)

    seed_of = dict(jobs)
    results = fly_all([d for d, _ in jobs], out, a.jobs,
                      lambda d, o, port: fly(d, seed_of[d], o, args, port), report)
    ok = sum(r["outcome"] == "success" for r in results)
    causes = collections.Counter(cause(r) for r in results if r["outcome"] != "success")
    print("%s, pursue %s, use_target_state %s, seeds %s: %d of %d succeeded; failures: %s" % (
        a.world, a.pursue, a.use_target_state, ",".join(str(s) for s in a.seeds), ok, len(results),
        ", ".join("%s %d" % kv for kv in sorted(causes.items())) or "none"))
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump({"seeds": a.seeds, "world": a.world, "pursue": a.pursue, "use_target_state": a.use_target_state,
                   "track_boxes": a.track_boxes,
                   "succeeded": ok, "failures": dict(causes), "runs": results}, f, indent=1)
    print("results in", out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
