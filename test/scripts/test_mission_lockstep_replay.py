"""Replays of a whole mission: the same scenario, mode and seed run twice in lock-step mode
(mission.launch lockstep:=true: simulator, ADK, planner and the baseline clients taking turns)
give the same messages, payload for payload, stamps included.

For each mode (end_to_end: detector, ADK, search client, planner; maneuver_only: ADK with
perfect perception, search client claiming, planner) the mission runs twice on the default
scenario with a short time limit; the simulator stops at the limit, so both runs end at the
same sim time. `rosbag record` subscribes to every topic of the mission before it starts. The two
bags must hold, topic by topic, the same messages in the same order, byte for byte (compared
with Python rosbag), and the ADK's metrics.json must be byte-identical. The only messages left
out are the simulator's "t = 1 ns" clock ticks, published while it waits for its subscribers
(their number depends on start-up timing; docs/explanation/lockstep.md).

Beyond the shipped scenario: one generated scenario of each class (hameritt_generate
--scenario-seed, area_search, route_search and pursuit) flies twice in maneuver_only mode for
3 sim s without a time limit (the simulator's duration ends it: outcome `ended` in both runs),
with the same comparison.

A participant that never joins (a simulator alone, told to wait for "/ghost", with a 3 s
lockstep_timeout) must not hang the simulator: it logs the error and runs to its duration.

Negative control: a third end_to_end run with lock-step cycles of 0.04 s instead of 0.02 s
(setpoints then change at other sim times) must differ on the setpoints and the flight, so the
comparison is shown to see a change.
"""
import hashlib
import json
import os
import signal
import subprocess
import sys
import tempfile
import time

import rosbag

from graph_util import (private_master_port, start_master, stop_master,  # test/scripts/
                        subscribed, wait_for)

SRC = os.environ["HAMERITT_SOURCE_DIR"]
PORT = private_master_port(18000)

TOPICS = ["/clock", "/tf", "/tf_static", "/uav/odom", "/uav/imu", "/ground_truth/entities",
          "/uav/crash", "/mission", "/mission/markers", "/adk/constraints",
          "/adk/constraint_events", "/adk/perfect_perception", "/adk/detection_scores",
          "/adk/state", "/adk/metrics", "/uav/cmd_pose", "/planner/path", "/planner/progress",
          "/planner/waypoints", "/coverage_search_client/plan", "/perception/detections"]
for cam in ["down", "front"]:
    for kind in ["image_raw", "depth", "segmentation", "instances", "camera_info", "boxes"]:
        TOPICS.append("/uav/camera/%s/%s" % (cam, kind))

# Topics that must carry messages in every run of a mode (the rest may be empty, e.g. no crash).
MUST = ["/clock", "/uav/odom", "/ground_truth/entities", "/mission", "/adk/state", "/adk/metrics",
        "/adk/constraints", "/uav/cmd_pose", "/planner/path", "/planner/progress",
        "/planner/waypoints", "/uav/camera/down/image_raw", "/uav/camera/front/boxes"]
MODES = [("end_to_end", 6.0, []), ("maneuver_only", 5.0, ["/adk/perfect_perception"])]
# Generated scenarios: class, scenario seed; flown for GENERATED_DURATION sim s.
GENERATED = [("area_search", 11), ("route_search", 12), ("pursuit", 13)]
GENERATED_DURATION = 3.0
GENERATED_MUST = ["/clock", "/uav/odom", "/ground_truth/entities", "/mission", "/adk/state",
                  "/adk/metrics", "/uav/camera/down/image_raw", "/uav/camera/front/boxes"]


