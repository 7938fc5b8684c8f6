#!/usr/bin/python3
"""hameritt_campaign: scenario generation and mission runs at scale, sharded, on Slurm.

  hameritt_campaign plan   CONFIG --out DIR      write DIR/plan.json (deterministic work units)
  hameritt_campaign run    DIR --local [--jobs J] [--shard K ...]   run shards on this machine
  hameritt_campaign submit DIR --slurm [--resubmit-missing] [--dry-run]   sbatch job array
  hameritt_campaign status DIR [--wait [SECONDS]] [--json]   units done / missing, Slurm jobs
  hameritt_campaign merge  DIR                   DIR/merged: scenarios, manifest.json, summary
  hameritt_campaign compare A.json B.json        merged manifests, run-specific fields aside
  hameritt_campaign run-shard DIR --shard K      one shard (what each Slurm array task runs)

Exit codes: 0 success, 2 bad input (config, arguments, campaign directory), 1 a unit or a
command failed, 3 (status, merge) units are missing.

A campaign directory holds plan.json, units/<unit>/ (each complete unit, moved there by one
rename when complete), units/.work/ (units in progress), shards/<k>/ (per-shard logs),
slurm/ (the sbatch script, job ids, array task output) and merged/.
"""

import argparse
import datetime
import hashlib
import json
import math
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

SCHEMA_PLAN = "hameritt/campaign_plan"
SCHEMA_MANIFEST = "hameritt/campaign_manifest"
SCHEMA_VERSION = 1
CLASSES = ("area_search", "route_search", "pursuit", "follow", "track")
# What "all" means, as for hameritt_generate --class all: the three search classes.
ALL_CLASSES = CLASSES[:3]
MODES = ("maneuver_only", "perception_only", "end_to_end")
# Fields of a merged manifest that belong to one run, not to the campaign: where and when a
# unit ran, and what a ROS graph's scheduling decides (see compare_manifests).
RUN_SPECIFIC_SECTIONS = ("run",)
RUN_SPECIFIC_UNIT_FIELDS = ("shard", "host", "job", "wall_time", "finished")
# Mission figures that two runs of one mission do not reproduce exactly: the ROS graph's message
# interleaving moves the flown path by millimetres (path_length, energy, coverage), a free-running
# mission's ADK sees the sim time that ends it a few clock messages late on a loaded machine
# (end_time: 6.4 s against 6.0 s for a 6 s time limit, seen once in a whole test run), and the
# recorder's chunking and compression change the bag's size. compare checks them for presence
# and type only (summary.bag_bytes likewise); lock-step missions reproduce them exactly.
RUN_DEPENDENT_MISSION_FIELDS = ("bag_size", "energy", "path_length", "coverage", "end_time")
RUN_DEPENDENT_SUMMARY_FIELDS = ("bag_bytes",)


class CampaignError(Exception):
    """Bad input: a config field, an argument or a campaign directory; exit code 2."""


# The limits every JSON reader of the project holds (include/hameritt/scenario/bounded_json.h):
# a larger file is refused before it is read, deeper nesting before it is parsed.
MAX_JSON_BYTES = 64 << 20
MAX_JSON_DEPTH = 64
_JSON_STRING = re.compile(r'"(?:[^"\\]|\\.)*"', re.S)
_JSON_BRACKET = re.compile(r"[\[\]{}]")


def check_json_depth(text, path, max_depth=MAX_JSON_DEPTH):
    """CampaignError naming the file and the limit when arrays and objects nest deeper."""
    depth = 0
    for m in _JSON_BRACKET.finditer(_JSON_STRING.sub('""', text)):
        if m.group() in "[{":
            depth += 1
            if depth > max_depth:
                raise CampaignError("%s: JSON nested deeper than the limit of %d levels"
                                    % (path, max_depth))
        elif depth > 0:
            depth -= 1


def load_json(path, hint="", max_bytes=MAX_JSON_BYTES):
    """The parsed JSON file `path` within the size and depth limits; CampaignError (exit 2)
    naming the file, and the limit or the reason, otherwise."""
    try:
        with open(path, "rb") as f:
            size = os.fstat(f.fileno()).st_size
            if size > max_bytes:
                raise CampaignError("%s: %d bytes, more than the limit of %d bytes (%d MiB) for a "
                                    "JSON document" % (path, size, max_bytes, max_bytes >> 20))
            data = f.read(max_bytes + 1)
    except OSError as e:
        raise CampaignError("%s: cannot read%s: %s" % (path, hint, e.strerror))
    if len(data) > max_bytes:
        raise CampaignError("%s: more than the limit of %d bytes (%d MiB) for a JSON document"
                            % (path, max_bytes, max_bytes >> 20))
    try:
        text = data.decode("utf-8")
        check_json_depth(text, path)
        return json.loads(text)
    except ValueError as e:  # UnicodeDecodeError and JSONDecodeError
        raise CampaignError("%s: not valid JSON: %s" % (path, e))


# ---------------------------------------------------------------------------- config


def _expect(cond, path, field, expected, got):
    if not cond:
        raise CampaignError("%s: field '%s': expected %s, got %r" % (path, field, expected, got))


def _int_field(d, path, field, default, lo, hi, section=""):
    v = d.get(field, default)
    _expect(isinstance(v, int) and not isinstance(v, bool) and lo <= v <= hi, path,
            section + field,
            "an integer from %d to %d" % (lo, hi), v)
    return v


def _num_field(d, path, field, default, lo, hi, section=""):
    v = d.get(field, default)
    _expect(isinstance(v, (int, float)) and not isinstance(v, bool) and lo <= v <= hi
            and math.isfinite(v), path, section + field, "a number from %g to %g" % (lo, hi), v)
    return float(v)


def _bool_field(d, path, field, default, section=""):
    v = d.get(field, default)
    _expect(isinstance(v, bool), path, section + field, "true or false", v)
    return v


def _list_field(d, path, field, default, allowed, section="", all_values=None):
    v = d.get(field, default)
    if v == "all":
        v = list(all_values or allowed)
    if isinstance(v, str):
        v = [v]
    _expect(isinstance(v, list) and v and all(isinstance(x, str) and x in allowed for x in v)
            and len(set(v)) == len(v), path, section + field,
            "'all' or a list of distinct names from %s" % ", ".join(allowed), d.get(field))
    return v


