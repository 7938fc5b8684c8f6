"""Shared pieces of the write-fault, full-disk, duration-end, pursuit, follow and track tests: a
tally of checks, the metrics.json schema (python3-jsonschema), an ADK that writes its metrics
without a mission, one generated scenario, and a mission.launch run read back (with the adk/phase
changes rostopic saw)."""
import csv
import json
import os
import signal
import subprocess
import time

from jsonschema import Draft7Validator

SRC = os.environ["HAMERITT_SOURCE_DIR"]
BIN = os.environ["HAMERITT_BIN_DIR"]
SCENARIO = os.path.join(SRC, "scenarios", "default")


class Checks:
    """Counts checks; prints and keeps each failure."""

    def __init__(self):
        self.passed = 0
        self.fails = []

    def __call__(self, cond, what):
        if cond:
            self.passed += 1
        else:
            self.fails.append(what)
            print("FAIL:", what)
        return cond

    def summary(self, kept):
        print("%d passed, %d failed" % (self.passed, len(self.fails)))
        if self.fails:
            print("FAIL (outputs kept in %s):\n  %s" % (kept, "\n  ".join(self.fails)))
        return 1 if self.fails else 0


def metrics_validator():
    with open(os.path.join(SRC, "config", "schema", "metrics.schema.json")) as f:
        return Draft7Validator(json.load(f))


def metrics_state(path, validator):
    """("absent" | "complete" | "half (why)", the document when complete)."""
    if not os.path.exists(path):
        return "absent", None
    try:
        with open(path) as f:
            doc = json.load(f)
    except ValueError as e:
        return "half (%s)" % e, None
    errors = [e.message for e in validator.iter_errors(doc)]
    return ("half (schema: %s)" % errors[0], None) if errors else ("complete", doc)


def run_adk(out, log, name, params=(), env=None):
    """The adk node on the default scenario (a master must run) until it is up, then SIGINT:
    it ends the mission `aborted` and writes OUT/metrics.json at once. Returns its exit code
    (negative: the signal that killed it)."""
    p = subprocess.Popen(
        [os.path.join(BIN, "adk"), "__name:=" + name, "_mission:=%s/mission.json" % SCENARIO,
         "_sim_config:=%s/sim_config.json" % SCENARIO, "_output_dir:=" + out,
         "_clock_timeout:=0"] + list(params),
        stdout=open(log, "w"), stderr=subprocess.STDOUT,
        env=dict(env or os.environ, ROSCONSOLE_STDOUT_LINE_BUFFERED="1"))
    deadline = time.time() + 60
    while time.time() < deadline and p.poll() is None:
        if "metrics to" in open(log).read():
            break
        time.sleep(0.05)
    p.send_signal(signal.SIGINT)
    try:
        return p.wait(60)
    except subprocess.TimeoutExpired:
        p.kill()
        return p.wait()


def generate_one(tmp, cls, seed):
    """The scenario of `hameritt_generate --class CLS --count 1 --seed SEED` under tmp."""
    out = os.path.join(tmp, "scenarios")
    subprocess.run(["rosrun", "hameritt", "hameritt_generate", "--class", cls, "--count", "1",
                    "--seed", str(seed), "--out", out], check=True, stdout=subprocess.DEVNULL)
    dirs = [d for d in sorted(os.listdir(out)) if d.startswith(cls + "-")]
    assert len(dirs) == 1, dirs
    return os.path.join(out, dirs[0])


def launch_mission(args, out, log, label, check, guard, master_uri=None):
    """Runs `roslaunch hameritt mission.launch ARGS output_dir:=OUT` (its output in LOG) until it
    ends by itself; after `guard` wall seconds (a hang, not a timing) it is stopped and that is a
    failed check. `master_uri`: another master than ROS_MASTER_URI's (two missions at once).
    Returns (exit code, log text, metrics.json or None: a failed check)."""
    env = dict(os.environ, ROSCONSOLE_STDOUT_LINE_BUFFERED="1")
    if master_uri:
        env["ROS_MASTER_URI"] = master_uri
    launch = subprocess.Popen(
        ["roslaunch", "hameritt", "mission.launch"] + list(args) + ["output_dir:=" + out],
        stdout=open(log, "w"), stderr=subprocess.STDOUT, env=env)
    try:
        rc = launch.wait(guard)
    except subprocess.TimeoutExpired:
        launch.send_signal(signal.SIGINT)
        rc = launch.wait(60)
        check(False, "%s: the launch did not end by itself" % label)
    with open(log) as f:
        text = f.read()
    try:
        with open(os.path.join(out, "metrics.json")) as f:
            return rc, text, json.load(f)
    except (OSError, ValueError) as e:
        check(False, "%s: metrics.json: %s" % (label, e))
        return rc, text, None


def phase_changes(path):
    """[(phase, type, state)] from `rostopic echo -p` output, in order."""
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return [(r["field.phase"], r["field.type"], r["field.state"]) for r in rows]


def launch_mission_phases(args, out, log, phases, label, check, guard, echoes=None):
    """launch_mission, with adk/phase as `rostopic echo` (not our code) sees it written to PHASES:
    subscribed before the ADK starts, so no change is missed; `echoes` ({topic: path}) are
    recorded the same way. Returns (exit code, log text, metrics.json or None, [(phase, type,
    state)] in order)."""
    topics = dict(echoes or {}, **{"/adk/phase": phases})
    procs = [subprocess.Popen(["rostopic", "echo", "-p", t], stdout=open(p, "w"),
                              stderr=subprocess.DEVNULL) for t, p in topics.items()]
    try:
        rc, text, m = launch_mission(args, out, log, label, check, guard)
    finally:
        for e in procs:
            e.send_signal(signal.SIGINT)
            e.wait(30)
    return rc, text, m, phase_changes(phases)
