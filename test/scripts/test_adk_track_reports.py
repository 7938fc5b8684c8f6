#!/usr/bin/python3
"""The ADK scores a track phase and counts a client's malformed track reports.

An adk node alone on a private master, on a generated track scenario (hameritt_generate
--class track), is fed by this test (rospy): /clock, uav/odom and the scored camera's boxes
(the targets' boxes, visible and total pixels) every 0.2 s of sim time, and track reports on
perception/tracks. Run "tracked": every target in view from t = 1 s, so the find at 1 s starts
the track phase, which succeeds at its duration; each frame's report (its exact boxes) goes out
one step after the frame (up to 1 s before the phase's end), and on some frames a malformed one
too: a NaN box, a negative width, an unknown id, a repeated id, a stamp between frames
(unmatched), a stamp before the last report's (out of order), and a report of another camera
(ignored, not an error). metrics.json
(python3-jsonschema against config/schema/metrics.schema.json) must count each kind exactly,
score precision 1 on the frames with a report, and say success. Negative controls, run here:
run "lost" hides the targets from t = 3 s and sends no report: the phase fails as soon as a loss
passes max_reacquire_s, with no report and no error counted; a metrics.json doctored with a
negative count or without its report_errors fails the schema.
Run "lost" also shows that a hidden target in the camera's view counts at occlusion level
"full": the UAV hovers 40 m above the first target (its sim_config trajectory) until half the
reacquire limit after the loss, so its hidden frames until then project into the image and
count as "full"; then it hovers 300 m off, and its frames there are out of view (not in
in_view_frames, in no level): the frames a renderer-only ground truth loses.
"""
import copy
import json
import math
import os
import signal
import subprocess
import sys
import tempfile
import time

import rospy
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock

from fault_util import BIN, Checks, generate_one, metrics_state, metrics_validator
from graph_util import private_master_port, start_master, stop_master

from hameritt.msg import BoundingBox, BoundingBoxArray, TrackedBox, TrackReport

PORT = private_master_port(35000)
SEED = 2
DT = 0.2
KINDS = 3  # each kind of malformed report, this many times
check = Checks()
METRICS = metrics_validator()


def box(eid, x):
    b = BoundingBox(entity_id=eid, entity_class="car", role="target", instance_id=1,
                    x_min=x, y_min=100, x_max=x + 39, y_max=139)
    b.visible_pixels = b.total_pixels = 1600
    b.occlusion = 0.0
    return b


def tracked(eid, x, w=40.0):
    return TrackedBox(target_id=eid, x=float(x), y=100.0, w=w, h=40.0)


def position_at(trajectory, t):
    """(x, y, z) of a sim_config trajectory ([t, x, y, z, yaw] points) at t, linear between
    its points."""
    pts = trajectory
    if t <= pts[0][0]:
        return tuple(pts[0][1:4])
    for a, b in zip(pts, pts[1:]):
        if t <= b[0]:
            f = (t - a[0]) / (b[0] - a[0])
            return tuple(a[k] + f * (b[k] - a[k]) for k in (1, 2, 3))
    return tuple(pts[-1][1:4])