def parse_config(text, path="campaign.yaml"):
    """Parses and checks a campaign config (YAML or JSON text); returns a normalized dict."""
    import yaml
    try:
        raw = yaml.safe_load(text)
    except yaml.YAMLError as e:
        raise CampaignError("%s: not valid YAML: %s" % (path, str(e).replace("\n", " ")))
    _expect(isinstance(raw, dict), path, "(top level)", "a mapping", raw)
    known = {"name", "seed", "classes", "count", "shards", "world", "generate", "missions", "slurm",
             "spec", "spec_params", "sampler"}
    for k in raw:
        _expect(k in known, path, k, "one of " + ", ".join(sorted(known)), "unknown field")
    name = raw.get("name", "campaign")
    _expect(isinstance(name, str) and name and all(c.isalnum() or c in "-_." for c in name),
            path, "name", "letters, digits, '-', '_' or '.'", name)
    cfg = {
        "name": name,
        "seed": _int_field(raw, path, "seed", None, 0, 2**63 - 1),
        "classes": _list_field(raw, path, "classes", "all", CLASSES, all_values=ALL_CLASSES),
        "count": _int_field(raw, path, "count", None, 1, 10000000),
        "shards": _int_field(raw, path, "shards", 1, 1, 10000),
    }
    # A scenario-language spec instead of classes (hameritt_generate --spec): its path relative
    # to the config file; the class comes from the spec (make_plan asks the generator).
    if "spec" in raw:
        _expect("classes" not in raw, path, "classes", "no classes with spec (a spec names its "
                "class)", raw.get("classes"))
        spec = raw["spec"]
        _expect(isinstance(spec, str) and spec, path, "spec", "a .hspec file", spec)
        spec = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(path)), spec))
        _expect(os.path.isfile(spec), path, "spec", "a readable .hspec file", raw["spec"])
        params = raw.get("spec_params", {}) or {}
        _expect(isinstance(params, dict) and all(
            isinstance(k, str) and isinstance(v, (int, float, str)) and not isinstance(v, bool)
            for k, v in params.items()), path, "spec_params",
            "a mapping of parameter names to values", params)
        sampler = raw.get("sampler", "random")
        _expect(sampler in ("random", "halton"), path, "sampler", "random or halton", sampler)
        cfg["spec"] = {"file": spec, "sampler": sampler,
                       "params": ["%s=%s" % (k, params[k]) for k in sorted(params)]}
        cfg["classes"] = []
    else:
        for k in ("spec_params", "sampler"):
            _expect(k not in raw, path, k, "only with spec", raw.get(k))
    # The world type (hameritt_generate --world); kept out of the plan when it is the default.
    world = raw.get("world", "suburb")
    _expect(world in ("suburb", "city"), path, "world", "suburb or city", world)
    if world != "suburb":
        cfg["world"] = world
    gen = raw.get("generate", {}) or {}
    _expect(isinstance(gen, dict), path, "generate", "a mapping", gen)
    for k in gen:
        _expect(k in ("unit_size", "jobs"), path, "generate." + k, "unit_size or jobs",
                "unknown field")
    default_unit = int(math.ceil(cfg["count"] / float(cfg["shards"])))
    cfg["generate"] = {
        "unit_size": _int_field(gen, path, "unit_size", default_unit, 1, 10000000, "generate."),
        "jobs": _int_field(gen, path, "jobs", 1, 1, 256, "generate."),
    }
    mis = raw.get("missions", {}) or {}
    _expect(isinstance(mis, dict), path, "missions", "a mapping", mis)
    mkeys = ("count", "scenarios", "modes", "cameras", "time_limit", "real_time_factor",
             "record", "record_all", "record_image_rate", "timeout")
    for k in mis:
        _expect(k in mkeys, path, "missions." + k, "one of " + ", ".join(mkeys), "unknown field")
    scen = mis.get("scenarios", None)
    if scen is None:
        n = _int_field(mis, path, "count", 0, 0, cfg["count"], "missions.")
        scen = list(range(n))
    else:
        _expect(isinstance(scen, list) and all(isinstance(i, int) and not isinstance(i, bool)
                                               and 0 <= i < cfg["count"] for i in scen)
                and len(set(scen)) == len(scen), path, "missions.scenarios",
                "distinct scenario indices from 0 to %d" % (cfg["count"] - 1), scen)
    cameras = mis.get("cameras", "all")
    _expect(cameras == "all" or (isinstance(cameras, list) and cameras and
                                 all(isinstance(c, str) and c for c in cameras)),
            path, "missions.cameras", "'all' or a list of camera names", cameras)
    cfg["missions"] = {
        "scenarios": sorted(scen),
        "modes": _list_field(mis, path, "modes", ["end_to_end"], MODES, "missions."),
        "cameras": cameras,
        "time_limit": _num_field(mis, path, "time_limit", 0, 0, 1e6, "missions."),
        "real_time_factor": _num_field(mis, path, "real_time_factor", 0, 0, 1000, "missions."),
        "record": _bool_field(mis, path, "record", True, "missions."),
        "record_all": _bool_field(mis, path, "record_all", False, "missions."),
        "record_image_rate": _num_field(mis, path, "record_image_rate", 2, 0, 1000, "missions."),
        "timeout": _num_field(mis, path, "timeout", 3600, 1, 1e7, "missions."),
    }
    sl = raw.get("slurm", {}) or {}
    _expect(isinstance(sl, dict), path, "slurm", "a mapping", sl)
    for k in sl:
        _expect(k in ("partition", "time", "cpus_per_task", "mem", "max_parallel", "extra"),
                path, "slurm." + k, "partition, time, cpus_per_task, mem, max_parallel or extra",
                "unknown field")
    part = sl.get("partition", "")
    _expect(isinstance(part, str), path, "slurm.partition", "a partition name", part)
    tl = sl.get("time", "01:00:00")
    _expect(isinstance(tl, str) and tl and all(c.isdigit() or c in ":-" for c in tl), path,
            "slurm.time", "a Slurm time limit such as 01:00:00", tl)
    mem = sl.get("mem", "4G")
    _expect(isinstance(mem, str) and mem[:1].isdigit(), path, "slurm.mem", "e.g. 4G", mem)
    extra = sl.get("extra", [])
    _expect(isinstance(extra, list) and all(isinstance(x, str) and x.startswith("--")
                                            for x in extra), path, "slurm.extra",
            "a list of sbatch options such as --qos=normal", extra)
    cfg["slurm"] = {
        "partition": part, "time": tl, "mem": mem, "extra": extra,
        "cpus_per_task": _int_field(sl, path, "cpus_per_task", 2, 1, 1024, "slurm."),
        "max_parallel": _int_field(sl, path, "max_parallel", 0, 0, 100000, "slurm."),
    }
    return cfg


