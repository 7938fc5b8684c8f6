#!/usr/bin/env python3
"""Benchmark of a whole mission: simulator with both payload cameras rendering every modality,
ADK, planner, baseline clients and rosbag recording, on the default scenario (or --scenario DIR).

Runs `roslaunch hameritt mission.launch` for --sim-seconds of sim time (the ADK's time limit),
measures the wall time from the first to the last message in the bag, and checks the bag:
every camera topic must hold one message per camera period (no drops) and rosbag must not have
reported a dropped message. Prints the real-time factor, per-topic counts and the simulator's
peak resident memory.

  /usr/bin/python3 bench/bench_mission.py [--sim-seconds 60] [--real-time-factor 0]
      [--record-all] [--record-png] [--record-depth 16UC1|32FC1] [--record-rgb-noise]
      [--compression lz4|bz2] [--mode end_to_end] [--lockstep [--lockstep-period 0.02]]
      [--out DIR]

With --lockstep the mission runs in lock-step (docs/explanation/lockstep.md; the simulator stops
at --sim-seconds) and the real-time factor is the lock-step loop's.

Also prints the bag's MB per sim second and its bytes per topic group (uncompressed), so that
the recording's size can be traced to its streams.
"""
import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time


def processes():
    """(pid, argv) of every process readable now (argv as bytes)."""
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        try:
            with open("/proc/%s/cmdline" % pid, "rb") as f:
                yield pid, f.read().split(b"\0")
        except OSError:
            pass


def sample_recorder_cpu(seen, out):
    """CPU seconds (user + system) so far of the rosbag recorder writing into `out`, by pid."""
    tick = os.sysconf("SC_CLK_TCK")
    for pid, argv in processes():
        if not argv[0].endswith(b"rosbag/record") or not any(out.encode() in a for a in argv):
            continue
        try:
            with open("/proc/%s/stat" % pid) as f:
                fields = f.read().rsplit(")", 1)[1].split()
            seen[pid] = (int(fields[11]) + int(fields[12])) / tick
        except (OSError, IndexError, ValueError):
            pass


