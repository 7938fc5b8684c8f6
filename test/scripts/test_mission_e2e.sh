#!/bin/bash
# End to end, as a user runs it: roslaunch mission.launch (simulator with both cameras rendering
# every modality, ADK, planner, baseline clients, rosbag recording) on the shipped scenario with
# a short time limit. The launch must end by itself (the ADK ends the mission), metrics.json
# must be complete, Python rosbag must read every training topic back at its rate (the compact
# image stream: every 0.5 s period, 16UC1 depth), `rosbag info` must agree and `rosbag play`
# must deliver every compact-stream image to a subscriber.
set -euo pipefail
export PATH="/usr/bin:/bin:$PATH"
src="${HAMERITT_SOURCE_DIR:?}"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
port=$((12000 + $$ % 2000))
export ROS_MASTER_URI="http://localhost:$port"
limit=20
echo "mission.launch: time_limit $limit s, record on, output $out"
if ! timeout 600 roslaunch -p "$port" hameritt mission.launch scenario:="$src/scenarios/default" \
     mode:=end_to_end record:=true time_limit:=$limit real_time_factor:=0 output_dir:="$out" \
     >"$out/launch.log" 2>&1; then
  echo "FAIL: roslaunch exited non-zero or timed out"; tail -60 "$out/launch.log"; exit 1
fi
grep -E "simulator: sim|adk|Dropping" "$out/launch.log" | tail -8 || true
/usr/bin/python3 - "$out" "$src" "$limit" <<'PY'
import json, math, os, sys
import rosbag
out, src, limit = sys.argv[1], sys.argv[2], float(sys.argv[3])
fails = []
m = json.load(open(os.path.join(out, "metrics.json")))
for key in ["scenario_id", "outcome", "end_time", "targets", "detections", "keep_out_zones", "flight",
            "coverage", "time_to_first_correct_detection"]:
    if key not in m:
        fails.append("metrics.json lacks %s" % key)
if m.get("outcome") not in ("success", "timeout"):
    fails.append("outcome %r" % m.get("outcome"))
flight = m.get("flight", {})
if flight.get("path_length", 0) <= 20.0 or flight.get("energy", 0) <= 0:
    fails.append("the UAV did not fly (flight %r)" % flight)
if m.get("keep_out_zones", {}).get("violation_count", -1) != 0:
    fails.append("keep-out violations: %r" % m.get("keep_out_zones"))
bag_path = os.path.join(out, "mission.bag")
if not os.path.exists(bag_path):
    fails.append("no mission.bag (left: %s)" % os.listdir(out))
else:
    bag = rosbag.Bag(bag_path)
    topics = {t: v.message_count for t, v in bag.get_type_and_topic_info().topics.items()}
    cfg = json.load(open(os.path.join(src, "scenarios/default/sim_config.json")))
    t_end = min(limit, m.get("end_time", limit))
    need = {"/uav/odom": 200 * t_end, "/tf": 200 * t_end, "/mission": 1, "/ground_truth/entities": 15 * t_end}
    for cam in cfg["uav"]["payload"]["cameras"]:
        n = math.floor(t_end * cam["rate_hz"] + 1e-9)
        b = "/uav/camera/%s/" % cam["name"]
        need[b + "boxes"] = n
        need[b + "camera_info"] = n
        for img in ["image_raw", "depth", "segmentation", "instances"]:
            need[b + "decimated/" + img] = math.floor(t_end * 2 + 1e-9)
    for t, n in sorted(need.items()):
        got = topics.get(t, 0)
        print("  %-44s %6d (need %d)" % (t, got, n))
        if got < n:
            fails.append("%s: %d messages, expected %d" % (t, got, n))
    # The compact stream: every camera message of every period (one per 0.5 s of sim time, no
    # gap, no duplicate stamp), each image of the advertised size and encoding (depth 16UC1
    # millimetres by default; the codecs themselves: test_mission_record_codec.sh).
    encodings = {"image_raw": ("rgb8", 3), "depth": ("16UC1", 2), "segmentation": ("mono8", 1),
                 "instances": ("16UC1", 2)}
    dec_topics = [t for t in need if "/decimated/" in t]
    stamps = {t: [] for t in dec_topics}
    for topic, msg, _ in bag.read_messages(topics=dec_topics):
        enc, bpp = encodings[topic.split("/")[-1]]
        if msg.encoding != enc or len(msg.data) != msg.width * msg.height * bpp or msg.width * msg.height == 0:
            fails.append("bad image on %s: %s %dx%d %d bytes" % (topic, msg.encoding, msg.width, msg.height, len(msg.data)))
        stamps[topic].append(msg.header.stamp.to_sec())
    for t, st in sorted(stamps.items()):
        periods = [round(x * 2) for x in sorted(st)]
        if not periods or periods != list(range(periods[0], periods[0] + len(periods))):
            fails.append("%s: stamps do not cover every 0.5 s period once: %s" % (t, sorted(st)))
    bag.close()
    json.dump({t: topics.get(t, 0) for t in need}, open(os.path.join(out, "counts.json"), "w"))