def load_config(path):
    try:
        with open(path) as f:
            text = f.read()
    except OSError as e:
        raise CampaignError("%s: cannot read: %s" % (path, e.strerror))
    return parse_config(text, path)


# ---------------------------------------------------------------------------- plan


def class_of(cfg, index):
    """Class of scenario `index`, as hameritt_generate assigns it: classes[index mod k]."""
    return cfg["classes"][index % len(cfg["classes"])]


def unit_cost(unit):
    """A rough cost in seconds, to balance shards (missions dominate)."""
    if unit["kind"] == "generate":
        return 0.05 * unit["count"]
    return 15.0 + unit["time_limit"] * 2.0


def source_args(cfg):
    """hameritt_generate's flags that say what to generate: the classes or the spec."""
    if "spec" not in cfg:
        return ["--class", ",".join(cfg["classes"])]
    args = ["--spec", cfg["spec"]["file"], "--sampler", cfg["spec"]["sampler"]]
    for p in cfg["spec"]["params"]:
        args += ["--param", p]
    return args


def spec_class(cfg):
    """The class of a spec campaign's scenarios: the generator compiles the spec (a bad or
    unsatisfiable spec is a CampaignError naming the generator's message) and writes scenario 0,
    whose mission.json names the class."""
    tmp = tempfile.mkdtemp(prefix="hameritt_campaign_spec_")
    try:
        cmd = [os.path.join(tool_dir(), "hameritt_generate")] + source_args(cfg) + [
            "--seed", str(cfg["seed"]), "--into", os.path.join(tmp, "s"), "--quiet"] + \
            world_args(cfg)
        r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           universal_newlines=True)
        if r.returncode != 0:
            raise CampaignError("spec %s: %s" % (cfg["spec"]["file"],
                                                 r.stderr.strip().split("\n")[0]))
        return load_json(os.path.join(tmp, "s", "mission.json"))["class"]
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def make_plan(cfg):
    """The deterministic list of work units and their shards for a config."""
    if "spec" in cfg and not cfg["classes"]:
        cfg["classes"] = [spec_class(cfg)]
    units = []
    size = cfg["generate"]["unit_size"]
    for k, first in enumerate(range(0, cfg["count"], size)):
        units.append({"id": "gen-%06d" % k, "kind": "generate", "first": first,
                      "count": min(size, cfg["count"] - first)})
    m = cfg["missions"]
    missions = []
    for i in m["scenarios"]:
        for mode in m["modes"]:
            missions.append({"id": "mission-%06d-%s" % (i, mode), "kind": "mission",
                             "scenario_index": i, "class": class_of(cfg, i), "mode": mode,
                             "time_limit": m["time_limit"]})
    # Each unit onto the least loaded shard (ties: the lowest), generation first: the
    # generation spreads evenly and the missions balance around it. Deterministic.
    load = [0.0] * cfg["shards"]
    for u in units + missions:
        s = min(range(cfg["shards"]), key=lambda j: (load[j], j))
        u["shard"] = s
        load[s] += unit_cost(u)
    units = units + missions
    return {"schema": SCHEMA_PLAN, "schema_version": SCHEMA_VERSION, "config": cfg,
            "units": units}


def write_atomic(path, text):
    tmp = "%s.tmp.%d" % (path, os.getpid())
    with open(tmp, "w") as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def dump_json(obj):
    return json.dumps(obj, indent=2, sort_keys=True) + "\n"


def load_plan(cdir):
    path = os.path.join(cdir, "plan.json")
    plan = load_json(path, " (run 'hameritt_campaign plan' first)")
    if not isinstance(plan, dict) or plan.get("schema") != SCHEMA_PLAN:
        raise CampaignError("%s: field 'schema': expected %s" % (path, SCHEMA_PLAN))
    return plan


def cmd_plan(args):
    cfg = load_config(args.config)
    plan = make_plan(cfg)
    os.makedirs(os.path.join(args.out, "units", ".work"), exist_ok=True)
    path = os.path.join(args.out, "plan.json")
    text = dump_json(plan)
    if os.path.exists(path):
        with open(path) as f:
            if f.read() != text:
                raise CampaignError("%s: a different plan is already there (another config?); "
                                    "use a new directory" % path)
    write_atomic(path, text)
    shards = {}
    for u in plan["units"]:
        shards[u["shard"]] = shards.get(u["shard"], 0) + 1
    print("hameritt_campaign: %d units in %d shards -> %s" % (len(plan["units"]), cfg["shards"],
                                                              path))
    return 0


# ---------------------------------------------------------------------------- running units


def tool_dir():
    """Where hameritt_generate lies: beside this script once built, else HAMERITT_BIN_DIR."""
    here = os.path.dirname(os.path.realpath(__file__))
    for d in (here, os.environ.get("HAMERITT_BIN_DIR", "")):
        if d and os.access(os.path.join(d, "hameritt_generate"), os.X_OK):
            return d
    raise CampaignError("hameritt_generate not found beside %s nor in HAMERITT_BIN_DIR; "
                        "source the build's devel/setup.bash" % here)


def port_is_free(port):
    s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    try:
        s.bind(("127.0.0.1", port))
        return True
    except OSError:
        return False
    finally:
        s.close()


def pick_port(task_id, slot, is_free=port_is_free):
    """A ROS master port for array task `task_id`'s `slot`-th unit: 20000 + 16 * (task mod
    1500) + slot mod 16, the next free one after it when taken (bind test), else one the
    kernel picks."""
    base = 20000 + 16 * (task_id % 1500)
    for k in range(64):
        p = base + (slot + k) % 16 if k < 16 else 44000 + (task_id * 64 + slot + k) % 20000
        if is_free(p):
            return p
    s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    s.bind(("127.0.0.1", 0))
    p = s.getsockname()[1]
    s.close()
    return p


def unit_paths(cdir, unit_id, tag):
    units = os.path.join(cdir, "units")
    return os.path.join(units, unit_id), os.path.join(units, ".work", "%s@%s" % (unit_id, tag))


