#!/usr/bin/python3
"""Benchmark of hameritt_campaign on this machine: scenarios/s of a generation-only campaign
and missions/hour of a mission campaign, for 1, 2 and 4 local shards (run --local --jobs S,
each shard its own process; the missions each with their own ROS master).

  /usr/bin/python3 bench/bench_campaign.py [--scenarios 3000] [--missions 4] [--time-limit 10]
      [--mode end_to_end] [--shards 1,2,4] [--keep DIR]

Needs the build (build/devel, or HAMERITT_BIN_DIR naming devel/lib/hameritt) and, for the
missions, a sourced devel/setup.bash (roslaunch finds the package). Prints one line per shard
count and a JSON summary; the wall time includes process start-up, the world build of every
generation unit and each mission's ROS graph start and shutdown.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def campaign_tool():
    for d in (os.environ.get("HAMERITT_BIN_DIR", ""),
              os.path.join(HERE, "..", "build", "devel", "lib", "hameritt")):
        p = os.path.join(d, "hameritt_campaign")
        if d and os.access(p, os.X_OK):
            return p
    sys.exit("bench_campaign: hameritt_campaign not built (set HAMERITT_BIN_DIR)")


def run_campaign(tool, root, name, text, shards):
    cdir = os.path.join(root, name)
    cfg = os.path.join(root, name + ".yaml")
    with open(cfg, "w") as f:
        f.write(text)
    subprocess.run([tool, "plan", cfg, "--out", cdir], check=True, stdout=subprocess.DEVNULL)
    t0 = time.time()
    r = subprocess.run([tool, "run", cdir, "--local", "--jobs", str(shards)],
                       stdout=subprocess.PIPE, universal_newlines=True)
    wall = time.time() - t0
    if r.returncode != 0:
        sys.exit("bench_campaign: %s failed:\n%s" % (name, r.stdout))
    subprocess.run([tool, "merge", cdir], check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(cdir, "merged", "manifest.json")) as f:
        return wall, json.load(f)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenarios", type=int, default=3000)
    ap.add_argument("--missions", type=int, default=4)
    ap.add_argument("--time-limit", type=float, default=10.0)
    ap.add_argument("--mode", default="end_to_end")
    ap.add_argument("--shards", default="1,2,4")
    ap.add_argument("--keep", default="", help="keep the campaigns in this directory")
    args = ap.parse_args()
    tool = campaign_tool()
    root = args.keep or tempfile.mkdtemp(prefix="hameritt_bench_campaign_")
    os.makedirs(root, exist_ok=True)
    results = []
    try:
        with open("/proc/loadavg") as f:
            load0 = f.read().split()[0]
        for s in [int(x) for x in args.shards.split(",")]:
            gen = ("name: gen%d\nseed: 1\nclasses: all\ncount: %d\nshards: %d\n"
                   % (s, args.scenarios, s))
            gwall, gm = run_campaign(tool, root, "gen%d" % s, gen, s)
            mis = ("name: mis%d\nseed: 1\nclasses: all\ncount: %d\nshards: %d\n"
                   "missions: {count: %d, modes: [%s], time_limit: %g, real_time_factor: 0,"
                   " record: true}\n" % (s, args.missions, s, args.missions, args.mode,
                                          args.time_limit))
            mwall, mm = run_campaign(tool, root, "mis%d" % s, mis, s)
            row = {"shards": s, "scenarios": len(gm["scenarios"]),
                   "generation_wall_s": round(gwall, 2),
                   "scenarios_per_s": round(len(gm["scenarios"]) / gwall, 1),
                   "missions": len(mm["missions"]), "mission_sim_s": args.time_limit,
                   "missions_wall_s": round(mwall, 2),
                   "missions_per_hour": round(len(mm["missions"]) * 3600.0 / mwall, 1),
                   "mean_mission_wall_s": round(sum(e["wall_time"] for e in mm["missions"])
                                                / len(mm["missions"]), 2),
                   "bag_mb_per_mission": round(mm["summary"]["bag_bytes"] / 1e6
                                               / len(mm["missions"]), 1)}
            results.append(row)
            print("shards %d: %d scenarios in %.2f s = %.1f scenarios/s; %d missions of %g sim s "
                  "in %.1f s = %.1f missions/hour (mean %.1f s per mission)"
                  % (s, row["scenarios"], gwall, row["scenarios_per_s"], row["missions"],
                     args.time_limit, mwall, row["missions_per_hour"],
                     row["mean_mission_wall_s"]), flush=True)
        with open("/proc/loadavg") as f:
            load1 = f.read().split()[0]
        print(json.dumps({"cores": os.cpu_count(), "load_before": load0, "load_after": load1,
                          "mode": args.mode, "results": results}, indent=1))
    finally:
        if not args.keep:
            shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    main()