def sample_simulator_rss(peak):
    """The simulator node's peak resident set so far (VmHWM, MB) into peak[0]."""
    for pid, argv in processes():
        if not argv[0].endswith(b"hameritt/simulator"):
            continue
        try:
            with open("/proc/%s/status" % pid) as f:
                for line in f:
                    if line.startswith("VmHWM:"):
                        peak[0] = max(peak[0], int(line.split()[1]) / 1024.0)
        except (OSError, IndexError, ValueError):
            pass


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenario", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenarios", "default"))
    ap.add_argument("--sim-seconds", type=float, default=60.0)
    ap.add_argument("--real-time-factor", type=float, default=0.0, help="0 = as fast as possible")
    ap.add_argument("--record-all", action="store_true")
    ap.add_argument("--record-png", action="store_true", help="PNG CompressedImage compact stream")
    ap.add_argument("--record-depth", default="16UC1", choices=["16UC1", "32FC1"])
    ap.add_argument("--record-rgb-noise", action="store_true", help="compact colour image with noise")
    ap.add_argument("--compression", default="lz4", choices=["lz4", "bz2"])
    ap.add_argument("--mode", default="end_to_end")
    ap.add_argument("--lockstep", action="store_true", help="run the mission in lock-step")
    ap.add_argument("--lockstep-period", type=float, default=0.02)
    ap.add_argument("--out", default="")
    args = ap.parse_args()

    out = args.out or tempfile.mkdtemp(prefix="hameritt_bench_mission_")
    os.makedirs(out, exist_ok=True)
    port = 11500 + os.getpid() % 400
    env = dict(os.environ, ROS_MASTER_URI="http://localhost:%d" % port)
    cmd = ["roslaunch", "-p", str(port), "hameritt", "mission.launch",
           "scenario:=" + os.path.abspath(args.scenario), "mode:=" + args.mode, "record:=true",
           "record_all:=" + ("true" if args.record_all else "false"),
           "record_png:=" + ("true" if args.record_png else "false"),
           "record_depth:=" + args.record_depth,
           "record_rgb_noise:=" + ("true" if args.record_rgb_noise else "false"),
           "real_time_factor:=%g" % args.real_time_factor, "time_limit:=%g" % args.sim_seconds,
           "record_compression:=" + args.compression, "output_dir:=" + out]
    if args.lockstep:
        cmd += ["lockstep:=true", "lockstep_period:=%g" % args.lockstep_period,
                "duration:=%g" % args.sim_seconds]
    log_path = os.path.join(out, "roslaunch.log")
    t0 = time.time()
    recorder = {}
    sim_rss = [0.0]
    with open(log_path, "w") as log:
        proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, env=env)
        while proc.poll() is None and time.time() - t0 < max(600.0, 20 * args.sim_seconds):
            sample_recorder_cpu(recorder, out)
            sample_simulator_rss(sim_rss)
            time.sleep(0.5)
        if proc.poll() is None:
            proc.kill()
        rc = proc.wait()
    wall_total = time.time() - t0
    log_text = open(log_path).read()
    bag_path = os.path.join(out, "mission.bag")
    if not os.path.exists(bag_path):
        print("no bag written; see", log_path)
        return 1

    import rosbag  # noqa: E402  (python3-rosbag)
    bag = rosbag.Bag(bag_path)
    info = bag.get_type_and_topic_info()
    counts = {t: v.message_count for t, v in info.topics.items()}
    # Uncompressed bytes per topic group (images per modality, everything else together).
    group_bytes = {}
    for topic, raw, _ in bag.read_messages(raw=True):
        parts = topic.split("/")
        group = "/".join(parts[4:]) if "/decimated/" in topic else ("full-rate " + parts[4] if len(parts) == 5 and parts[4] in ("image_raw", "depth", "segmentation", "instances") else "other topics")
        group_bytes[group] = group_bytes.get(group, 0) + len(raw[1])
    # Sim-time span covered by the camera boxes (one per frame).
    bag.close()
    metrics = {}
    mpath = os.path.join(out, "metrics.json")
    if os.path.exists(mpath):
        metrics = json.load(open(mpath))
    sim_seconds = metrics.get("end_time", args.sim_seconds)

    with open(os.path.join(args.scenario, "sim_config.json")) as f:
        cfg = json.load(f)
    expected = {}
    decim_rate = 2.0
    for cam in cfg["uav"]["payload"]["cameras"]:
        n = int(math.floor(sim_seconds * cam["rate_hz"] + 1e-9))
        base = "/uav/camera/%s/" % cam["name"]
        expected[base + "boxes"] = n
        expected[base + "camera_info"] = n
        mods = {"rgb": "image_raw", "depth": "depth", "segmentation": "segmentation", "instances": "instances"}
        for m in cam["modalities"]:
            if args.record_all:
                expected[base + mods[m]] = n
            else:
                png = args.record_png and not (m == "depth" and args.record_depth == "32FC1")
                topic = base + "decimated/" + mods[m] + ("/compressed" if png else "")
                expected[topic] = int(math.floor(sim_seconds * decim_rate + 1e-9))
    dropped_log = len(re.findall(r"Dropping", log_text))
    missing = {t: (e, counts.get(t, 0)) for t, e in expected.items() if counts.get(t, 0) < e}
    # The simulator logs sim time against wall time since its clock started, every 10 sim s.
    m = re.findall(r"simulator: (?:lock-step cycle \d+: )?sim ([0-9.]+) s in wall ([0-9.]+) s",
                   log_text)
    # In lock-step: once the simulator stops at the duration.
    m += re.findall(r"lock-step: stopped at the duration, sim ([0-9.]+) s, cycle \d+, in wall ([0-9.]+) s",
                    log_text)
    rt_sim, rt_wall = (float(m[-1][0]), float(m[-1][1])) if m else (sim_seconds, wall_total)
    size_mb = os.path.getsize(bag_path) / 1e6
    print("scenario:      %s (mode %s%s, %s recording%s)" % (cfg["scenario_id"], args.mode, ", lock-step %g s" % args.lockstep_period if args.lockstep else "", "full" if args.record_all else "compact", "" if args.record_all else ", depth %s, colour %s%s, %s chunks" % (args.record_depth, "noisy" if args.record_rgb_noise else "noise-free", ", PNG" if args.record_png else "", args.compression)))
    print("sim time:      %.1f s; simulator clock: %.1f sim s in %.1f wall s -> real-time factor %.2fx (launch total %.1f s wall)" % (sim_seconds, rt_sim, rt_wall, rt_sim / max(rt_wall, 1e-9), wall_total))
    print("bag:           %.1f MB (%.2f MB per sim second), %d topics" % (size_mb, size_mb / max(sim_seconds, 1e-9), len(counts)))
    print("rosbag drops:  %d 'Dropping' warnings" % dropped_log)
    rec_cpu = sum(recorder.values())
    print("recorder CPU:  %.1f s (%.0f%% of one core over the simulator's %.1f wall s; last sample)" % (rec_cpu, 100.0 * rec_cpu / max(rt_wall, 1e-9), rt_wall))
    print("simulator RSS: %.0f MB peak (VmHWM, last sample)" % sim_rss[0])
    raw_total = sum(group_bytes.values())
    print("uncompressed:  %.1f MB (%.2f MB per sim second); on disk %.0f%% of it" % (raw_total / 1e6, raw_total / 1e6 / max(sim_seconds, 1e-9), 100.0 * size_mb * 1e6 / max(raw_total, 1)))
    for g in sorted(group_bytes, key=lambda g: -group_bytes[g]):
        print("  %-48s %8.2f MB per sim second uncompressed" % (g, group_bytes[g] / 1e6 / max(sim_seconds, 1e-9)))
    for t in sorted(expected):
        print("  %-48s %6d / %6d expected" % (t, counts.get(t, 0), expected[t]))
    for t in sorted(set(counts) - set(expected)):
        print("  %-48s %6d" % (t, counts[t]))
    print("outcome:       %s (roslaunch exit %d)" % (metrics.get("outcome", "?"), rc))
    print("dropped/missing camera messages: %d" % sum(e - c for e, c in missing.values()))
    print("summary:       %.2f MB per sim second, %.2fx real time, %d camera messages dropped" % (size_mb / max(sim_seconds, 1e-9), rt_sim / max(rt_wall, 1e-9), sum(e - c for e, c in missing.values()) + dropped_log))
    return 0 if not missing and dropped_log == 0 else 3


if __name__ == "__main__":
    sys.exit(main())