def fly(scenario, out, log, camera, targets, duration, lost_from, above=None):
    """One ADK run; returns (exit code, expected counts) once it has ended (metrics written).
    above: (trajectory, until): the UAV hovers 40 m above that trajectory until sim time
    `until`, 300 m east of it after; None: at (0, 0, 40)."""
    adk = subprocess.Popen(
        [os.path.join(BIN, "adk"), "__name:=adk", "_mission:=%s/mission.json" % scenario,
         "_sim_config:=%s/sim_config.json" % scenario, "_output_dir:=" + out,
         "_clock_timeout:=0", "_end_linger:=0"],
        stdout=open(log, "w"), stderr=subprocess.STDOUT,
        env=dict(os.environ, ROSCONSOLE_STDOUT_LINE_BUFFERED="1"))
    pubs = {
        "clock": rospy.Publisher("/clock", Clock, queue_size=100),
        "odom": rospy.Publisher("/uav/odom", Odometry, queue_size=100),
        "boxes": rospy.Publisher("/uav/camera/%s/boxes" % camera, BoundingBoxArray,
                                 queue_size=100),
        "tracks": rospy.Publisher("/perception/tracks", TrackReport, queue_size=100),
    }
    deadline = time.time() + 60
    while time.time() < deadline and adk.poll() is None and not all(
            p.get_num_connections() > 0 for p in pubs.values()):
        time.sleep(0.05)
    expected = {"unknown_id": 0, "bad_box": 0, "duplicate_id": 0, "out_of_order": 0,
                "unmatched_stamp": 0, "reports": 0}
    xs = {eid: 100 + 60 * i for i, eid in enumerate(targets)}
    prev = None  # the previous frame's stamp and whether it showed the targets
    t = 0.0
    n = 0
    end = 1.0 + duration + 5.0
    while adk.poll() is None and t < end + 2.0:
        n += 1
        t = round(n * DT, 6)
        stamp = rospy.Time.from_sec(t)
        pubs["clock"].publish(Clock(clock=stamp))
        od = Odometry()
        od.header.stamp = stamp
        od.header.frame_id = "map"
        od.pose.pose.position.z = 40.0
        od.pose.pose.orientation.w = 1.0
        if above is not None:
            x, y, z = position_at(above[0], t)
            od.pose.pose.position.x = x + (0.0 if t < above[1] - 1e-9 else 300.0)
            od.pose.pose.position.y = y
            od.pose.pose.position.z = z + 40.0
        pubs["odom"].publish(od)
        if above is not None:
            time.sleep(0.004)  # the frame follows its odometry, as the simulator's render does
        shows = t >= 1.0 - 1e-9 and (lost_from is None or t < lost_from)
        arr = BoundingBoxArray(camera=camera)
        arr.header.stamp = stamp
        if shows:
            arr.boxes = [box(eid, xs[eid]) for eid in targets]
        pubs["boxes"].publish(arr)
        time.sleep(0.004)
        # The previous frame's report, then on some frames one malformed report of each kind.
        # Reports for the frames of the phase only (it starts at the find at 1 s), 1 s clear of
        # its end: a report after it is not scored, and its frames are no longer recorded.
        if (lost_from is None and prev is not None and prev[1] and
                1.3 < prev[0] < 1.0 + duration - 1.0):
            k = int(round(prev[0] / DT))
            good = [tracked(eid, xs[eid]) for eid in targets]
            r = TrackReport(camera=camera, tracks=list(good))
            r.header.stamp = rospy.Time.from_sec(prev[0])
            slot = k % 10
            if k < 10 * (KINDS + 1) and slot == 1:
                r.tracks.append(tracked(targets[0], 0, w=float("nan")))
                r.tracks.append(tracked(targets[0], 0, w=-4.0))
                r.tracks.append(tracked("car_999999", 0))
                r.tracks.append(tracked(targets[0], 7))  # the same id again
                expected["bad_box"] += 2
                expected["unknown_id"] += 1
                expected["duplicate_id"] += 1
            pubs["tracks"].publish(r)
            expected["reports"] += 1
            if k < 10 * (KINDS + 1) and slot == 3:
                late = TrackReport(camera=camera, tracks=list(good))
                late.header.stamp = rospy.Time.from_sec(prev[0] - DT)  # before the last
                pubs["tracks"].publish(late)
                between = TrackReport(camera=camera, tracks=list(good))
                between.header.stamp = rospy.Time.from_sec(prev[0] + 0.1)  # no such frame
                pubs["tracks"].publish(between)
                other = TrackReport(camera=camera + "_other", tracks=list(good))
                other.header.stamp = rospy.Time.from_sec(prev[0] + 0.15)
                pubs["tracks"].publish(other)  # ignored: not the scored camera
                expected["out_of_order"] += 1
                expected["unmatched_stamp"] += 1
                expected["reports"] += 2
        prev = (t, shows)
        time.sleep(0.004)
    try:
        rc = adk.wait(30)
    except subprocess.TimeoutExpired:
        adk.send_signal(signal.SIGINT)
        rc = adk.wait(30)
        check(False, "%s: the ADK did not end the mission by itself (see %s)" % (out, log))
    return rc, expected