def pid_alive(pid):
    try:
        os.kill(pid, 0)
        return True
    except ProcessLookupError:
        return False
    except PermissionError:
        return True


def clean_stale_work(cdir, unit_ids):
    """Removes work directories of these units left by dead processes on this host."""
    work = os.path.join(cdir, "units", ".work")
    host = socket.gethostname()
    removed = []
    for name in sorted(os.listdir(work)) if os.path.isdir(work) else []:
        uid, _, tag = name.partition("@")
        parts = tag.split("@")
        if uid not in unit_ids or len(parts) != 2 or parts[0] != host:
            continue
        try:
            pid = int(parts[1])
        except ValueError:
            continue
        if pid != os.getpid() and not pid_alive(pid):
            shutil.rmtree(os.path.join(work, name), ignore_errors=True)
            removed.append(name)
    return removed


def finish_unit(work, final, record):
    """Writes unit.json and moves the work directory into place by one rename. Returns False
    when another run completed the unit first (its copy is kept, ours removed)."""
    write_atomic(os.path.join(work, "unit.json"), dump_json(record))
    try:
        os.rename(work, final)
        return True
    except OSError:
        if os.path.isdir(final):
            shutil.rmtree(work, ignore_errors=True)
            return False
        raise


def world_args(cfg):
    """hameritt_generate's --world flag for a campaign that names a world type."""
    return ["--world", cfg["world"]] if "world" in cfg else []


def run_generate_unit(cfg, unit, work, log):
    cmd = [os.path.join(tool_dir(), "hameritt_generate")] + source_args(cfg) + [
           "--count", str(unit["count"]), "--first", str(unit["first"]), "--seed",
           str(cfg["seed"]), "--out", os.path.join(work, "scenarios"), "--jobs",
           str(cfg["generate"]["jobs"]), "--quiet"] + world_args(cfg)
    r = subprocess.run(cmd, stdout=log, stderr=log)
    if r.returncode != 0:
        raise RuntimeError("hameritt_generate exited %d" % r.returncode)
    man = load_json(os.path.join(work, "scenarios", "manifest.json"))
    return {"scenarios": [{"index": s["index"], "id": s["id"], "class": s["class"],
                           "seed": s["seed"]} for s in man["scenarios"]]}


def filter_cameras(sim_config, cameras):
    """The sim_config with only the named payload cameras (cameras: 'all' or a list)."""
    if cameras == "all":
        return sim_config
    have = [c["name"] for c in sim_config["uav"]["payload"]["cameras"]]
    missing = [c for c in cameras if c not in have]
    if missing:
        raise CampaignError("missions.cameras: %s not in the scenario's cameras (%s)"
                            % (", ".join(missing), ", ".join(have)))
    out = json.loads(json.dumps(sim_config))
    out["uav"]["payload"]["cameras"] = [c for c in out["uav"]["payload"]["cameras"]
                                        if c["name"] in cameras]
    return out


def stop_group(proc, grace=15.0):
    """SIGINT to the process group (roslaunch shuts its nodes down), SIGKILL after `grace`."""
    for sig, wait in ((signal.SIGINT, grace), (signal.SIGKILL, 5.0)):
        try:
            os.killpg(proc.pid, sig)
        except ProcessLookupError:
            return
        try:
            proc.wait(timeout=wait)
            # The leader is gone; its nodes may linger a moment: SIGKILL the rest.
            os.killpg(proc.pid, signal.SIGKILL)
            return
        except subprocess.TimeoutExpired:
            continue
        except ProcessLookupError:
            return


def run_process_group(cmd, out, env, timeout, grace=15.0):
    """Runs cmd in its own process group; returns its exit code, or None when it ran past
    `timeout` seconds. On a timeout or an exception (SIGTERM, Ctrl-C) the whole group is
    stopped (SIGINT, SIGKILL after `grace` s), so that no ROS node outlives its unit."""
    proc = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT, env=env,
                            start_new_session=True)
    try:
        return proc.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        stop_group(proc, grace)
        return None
    except BaseException:
        stop_group(proc, min(grace, 5.0))
        raise


def run_mission_unit(cfg, unit, work, log, task_id, slot):
    m = cfg["missions"]
    scen_dir = os.path.join(work, "scenario")
    gen = os.path.join(work, "gen")
    # The scenario alone (--first INDEX --count 1): byte-identical to the batch's, no shared state.
    cmd = [os.path.join(tool_dir(), "hameritt_generate")] + source_args(cfg) + [
           "--count", "1", "--first", str(unit["scenario_index"]), "--seed", str(cfg["seed"]),
           "--out", gen, "--jobs", "1", "--quiet"] + world_args(cfg)
    r = subprocess.run(cmd, stdout=log, stderr=log)
    if r.returncode != 0:
        raise RuntimeError("hameritt_generate exited %d" % r.returncode)
    sid = load_json(os.path.join(gen, "manifest.json"))["scenarios"][0]["id"]
    os.rename(os.path.join(gen, sid), scen_dir)
    shutil.rmtree(gen)
    sim_cfg_path = os.path.join(scen_dir, "sim_config.json")
    if m["cameras"] != "all":
        sc = filter_cameras(load_json(sim_cfg_path), m["cameras"])
        sim_cfg_path = os.path.join(work, "sim_config_cameras.json")
        write_atomic(sim_cfg_path, json.dumps(sc, indent=2) + "\n")
    out = os.path.join(work, "output")
    os.makedirs(out)
    env = dict(os.environ)
    env["ROS_LOG_DIR"] = os.path.join(work, "ros_log")
    env["ROS_HOME"] = os.path.join(work, "ros_home")
    launch_log = os.path.join(out, "launch.log")
    for attempt in range(3):
        port = pick_port(task_id, slot + attempt)
        env["ROS_MASTER_URI"] = "http://localhost:%d" % port
        cmd = ["roslaunch", "-p", str(port), "hameritt", "mission.launch",
               "scenario:=" + scen_dir, "sim_config:=" + sim_cfg_path, "mode:=" + unit["mode"],
               "record:=" + ("true" if m["record"] else "false"),
               "record_all:=" + ("true" if m["record_all"] else "false"),
               "record_image_rate:=%g" % m["record_image_rate"],
               "time_limit:=%g" % m["time_limit"], "real_time_factor:=%g" % m["real_time_factor"],
               "output_dir:=" + out]
        log.write(("port %d: %s\n" % (port, " ".join(cmd))).encode())
        log.flush()
        with open(launch_log, "wb") as ll:
            rc = run_process_group(cmd, ll, env, m["timeout"])
        if rc is None:
            raise RuntimeError("roslaunch ran past missions.timeout (%g s); its process group "
                               "was stopped" % m["timeout"])
        with open(launch_log, "rb") as ll:
            text = ll.read()
        if rc != 0 and b"Address already in use" in text:
            continue  # another process took the port between the bind test and the launch
        break
    if rc != 0:
        raise RuntimeError("roslaunch exited %d (log: %s)" % (rc, launch_log))
    metrics_path = os.path.join(out, "metrics.json")
    if not os.path.exists(metrics_path):
        raise RuntimeError("the mission wrote no metrics.json")
    if m["record"] and not os.path.exists(os.path.join(out, "mission.bag")):
        raise RuntimeError("record is on but there is no mission.bag")
    metrics = load_json(metrics_path)
    return {"scenario_id": sid, "port": port, "metrics": metrics}


