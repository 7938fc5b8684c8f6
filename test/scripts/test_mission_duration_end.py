#!/usr/bin/python3
"""A mission that ends at `duration:=`: the simulator stops at its duration, announces it on
/simulator/end, and the ADK ends the mission there with outcome `ended` and the reason
"simulation duration 4 s reached"; the launch then exits by itself.

mission.launch duration:=4 without a time limit (the default scenario's is 472 s), maneuver_only,
in both modes: lock-step (lockstep:=true) and free running (unpaced). For each run:
  * metrics.json validates against config/schema/metrics.schema.json (python3-jsonschema), with
    outcome "ended", that reason, and end_time = 4 s;
  * the ADK's log shows it ended on the simulator's end message ("the simulator stopped at sim
    time 4.000 s") and never on its clock watchdog ("no new /clock");
  * the simulator's log says it reached its duration before the ADK's end.

Negative controls, run here: the schema rejects a metrics.json whose outcome is not one of its
five; the log check rejects a log in which the watchdog ended the mission.
"""
import copy
import os
import shutil
import sys
import tempfile

from graph_util import private_master_port, start_master, stop_master
from fault_util import Checks, launch_mission, metrics_validator

PORT = private_master_port(25000)
DURATION = 4
REASON = "simulation duration %d s reached" % DURATION
ADK_END = "adk: the simulator stopped at sim time %.3f s" % DURATION
SIM_END = "simulator: %s" % REASON
WATCHDOG = "no new /clock"
METRICS = metrics_validator()
check = Checks()


def log_problems(text):
    """Why a launch log does not show a mission ended by the simulator's end message."""
    problems = []
    if WATCHDOG in text:
        problems.append("the ADK's clock watchdog fired")
    if ADK_END not in text:
        problems.append("no '%s' in the log" % ADK_END)
    elif SIM_END not in text or text.index(SIM_END) > text.index(ADK_END):
        problems.append("the simulator did not say it reached its duration before the ADK ended")
    return problems


def run(tmp, label, lockstep):
    out = os.path.join(tmp, label)
    log = os.path.join(tmp, label + ".log")
    # A guard against a hang only (longer than the lock-step watchdog's 130 s): what is judged
    # is how the mission ended, not how long it took.
    rc, text, m = launch_mission(
        ["lockstep:=%s" % lockstep, "duration:=%d" % DURATION, "mode:=maneuver_only",
         "real_time_factor:=0"], out, log, label, check, 400)
    if m is None:
        return None
    errors = [e.message for e in METRICS.iter_errors(m)]
    print("%s: launch exit %d, outcome %s, reason %r, end_time %.3f s; schema: %s; log: %s" % (
        label, rc, m["outcome"], m["reason"], m["end_time"], errors or "valid",
        "; ".join(log_problems(text)) or "ended on the simulator's end message"))
    check(rc == 0, "%s: the launch exited %d" % (label, rc))
    check(not errors, "%s: metrics.json does not validate: %s" % (label, errors))
    check(m["outcome"] == "ended", "%s: outcome %r, expected 'ended'" % (label, m["outcome"]))
    check(m["reason"] == REASON, "%s: reason %r, expected %r" % (label, m["reason"], REASON))
    check(abs(m["end_time"] - DURATION) < 1e-6, "%s: end_time %r" % (label, m["end_time"]))
    check(not log_problems(text), "%s: %s" % (label, "; ".join(log_problems(text))))
    return m, text


def main():
    tmp = tempfile.mkdtemp(prefix="hameritt_duration_end.")
    core = start_master(PORT)
    try:
        got = run(tmp, "lockstep", "true")
        run(tmp, "free_running", "false")
        if got:
            m, text = got
            bad = copy.deepcopy(m)
            bad["outcome"] = "finished"
            rejected = any(True for _ in METRICS.iter_errors(bad))
            print("negative control: outcome 'finished' %s by the schema"
                  % ("rejected" if rejected else "ACCEPTED"))
            check(rejected, "negative control: the schema accepts outcome 'finished'")
            stalled = text.replace(ADK_END, "adk: sim time stopped at 4.000 s: " + WATCHDOG)
            check(log_problems(stalled), "negative control: a watchdog end passes the log check")
            print("negative control: a log ended by the watchdog: %s" % "; ".join(
                log_problems(stalled)))
    finally:
        stop_master(core)
        if not check.fails:
            shutil.rmtree(tmp, ignore_errors=True)
    return check.summary(tmp)


if __name__ == "__main__":
    sys.exit(main())
