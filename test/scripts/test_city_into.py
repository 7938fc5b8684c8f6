#!/usr/bin/python3
"""A single city scenario written with hameritt_generate --into carries its ambient traffic by
reference, like a batch: DIR holds mission.json, sim_config.json and the one traffic episode file
that its "traffic" reference names (no "../": the directory stands alone), and nothing else.
Judged with Python's json and hashlib: the reference's SHA-256 is the file's, its car and
pedestrian ids are the episode's counts, sim_config.json is small (no inline keyframes of the
traffic cars), and hameritt_validate accepts DIR/sim_config.json. Negative controls: with the
episode file moved away and with one byte of it changed, hameritt_validate exits 2 naming the
traffic reference. Prints the figures; "N passed, N failed"; exits 1 on any failure.
"""

import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile

from tool_checks import BIN, ENV, SRC, check, counts, run  # noqa: E402


def main():
    with tempfile.TemporaryDirectory(prefix="hameritt_into_") as tmp:
        d = os.path.join(tmp, "one")
        r = run("hameritt_generate", "--world", "city", "--class", "route_search", "--seed", "3",
                "--into", d, "--quiet")
        check(r.returncode == 0, "generate --world city --into", r.stderr)
        files = sorted(os.listdir(d)) if os.path.isdir(d) else []
        episodes = [f for f in files if f.startswith("traffic_episode_")]
        check(len(episodes) == 1 and sorted(set(files) - set(episodes)) ==
              ["mission.json", "sim_config.json"], "DIR holds the two documents and one episode",
              str(files))
        check(sorted(os.listdir(tmp)) == ["one"], "nothing written beside DIR",
              str(os.listdir(tmp)))
        if len(episodes) != 1:
            return
        sim_path = os.path.join(d, "sim_config.json")
        ep_path = os.path.join(d, episodes[0])
        with open(sim_path) as f:
            sim = json.load(f)
        ref = sim.get("traffic", {})
        check(ref.get("file") == episodes[0], "the reference names the file in DIR",
              str(ref.get("file")))
        with open(ep_path, "rb") as f:
            good = f.read()
        check(hashlib.sha256(good).hexdigest() == ref.get("sha256"), "SHA-256 of the episode")
        ep = json.loads(good)
        check(len(ref.get("cars", [])) == len(ep["cars"]) > 0 and
              len(ref.get("pedestrians", [])) == len(ep["pedestrians"]) > 0,
              "a car and a pedestrian id for each of the episode's",
              "%d/%d cars, %d/%d pedestrians" % (len(ref.get("cars", [])), len(ep["cars"]),
                                                 len(ref.get("pedestrians", [])),
                                                 len(ep["pedestrians"])))
        traffic_inline = sum(1 for e in sim["entities"] if e["role"] == "traffic")
        check(traffic_inline == 0, "no traffic car inline", str(traffic_inline))
        size = os.path.getsize(sim_path)
        check(size < 200_000, "sim_config.json under 200 KB", str(size))
        r = run("hameritt_validate", sim_path)
        check(r.returncode == 0, "hameritt_validate accepts DIR/sim_config.json", r.stderr)
        print("--into: sim_config.json %d bytes, %s %d bytes (%d cars, %d pedestrians)"
              % (size, episodes[0], len(good), len(ep["cars"]), len(ep["pedestrians"])))

        # Negative controls: the episode file moved away, then one byte of it changed.
        moved = os.path.join(tmp, episodes[0])
        shutil.move(ep_path, moved)
        r = run("hameritt_validate", sim_path)
        check(r.returncode == 2 and "traffic" in r.stderr,
              "control: hameritt_validate refuses a missing episode file", r.stderr[-300:])
        bad = bytearray(good)
        k = len(bad) // 2
        bad[k] = ord("1") if bad[k] != ord("1") else ord("2")
        with open(ep_path, "wb") as f:
            f.write(bytes(bad))
        r = run("hameritt_validate", sim_path)
        check(r.returncode == 2 and "traffic.sha256" in r.stderr,
              "control: hameritt_validate refuses a changed episode file", r.stderr[-300:])
    print(counts.summary())
    sys.exit(1 if counts.failed else 0)


if __name__ == "__main__":
    main()