def run_shard(cdir, shard, task_id=None, job=""):
    """Runs the units of one shard that are not complete yet. Returns the number of units
    that failed."""
    cdir = os.path.abspath(cdir)
    plan = load_plan(cdir)
    cfg = plan["config"]
    if not 0 <= shard < cfg["shards"]:
        raise CampaignError("--shard: expected 0 to %d, got %d" % (cfg["shards"] - 1, shard))
    mine = [u for u in plan["units"] if u["shard"] == shard]
    host = socket.gethostname()
    tag = "%s@%d" % (host, os.getpid())
    task_id = shard if task_id is None else task_id
    logdir = os.path.join(cdir, "shards", str(shard))
    os.makedirs(logdir, exist_ok=True)
    os.makedirs(os.path.join(cdir, "units", ".work"), exist_ok=True)
    for name in clean_stale_work(cdir, {u["id"] for u in mine}):
        print("shard %d: removed the stale work directory %s" % (shard, name), flush=True)
    failed = 0
    for slot, unit in enumerate(mine):
        final, work = unit_paths(cdir, unit["id"], tag)
        if os.path.isdir(final):
            print("shard %d: %s already complete" % (shard, unit["id"]), flush=True)
            continue
        shutil.rmtree(work, ignore_errors=True)
        os.makedirs(work)
        t0 = time.time()
        print("shard %d: %s started" % (shard, unit["id"]), flush=True)
        log_path = os.path.join(logdir, unit["id"] + ".log")
        try:
            with open(log_path, "ab") as log:
                if unit["kind"] == "generate":
                    result = run_generate_unit(cfg, unit, work, log)
                else:
                    result = run_mission_unit(cfg, unit, work, log, task_id, slot)
        except (RuntimeError, OSError, ValueError, KeyError, CampaignError) as e:
            failed += 1
            print("shard %d: %s FAILED: %s (log %s; work dir kept: %s)"
                  % (shard, unit["id"], e, log_path, work), flush=True)
            continue
        record = {"unit": unit, "result": result, "host": host, "job": job, "shard": shard,
                  "wall_time": round(time.time() - t0, 3),
                  "finished": datetime.datetime.utcnow().strftime("%Y-%m-%dT%H:%M:%SZ")}
        done = finish_unit(work, final, record)
        print("shard %d: %s %s in %.1f s" % (shard, unit["id"], "complete" if done else
                                             "already completed by another run; ours dropped",
                                             time.time() - t0), flush=True)
    return failed


def _exit_on_sigterm(signum, frame):
    raise SystemExit(128 + signum)


def cmd_run_shard(args):
    # Slurm ends a task (scancel, time limit, requeue) with SIGTERM: stop the unit's ROS graph.
    signal.signal(signal.SIGTERM, _exit_on_sigterm)
    task = os.environ.get("SLURM_ARRAY_TASK_ID")
    shard = args.shard if args.shard is not None else (int(task) if task else None)
    if shard is None:
        raise CampaignError("--shard is required outside a Slurm array task")
    job = ""
    if os.environ.get("SLURM_ARRAY_JOB_ID"):
        job = "%s_%s" % (os.environ["SLURM_ARRAY_JOB_ID"], task)
    return 1 if run_shard(args.dir, shard, int(task) if task else shard, job) else 0


def cmd_run(args):
    if not args.local:
        raise CampaignError("run: --local is required (on a cluster: submit --slurm)")
    plan = load_plan(args.dir)
    n = plan["config"]["shards"]
    shards = args.shard if args.shard else list(range(n))
    for s in shards:
        if not 0 <= s < n:
            raise CampaignError("--shard: expected 0 to %d, got %d" % (n - 1, s))
    # Each shard is its own process, as on the cluster: J at a time.
    me = os.path.realpath(__file__)
    pending, running, failed = list(shards), [], 0
    while pending or running:
        while pending and len(running) < args.jobs:
            s = pending.pop(0)
            logf = open(os.path.join(args.dir, "shard-%d.local.log" % s), "w")
            running.append((s, subprocess.Popen([sys.executable, me, "run-shard", args.dir,
                                                 "--shard", str(s)], stdout=logf,
                                                stderr=subprocess.STDOUT), logf))
        time.sleep(0.1)
        for item in list(running):
            s, p, logf = item
            if p.poll() is not None:
                logf.close()
                running.remove(item)
                if p.returncode != 0:
                    failed += 1
                    print("shard %d failed (exit %d; log %s)" % (s, p.returncode, logf.name))
    st = campaign_status(args.dir)
    print("hameritt_campaign: %d of %d units complete" % (st["complete"], st["total"]))
    return 1 if failed or st["missing"] else 0


# ---------------------------------------------------------------------------- status


def campaign_status(cdir):
    plan = load_plan(cdir)
    done, missing, in_progress = [], [], []
    work = os.path.join(cdir, "units", ".work")
    busy = {n.partition("@")[0] for n in os.listdir(work)} if os.path.isdir(work) else set()
    for u in plan["units"]:
        if os.path.isfile(os.path.join(cdir, "units", u["id"], "unit.json")):
            done.append(u["id"])
        else:
            missing.append(u["id"])
            if u["id"] in busy:
                in_progress.append(u["id"])
    shards_missing = sorted({u["shard"] for u in plan["units"] if u["id"] in set(missing)})
    return {"total": len(plan["units"]), "complete": len(done), "missing": missing,
            "work_dirs": in_progress, "shards_missing": shards_missing}


