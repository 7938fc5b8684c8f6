#!/usr/bin/python3
"""A seeded pursuit mission that the baseline now succeeds: after the find, the search client
pursues the target as it drives off and keeps it in view (its objective), where hovering at the
find fails.

The pursuit scenario of `hameritt_generate --class pursuit --count 1 --seed SEED` flies in
mission.launch, maneuver_only, lock-step, as fast as it goes, with the time limit cut to
TIME_LIMIT s (seed 1: the black Ford Explorer is found at about 7 s, drives off at 38 s and is
still driving at 100 s). Twice:

  * pursue:=true (the default): outcome "success"; the target in view for at least half the
    mission (track_fraction 0.5; in_view_time from metrics.json, which validates against
    config/schema/metrics.schema.json with python3-jsonschema); the client's log says it
    started pursuing, and the number of losses it prints at the end equals the number of
    "lost the target" lines;
  * negative control, pursue:=false (the behaviour before: hover at the find): outcome
    "timeout", in view for less than half the mission.

The in-view time is the ADK's (ground truth: camera boxes with enough visible pixels), not the
client's own account.
"""
import os
import re
import shutil
import sys
import tempfile

from graph_util import private_master_port, start_master, stop_master
from fault_util import Checks, generate_one, launch_mission, metrics_validator

PORT = private_master_port(27000)
SEED = int(os.environ.get("HAMERITT_PURSUIT_SEED", "1"))
TIME_LIMIT = int(os.environ.get("HAMERITT_PURSUIT_TIME_LIMIT", "100"))
METRICS = metrics_validator()
check = Checks()


def run(tmp, scenario, pursue):
    label = "pursue" if pursue else "hover"
    out = os.path.join(tmp, label)
    log = os.path.join(tmp, label + ".log")
    # A guard against a hang only: what is judged is the outcome, not how long it took.
    rc, text, m = launch_mission(
        ["scenario:=" + scenario, "mode:=maneuver_only", "lockstep:=true", "real_time_factor:=0",
         "time_limit:=%d" % TIME_LIMIT, "pursue:=%s" % ("true" if pursue else "false")],
        out, log, label, check, 900)
    if m is None:
        return None, text
    errors = [e.message for e in METRICS.iter_errors(m)]
    check(rc == 0, "%s: the launch exited %d" % (label, rc))
    check(not errors, "%s: metrics.json does not validate: %s" % (label, errors))
    check(len(m["targets"]) == 1, "%s: %d targets" % (label, len(m["targets"])))
    in_view = m["targets"][0]["in_view_time"]
    print("%s: outcome %s, end_time %.1f s, target in view %.1f s (%.0f %% of the mission)" % (
        label, m["outcome"], m["end_time"], in_view, 100.0 * in_view / TIME_LIMIT))
    return m, text


def main():
    tmp = tempfile.mkdtemp(prefix="hameritt_pursuit.")
    core = start_master(PORT)
    try:
        scenario = generate_one(tmp, "pursuit", SEED)
        print("scenario %s (seed %d), time limit %d s" % (os.path.basename(scenario), SEED,
                                                          TIME_LIMIT))
        m, text = run(tmp, scenario, True)
        if m:
            in_view = m["targets"][0]["in_view_time"]
            check(m["outcome"] == "success", "pursue: outcome %r, expected 'success'"
                  % m["outcome"])
            check(in_view >= 0.5 * TIME_LIMIT, "pursue: in view %.1f s, less than half of %d s"
                  % (in_view, TIME_LIMIT))
            check("pursuing it from" in text, "pursue: the client never started pursuing")
            losses = len(re.findall(r"pursuit: lost the target \(loss \d+\)", text))
            said = re.findall(r"pursuit over: the target was lost (\d+) times", text)
            print("pursue: the client lost the target %d times, and says %s" % (
                losses, said[0] if said else "nothing"))
            check(said and int(said[0]) == losses,
                  "pursue: the client's loss count %s differs from its %d loss lines"
                  % (said, losses))
        # Negative control: hovering at the find.
        h, htext = run(tmp, scenario, False)
        if h:
            in_view = h["targets"][0]["in_view_time"]
            check(h["outcome"] == "timeout", "hover: outcome %r, expected 'timeout'"
                  % h["outcome"])
            check(in_view < 0.5 * TIME_LIMIT, "hover: in view %.1f s, half of %d s or more: the "
                  "test cannot tell pursuit from hovering" % (in_view, TIME_LIMIT))
            check("pursuing it from" not in htext, "hover: the client pursued with pursue:=false")
    finally:
        stop_master(core)
        if not check.fails:
            shutil.rmtree(tmp, ignore_errors=True)
    return check.summary(tmp)


if __name__ == "__main__":
    sys.exit(main())
