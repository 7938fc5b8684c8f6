#!/usr/bin/python3
"""Faults at write time: SIGKILL inside the writers, swept over every point of their output.

An LD_PRELOAD shim (test/faults/kill_at_write.c, compiled here) counts the file-output events
of a process on paths that contain a pattern (open, each write, fsync, syncfs, close, rename
before and after) and SIGKILLs it at the Nth one; at a write it first writes half the bytes.
A counting run gives the number of events E; then the writer is killed at N = 1..E:
  * the ADK writing metrics.json (adk node on a private master, stopped with SIGINT so that it
    writes its metrics at once): every N, with and without a previous metrics.json;
  * hameritt_export writing a dataset from a small synthetic bag (synthetic_bag.py): N at
    1, E/4, E/2, 3E/4 and each of the last 6 events (the rename), with and without a previous
    dataset (--force; a counting run for each, as replacing takes more events).
After each kill the final name holds nothing, the previous complete output, or the complete new
output: metrics.json parses and validates against config/schema/metrics.schema.json
(python3-jsonschema); a dataset's COCO file parses and every image it lists is a whole PNG that
OpenCV decodes. Over increasing N the outputs must read old (or nothing) up to one event and
new from there on, both seen; for metrics.json only the kill after the rename (the last event)
may show the new file.

Negative controls, run here: a writer that writes the final name in place (test/faults/
direct_writer.c) under the same sweep leaves a half file that the same check catches; a
truncated PNG and a truncated COCO file in a copy of a complete dataset are caught.
"""
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import cv2

from fault_util import BIN, SRC, Checks, metrics_state, metrics_validator, run_adk

PORT = 21000 + os.getpid() % 2000
PNG_END = b"IEND\xaeB`\x82"
METRICS = metrics_validator()
check = Checks()
RUNS = [0]


def metrics_kind(path):
    """absent | old | new (a complete metrics.json, told apart by its reason) | half (why)"""
    state, doc = metrics_state(path, METRICS)
    if state != "complete":
        return state
    return "old" if doc["reason"] == "previous run" else "new"


def dataset_state(path):
    """absent | a complete dataset's image count | half: why"""
    if not os.path.exists(path):
        return "absent"
    try:
        with open(os.path.join(path, "annotations", "instances_train.json")) as f:
            coco = json.load(f)
    except (OSError, ValueError) as e:
        return "half: annotations: %s" % e
    names = []
    for im in coco["images"]:
        names.append(im["file_name"])
        for key in ("depth_file", "segmentation_file", "instances_file"):
            if im.get("extra", {}).get(key):
                names.append(im["extra"][key])
    if not coco["images"]:
        return "half: no images"
    for name in names:
        p = os.path.join(path, name)
        try:
            with open(p, "rb") as f:
                data = f.read()
        except OSError as e:
            return "half: %s" % e
        if not data.endswith(PNG_END) or cv2.imread(p, cv2.IMREAD_UNCHANGED) is None:
            return "half: %s is not a whole PNG" % name
    return "images=%d" % len(coco["images"])


def shim(pattern, at, count=None):
    env = dict(os.environ, LD_PRELOAD=SHIM, KILL_PATTERN=pattern, KILL_AT=str(at))
    if count:
        env["KILL_COUNT"] = count
    return env


def count_of(path):
    with open(path) as f:
        return int(f.read())


# ------------------------------------------------------------------------------- the ADK
def previous_metrics(out, template):
    with open(template) as f:
        doc = json.load(f)
    doc["reason"] = "previous run"
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "metrics.json"), "w") as f:
        json.dump(doc, f, indent=2)


def monotone(label, states, before, after):
    """Every kill left `before` (nothing, or the previous output) up to some event and the
    complete new output `after` from there on; never a half output."""
    half = [n for n, st in states if st == "half"]
    check(not half, "%s: a half output carried the final name (kills at events %s)" % (label, half))
    seq = [st for _, st in states]
    first_after = seq.index(after) if after in seq else len(seq)
    check(0 < first_after < len(seq) and seq == [before] * first_after +
          [after] * (len(seq) - first_after),
          "%s: expected %s, then from one event on %s; got %s" % (label, before, after, states))
    return seq.count(before), seq.count(after)