def main():
    tmp = tempfile.mkdtemp(prefix="hameritt_track_reports_")
    scenario = generate_one(tmp, "track", SEED)
    with open(os.path.join(scenario, "mission.json")) as f:
        mission = json.load(f)
    with open(os.path.join(scenario, "sim_config.json")) as f:
        names = [c["name"] for c in json.load(f)["uav"]["payload"]["cameras"]]
    camera = "down" if "down" in names else names[0]  # the ADK's default ~track_camera
    phase = mission["phases"][1]
    targets, duration = phase["targets"], phase["duration"]
    limit = phase["criteria"]["max_reacquire_s"]
    print("scenario %s: targets %s, track phase %.0f s, camera %s"
          % (os.path.basename(scenario), targets, duration, camera))
    core = start_master(PORT)
    try:
        rospy.init_node("track_reports_test", anonymous=True, disable_signals=True)
        # Run "tracked": success, every malformed report counted.
        out = os.path.join(tmp, "tracked")
        rc, want = fly(scenario, out, os.path.join(tmp, "tracked.log"), camera, targets,
                       duration, None)
        check(rc == 0, "tracked: adk exit %s" % rc)
        state, m = metrics_state(os.path.join(out, "metrics.json"), METRICS)
        check(state == "complete", "tracked: metrics.json %s" % state)
        tr = (m or {}).get("track", {})
        errors = tr.get("report_errors", {})
        print("tracked: outcome %s, %s frames, %s reports, errors %s (expected %s)"
              % ((m or {}).get("outcome"), tr.get("frames"), tr.get("reports"), errors, want))
        check((m or {}).get("outcome") == "success", "tracked: outcome %s (%s)"
              % ((m or {}).get("outcome"), (m or {}).get("reason")))
        check(tr.get("state") == "succeeded", "tracked: track state %s" % tr.get("state"))
        for kind in ("unknown_id", "bad_box", "duplicate_id", "out_of_order", "unmatched_stamp"):
            check(errors.get(kind) == want[kind],
                  "tracked: %s %s, expected %d" % (kind, errors.get(kind), want[kind]))
        check(want["bad_box"] == 2 * KINDS and want["out_of_order"] == KINDS,
              "tracked: the test sent %s" % want)
        check(errors.get("total") == sum(want[k] for k in want if k != "reports"),
              "tracked: total %s" % errors.get("total"))
        check(tr.get("reports") == want["reports"],
              "tracked: reports %s, expected %d" % (tr.get("reports"), want["reports"]))
        frames = tr.get("frames", 0)
        check(abs(frames - duration / DT) <= 2,
              "tracked: %s frames, expected about %.0f" % (frames, duration / DT))
        check(tr.get("tracked_fraction") == 1.0, "tracked: fraction %s"
              % tr.get("tracked_fraction"))
        for pt in tr.get("per_target", []):
            # Every frame but the first and the last 1 s has its report, with the exact box.
            check(pt["precision"] >= 1.0 - (3.0 + 1.0 / DT) / max(frames, 1),
                  "tracked: %s precision %s" % (pt["id"], pt["precision"]))
            check(pt["breaks"] == 0, "tracked: %s breaks %s" % (pt["id"], pt["breaks"]))
        check(len(tr.get("per_target", [])) == len(targets), "tracked: per_target")
        # Schema negative controls on the good document.
        if m:
            bad = copy.deepcopy(m)
            bad["track"]["report_errors"]["bad_box"] = -1
            check(any(METRICS.iter_errors(bad)), "schema accepts a negative count")
            bad = copy.deepcopy(m)
            del bad["track"]["report_errors"]
            check(any(METRICS.iter_errors(bad)), "schema accepts a track without report_errors")
        # Run "lost" (negative control): the targets hidden from t = 3 s fail the phase.
        with open(os.path.join(scenario, "sim_config.json")) as f:
            first = [e for e in json.load(f)["entities"] if e["id"] == targets[0]][0]
        switch = 3.0 + limit / 2
        out = os.path.join(tmp, "lost")
        rc, _ = fly(scenario, out, os.path.join(tmp, "lost.log"), camera, targets, duration,
                    3.0, (first["trajectory"], switch))
        check(rc == 0, "lost: adk exit %s" % rc)
        state, m = metrics_state(os.path.join(out, "metrics.json"), METRICS)
        check(state == "complete", "lost: metrics.json %s" % state)
        tr = (m or {}).get("track", {})
        print("lost: outcome %s at %s s, failure '%s'"
              % ((m or {}).get("outcome"), (m or {}).get("end_time"), tr.get("failure")))
        check((m or {}).get("outcome") == "failed", "lost: outcome %s" % (m or {}).get("outcome"))
        check("lost for more than" in tr.get("failure", ""), "lost: failure %s"
              % tr.get("failure"))
        end = (m or {}).get("end_time") or 0.0
        check(3.0 + limit < end < 3.0 + limit + 1.0, "lost: ended at %s s" % end)
        check(tr.get("reports") == 0 and tr.get("report_errors", {}).get("total") == 0,
              "lost: reports %s" % tr.get("reports"))
        # The first target: shown from the frame after the find's (the find at 1 s starts the
        # phase after its own frame is judged) to 2.8 s, hidden in view from 3 s until the
        # switch ("full"), out of view after it.
        shown = int(round((3.0 - (tr.get("start_time") or 0.0)) / DT)) - 1
        pt = (tr.get("per_target") or [{}])[0]
        levels = pt.get("by_occlusion", {})
        want_full = int(round((switch - 3.0) / DT))
        full = levels.get("full", {})
        out_of_view = pt.get("frames", 0) - pt.get("in_view_frames", 0)
        print("lost: %s: %s frames, none %s, full %s (expected %d, tracked %s), out of view %s"
              % (pt.get("id"), pt.get("frames"), levels.get("none", {}).get("frames"),
                 full.get("frames"), want_full, full.get("tracked_fraction"), out_of_view))
        check(levels.get("none", {}).get("frames") == shown and shown == 9,
              "lost: none %s, expected %d" % (levels.get("none"), shown))
        check(full.get("frames") == want_full and want_full > 0, "lost: full %s" % full)
        check(full.get("tracked_fraction") == 0.0, "lost: full tracked %s" % full)
        check(pt.get("in_view_frames") == shown + want_full, "lost: in view %s"
              % pt.get("in_view_frames"))
        check(out_of_view > 0, "lost: out of view %s" % out_of_view)
    finally:
        stop_master(core)
    return check.summary(tmp)


if __name__ == "__main__":
    sys.exit(main())