print(json.dumps({"outcome": m.get("outcome"), "end_time": m.get("end_time"),
                  "path_length": m.get("flight", {}).get("path_length"),
                  "coverage": m.get("coverage", {}).get("prior_weighted")}))
if fails:
    print("FAIL:\n  " + "\n  ".join(fails)); sys.exit(1)
print("PASS: mission ran end to end; metrics.json and the bag are complete")
PY
# Outside judges of the bag: `rosbag info` (exit 0, lz4 chunks, the same counts as Python rosbag)
# and `rosbag play` into a subscriber that counts every compact-stream image it receives.
if ! rosbag info --yaml "$out/mission.bag" >"$out/info.yaml" 2>"$out/info.err"; then
  echo "FAIL: rosbag info"; cat "$out/info.err"; exit 1
fi
roscore -p "$port" >"$out/roscore.log" 2>&1 &
core=$!
trap 'kill $core 2>/dev/null; wait $core 2>/dev/null; rm -rf "$out"' EXIT
/usr/bin/python3 - "$out" <<'PY'
import json, os, signal, subprocess, sys, time
import rosgraph, rospy, yaml
out = sys.argv[1]
counts = json.load(open(os.path.join(out, "counts.json")))
info = yaml.safe_load(open(os.path.join(out, "info.yaml")))
fails = []
if info.get("compression") != "lz4":
    fails.append("rosbag info: compression %r, expected lz4" % info.get("compression"))
info_counts = {t["topic"]: t["messages"] for t in info.get("topics", [])}
for t, n in counts.items():
    if info_counts.get(t) != n:
        fails.append("rosbag info: %s has %r messages, Python rosbag %d" % (t, info_counts.get(t), n))
for _ in range(100):
    if rosgraph.is_master_online():
        break
    time.sleep(0.1)
rospy.init_node("bag_play_counter", anonymous=True)
topics = sorted(t for t in counts if "/decimated/" in t)
received = {t: 0 for t in topics}
def counter(t):
    def cb(_):
        received[t] += 1
    return cb
subs = [rospy.Subscriber(t, rospy.AnyMsg, counter(t), queue_size=1000, buff_size=1 << 26) for t in topics]
# --keep-alive: rosbag play stays up after the bag's end until every image has arrived (a player
# that exits at once drops what its outgoing queues still hold when a loaded subscriber lags).
play = subprocess.Popen(["rosbag", "play", "-q", "-r", "10", "--wait-for-subscribers",
                         "--keep-alive", os.path.join(out, "mission.bag"), "--topics"] + topics)
deadline = time.time() + 120
while (time.time() < deadline and play.poll() is None
       and any(received[t] < counts[t] for t in topics)):
    time.sleep(0.1)
if play.poll() is not None:
    fails.append("rosbag play exited %d before every image arrived" % play.returncode)
else:
    play.send_signal(signal.SIGINT)
    play.wait(30)
for t in topics:
    if received[t] != counts[t]:
        fails.append("rosbag play: %s delivered %d of %d" % (t, received[t], counts[t]))
print("rosbag play delivered %d compact-stream images on %d topics" % (sum(received.values()), len(topics)))
if fails:
    print("FAIL:\n  " + "\n  ".join(fails)); sys.exit(1)
print("PASS: rosbag info and rosbag play agree with Python rosbag")
PY
