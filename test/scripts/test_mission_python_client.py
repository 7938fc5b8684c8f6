"""The Python example client (scripts/example_client.py) in place of the baselines, as a user
runs it: `roslaunch hameritt mission.launch clients:=none client_nodes:=/example_client` and the
client started beside it.

1. maneuver_only, free running: the mission must succeed with the reason "target sighted" and
   the client must exit by itself (exit code 0) once the ADK says the mission is over.
2. end_to_end (the client's colour detector on the down camera), free running, 12 s: the
   mission must complete (success or timeout), the UAV must have flown the client's search, and
   the client must exit by itself.
3. lock-step, maneuver_only, twice with a 6 s limit and `rosbag record` started first: the two
   bags must hold the same messages on every recorded topic byte for byte (the simulator's
   t = 1 ns ticks before the start left out), metrics.json must be byte-identical, the
   simulator's turn order must name /example_client and no turn may time out.
   Negative control: the comparison must report a difference in a copy of the first run's
   messages with one odometry message dropped and one waypoint list altered.
"""
import json
import os
import signal
import subprocess
import sys
import tempfile
import time

import rosbag
import rosgraph

from graph_util import (private_master_port, start_master, stop_master,  # test/scripts/
                        subscribed, wait_for)

SRC = os.environ["HAMERITT_SOURCE_DIR"]
PORT = private_master_port(14000)
CLIENT = os.path.join(SRC, "scripts", "example_client.py")
TOPICS = ["/clock", "/uav/odom", "/mission", "/mission/uav", "/adk/state", "/adk/constraints",
          "/adk/perfect_perception", "/adk/detection_scores", "/adk/metrics", "/uav/cmd_pose",
          "/planner/path", "/planner/progress", "/planner/waypoints", "/perception/detections",
          "/uav/camera/down/boxes", "/uav/camera/front/boxes"]
MUST = ["/clock", "/uav/odom", "/mission", "/mission/uav", "/adk/state", "/adk/perfect_perception",
        "/planner/waypoints", "/planner/path", "/uav/cmd_pose", "/adk/metrics"]


def nodes():
    """The nodes the master knows (empty while it cannot be asked)."""
    try:
        state = rosgraph.Master("/test").getSystemState()
    except Exception:
        return set()
    return {n for kind in state for _, names in kind for n in names}


def run(out, mode, limit, lockstep=False):
    """mission.launch plus the example client, on a master of its own; returns (metrics, client
    exit code, launch log). A master shared by the runs kept the last run's registrations: a
    node that registers a name the master knows makes it tell the old node's URI to shut down,
    and that port may now be a new node's (a loaded run's planner took the call and ended)."""
    core = start_master(PORT)
    try:
        return run_on_master(out, mode, limit, lockstep)
    finally:
        stop_master(core)


def run_on_master(out, mode, limit, lockstep):
    os.makedirs(out)
    env = dict(os.environ, ROS_LOG_DIR=os.path.join(out, "log"), ROSCONSOLE_STDOUT_LINE_BUFFERED="1")
    rec = None
    if lockstep:  # its own session: `rosbag record` wraps the recorder, both get the SIGINT
        rec = subprocess.Popen(["rosbag", "record", "__name:=py_recorder", "-O",
                                os.path.join(out, "mission.bag")] + TOPICS,
                               stdout=open(os.path.join(out, "rec.log"), "w"),
                               stderr=subprocess.STDOUT, env=env, start_new_session=True)
        wait_for(lambda: set(TOPICS) <= subscribed("/py_recorder"), 60, "the recorder")
    args = ["mode:=" + mode, "time_limit:=%g" % limit, "real_time_factor:=0", "output_dir:=" + out,
            "clients:=none", "client_nodes:=/example_client"]
    if lockstep:
        args += ["lockstep:=true", "duration:=%g" % limit]
    launch = subprocess.Popen(["roslaunch", "hameritt", "mission.launch"] + args,
                              stdout=open(os.path.join(out, "launch.log"), "w"),
                              stderr=subprocess.STDOUT, env=env)
    client = None
    try:
        # The launch sets /use_sim_time and /lockstep before it starts its nodes: the client
        # reads them when it starts.
        wait_for(lambda: "/simulator" in nodes(), 60, "the simulator node")
        client = subprocess.Popen(["/usr/bin/python3", CLIENT],
                                  stdout=open(os.path.join(out, "client.log"), "w"),
                                  stderr=subprocess.STDOUT, env=env)
        launch.wait(300)
        rc = client.wait(30)  # it exits by itself once /adk/state says the mission is over
        client = None
    finally:
        for p in (launch, client):
            if p is not None and p.poll() is None:
                p.send_signal(signal.SIGINT)
                p.wait(60)
        if rec is not None:
            time.sleep(1.0)  # the recorder writes what it received
            os.killpg(rec.pid, signal.SIGINT)
            rec.wait(60)
            wait_for(lambda: os.path.exists(os.path.join(out, "mission.bag")), 60, "the closed bag")
    with open(os.path.join(out, "launch.log")) as f:
        log = f.read()
    with open(os.path.join(out, "metrics.json")) as f:
        return json.load(f), rc, log


