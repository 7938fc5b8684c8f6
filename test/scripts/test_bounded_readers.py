#!/usr/bin/python3
"""Every JSON reader of the tools refuses a document beyond the limits of
include/hameritt/scenario/bounded_json.h (nesting deeper than 64 levels, a file larger than
64 MiB; 1 GiB for the dataset annotations read by hameritt_export --preview) with exit code 2
and a message naming the file and the limit, in little memory.

Inputs per reader: 100,000-deep nesting ("[[[...]]]", 200 KB) and an over-size file (sparse:
its size is known before reading). Each run's maximum resident set size comes from wait4()
(the kernel's own accounting of the child) and must stay under 100 MB. Control, per reader:
the same document at the limit's edge, 64 levels deep, is not refused for its depth (the
message names no limit), and 65 levels are - so the depth check is the one that fires, at the
stated limit, not another error.

Prints one line per reader and input; exits 1 on any failure.
"""

import os
import resource
import shutil
import subprocess
import sys
import tempfile

BIN = os.environ["HAMERITT_BIN_DIR"]
SRC = os.environ["HAMERITT_SOURCE_DIR"]
DEPTH_LIMIT = 64
MAX_RSS_KB = 100 * 1024

passed = failed = 0


def check(ok, what):
    global passed, failed
    if ok:
        passed += 1
    else:
        failed += 1
        print("FAIL:", what)


def run(cmd):
    """(exit code, stderr, maximum resident set size in KiB) of cmd."""
    err = tempfile.TemporaryFile()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=err)
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    err.seek(0)
    return proc.returncode, err.read().decode(errors="replace"), usage.ru_maxrss


def nested(depth):
    return "[" * depth + "]" * depth


def main():
    work = tempfile.mkdtemp(prefix="hameritt_bounded_")
    try:
        return cases(work)
    finally:
        shutil.rmtree(work)


def cases(work):
    tools = {
        # name: (command builder taking the path of the bad file, the file's role)
        "hameritt_validate": lambda f: [f"{BIN}/hameritt_validate", f],
        "hameritt_generate --world-config": lambda f: [
            f"{BIN}/hameritt_generate", "--class", "all", "--count", "1", "--seed", "1",
            "--out", f"{work}/gen_out", "--world-config", f],
        "hameritt_generate --generator-config": lambda f: [
            f"{BIN}/hameritt_generate", "--class", "all", "--count", "1", "--seed", "1",
            "--out", f"{work}/gen_out", "--generator-config", f],
        "hameritt_world": lambda f: [f"{BIN}/hameritt_world", "--world-config", f, "--out",
                                     f"{work}/world_out.json"],
        "hameritt_check_path": lambda f: [f"{BIN}/hameritt_check_path", "--mission", f,
                                          "--path", f"{work}/path.csv"],
        "hameritt_summary": lambda f: [f"{BIN}/hameritt_summary", scenario_dir(f)],
        "hameritt_map": lambda f: [f"{BIN}/hameritt_map", scenario_dir(f), "--out",
                                   f"{work}/map.png"],
        "hameritt_export --preview": lambda f: [f"{BIN}/hameritt_export", "--preview",
                                                coco_dir(f), "--image-id", "most", "--out",
                                                f"{work}/preview.png"],
        "hameritt_campaign compare": lambda f: [
            "/usr/bin/python3", f"{SRC}/src/tools/hameritt_campaign.py", "compare", f, f],
    }
    shown = {}  # the path a tool names for a file it reads through a directory

    big_limit = {"hameritt_export --preview": 1 << 30}
    with open(f"{work}/path.csv", "w") as out:
        out.write("t,x,y,z\n0,0,0,10\n")

    def scenario_dir(f):
        """A scenario directory whose mission.json is f (sim_config.json the shipped one)."""
        d = f + ".scenario"
        if not os.path.isdir(d):
            os.makedirs(d)
            os.symlink(f, f"{d}/mission.json")
            shown[f] = f"{d}/mission.json"
            shutil.copy(f"{SRC}/scenarios/default/sim_config.json", f"{d}/sim_config.json")
        return d

    def coco_dir(f):
        d = f + ".coco"
        if not os.path.isdir(d):
            os.makedirs(f"{d}/annotations")
            os.symlink(f, f"{d}/annotations/instances_train.json")
            shown[f] = f"{d}/annotations/instances_train.json"
        return d

    for name, cmd in tools.items():
        tag = name.replace(" ", "_").replace("-", "")
        files = {}
        for depth in (100000, DEPTH_LIMIT + 1, DEPTH_LIMIT):
            files[depth] = f"{work}/{tag}_deep{depth}.json"
            with open(files[depth], "w") as out:
                out.write(nested(depth))
        size_limit = big_limit.get(name, 64 << 20)
        huge = f"{work}/{tag}_huge.json"
        with open(huge, "w") as out:
            out.write("[")
            out.truncate(size_limit + 1)  # sparse: no disk, no time
        for label, f, limit_text in (("100000-deep", files[100000], f"limit of {DEPTH_LIMIT} levels"),
                                     (f"{DEPTH_LIMIT + 1}-deep", files[DEPTH_LIMIT + 1],
                                      f"limit of {DEPTH_LIMIT} levels"),
                                     ("over-size", huge, f"limit of {size_limit} bytes")):
            rc, err, rss = run(cmd(f))
            print(f"{name} {label}: exit {rc}, max RSS {rss / 1024:.1f} MB")
            check(rc == 2, f"{name} {label}: exit {rc}, expected 2: {err[-300:]}")
            named = shown.get(f, f)
            check(named in err and limit_text in err,
                  f"{name} {label}: message does not name {named} and '{limit_text}': {err[-300:]}")
            check(rss < MAX_RSS_KB, f"{name} {label}: {rss} KiB resident, limit {MAX_RSS_KB}")
        # Control: at the limit the depth check lets the document through to the reader's own
        # checks (which refuse an array where they expect an object, or accept it).
        rc, err, rss = run(cmd(files[DEPTH_LIMIT]))
        print(f"{name} {DEPTH_LIMIT}-deep (control): exit {rc}")
        check("limit of" not in err, f"{name} {DEPTH_LIMIT}-deep was refused for a limit: {err[-300:]}")
    print(f"{len(tools)} readers; {passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