def slurm_jobs(cdir):
    path = os.path.join(cdir, "slurm", "jobs.json")
    if not os.path.exists(path):
        return []
    return load_json(path)


def queued_tasks(job_ids):
    """Array tasks of these jobs still in the Slurm queue: list of (jobid_task, state)."""
    if not job_ids or not shutil.which("squeue"):
        return []
    r = subprocess.run(["squeue", "-h", "-r", "-j", ",".join(job_ids), "-o", "%i %T"],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
    if r.returncode != 0:
        return []  # jobs that left the queue long ago make squeue complain
    return [tuple(l.split()) for l in r.stdout.splitlines() if l.strip()]


def cmd_status(args):
    jobs = [j["job_id"] for j in slurm_jobs(args.dir)]
    deadline = time.time() + (args.wait if args.wait else 0)
    queued = queued_tasks(jobs)
    while args.wait and queued and time.time() < deadline:
        time.sleep(1)
        queued = queued_tasks(jobs)
    st = campaign_status(args.dir)
    st["slurm_jobs"] = jobs
    st["slurm_queued"] = [" ".join(q) for q in queued]
    if args.json:
        print(dump_json(st), end="")
    else:
        print("units: %d of %d complete" % (st["complete"], st["total"]))
        for uid in st["missing"]:
            print("  missing: %s%s" % (uid, " (work dir present)" if uid in st["work_dirs"]
                                       else ""))
        if jobs:
            print("slurm jobs: %s; in the queue: %s" % (", ".join(jobs), ", ".join(
                st["slurm_queued"]) or "none"))
    if args.wait and queued:
        return 1
    return 3 if st["missing"] else 0


# ---------------------------------------------------------------------------- slurm


def array_spec(tasks):
    """Slurm's --array list of task ids, runs of consecutive ids as ranges: 0-3,7,9-10."""
    parts, run = [], []
    for t in sorted(tasks):
        if run and t != run[-1] + 1:
            parts.append(str(run[0]) if len(run) == 1 else "%d-%d" % (run[0], run[-1]))
            run = []
        run.append(t)
    if run:
        parts.append(str(run[0]) if len(run) == 1 else "%d-%d" % (run[0], run[-1]))
    return ",".join(parts)


def sbatch_script(cdir, cfg, tasks):
    """The sbatch script of a job array over the shards `tasks` (array task id = shard)."""
    cdir = os.path.abspath(cdir)
    s = cfg["slurm"]
    spec = array_spec(tasks)
    if s["max_parallel"]:
        spec += "%%%d" % s["max_parallel"]
    lines = ["#!/bin/bash",
             "# hameritt_campaign: one array task per shard; a task runs the units of its shard",
             "# that are not complete yet, so a requeued or resubmitted task redoes no work.",
             "#SBATCH --job-name=hameritt-%s" % cfg["name"],
             "#SBATCH --array=%s" % spec,
             "#SBATCH --cpus-per-task=%d" % s["cpus_per_task"],
             "#SBATCH --mem=%s" % s["mem"],
             "#SBATCH --time=%s" % s["time"],
             "#SBATCH --requeue",
             "#SBATCH --output=%s/slurm/%%A_%%a.out" % cdir,
             "#SBATCH --chdir=%s" % cdir]
    if s["partition"]:
        lines.append("#SBATCH --partition=%s" % s["partition"])
    lines += ["#SBATCH %s" % x for x in s["extra"]]
    setup = ""
    for d in os.environ.get("CMAKE_PREFIX_PATH", "").split(":"):
        if d and os.path.isfile(os.path.join(d, "setup.bash")):
            setup = os.path.join(d, "setup.bash")
            break
    if setup:
        lines.append("source %s" % setup)
    lines.append("exec /usr/bin/python3 %s run-shard %s --shard \"$SLURM_ARRAY_TASK_ID\""
                 % (os.path.realpath(__file__), cdir))
    return "\n".join(lines) + "\n"


def cmd_submit(args):
    if not args.slurm:
        raise CampaignError("submit: --slurm is required")
    plan = load_plan(args.dir)
    cfg = plan["config"]
    if args.resubmit_missing:
        st = campaign_status(args.dir)
        queued = queued_tasks([j["job_id"] for j in slurm_jobs(args.dir)])
        if queued:
            raise CampaignError("tasks of this campaign are still queued or running (%s); "
                                "wait for them (status --wait) before resubmitting"
                                % ", ".join(" ".join(q) for q in queued))
        tasks = st["shards_missing"]
        if not tasks:
            print("hameritt_campaign: nothing missing; nothing submitted")
            return 0
    else:
        tasks = list(range(cfg["shards"]))
    sdir = os.path.join(args.dir, "slurm")
    os.makedirs(sdir, exist_ok=True)
    jobs = slurm_jobs(args.dir)
    script = os.path.join(sdir, "campaign-%d.sbatch" % len(jobs))
    write_atomic(script, sbatch_script(args.dir, cfg, tasks))
    if args.dry_run:
        print(script)
        return 0
    if not shutil.which("sbatch"):
        raise CampaignError("sbatch not found: submit needs a Slurm client")
    r = subprocess.run(["sbatch", "--parsable", script], stdout=subprocess.PIPE,
                       stderr=subprocess.PIPE, universal_newlines=True)
    if r.returncode != 0:
        print("hameritt_campaign: sbatch failed: %s" % r.stderr.strip(), file=sys.stderr)
        return 1
    job_id = r.stdout.strip().split(";")[0]
    jobs.append({"job_id": job_id, "shards": tasks, "script": os.path.basename(script)})
    write_atomic(os.path.join(sdir, "jobs.json"), dump_json(jobs))
    print("hameritt_campaign: submitted job %s, array %s (%d tasks); output %s/%s_<task>.out"
          % (job_id, ",".join(map(str, tasks)), len(tasks), sdir, job_id))
    return 0


# ---------------------------------------------------------------------------- merge


def sha256_file(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def mission_entry(unit, result, cdir, record):
    m = result["metrics"]
    koz = m.get("keep_out_zones", {})
    out = os.path.join("units", unit["id"], "output")
    bag = os.path.join(out, "mission.bag")
    bag_abs = os.path.join(cdir, bag)
    det = m.get("detections", {})
    flight = m.get("flight", {})
    return {
        "unit": unit["id"], "scenario_index": unit["scenario_index"],
        "scenario_id": result["scenario_id"], "class": unit["class"], "mode": unit["mode"],
        "outcome": m.get("outcome"), "reason": m.get("reason"), "end_time": m.get("end_time"),
        "time_limit": m.get("time_limit"),
        "time_to_first_correct_detection": m.get("time_to_first_correct_detection"),
        "time_to_all_targets_found": m.get("time_to_all_targets_found"),
        "targets": len(m.get("targets", [])),
        "targets_found": sum(1 for t in m.get("targets", []) if t.get("found")),
        "detections": det,
        "koz_violation_count": koz.get("violation_count"),
        "koz_violation_duration": koz.get("violation_duration"),
        "path_length": flight.get("path_length"), "energy": flight.get("energy"),
        "coverage": m.get("coverage", {}).get("prior_weighted"),
        "metrics_path": os.path.join(out, "metrics.json"),
        "bag_path": bag if os.path.exists(bag_abs) else None,
        "bag_size": os.path.getsize(bag_abs) if os.path.exists(bag_abs) else None,
        "shard": record["shard"], "host": record["host"], "job": record["job"],
        "wall_time": record["wall_time"], "finished": record["finished"],
    }


def summarize(cfg, missions):
    """Success rate per class and mode, mean time to the first correct detection, keep-out
    violations: computed from the mission entries."""
    groups = {}
    for e in missions:
        groups.setdefault((e["class"], e["mode"]), []).append(e)
    per = []
    for (cls, mode) in sorted(groups):
        es = groups[(cls, mode)]
        ttd = [e["time_to_first_correct_detection"] for e in es
               if e["time_to_first_correct_detection"] is not None]
        per.append({"class": cls, "mode": mode, "missions": len(es),
                    "successes": sum(1 for e in es if e["outcome"] == "success"),
                    "success_rate": round(sum(1 for e in es if e["outcome"] == "success")
                                          / float(len(es)), 6),
                    "mean_time_to_detect": round(sum(ttd) / len(ttd), 6) if ttd else None,
                    "detected": len(ttd),
                    "koz_violations": sum(e["koz_violation_count"] or 0 for e in es),
                    "missions_with_koz_violations": sum(1 for e in es
                                                        if (e["koz_violation_count"] or 0) > 0)})
    ttd = [e["time_to_first_correct_detection"] for e in missions
           if e["time_to_first_correct_detection"] is not None]
    outcomes = {}
    for e in missions:
        outcomes[e["outcome"]] = outcomes.get(e["outcome"], 0) + 1
    return {"missions": len(missions), "outcomes": outcomes,
            "success_rate": round(sum(1 for e in missions if e["outcome"] == "success")
                                  / float(len(missions)), 6) if missions else None,
            "mean_time_to_detect": round(sum(ttd) / len(ttd), 6) if ttd else None,
            "koz_violations": sum(e["koz_violation_count"] or 0 for e in missions),
            "bag_bytes": sum(e["bag_size"] or 0 for e in missions),
            "by_class_and_mode": per}


def merge(cdir):
    """Builds DIR/merged (scenarios/, world.json, manifest.json) from the complete units.
    Raises CampaignError when units are missing."""
    plan = load_plan(cdir)
    cfg = plan["config"]
    st = campaign_status(cdir)
    if st["missing"]:
        raise CampaignError("%d units missing (%s); run them first (status lists them)"
                            % (len(st["missing"]), ", ".join(st["missing"][:5])))
    merged = os.path.join(cdir, "merged")
    tmp = merged + ".tmp.%d" % os.getpid()
    shutil.rmtree(tmp, ignore_errors=True)
    os.makedirs(os.path.join(tmp, "scenarios"))
    scenarios, missions, world, shards, hosts, jobs, wall = [], [], None, set(), set(), set(), 0.0
    for u in sorted(plan["units"], key=lambda u: u["id"]):
        udir = os.path.join(cdir, "units", u["id"])
        rec = load_json(os.path.join(udir, "unit.json"))
        if rec["unit"] != u:
            raise CampaignError("%s/unit.json: the unit differs from plan.json's" % udir)
        shards.add(rec["shard"])
        hosts.add(rec["host"])
        if rec["job"]:
            jobs.add(rec["job"])
        wall += rec["wall_time"]
        if u["kind"] == "generate":
            src = os.path.join(udir, "scenarios")
            w = os.path.join(src, "world.json")
            if world is None:
                shutil.copyfile(w, os.path.join(tmp, "world.json"))
                world = sha256_file(w)
            elif sha256_file(w) != world:
                raise CampaignError("%s: world.json differs between units" % src)
            for s in rec["result"]["scenarios"]:
                dst = os.path.join(tmp, "scenarios", s["id"])
                os.makedirs(dst)
                files = {}
                for name in ("mission.json", "sim_config.json"):
                    shutil.copyfile(os.path.join(src, s["id"], name), os.path.join(dst, name))
                    files[name] = sha256_file(os.path.join(dst, name))
                scenarios.append(dict(s, path=os.path.join("scenarios", s["id"]),
                                      sha256=files))
        else:
            missions.append(mission_entry(u, rec["result"], cdir, rec))
    scenarios.sort(key=lambda s: s["index"])
    idx = [s["index"] for s in scenarios]
    if idx != list(range(cfg["count"])):
        raise CampaignError("scenario indices are not exactly 0..%d (duplicates or gaps)"
                            % (cfg["count"] - 1))
    by_index = {s["index"]: s["id"] for s in scenarios}
    for e in missions:
        if by_index[e["scenario_index"]] != e["scenario_id"]:
            raise CampaignError("%s: ran scenario %s but index %d is %s"
                                % (e["unit"], e["scenario_id"], e["scenario_index"],
                                   by_index[e["scenario_index"]]))
    missions.sort(key=lambda e: (e["scenario_index"], MODES.index(e["mode"])))
    campaign = {k: cfg[k] for k in ("name", "seed", "classes", "count", "spec") if k in cfg}
    campaign["missions"] = {k: v for k, v in cfg["missions"].items()}
    manifest = {
        "schema": SCHEMA_MANIFEST, "schema_version": SCHEMA_VERSION, "campaign": campaign,
        "world": {"file": "world.json", "sha256": world}, "scenarios": scenarios,
        "missions": missions, "summary": summarize(cfg, missions),
        "run": {"shards": cfg["shards"], "units": len(plan["units"]), "hosts": sorted(hosts),
                "jobs": sorted(jobs), "unit_wall_time": round(wall, 3),
                "merged": datetime.datetime.utcnow().strftime("%Y-%m-%dT%H:%M:%SZ")},
    }
    write_atomic(os.path.join(tmp, "manifest.json"), dump_json(manifest))
    old = merged + ".old.%d" % os.getpid()
    if os.path.exists(merged):
        os.rename(merged, old)
    os.rename(tmp, merged)
    shutil.rmtree(old, ignore_errors=True)
    return manifest


def cmd_merge(args):
    try:
        m = merge(args.dir)
    except CampaignError as e:
        if "units missing" in str(e):
            print("hameritt_campaign: error: %s" % e, file=sys.stderr)
            return 3
        raise
    s = m["summary"]
    print("hameritt_campaign: merged %d scenarios and %d missions -> %s" % (
        len(m["scenarios"]), len(m["missions"]), os.path.join(args.dir, "merged")))
    print(json.dumps({k: s[k] for k in ("missions", "outcomes", "success_rate",
                                        "mean_time_to_detect", "koz_violations")},
                     sort_keys=True))
    return 0


def compare_manifests(a, b, nondeterministic=RUN_DEPENDENT_MISSION_FIELDS):
    """Differences between two merged manifests, field by field, leaving out the run-specific
    fields (RUN_SPECIFIC_SECTIONS, RUN_SPECIFIC_UNIT_FIELDS) and, in missions, the fields named
    in `nondeterministic` (which still must be present and of the same type)."""
    diffs = []

    def walk(x, y, path):
        if isinstance(x, dict) and isinstance(y, dict):
            for k in sorted(set(x) | set(y)):
                if k not in x or k not in y:
                    diffs.append("%s.%s: only in %s" % (path, k, "first" if k in x else "second"))
                    continue
                if path == "" and k in RUN_SPECIFIC_SECTIONS:
                    continue
                in_mission = path.startswith(".missions[")
                if in_mission and path.count(".") == 1 and k in RUN_SPECIFIC_UNIT_FIELDS:
                    continue
                if in_mission and path.count(".") == 1 and k in nondeterministic:
                    if type(x[k]) is not type(y[k]) and None not in (x[k], y[k]):
                        diffs.append("%s.%s: types differ" % (path, k))
                    continue
                if path == ".summary" and k in RUN_DEPENDENT_SUMMARY_FIELDS:
                    continue
                walk(x[k], y[k], "%s.%s" % (path, k))
        elif isinstance(x, list) and isinstance(y, list):
            if len(x) != len(y):
                diffs.append("%s: %d vs %d items" % (path, len(x), len(y)))
            for i, (p, q) in enumerate(zip(x, y)):
                walk(p, q, "%s[%d]" % (path, i))
        elif x != y or type(x) is not type(y):
            diffs.append("%s: %r vs %r" % (path, x, y))

    walk(a, b, "")
    return diffs


def cmd_compare(args):
    ms = []
    for p in (args.a, args.b):
        ms.append(load_json(p, " a manifest"))
    nd = list(RUN_DEPENDENT_MISSION_FIELDS) + [x for x in args.nondeterministic.split(",") if x]
    diffs = compare_manifests(ms[0], ms[1], nd)
    for d in diffs:
        print(d)
    print("hameritt_campaign: %s" % ("manifests equal (run-specific fields aside)" if not diffs
                                     else "%d differences" % len(diffs)))
    return 1 if diffs else 0


# ---------------------------------------------------------------------------- main


FLAG = {"action": "store_true"}
# The subcommands: name, function, help, arguments (name, argparse keywords).
COMMANDS = [
    ("plan", "cmd_plan", "write DIR/plan.json from a config",
     [("config", {}), ("--out", {"required": True, "help": "campaign directory"})]),
    ("run", "cmd_run", "run shards on this machine",
     [("dir", {}), ("--local", FLAG),
      ("--jobs", {"type": int, "default": 1, "help": "shards at a time (default 1)"}),
      ("--shard", {"type": int, "action": "append", "help": "only this shard (repeatable)"})]),
    ("run-shard", "cmd_run_shard", "run one shard (what a Slurm array task runs)",
     [("dir", {}), ("--shard", {"type": int, "help": "default: $SLURM_ARRAY_TASK_ID"})]),
    ("submit", "cmd_submit", "submit a Slurm job array, one task per shard",
     [("dir", {}), ("--slurm", FLAG),
      ("--resubmit-missing", dict(FLAG, help="only the shards with incomplete units")),
      ("--dry-run", dict(FLAG, help="write the sbatch script only"))]),
    ("status", "cmd_status", "units complete and missing, Slurm tasks queued",
     [("dir", {}),
      ("--wait", {"type": float, "nargs": "?", "const": 86400.0, "default": 0.0,
                  "help": "first wait (at most SECONDS) until no task of the campaign is queued"}),
      ("--json", FLAG)]),
    ("merge", "cmd_merge", "one manifest over all shards in DIR/merged", [("dir", {})]),
    ("compare", "cmd_compare", "compare two merged manifests",
     [("a", {}), ("b", {}),
      ("--nondeterministic", {"default": "", "help": "more comma-separated mission fields to "
                              "check for presence only (always: %s)"
                              % ", ".join(RUN_DEPENDENT_MISSION_FIELDS)})]),
]


def main(argv=None):
    p = argparse.ArgumentParser(prog="hameritt_campaign", description=__doc__.split("\n")[0])
    sub = p.add_subparsers(dest="cmd")
    for name, _, help_text, arguments in COMMANDS:
        a = sub.add_parser(name, help=help_text)
        for arg, kw in arguments:
            a.add_argument(arg, **kw)
    args = p.parse_args(argv)
    if args.cmd is None:
        p.print_help()
        return 2
    if getattr(args, "jobs", 1) is not None and getattr(args, "jobs", 1) < 1:
        print("hameritt_campaign: error: --jobs: expected at least 1", file=sys.stderr)
        return 2
    # Absolute: ROS nodes run in ROS_HOME, not here.
    for k in ("dir", "out"):
        if getattr(args, k, None):
            setattr(args, k, os.path.abspath(getattr(args, k)))
    fn = globals()[{c[0]: c[1] for c in COMMANDS}[args.cmd]]
    try:
        return fn(args)
    except CampaignError as e:
        print("hameritt_campaign: error: %s" % e, file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