def messages(path):
    """Per topic, each message's serialized bytes in order (the t = 1 ns ticks left out)."""
    out = {}
    tick = b"\x00\x00\x00\x00\x01\x00\x00\x00"
    with rosbag.Bag(path) as bag:
        for topic, raw, _ in bag.read_messages(raw=True):
            if not (topic == "/clock" and raw[1] == tick):
                out.setdefault(topic, []).append(raw[1])
    return out


def differences(a, b):
    return [t for t in TOPICS if a.get(t, []) != b.get(t, [])]


def main():
    base = tempfile.mkdtemp(prefix="hameritt_pyclient.")
    fails = []
    try:
        started = time.time()
        m, rc, _ = run(os.path.join(base, "maneuver"), "maneuver_only", 120)
        print("maneuver_only: %s at %.1f s (%s), client exit %s, %.0f wall s"
              % (m["outcome"], m["end_time"], m["reason"], rc, time.time() - started))
        if m["outcome"] != "success" or m["reason"] != "target sighted" or rc != 0:
            fails.append("maneuver_only: outcome %r, reason %r, client exit %r"
                         % (m["outcome"], m["reason"], rc))
        started = time.time()
        m, rc, _ = run(os.path.join(base, "e2e"), "end_to_end", 12)
        print("end_to_end: %s at %.1f s (%s), %.0f m flown, %d claims, client exit %s, %.0f wall s"
              % (m["outcome"], m["end_time"], m["reason"], m["flight"]["path_length"],
                 m["detections"]["total"], rc, time.time() - started))
        if m["outcome"] not in ("success", "timeout") or rc != 0:
            fails.append("end_to_end: outcome %r, client exit %r" % (m["outcome"], rc))
        if m["flight"]["path_length"] < 20:
            fails.append("end_to_end: the UAV flew %.1f m" % m["flight"]["path_length"])
        runs = []
        for i in (1, 2):
            # Both runs write to the same directory (/adk/metrics names the file), renamed after.
            d = os.path.join(base, "lockstep")
            started = time.time()
            m, rc, log = run(d, "maneuver_only", 6, lockstep=True)
            msgs = messages(os.path.join(d, "mission.bag"))
            runs.append((msgs, open(os.path.join(d, "metrics.json"), "rb").read()))
            os.rename(d, "%s_%d" % (d, i))
            print("lock-step run %d: %s at %.1f s, %d messages, client exit %s, %.0f wall s"
                  % (i, m["outcome"], m["end_time"], sum(map(len, msgs.values())), rc,
                     time.time() - started))
            if "turn order /adk, /example_client, /planner" not in log:
                fails.append("lock-step run %d: the turn order does not name /example_client" % i)
            for bad in ["did not answer", "did not join", "no longer reproducible"]:
                if bad in log:
                    fails.append("lock-step run %d: the launch log says '%s'" % (i, bad))
            fails += ["lock-step run %d: nothing on %s" % (i, t) for t in MUST if not msgs.get(t)]
        diff = differences(runs[0][0], runs[1][0])
        print("lock-step: %d topics compared, %d differ %s" % (len(TOPICS), len(diff), diff))
        if diff or runs[0][1] != runs[1][1]:
            fails.append("lock-step: the runs differ on %s%s"
                         % (diff, "" if runs[0][1] == runs[1][1] else " and metrics.json"))
        # Negative control: the comparison sees one dropped and one altered message.
        bad = dict(runs[0][0])
        bad["/uav/odom"] = bad["/uav/odom"][1:]
        bad["/planner/waypoints"] = [w[:-1] + bytes([w[-1] ^ 1]) for w in bad["/planner/waypoints"]]
        caught = differences(runs[0][0], bad)
        print("negative control: differences found on %s" % caught)
        if caught != ["/uav/odom", "/planner/waypoints"]:
            fails.append("negative control: expected /uav/odom and /planner/waypoints, got %s" % caught)
    except Exception as e:  # a timeout or a missing file: report it with the runs kept
        fails.append("%s: %s" % (type(e).__name__, e))
    if fails:
        print("FAIL (runs kept in %s):\n  " % base + "\n  ".join(fails))
        return 1
    subprocess.run(["rm", "-rf", base])
    print("PASS: the Python client succeeded in maneuver_only, completed end_to_end, and two "
          "lock-step runs gave the same %d topics and metrics.json" % len(TOPICS))
    return 0


if __name__ == "__main__":
    sys.exit(main())