def run_mission(base, name, mode, limit, period=0.02, scenario=None, time_limit=True):
    """One mission into base/name/mission.bag; returns the wall seconds of the launch.

    `limit` is the simulator's duration and, with `time_limit`, the mission's time limit.
    Every run writes to the same base/current (the metrics name their file), renamed after."""
    out = os.path.join(base, "current")
    os.makedirs(out)
    env = dict(os.environ, ROS_LOG_DIR=os.path.join(out, "log"))
    # Its own session: `rosbag record` is a wrapper around the recorder; both get the SIGINT.
    rec = subprocess.Popen(
        ["rosbag", "record", "__name:=lockstep_recorder", "-b", "512", "-O",
         os.path.join(out, "mission.bag")] + TOPICS,
        stdout=open(os.path.join(out, "rec.log"), "w"), stderr=subprocess.STDOUT, env=env,
        start_new_session=True)
    launch = None
    try:
        wait_for(lambda: set(TOPICS) <= subscribed("/lockstep_recorder"), 60, "the recorder")
        started = time.time()
        launch = subprocess.Popen(
            ["roslaunch", "hameritt", "mission.launch", "lockstep:=true", "real_time_factor:=0",
             "mode:=" + mode, "duration:=%g" % limit, "lockstep_period:=%g" % period,
             "output_dir:=" + out] + (["time_limit:=%g" % limit] if time_limit else []) +
            (["scenario:=" + scenario] if scenario else []),
            stdout=open(os.path.join(out, "launch.log"), "w"), stderr=subprocess.STDOUT, env=env)
        # The ADK ends the mission at the limit (or the simulator's end), lingers a second and
        # exits; the launch follows.
        launch.wait(240)
        wall = time.time() - started
        launch = None
        # The recorder writes what it received; under load it still receives for a while (a
        # run on a machine at load 10 once lost the last 0.3 sim s of the 250 Hz topics after 1 s).
        time.sleep(3.0)
    finally:
        if launch is not None:
            launch.send_signal(signal.SIGINT)
            launch.wait(60)
        os.killpg(rec.pid, signal.SIGINT)
        try:
            rec.wait(60)
        except subprocess.TimeoutExpired:
            os.killpg(rec.pid, signal.SIGKILL)
            rec.wait()
    # The recorder renames mission.bag.active when it has closed the bag.
    wait_for(lambda: os.path.exists(os.path.join(out, "mission.bag")), 60, "the closed bag")
    os.rename(out, os.path.join(base, name))
    return wall


def messages(path):
    """Per topic, the SHA-256 of each message's serialized bytes, in order; removes the bag."""
    out = {}
    # The ticks at t = 1 ns (sec 0, nsec 1) announced while the simulator waits for subscribers.
    tick = b"\x00\x00\x00\x00\x01\x00\x00\x00"
    with rosbag.Bag(path) as bag:
        for topic, raw, _t in bag.read_messages(raw=True):
            if topic == "/clock" and raw[1] == tick:
                continue
            out.setdefault(topic, []).append(hashlib.sha256(raw[1]).digest())
    os.remove(path)
    return out


def compare(a, b, fails, label):
    for topic in TOPICS:
        na, nb = len(a.get(topic, [])), len(b.get(topic, []))
        same = a.get(topic, []) == b.get(topic, [])
        print("  %-36s %6d %6d %s" % (topic, na, nb, "identical" if same else "DIFFERENT"))
        if not same:
            first = next((i for i, (x, y) in enumerate(zip(a.get(topic, []), b.get(topic, [])))
                          if x != y), min(na, nb))
            fails.append("%s: %s: %d vs %d messages, first difference at message %d"
                         % (label, topic, na, nb, first))


def ghost(out, fails):
    log = os.path.join(out, "ghost.log")
    subprocess.run(["rosparam", "set", "/lockstep", "true"], check=True)
    subprocess.run(["rosparam", "set", "/lockstep_timeout", "3"], check=True)
    sim = subprocess.Popen(
        ["roslaunch", "hameritt", "simulator.launch", "cameras:=false", "real_time_factor:=0",
         "duration:=1", "lockstep_participants:=/ghost",
         "sim_config:=%s/scenarios/default/sim_config.json" % SRC],
        stdout=open(log, "w"), stderr=subprocess.STDOUT, start_new_session=True,
        env=dict(os.environ, ROSCONSOLE_STDOUT_LINE_BUFFERED="1"))
    try:
        wait_for(lambda: "stopped at the duration" in open(log).read(), 90,
                 "the simulator to run to its duration without /ghost")
        text = open(log).read()
        print("ghost participant: the simulator ran to its duration")
        if "/ghost did not join within 3 s" not in text:
            fails.append("ghost: no error naming /ghost in the simulator's log")
    except RuntimeError as e:
        fails.append("ghost: %s (log %s)" % (e, log))
    finally:
        os.killpg(sim.pid, signal.SIGINT)
        sim.wait(60)
        subprocess.run(["rosparam", "delete", "/lockstep"])
        subprocess.run(["rosparam", "delete", "/lockstep_timeout"])


