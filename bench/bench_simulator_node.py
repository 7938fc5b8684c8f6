#!/usr/bin/env python3
"""Benchmark: the simulator node's real-time factor, unpaced, without cameras.

Starts `roslaunch hameritt simulator.launch real_time_factor:=0` on the shipped scenario (its own
roscore on a free port), listens to /clock and /uav/odom, and prints the real-time factor over
a window of sim time and the odometry messages received against those published (drops).
Run after sourcing build/devel/setup.bash:
  python3 bench/bench_simulator_node.py [SIM_SECONDS] [REAL_TIME_FACTOR]
REAL_TIME_FACTOR 0 (default) runs unpaced; a positive value paces the node, to see whether a
(Python) subscriber keeps up at that factor.
"""
import os
import subprocess
import sys
import time

import rospy
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "test", "scripts"))
from graph_util import free_port, start_master, stop_master, stop_process  # noqa: E402


def main():
    window = float(sys.argv[1]) if len(sys.argv) > 1 else 120.0
    pace = float(sys.argv[2]) if len(sys.argv) > 2 else 0.0
    master = free_port()
    os.environ["ROS_MASTER_URI"] = "http://localhost:%d" % master
    env = dict(os.environ)
    core = start_master(master)
    sim = subprocess.Popen(
        ["roslaunch", "hameritt", "simulator.launch", "real_time_factor:=%g" % pace, "start_paused:=true",
         "duration:=%g" % (window + 10.0)],
        env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        rospy.init_node("bench_simulator_node", anonymous=True, disable_signals=True)
        marks = {}
        odom = [0]
        start_at, end_at = 5.0, 5.0 + window

        def on_clock(msg):
            t = msg.clock.to_sec()
            now = time.monotonic()
            if t >= start_at and "start" not in marks:
                marks["start"] = (t, now, odom[0])
            if t >= end_at and "end" not in marks:
                marks["end"] = (t, now, odom[0])

        def on_odom(_):
            odom[0] += 1

        rospy.Subscriber("/clock", Clock, on_clock, queue_size=1000, tcp_nodelay=True)
        rospy.Subscriber("/uav/odom", Odometry, on_odom, queue_size=1000, tcp_nodelay=True)
        from hameritt.srv import SetPaused
        rospy.wait_for_service("/simulator/set_paused", timeout=60)
        time.sleep(1.0)  # let the subscriptions connect before time starts
        rospy.ServiceProxy("/simulator/set_paused", SetPaused)(False)
        deadline = time.monotonic() + 600
        while "end" not in marks and time.monotonic() < deadline:
            time.sleep(0.05)
        if "end" not in marks:
            print("simulator_node: did not reach t=%.0f s" % end_at)
            return 1
        (t0, w0, n0), (t1, w1, n1) = marks["start"], marks["end"]
        rtf = (t1 - t0) / (w1 - w0)
        rate = float(rospy.get_param("/simulator/publish_rate_hz", 250.0))
        expected = int(round((t1 - t0) * rate))
        print("sim_seconds                %.1f" % (t1 - t0))
        print("wall_seconds               %.2f" % (w1 - w0))
        print("requested_real_time_factor %s" % ("unpaced" if pace <= 0 else "%g" % pace))
        print("real_time_factor           %.1f (target >= 50)" % rtf)
        print("odometry_received          %d of %d published at %.0f Hz (%d dropped)"
              % (n1 - n0, expected, rate, max(0, expected - (n1 - n0))))
        return 0
    finally:
        stop_process(sim)
        stop_master(core)


if __name__ == "__main__":
    sys.exit(main())
