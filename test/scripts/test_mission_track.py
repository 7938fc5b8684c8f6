#!/usr/bin/python3
"""A seeded track mission flown end to end: the baseline finds the moving target, pursues it and
reports its box in the down-camera frames on perception/tracks; the ADK scores the track phase
from ground truth. Hovering at the find (the negative control) fails the phase.

The track scenario of `hameritt_generate --class track --count 1 --seed SEED` flies in
mission.launch, maneuver_only, lock-step, as fast as it goes, with found_by_sighting:=false (the
find, and so the track phase's start, is the client's claim). Twice:

  * pursue:=true (the default): metrics.json (valid against config/schema/metrics.schema.json,
    python3-jsonschema) has a `track` block of the mission's targets; the phase started at the
    client's claim; the outcome is "success" exactly when the track phase succeeded; the
    client's reports are counted, at most one per frame of the phase, and none is malformed
    (report_errors total 0, its kinds adding up); the client's log says it pursued; adk/phase
    (read with `rostopic echo`, not our code) carried search_1 active, search_1 succeeded,
    track_1 active, then track_1 in the block's state;
  * negative control, pursue:=false (hover at the claim): outcome "failed", the track phase
    failed before its end (a loss longer than max_reacquire_s), tracked at least 0.3 less than
    the pursuit, adk/phase ends with track_1 failed, and the client never pursued.

The pursuit also meets the track criteria on the default seed (asserted: the phase succeeded,
tracked >= min_tracked_fraction, every loss reacquired within max_reacquire_s; BENCHMARKS.md,
"Track baseline"; another seed through HAMERITT_TRACK_SEED may not). The tracked fractions are
the ADK's (ground truth: the down camera's instance boxes), not the client's own account.
"""
import json
import os
import shutil
import sys
import tempfile

from graph_util import private_master_port, start_master, stop_master
from fault_util import Checks, generate_one, launch_mission_phases, metrics_validator

PORT = private_master_port(33000)
SEED = int(os.environ.get("HAMERITT_TRACK_SEED", "8"))
# The find is the client's claim, which it makes once its down camera (the scored one) holds
# the target; found by sighting, the front camera's first glimpse from 100-200 m away would
# start the phase, and no UAV reaches the target within max_reacquire_s.
FIND = ["found_by_sighting:=false"]
METRICS = metrics_validator()
check = Checks()


def run(tmp, scenario, label, args):
    out = os.path.join(tmp, label)
    log = os.path.join(tmp, label + ".log")
    phases = os.path.join(tmp, label + "_phase.csv")
    # A guard against a hang only: what is judged is the outcome, not how long it took.
    rc, text, m, changes = launch_mission_phases(
        ["scenario:=" + scenario, "mode:=maneuver_only", "lockstep:=true",
         "real_time_factor:=0"] + args, out, log, phases, label, check, 900)
    if m is None:
        return None, text, []
    errors = [e.message for e in METRICS.iter_errors(m)]
    check(rc == 0, "%s: the launch exited %d" % (label, rc))
    check(not errors, "%s: metrics.json does not validate: %s" % (label, errors))
    check("track" in m, "%s: metrics.json has no track block" % label)
    t = m.get("track", {})
    per = ", ".join("%s tracked %.1f %% (%d of %d frames), precision %.3f, %d breaks" % (
        p["id"], 100 * p["tracked_fraction"], p["tracked_frames"], p["frames"],
        p["precision"], p["breaks"]) for p in t.get("per_target", []))
    print("%s: outcome %s (%s), end_time %.1f s; track phase %s (%s) from %s, %.1f of %.0f s, "
          "%d frames, %d reports, %d malformed; %s; adk/phase: %s" % (
              label, m["outcome"], m["reason"], m["end_time"], t.get("state"), t.get("failure"),
              t.get("start_time"), t.get("elapsed", 0), t.get("duration", 0), t.get("frames", 0),
              t.get("reports", 0), t.get("report_errors", {}).get("total", -1), per, changes))
    return m, text, changes


