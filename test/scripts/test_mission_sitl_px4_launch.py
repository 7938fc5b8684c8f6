#!/usr/bin/python3
"""A whole mission flown by PX4's simulator API: `roslaunch hameritt mission.launch
autopilot:=px4` with recording on and no client, flown by the stand-in autopilot
(px4_standin.py) from its sensors alone, while the rest of the mission runs as usual:

  * the stand-in arms, climbs to 10 m, holds, lands and disarms, and every HIL_SENSOR passed
    its checks;
  * the recording (judged with Python rosbag) holds both cameras' images, boxes and depth during
    the flight, the ADK's metrics and state, and /uav/odom, whose height follows the stand-in's
    flight (a peak of 10 m, back on the ground after);
  * the ADK ends the mission at its time limit and writes metrics.json, valid under
    config/schema/metrics.schema.json, whose flown path length counts the climb and descent.
Negative control, here: the same height check on the recorded trace cut at 5 m must fail.
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

import rosbag

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import px4_standin  # noqa: E402
from fault_util import Checks, metrics_validator  # noqa: E402
from graph_util import (private_master_port, start_master, stop_master,  # noqa: E402
                        stop_process)

PORT = private_master_port(29000)
SIM_PORT = 36560 + os.getpid() % 1000  # px4_port; instance 1 adds one
TIME_LIMIT = 40.0
check = Checks()
CAMERAS = ["/uav/camera/front", "/uav/camera/down"]


def flew(trace, z0):
    """(ok, text): the recorded height rose to 10 +- 0.5 m and came back to the ground."""
    if not trace:
        return False, "no odometry"
    peak = max(z for _, z in trace) - z0
    final = trace[-1][1] - z0
    return (9.5 <= peak <= 10.5 and abs(final) < 0.2,
            "peak %.2f m, final %.3f m above the start" % (peak, final))


def connect(seconds):
    """The stand-in, connected once the simulator listens (the launch starts it)."""
    end = time.time() + seconds
    while True:
        try:
            return px4_standin.Autopilot(SIM_PORT, hold_s=5.0)
        except ConnectionRefusedError:
            if time.time() > end:
                raise RuntimeError("the simulator's PX4 port %d never opened" % SIM_PORT)
            time.sleep(0.2)


def main():
    tmp = tempfile.mkdtemp(prefix="hameritt_sitl_px4_launch.")
    out = os.path.join(tmp, "run")
    os.makedirs(out)
    core = start_master(PORT)
    launch = None
    try:
        log = os.path.join(out, "launch.log")
        env = dict(os.environ, ROS_LOG_DIR=os.path.join(out, "log"),
                   ROSCONSOLE_STDOUT_LINE_BUFFERED="1")
        launch = subprocess.Popen(
            ["roslaunch", "hameritt", "mission.launch", "autopilot:=px4",
             "px4_port:=%d" % (SIM_PORT - 1), "instance:=1", "clients:=none", "record:=true",
             "real_time_factor:=0", "time_limit:=%g" % TIME_LIMIT, "output_dir:=" + out],
            stdout=open(log, "w"), stderr=subprocess.STDOUT, env=env)
        ap = connect(120)
        t_end = ap.run(max_wall_s=240)
        ap.close()
        print("stand-in: armed %s, landed and disarmed %s at sim %.2f s; sensor checks: %s" % (
            ap.was_armed, ap.done, t_end, "; ".join(ap.problems) or "all passed"))
        check(ap.was_armed and ap.done, "the stand-in did not arm, land and disarm")
        check(not ap.problems, "HIL_SENSOR checks: %s" % ap.problems)
        check(t_end < TIME_LIMIT, "the flight took %.1f sim s, past the time limit" % t_end)
        launch.wait(300)  # the ADK ends the mission at its time limit; the launch shuts down
        launch = None

        with open(os.path.join(out, "metrics.json")) as f:
            m = json.load(f)
        errors = [e.message for e in metrics_validator().iter_errors(m)]
        print("metrics.json: outcome %s at %.1f s (%s), %.1f m flown; schema errors: %s" % (
            m["outcome"], m["end_time"], m["reason"], m["flight"]["path_length"], errors or "none"))
        check(not errors, "metrics.json does not follow its schema: %s" % errors[:3])
        check(abs(m["end_time"] - TIME_LIMIT) < 1.0, "the mission ended at %.1f s" % m["end_time"])
        check(m["flight"]["path_length"] >= 19.0,
              "flown path %.1f m: the climb and descent are 20 m" % m["flight"]["path_length"])

        counts, trace = {}, []
        with rosbag.Bag(os.path.join(out, "mission.bag")) as bag:
            for topic, msg, _ in bag.read_messages():
                counts[topic] = counts.get(topic, 0) + 1
                if topic == "/uav/odom":
                    trace.append((msg.header.stamp.to_sec(), msg.pose.pose.position.z))
        print("recording: %s" % ", ".join("%s %d" % kv for kv in sorted(counts.items())))
        for cam in CAMERAS:
            for kind in ("image_raw", "depth", "boxes"):
                n = sum(c for t, c in counts.items() if t.startswith(cam + "/") and kind in t)
                check(n >= 2 * t_end * 0.5, "%s %s: %d messages in %.0f s of flight" % (
                    cam, kind, n, t_end))
        for topic in ("/adk/metrics", "/adk/state", "/mission", "/ground_truth/entities", "/uav/imu"):
            check(counts.get(topic, 0) > 0, "nothing recorded on %s" % topic)
        z0 = trace[0][1] if trace else 0.0
        ok, why = flew(trace, z0)
        print("recorded /uav/odom: %s" % why)
        check(ok, "the recorded flight: " + why)
        cut = [(t, min(z, z0 + 5.0)) for t, z in trace]
        check(not flew(cut, z0)[0], "negative control: a flight cut at 5 m passes the check")
    finally:
        stop_process(launch, 60)
        stop_master(core)
        if not check.fails:
            shutil.rmtree(tmp, ignore_errors=True)
    return check.summary(tmp)


if __name__ == "__main__":
    sys.exit(main())
