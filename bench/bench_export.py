#!/usr/bin/env python3
"""Benchmark of the dataset export (hameritt_export): frame sets/s and images/s exported from a
recorded mission bag, per setting (threads, PNG level, JPEG RGB), with the peak memory.

A frame set is one camera frame: RGB, depth, segmentation and instances (4 images written) plus
its annotations. The bag is given (--bag) or recorded first (mission.launch record:=true,
--sim-seconds). It is passed --repeat times on one command line, so that a short bag makes a
long enough run; the best of --runs runs is reported. --cpus pins the exporter (taskset).

  /usr/bin/python3 bench/bench_export.py [--bag BAG | --sim-seconds 8] [--repeat 10] [--runs 3]
      [--cpus 0,1]
"""
import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time


def record(tmp, seconds):
    out = os.path.join(tmp, "mission")
    port = 11900 + os.getpid() % 90
    env = dict(os.environ, ROS_MASTER_URI="http://localhost:%d" % port)
    src = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    subprocess.run(["roslaunch", "-p", str(port), "hameritt", "mission.launch",
                    "scenario:=" + os.path.join(src, "scenarios", "default"), "record:=true",
                    "time_limit:=%g" % seconds, "real_time_factor:=0", "output_dir:=" + out],
                   env=env, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return os.path.join(out, "mission.bag")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bag", default="")
    ap.add_argument("--sim-seconds", type=float, default=8.0)
    ap.add_argument("--repeat", type=int, default=10)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--cpus", default="0,1", help="taskset CPU list ('' = no pinning)")
    ap.add_argument("--bin", default=os.environ.get("HAMERITT_BIN_DIR", ""))
    args = ap.parse_args()
    exe = os.path.join(args.bin, "hameritt_export") if args.bin else shutil.which("hameritt_export")
    if not exe or not os.path.exists(exe):
        sys.exit("bench_export: hameritt_export not found (set HAMERITT_BIN_DIR or --bin)")
    tmp = tempfile.mkdtemp(prefix="hameritt_bench_export_")
    try:
        bag = args.bag or record(tmp, args.sim_seconds)
        size_mb = os.path.getsize(bag) / 1e6
        print("bag %s: %.1f MB, passed %d times; load: %s" % (bag, size_mb, args.repeat,
                                                             open("/proc/loadavg").read().split()[:3]))
        settings = [("png fast, 2 jobs", ["--jobs", "2"]),
                    ("png fast, 1 job", ["--jobs", "1"]),
                    ("png level 6, 2 jobs", ["--jobs", "2", "--png-level", "6"]),
                    ("jpg RGB, 2 jobs", ["--jobs", "2", "--image-format", "jpg"])]
        pin = ["taskset", "-c", args.cpus] if args.cpus else []
        rows = []
        for name, flags in settings:
            best = None
            for _ in range(args.runs):
                out = os.path.join(tmp, "ds")
                shutil.rmtree(out, ignore_errors=True)
                before = resource.getrusage(resource.RUSAGE_CHILDREN)
                t0 = time.perf_counter()
                r = subprocess.run(pin + [exe] + [bag] * args.repeat +
                                   ["--format", "coco", "--out", out, "--quiet"] + flags,
                                   capture_output=True, text=True)
                wall = time.perf_counter() - t0
                after = resource.getrusage(resource.RUSAGE_CHILDREN)
                if r.returncode != 0:
                    sys.exit("bench_export: %s failed: %s" % (name, r.stderr))
                frames = int(r.stdout.split(" images")[0].split()[-1])
                cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
                mb = sum(os.path.getsize(os.path.join(d, f)) for d, _, fs in os.walk(out) for f in fs) / 1e6
                row = {"setting": name, "frame_sets": frames, "wall_s": round(wall, 3),
                       "cpu_s": round(cpu, 3), "frame_sets_per_s": round(frames / wall, 1),
                       "images_per_s": round(4 * frames / wall, 1),
                       "cpu_ms_per_frame_set": round(1000 * cpu / frames, 2),
                       "dataset_mb": round(mb, 1), "max_rss_mb": round(after.ru_maxrss / 1024, 1)}
                if best is None or row["wall_s"] < best["wall_s"]:
                    best = row
            rows.append(best)
            print("%-22s %6d frame sets %7.2f s wall %7.2f s cpu  %7.1f frame sets/s %7.1f images/s"
                  "  %6.2f cpu ms/set  %7.1f MB  peak RSS %6.1f MB" %
                  (name, best["frame_sets"], best["wall_s"], best["cpu_s"], best["frame_sets_per_s"],
                   best["images_per_s"], best["cpu_ms_per_frame_set"], best["dataset_mb"],
                   best["max_rss_mb"]))
        print(json.dumps(rows))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
