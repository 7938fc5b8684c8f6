"""Shared by the seeded-mission benchmarks (bench_pursuit.py, bench_follow.py, bench_avoid.py):
the seeded scenarios generated, and each mission flown in mission.launch (maneuver_only,
lock-step, as fast as it goes) on its own ROS master."""
import json
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "test",
                                "scripts"))
from graph_util import start_master, stop_master  # noqa: E402


def fly_mission(scenario, out, port, args):
    """Flies `scenario` with the extra mission.launch `args`, its log in OUT.log and
    metrics.json in OUT. Returns (exit code, wall seconds, metrics dict or the error text)."""
    env = dict(os.environ, ROS_MASTER_URI="http://localhost:%d" % port,
               ROSCONSOLE_STDOUT_LINE_BUFFERED="1")
    core = start_master(port)
    t0 = time.time()
    try:
        with open(out + ".log", "w") as log:
            rc = subprocess.call(
                ["roslaunch", "-p", str(port), "hameritt", "mission.launch",
                 "scenario:=" + scenario, "mode:=maneuver_only", "lockstep:=true",
                 "real_time_factor:=0"] + list(args) + ["output_dir:=" + out],
                stdout=log, stderr=subprocess.STDOUT, env=env, timeout=3600)
    finally:
        stop_master(core)
    wall = time.time() - t0
    try:
        with open(os.path.join(out, "metrics.json")) as f:
            return rc, wall, json.load(f)
    except (OSError, ValueError) as e:
        return rc, wall, "no metrics: %s" % e


def generate(cls, count, seed, out, extra=()):
    """`hameritt_generate --class CLS --count COUNT --seed SEED` into OUT/scenarios: the
    scenario directories, in the manifest's order."""
    scen = os.path.join(out, "scenarios")
    subprocess.run(["rosrun", "hameritt", "hameritt_generate", "--class", cls, "--count",
                    str(count), "--seed", str(seed), "--out", scen] + list(extra), check=True,
                   stdout=subprocess.DEVNULL)
    with open(os.path.join(scen, "manifest.json")) as f:
        manifest = json.load(f)
    return [os.path.join(scen, s["path"]) for s in manifest["scenarios"]]


def fly_all(dirs, out, jobs, fly, report):
    """fly(scenario, out_prefix, port) for each scenario, `jobs` at once, each on its own ROS
    master; report(result) prints each result in order. Returns the results."""
    import concurrent.futures
    results = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
        futures = [pool.submit(fly, d, os.path.join(out, "run_%02d" % i),
                               21000 + 17 * i + os.getpid() % 1000)
                   for i, d in enumerate(dirs)]
        for fut in futures:
            r = fut.result()
            results.append(r)
            report(r)
    return results


def pursuit_arguments():
    """The options bench_pursuit.py and bench_follow.py share: --count, --seed, --first,
    --pursue, --jobs, --out."""
    import argparse
    ap = argparse.ArgumentParser()
    ap.add_argument("--count", type=int, default=10)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--first", type=int, default=0,
                    help="fly scenarios FIRST .. FIRST+COUNT-1 of the seed's batch (a shard)")
    ap.add_argument("--pursue", default="true", choices=["true", "false"])
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--out", default=None)
    return ap
