"""Helpers shared by the Python tests that drive a ROS graph (not a test: no test_ prefix)."""
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
