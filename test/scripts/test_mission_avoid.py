#!/usr/bin/python3
"""The avoid baseline flies a seeded avoid mission to its goal among the other aircraft.

Avoid scenarios of `hameritt_generate --class avoid --count 10 --seed 1`: the first whose
shortest path (mission.json) is within 1 % of the straight climb-and-fly, with three more
aircraft added to its sim_config.json that fly that straight line head-on from the goal end,
abreast 5 m apart, 1 m above it (the generated aircraft rarely force a conflict by themselves). It flies in mission.launch,
maneuver_only, lock-step, as fast as it goes; the baseline search client sees the avoid phase
and flies it with its pilot (clients::AvoidPilot): the shortest flight to the goal,
deconflicted from the aircraft that the ADK reports on /adk/traffic. Twice:

  * traffic_rate_hz:=2 (the default): outcome "success", the avoid block of metrics.json (which
    validates against config/schema/metrics.schema.json with python3-jsonschema) says success,
    a reach time, no separation loss, no contact and an SPL above 0.5; the client's log says
    it flew the path;
  * negative control, traffic_rate_hz:=0 (no reports: the pilot flies blind to the aircraft):
    separation is lost to a head-on aircraft, outcome "failed".

The separation is the ADK's (the aircraft's scripted trajectories against the odometry), not
the client's own account.
"""
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import threading

from graph_util import private_master_port, start_master, stop_master
from fault_util import Checks, launch_mission, metrics_validator

PORT = private_master_port(27100)
SEED = int(os.environ.get("HAMERITT_AVOID_SEED", "1"))
INTRUDER_SPEED = 6.0  # m/s
METRICS = metrics_validator()
check = Checks()


def straight_length(mission, sim):
    """The climb-and-fly length from the start to the avoid goal, and its corners."""
    goal = mission["phases"][0]["goal"]
    start = sim["uav"]["start"]
    floor = sim["uav"]["altitude"]["min"]
    top = max(goal[2], floor)
    p0 = (start["x"], start["y"], floor)
    p1 = (goal[0], goal[1], top)
    return floor + math.dist(p0, p1) + (top - goal[2]), p0, p1


def add_head_on(sim, p0, p1):
    """Three aircraft abreast (5 m apart across the path, so that a flight within 10 m of the
    straight line meets one within the horizontal minimum), from 40 m short of the goal end to
    30 m short of the start end, 1 m above the straight path, at INTRUDER_SPEED from t = 0,
    then holding there."""
    d = math.dist(p0, p1)
    a = [p1[i] + (p0[i] - p1[i]) * 40.0 / d for i in range(3)]
    b = [p0[i] + (p1[i] - p0[i]) * 30.0 / d for i in range(3)]
    yaw = math.atan2(b[1] - a[1], b[0] - a[0])
    across = (-math.sin(yaw), math.cos(yaw))
    t = round(math.dist(a, b) / INTRUDER_SPEED, 3)
    for k, side in enumerate((-5.0, 0.0, 5.0)):
        def at(p):
            return [round(p[0] + side * across[0], 3), round(p[1] + side * across[1], 3),
                    round(p[2] + 1.0, 3)]
        rows = [[0.0] + at(a) + [round(yaw, 3)], [t] + at(b) + [round(yaw, 3)],
                [round(t + 900.0, 3)] + at(b) + [round(yaw, 3)]]
        sim["aircraft"].append({"id": "aircraft_head_on_%d" % (k + 1), "model": "quadrotor",
                                "size": [0.6, 0.6, 0.25], "trajectory": rows})


