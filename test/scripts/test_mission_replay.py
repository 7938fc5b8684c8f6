"""Replays: the same scenario and seed run twice in lock-step gives the same messages.

Each run starts a fresh simulator paused (cameras on), starts `rosbag record` on the
simulator's topics once the simulator is up (so that neither bag holds its t = 0 state), then
a driver steps it 50 physics steps (0.1 s) at a time for 3 s of sim time, changing the velocity
setpoint at fixed sim times, each change published before the next step and given 0.2 wall s
to arrive. The two bags must hold, topic by topic, the same messages in the same order, byte for
byte (payloads, header stamps and sequence numbers included), compared with Python rosbag.
Covered: /clock, /uav/odom, /uav/imu, /tf, /tf_static, /ground_truth/entities and every camera
topic (image_raw, depth, segmentation, instances, camera_info, boxes) of both cameras.
"""
import os
import signal
import subprocess
import sys
import tempfile
import time

import rosbag
import rospy
from geometry_msgs.msg import Twist

from hameritt.srv import StepSimulation

from graph_util import (private_master_port, start_master, stop_master,  # test/scripts/
                        subscribed, wait_for)

SRC = os.environ["HAMERITT_SOURCE_DIR"]
PORT = private_master_port(16000)
TOPICS = ["/clock", "/uav/odom", "/uav/imu", "/tf", "/tf_static", "/ground_truth/entities"]
for cam in ["down", "front"]:
    for kind in ["image_raw", "depth", "segmentation", "instances", "camera_info", "boxes"]:
        TOPICS.append("/uav/camera/%s/%s" % (cam, kind))
# (sim time from which it holds, vx, vy, vz, yaw rate)
SCHEDULE = [(0.0, 0.0, 0.0, 2.0, 0.0), (1.0, 3.0, 1.0, 1.0, 0.3), (2.0, -2.0, 2.5, 0.0, -0.5)]
STEPS, CHUNK = 1500, 50


def record_run(out, bag_path):
    sim = subprocess.Popen(
        ["roslaunch", "hameritt", "simulator.launch", "start_paused:=true", "real_time_factor:=0",
         "sim_config:=%s/scenarios/default/sim_config.json" % SRC],
        stdout=open(bag_path + ".sim.log", "w"), stderr=subprocess.STDOUT)
    rec = None
    try:
        rospy.wait_for_service("/simulator/step", timeout=120)
        step = rospy.ServiceProxy("/simulator/step", StepSimulation)
        rec = subprocess.Popen(["rosbag", "record", "__name:=replay_recorder", "-O", bag_path] + TOPICS,
                               stdout=open(bag_path + ".rec.log", "w"), stderr=subprocess.STDOUT)
        wait_for(lambda: set(TOPICS) <= subscribed("/replay_recorder"), 60, "the recorder")
        pub = rospy.Publisher("/uav/cmd_vel", Twist, queue_size=10)
        wait_for(lambda: pub.get_num_connections() > 0, 30, "the simulator's cmd_vel")
        time.sleep(2.0)  # the recorder's connections to every publisher
        applied = -1
        for k in range(STEPS // CHUNK):
            t = k * CHUNK / 500.0
            i = max(j for j, s in enumerate(SCHEDULE) if s[0] <= t + 1e-9)
            if i != applied:
                m = Twist()
                _, m.linear.x, m.linear.y, m.linear.z, m.angular.z = SCHEDULE[i]
                pub.publish(m)
                time.sleep(0.2)
                applied = i
            r = step(CHUNK)
            if not r.success:
                raise RuntimeError("step: " + r.message)
        time.sleep(2.0)  # the recorder writes what it received
    finally:
        for p in [rec, sim]:
            if p is not None:
                p.send_signal(signal.SIGINT)
                try:
                    p.wait(30)
                except subprocess.TimeoutExpired:
                    p.kill()
                    p.wait()


def messages(path):
    out = {}
    with rosbag.Bag(path) as bag:
        for topic, raw, _t in bag.read_messages(raw=True):
            out.setdefault(topic, []).append(raw[1])
    return out


def main():
    out = tempfile.mkdtemp(prefix="hameritt_replay.")
    core = start_master(PORT)
    fails = []
    try:
        rospy.init_node("replay_driver", disable_signals=True)
        bags = []
        for run in (1, 2):
            path = os.path.join(out, "run%d.bag" % run)
            started = time.time()
            record_run(out, path)
            bags.append(messages(path))
            print("run %d: %d messages in %.1f wall s" % (run, sum(len(v) for v in bags[-1].values()),
                                                          time.time() - started))
        a, b = bags
        for topic in TOPICS:
            na, nb = len(a.get(topic, [])), len(b.get(topic, []))
            same = a.get(topic) == b.get(topic)
            print("  %-36s %5d %5d %s" % (topic, na, nb, "identical" if same else "DIFFERENT"))
            if na == 0:
                fails.append("%s: not recorded" % topic)
            elif not same:
                first = next((i for i, (x, y) in enumerate(zip(a[topic], b[topic])) if x != y),
                             min(na, nb))
                fails.append("%s: %d vs %d messages, first difference at message %d"
                             % (topic, na, nb, first))
        # /clock at 250 Hz, plus the state the simulator publishes again at the end of each call.
        expected_clock = STEPS // 2 + STEPS // CHUNK
        if len(a.get("/clock", [])) != expected_clock:
            fails.append("/clock: %d messages, expected %d (every publish tick, every call)"
                         % (len(a.get("/clock", [])), expected_clock))
    finally:
        stop_master(core)
        subprocess.run(["rm", "-rf", out])
    if fails:
        print("FAIL:\n  " + "\n  ".join(fails))
        return 1
    print("PASS: two lock-step runs recorded the same %d topics, byte for byte" % len(TOPICS))
    return 0


if __name__ == "__main__":
    sys.exit(main())