def sweep_metrics(label, total, run, prepare):
    """Kills at N = 1..total; returns the final state after each, [(N, state)]."""
    states = []
    tally = {}
    for n in range(1, total + 1):
        RUNS[0] += 1
        out = os.path.join(T, "run%03d" % RUNS[0])  # no "metrics.json" in the directory's name
        prepare(out)
        rc = run(out, n)
        check(rc == -signal.SIGKILL, "%s: kill at event %d: exit %s, expected SIGKILL" % (label, n, rc))
        state = metrics_kind(os.path.join(out, "metrics.json"))
        if state.startswith("half"):
            print("  %s: kill at event %d: metrics.json is %s" % (label, n, state))
            state = "half"
        tally[state] = tally.get(state, 0) + 1
        states.append((n, state))
    print("%s: %d kills: %s" % (label, total, ", ".join("%s %d" % kv for kv in sorted(tally.items()))))
    return states


def adk_faults():
    core = subprocess.Popen(["rosmaster", "--core", "-p", str(PORT)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    os.environ["ROS_MASTER_URI"] = "http://localhost:%d" % PORT
    os.environ["ROSCONSOLE_STDOUT_LINE_BUFFERED"] = "1"
    try:
        # Counting run: the events of one metrics.json.
        out = os.path.join(T, "adk_count")
        cnt = os.path.join(T, "adk.count")
        log = os.path.join(T, "adk_count.log")
        rc = run_adk(out, log, "adk_count", env=shim("metrics.json", 0, cnt))
        check(rc == 0, "adk counting run: exit %s (%s)" % (rc, log))
        template = os.path.join(out, "metrics.json")
        check(metrics_kind(template) == "new", "adk counting run: metrics.json %s"
              % metrics_kind(template))
        total = count_of(cnt)
        # open, write, fsync, close, rename (before, after): at least six.
        print("adk: %d output events while writing metrics.json" % total)
        check(total >= 6, "adk: %d output events, expected >= 6" % total)

        def run(o, n):
            return run_adk(o, os.path.join(T, "adk_kill_%d.log" % n), "adk_kill_%d" % n,
                           env=shim("metrics.json", n))

        # Only a kill after the rename (the last event) may leave the new file.
        label = "adk over a previous metrics.json"
        states = sweep_metrics(label, total, run, lambda o: previous_metrics(o, template))
        check(monotone(label, states, "old", "new") == (total - 1, 1),
              "%s: the new file before the rename: %s" % (label, states))
        label = "adk without a previous metrics.json"
        states = sweep_metrics(label, total, run, lambda o: os.makedirs(o, exist_ok=True))
        check(monotone(label, states, "absent", "new") == (total - 1, 1),
              "%s: the new file before the rename: %s" % (label, states))
    finally:
        core.send_signal(signal.SIGINT)
        core.wait(30)


def negative_control():
    """A writer that writes the final name in place is caught by the same check."""
    template = os.path.join(T, "adk_count", "metrics.json")
    src = os.path.join(T, "direct_source.json")  # not a watched name
    shutil.copy(template, src)
    cnt = os.path.join(T, "direct.count")

    def run(out, n):
        return subprocess.run([DIRECT, src, os.path.join(out, "metrics.json")],
                              env=shim("metrics.json", n)).returncode

    rc = subprocess.run([DIRECT, src, os.path.join(T, "direct_count.metrics.json")],
                        env=shim("metrics.json", 0, cnt)).returncode
    total = count_of(cnt)
    check(rc == 0 and total == 3, "direct writer: exit %d, %d events (expected 0, 3)" % (rc, total))
    states = sweep_metrics("negative control: direct writer", total, run,
                           lambda o: previous_metrics(o, template))
    # open (previous intact), write (half written: caught), close (the new file whole).
    check([st for _, st in states] == ["old", "half", "new"],
          "negative control: the direct writer's half file was not caught (%s)" % states)


# ------------------------------------------------------------------------------ the exporter
def export(bag, out, env=None, *extra):
    return subprocess.run([os.path.join(BIN, "hameritt_export"), bag, "--format", "coco",
                           "--out", out, "--quiet", "--jobs", "2"] + list(extra),
                          env=env, capture_output=True, text=True)


def export_faults():
    bag = os.path.join(T, "synthetic.bag")
    subprocess.run([sys.executable, os.path.join(SRC, "test", "scripts", "synthetic_bag.py"),
                    bag, "6"], check=True)
    # The previous dataset: every other frame.
    prev = os.path.join(T, "previous_dataset")
    r = export(bag, prev, None, "--every", "2")
    check(r.returncode == 0, "export: %s" % r.stderr)
    prev_state = dataset_state(prev)
    check(prev_state == "images=3", "export: the previous dataset: %s" % prev_state)
    for label, with_prev in (("over a previous dataset", True), ("into a new name", False)):
        # Counting run in the same situation (replacing a dataset takes more steps).
        cnt = os.path.join(T, "export.count")
        out = os.path.join(T, "ds_count_%d" % with_prev)
        if with_prev:
            shutil.copytree(prev, out)
        r = export(bag, out, shim(out, 0, cnt), "--force")
        check(r.returncode == 0, "export counting run %s: %s" % (label, r.stderr))
        check(dataset_state(out) == "images=6", "export counting run: %s" % dataset_state(out))
        total = count_of(cnt)
        # 6 frames x 4 PNGs x (open, write, close), the COCO file, syncfs, the rename: > 75.
        print("export %s: %d output events while writing a 6-image dataset" % (label, total))
        check(total > 75, "export: %d output events, expected > 75" % total)
        points = sorted(set([1] + [total * k // 4 for k in range(1, 4)] +
                            list(range(total - 5, total + 1))))
        tally = {}
        states = []
        for n in points:
            out = os.path.join(T, "ds_%s_%d" % ("prev" if with_prev else "new", n))
            if with_prev:
                shutil.copytree(prev, out)
            r = export(bag, out, shim(out, n), "--force")
            check(r.returncode == -signal.SIGKILL,
                  "export %s: kill at event %d: exit %s" % (label, n, r.returncode))
            state = dataset_state(out)
            if state.startswith("half"):
                print("  export %s: kill at event %d: %s" % (label, n, state))
                state = "half"
            tally[state] = tally.get(state, 0) + 1
            states.append((n, state))
        print("export %s: %d kills at events %s..%s: %s" % (
            label, len(points), points[0], points[-1],
            ", ".join("%s %d" % kv for kv in sorted(tally.items()))))
        monotone("export " + label, states, "images=3" if with_prev else "absent", "images=6")
    # Negative controls of the dataset check: a truncated PNG, a truncated COCO file.
    for what, rel in (("a truncated PNG", None), ("a truncated COCO file",
                                                  "annotations/instances_train.json")):
        bad = os.path.join(T, "ds_broken_%d" % len(rel or ""))
        shutil.copytree(prev, bad)
        if rel is None:
            rel = os.path.join("images", "train", sorted(os.listdir(
                os.path.join(bad, "images", "train")))[0])
        p = os.path.join(bad, rel)
        size = os.path.getsize(p)
        with open(p, "r+b") as f:
            f.truncate(size // 2)
        state = dataset_state(bad)
        print("negative control: %s: %s" % (what, state))
        check(state.startswith("half"), "negative control: %s was not caught (%s)" % (what, state))


def main():
    global T, SHIM, DIRECT
    T = tempfile.mkdtemp(prefix="hameritt_write_faults.")
    SHIM = os.path.join(T, "kill_at_write.so")
    DIRECT = os.path.join(T, "direct_writer")
    faults = os.path.join(SRC, "test", "faults")
    subprocess.run(["cc", "-O1", "-shared", "-fPIC", "-o", SHIM,
                    os.path.join(faults, "kill_at_write.c"), "-ldl"], check=True)
    subprocess.run(["cc", "-O1", "-o", DIRECT, os.path.join(faults, "direct_writer.c")],
                   check=True)
    try:
        for part in (adk_faults, negative_control, export_faults):
            t0 = time.time()
            part()
            print("(%s: %.1f wall s)" % (part.__name__, time.time() - t0))
    finally:
        if not check.fails:
            shutil.rmtree(T, ignore_errors=True)
    return check.summary(T)


if __name__ == "__main__":
    sys.exit(main())
