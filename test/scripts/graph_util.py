"""Helpers shared by the Python tests that drive a ROS graph (not a test: no test_ prefix)."""
import os
import signal
import socket
import subprocess
import time

import rosgraph


def wait_for(cond, seconds, what):
    """Polls cond() every 50 ms; RuntimeError naming `what` after `seconds`."""
    end = time.time() + seconds
    while time.time() < end:
        if cond():
            return
        time.sleep(0.05)
    raise RuntimeError("timed out waiting for " + what)


def subscribed(node):
    """The topics the master lists `node` as subscribed to (empty while it cannot be asked)."""
    try:
        _, subs, _ = rosgraph.Master("/graph_util").getSystemState()
    except Exception:
        return set()
    return {t for t, nodes in subs if node in nodes}


def private_master_port(base):
    """This test's own master port (base + pid % 2000), exported as ROS_MASTER_URI so that every
    node, roslaunch and rospy call of the test uses it; tests pick distinct bases."""
    port = base + os.getpid() % 2000
    os.environ["ROS_MASTER_URI"] = "http://localhost:%d" % port
    return port


def free_port():
    """A TCP port free on localhost now (the benchmarks' masters and autopilot ports)."""
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def start_master(port, seconds=30):
    """Starts `roscore -p port` and returns its process once the master answers: roslaunch
    starts a master of its own unless one answers, so a test waits for its own first. Stop it
    with stop_master(); if it never answers, it is stopped here and RuntimeError is raised."""
    core = subprocess.Popen(["roscore", "-p", str(port)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    uri = "http://localhost:%d" % port
    try:
        wait_for(lambda: rosgraph.is_master_online(master_uri=uri), seconds,
                 "the master on port %d" % port)
    except RuntimeError:
        stop_master(core)
        raise
    return core


def stop_process(proc, seconds=30):
    """Stops a node, launch or master process: SIGINT (a node's or roslaunch's orderly
    shutdown), then SIGKILL if it has not exited in `seconds`. None or an exited one is left."""
    if proc is None or proc.poll() is not None:
        return
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(seconds)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def stop_master(core):
    """Stops a master from start_master()."""
    stop_process(core)