def generated(out, fails):
    """A generated scenario of each class, twice, compared as above."""
    gen = os.path.join(out, "generated")
    for cls, seed in GENERATED:
        r = subprocess.run([os.path.join(os.environ["HAMERITT_BIN_DIR"], "hameritt_generate"),
                            "--class", cls, "--scenario-seed", str(seed), "--out", gen],
                           capture_output=True, text=True)
        ids = r.stdout.split()  # the generated scenario's id
        if r.returncode != 0 or len(ids) != 1:
            fails.append("hameritt_generate --class %s: exit %d, %s (%s)"
                         % (cls, r.returncode, ids, r.stderr.strip()))
            continue
        scenario = os.path.join(gen, ids[0])
        runs = []
        for run in (1, 2):
            name = "%s_%d" % (cls, run)
            wall = run_mission(out, name, "maneuver_only", GENERATED_DURATION, scenario=scenario,
                               time_limit=False)
            d = os.path.join(out, name)
            msgs = messages(os.path.join(d, "mission.bag"))
            metrics = open(os.path.join(d, "metrics.json"), "rb").read()
            outcome = json.loads(metrics)["outcome"]
            runs.append((msgs, metrics))
            print("%s (%s) run %d: %d messages, %.1f sim s in %.1f wall s, outcome %s"
                  % (cls, ids[0], run, sum(len(v) for v in msgs.values()), GENERATED_DURATION,
                     wall, outcome))
            if outcome != "ended":
                fails.append("%s run %d: outcome %s, expected ended (the simulator's duration)"
                             % (cls, run, outcome))
            for topic in GENERATED_MUST:
                if not msgs.get(topic):
                    fails.append("%s run %d: nothing on %s" % (cls, run, topic))
        compare(runs[0][0], runs[1][0], fails, cls)
        if runs[0][1] != runs[1][1]:
            fails.append("%s: metrics.json differs" % cls)


def main():
    out = tempfile.mkdtemp(prefix="hameritt_lockstep.")
    core = start_master(PORT)
    fails = []
    try:
        for mode, limit, must in MODES:
            runs = []
            for run in (1, 2):
                d = os.path.join(out, "%s_%d" % (mode, run))
                wall = run_mission(out, os.path.basename(d), mode, limit)
                msgs = messages(os.path.join(d, "mission.bag"))
                metrics = open(os.path.join(d, "metrics.json"), "rb").read()
                runs.append((d, msgs, metrics))
                print("%s run %d: %d messages, %.1f sim s in %.1f wall s"
                      % (mode, run, sum(len(v) for v in msgs.values()), limit, wall))
                for topic in MUST + must:
                    if not msgs.get(topic):
                        fails.append("%s run %d: nothing on %s" % (mode, run, topic))
                with open(os.path.join(d, "launch.log")) as f:
                    log = f.read()
                for bad in ["lock-step: still", "did not answer", "did not join",
                            "no longer reproducible"]:
                    if bad in log:
                        fails.append("%s run %d: the launch log says '%s'" % (mode, run, bad))
            compare(runs[0][1], runs[1][1], fails, mode)
            if runs[0][2] != runs[1][2]:
                fails.append("%s: metrics.json differs" % mode)
            if mode == "end_to_end":
                # Negative control: other cycles, other setpoint times, another flight.
                d = os.path.join(out, "end_to_end_period_0.04")
                run_mission(out, os.path.basename(d), mode, limit, 0.04)
                other = messages(os.path.join(d, "mission.bag"))
                for topic in ["/uav/cmd_pose", "/planner/progress", "/uav/odom"]:
                    same = other.get(topic, []) == runs[0][1].get(topic, [])
                    print("  cycles of 0.04 s vs 0.02 s: %-18s %s"
                          % (topic, "identical" if same else "different"))
                    if same:
                        fails.append("cycles of 0.04 s: %s is the same as with 0.02 s" % topic)
        generated(out, fails)
        ghost(out, fails)
    finally:
        stop_master(core)
        if not fails:
            subprocess.run(["rm", "-rf", out])
    if fails:
        print("FAIL (runs kept in %s):\n  " % out + "\n  ".join(fails))
        return 1
    print("PASS: each mode's and each generated class's two lock-step missions recorded the same "
          "%d topics, byte for byte, and the same metrics.json" % len(TOPICS))
    return 0


if __name__ == "__main__":
    sys.exit(main())
