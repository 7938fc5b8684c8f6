"""Shared by the seeded-mission benchmarks (bench_pursuit.py, bench_avoid.py): one mission flown
in mission.launch (maneuver_only, lock-step, as fast as it goes) on its own ROS master."""
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