def main():
    tmp = tempfile.mkdtemp(prefix="hameritt_track.")
    core = start_master(PORT)
    try:
        scenario = generate_one(tmp, "track", SEED)
        with open(os.path.join(scenario, "mission.json")) as fh:
            mission = json.load(fh)
        phase = mission["phases"][1]
        crit = phase["criteria"]
        print("scenario %s (seed %d): track %s for %g s, tracked >= %g of the frames, losses "
              "reacquired within %g s" % (
                  os.path.basename(scenario), SEED, phase["targets"], phase["duration"],
                  crit["min_tracked_fraction"], crit["max_reacquire_s"]))
        m, text, changes = run(tmp, scenario, "track", FIND)
        tracked = None
        if m and "track" in m:
            t = m["track"]
            tracked = t["tracked_fraction"]
            check(t["start_time"] is not None, "track: the track phase never started")
            check(t["elapsed"] > 0 and (t["success"] or t["elapsed"] < phase["duration"]),
                  "track: %.1f s of the %g s phase flown, success %s" % (
                      t["elapsed"], phase["duration"], t["success"]))
            check(t["start_time"] is not None and
                  abs(m["end_time"] - t["start_time"] - t["elapsed"]) < 0.5,
                  "track: the mission did not end at the phase's end")
            check("first sighting at" in text,
                  "track: the pursuit did not start at the first sighting")
            check(sorted(t["targets"]) == sorted(phase["targets"]),
                  "track: targets %s, expected %s" % (t["targets"], phase["targets"]))
            check(all(p["tracked_fraction"] >= tracked - 1e-9 for p in t["per_target"]),
                  "track: tracked_fraction is not the lowest of the targets'")
            check((m["outcome"] == "success") == t["success"],
                  "track: outcome %r with the track phase %s" % (m["outcome"], t["state"]))
            check(t["success"] == (t["state"] == "succeeded"),
                  "track: success %s with the phase %s" % (t["success"], t["state"]))
            check(0 < t["reports"] <= t["frames"],
                  "track: %d reports for %d frames" % (t["reports"], t["frames"]))
            check(t["report_errors"]["total"] == 0,
                  "track: malformed reports: %s" % t["report_errors"])
            check(sum(v for k, v in t["report_errors"].items() if k != "total") ==
                  t["report_errors"]["total"], "track: report_errors do not add up")
            check("pursuing it from" in text, "track: the client never pursued")
            expected = [("search_1", "search", "active"), ("search_1", "search", "succeeded"),
                        ("track_1", "track", "active"), ("track_1", "track", t["state"])]
            check(changes == expected, "track: adk/phase carried %s, expected %s"
                  % (changes, expected))
            print("track: the baseline %s the track criteria (tracked %.1f %%, at least %g %%)"
                  % ("meets" if t["success"] else "does NOT meet", 100 * tracked,
                     100 * crit["min_tracked_fraction"]))
            check(t["success"] and m["outcome"] == "success" and
                  tracked >= crit["min_tracked_fraction"],
                  "track: the baseline does not meet the track criteria: %s (tracked %.3f)"
                  % (t.get("failure"), tracked))
        # Negative control: hovering at the find.
        h, htext, hchanges = run(tmp, scenario, "hover", FIND + ["pursue:=false"])
        if h and "track" in h:
            t = h["track"]
            check(h["outcome"] == "failed", "hover: outcome %r, expected 'failed'" % h["outcome"])
            check(not t["success"] and t["state"] == "failed",
                  "hover: the track phase %s" % t["state"])
            check(t["elapsed"] < phase["duration"], "hover: the phase ran to its end")
            check(tracked is not None and t["tracked_fraction"] <= tracked - 0.3,
                  "hover: tracked %.3f, not 0.3 below the pursuit's %s" % (
                      t["tracked_fraction"], tracked))
            check(hchanges[-1:] == [("track_1", "track", "failed")],
                  "hover: adk/phase ends with %s, expected track_1 failed" % hchanges[-1:])
            check("pursuing it from" not in htext,
                  "hover: the client pursued with pursue:=false")
    finally:
        stop_master(core)
        if not check.fails:
            shutil.rmtree(tmp, ignore_errors=True)
    return check.summary(tmp)


if __name__ == "__main__":
    sys.exit(main())