def generate(tmp):
    out = os.path.join(tmp, "scenarios")
    subprocess.run(["rosrun", "hameritt", "hameritt_generate", "--class", "avoid", "--count",
                    "10", "--seed", str(SEED), "--out", out], check=True,
                   stdout=subprocess.DEVNULL)
    for d in sorted(os.listdir(out)):
        if not d.startswith("avoid-"):
            continue
        path = os.path.join(out, d)
        with open(os.path.join(path, "mission.json")) as f:
            mission = json.load(f)
        with open(os.path.join(path, "sim_config.json")) as f:
            sim = json.load(f)
        length, p0, p1 = straight_length(mission, sim)
        shortest = mission["phases"][0]["shortest_path_m"]
        if shortest > 1.01 * length:
            continue
        add_head_on(sim, p0, p1)
        with open(os.path.join(path, "sim_config.json"), "w") as f:
            json.dump(sim, f, indent=2)
        print("scenario %s: shortest path %.1f m, straight %.1f m; head-on aircraft added"
              % (d, shortest, length))
        return path
    check(False, "none of the 10 scenarios has a straight shortest path")
    return None


def launch(tmp, scenario, rate, port):
    """Starts one flight on its own master (the two flights run at once, one per core)."""
    label = "reported" if rate > 0 else "blind"
    out = os.path.join(tmp, label)
    log = os.path.join(tmp, label + ".log")
    result = {}

    def fly():
        # A guard against a hang only: what is judged is the outcome, not how long it took.
        result["run"] = launch_mission(
            ["scenario:=" + scenario, "mode:=maneuver_only", "lockstep:=true",
             "real_time_factor:=0", "traffic_rate_hz:=%g" % rate], out, log, label, check, 900,
            master_uri="http://localhost:%d" % port)

    thread = threading.Thread(target=fly)
    thread.start()
    return label, thread, result


def judge(label, rc, text, m):
    if m is None:
        return None, text
    errors = [e.message for e in METRICS.iter_errors(m)]
    check(rc == 0, "%s: the launch exited %d" % (label, rc))
    check(not errors, "%s: metrics.json does not validate: %s" % (label, errors))
    check("avoid" in m, "%s: metrics.json has no avoid block" % label)
    if "avoid" not in m:
        return None, text
    a = m["avoid"]
    print("%s: outcome %s at %.1f s; avoid: success %s (%s), reach %s, SPL %.3f, min separation "
          "%s m (%s), %.2f s below the minimum, %d losses" % (
              label, m["outcome"], m["end_time"], a["success"], a["failure"] or "-",
              a["reach_time"], a["spl"], a["min_separation"], a["closest_aircraft"],
              a["seconds_below_minimum"], a["separation_losses"]))
    return m, text


def main():
    tmp = tempfile.mkdtemp(prefix="hameritt_avoid.")
    core = start_master(PORT)
    blind_port = 31000 + os.getpid() % 2000
    blind_core = start_master(blind_port)
    try:
        scenario = generate(tmp)
        if scenario is None:
            return check.summary(tmp)
        flights = [launch(tmp, scenario, 2, PORT), launch(tmp, scenario, 0, blind_port)]
        results = {}
        for label, thread, result in flights:
            thread.join()
            results[label] = judge(label, *result["run"])
        m, text = results["reported"]
        if m and "avoid" in m:
            a = m["avoid"]
            check(m["outcome"] == "success", "reported: outcome %r, expected 'success'"
                  % m["outcome"])
            check(a["success"] and a["failure"] == "", "reported: avoid failed: %s" % a["failure"])
            check(a["reach_time"] is not None, "reported: the goal was not reached")
            check(a["separation_losses"] == 0 and a["seconds_below_minimum"] == 0.0,
                  "reported: separation lost %d times" % a["separation_losses"])
            check(not a["contact"], "reported: contact")
            check(a["spl"] > 0.5, "reported: SPL %.3f, expected > 0.5" % a["spl"])
            check("avoid: flying a" in text, "reported: the client did not say it flew the path")
        m, text = results["blind"]
        if m and "avoid" in m:
            a = m["avoid"]
            check(m["outcome"] == "failed", "blind: outcome %r, expected 'failed' (the "
                  "negative control: without reports separation is lost)" % m["outcome"])
            check(a["separation_losses"] > 0, "blind: no separation loss")
    finally:
        stop_master(core)
        stop_master(blind_core)
        if not check.fails:
            shutil.rmtree(tmp, ignore_errors=True)
    return check.summary(tmp)


if __name__ == "__main__":
    sys.exit(main())
