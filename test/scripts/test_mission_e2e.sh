#!/bin/bash
# End to end, as a user runs it: roslaunch mission.launch (simulator with both cameras rendering
# every modality, ADK, planner, baseline clients, rosbag recording) on the shipped scenario with
# a short time limit. The launch must end by itself (the ADK ends the mission), metrics.json
# must be complete, and Python rosbag must read every training topic back at its rate.
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
    # Images decode to the advertised size and encoding.
    for topic, msg, _ in bag.read_messages(topics=["/uav/camera/down/decimated/depth"]):
        if msg.encoding != "32FC1" or len(msg.data) != msg.width * msg.height * 4:
            fails.append("bad depth image: %s %dx%d %d bytes" % (msg.encoding, msg.width, msg.height, len(msg.data)))
        break
    bag.close()
print(json.dumps({"outcome": m.get("outcome"), "end_time": m.get("end_time"),
                  "path_length": m.get("flight", {}).get("path_length"),
                  "coverage": m.get("coverage", {}).get("prior_weighted")}))
if fails:
    print("FAIL:\n  " + "\n  ".join(fails)); sys.exit(1)
print("PASS: mission ran end to end; metrics.json and the bag are complete")
PY
