#!/bin/bash
# Faults: kill -9 the simulator, the ADK and the recorder at seeded random points of recorded
# missions (mission.launch record:=true, private master), and an ADK restarted in a running
# graph whose simulator then dies. After each: metrics.json is absent or complete valid JSON with
# the right outcome, no temporary file looks like a finished output, and the bag (closed, or
# left .active and recovered by `rosbag reindex`) is read by `rosbag info` and Python rosbag.
# Usage: test_mission_faults.sh [SEED]
set -uo pipefail
export PATH="/usr/bin:/bin:$PATH"
src="${HAMERITT_SOURCE_DIR:?}"
seed="${1:-${HAMERITT_FAULT_SEED:-7}}"
RANDOM=$seed
T="$(mktemp -d /tmp/hameritt_faults.XXXXXX)"
port=$((14000 + $$ % 2000))
export ROS_MASTER_URI="http://localhost:$port"
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -INT "$p" 2>/dev/null; done
  for _ in $(seq 50); do
    alive=0
    for p in "${pids[@]}"; do kill -0 "$p" 2>/dev/null && alive=1; done
    [[ $alive -eq 0 ]] && break
    sleep 0.1
  done
  for p in "${pids[@]}"; do kill -9 "$p" 2>/dev/null; done
  wait 2>/dev/null
  rm -rf "$T"
}
trap cleanup EXIT
pass=0
fail=0
faults=0
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAIL: $*"; }
scenario="$src/scenarios/default"

roscore -p "$port" >"$T/roscore.log" 2>&1 &
pids+=($!)
for _ in $(seq 100); do rosparam list >/dev/null 2>&1 && break; sleep 0.2; done

# child PID NAME: the child process of PID whose command is NAME.
child() { ps -o pid=,comm= --ppid "$1" | awk -v n="$2" '$2 == n {print $1; exit}'; }
# wait_file PATH SECONDS
wait_file() {
  for _ in $(seq $(($2 * 10))); do [[ -e "$1" ]] && return 0; sleep 0.1; done
  return 1
}

# check_outputs DIR EXPECT_METRICS (none | OUTCOME) REASON_PATTERN [BAG: yes | no]
check_outputs() {
  /usr/bin/python3 - "$@" <<'PY'
import glob, json, os, re, subprocess, sys
import rosbag
out, expect, pattern = sys.argv[1], sys.argv[2], sys.argv[3]
want_bag = len(sys.argv) < 5 or sys.argv[4] == "yes"
fails = []
names = sorted(os.listdir(out))
metrics = os.path.join(out, "metrics.json")
# A temporary file never carries a finished output's name.
for n in names:
    if n.endswith(".json") and n != "metrics.json":
        fails.append("%s looks like a finished output" % n)
if expect == "none":
    if os.path.exists(metrics):
        fails.append("metrics.json written by a killed ADK: %s" % open(metrics).read()[:200])
else:
    try:
        m = json.load(open(metrics))
    except Exception as e:
        m = {}
        fails.append("metrics.json missing or invalid: %s (dir: %s)" % (e, names))
    for key in ["schema", "scenario_id", "outcome", "reason", "end_time", "flight", "coverage"]:
        if m and key not in m:
            fails.append("metrics.json lacks %s" % key)
    if m and m.get("outcome") != expect:
        fails.append("outcome %r, expected %r (reason %r)" % (m.get("outcome"), expect, m.get("reason")))
    if m and not re.search(pattern, m.get("reason", "")):
        fails.append("reason %r does not match /%s/" % (m.get("reason"), pattern))
    if m:
        print("  metrics: outcome %s, reason %r, start %s, end %s" % (m["outcome"], m["reason"], m["start_time"], m["end_time"]))
bags = [n for n in names if n.startswith("mission.bag")]
if want_bag:
    if "mission.bag" in names:
        bag = os.path.join(out, "mission.bag")
        how = "closed"
    elif "mission.bag.active" in names:
        bag = os.path.join(out, "mission.bag.active")
        how = "reindexed"
        r = subprocess.run(["rosbag", "reindex", "--output-dir", out, bag], capture_output=True, text=True)
        if r.returncode != 0:
            fails.append("rosbag reindex failed: %s" % r.stderr[-400:])
        bag = os.path.join(out, "mission.bag.active")
    else:
        bag = None
        fails.append("no bag at all: %s" % names)
    if bag:
        r = subprocess.run(["rosbag", "info", bag], capture_output=True, text=True)
        if r.returncode != 0:
            fails.append("rosbag info %s: %s" % (bag, r.stderr[-300:]))
        try:
            b = rosbag.Bag(bag)
            n = 0
            for _topic, msg, _t in b.read_messages(topics=["/uav/odom"]):
                n += 1
            b.close()
            print("  bag %s (%s): %d odometry messages read back" % (os.path.basename(bag), how, n))
            if n == 0:
                fails.append("the bag holds no odometry")
        except Exception as e:
            fails.append("Python rosbag cannot read %s: %s" % (bag, e))
if fails:
    print("\n".join("FAIL: " + f for f in fails))
    sys.exit(1)
PY
}

# kill_in_mission NAME OUTCOME REASON: a recorded mission, NAME (simulator | adk | record) killed
# with SIGKILL at a random time after the clock started.
kill_in_mission() {
  local name="$1" expect="$2" reason="$3" out="$T/kill_$1"
  local delay="$((RANDOM % 30 + 5))"
  roslaunch hameritt mission.launch scenario:="$scenario" mode:=maneuver_only record:=true \
    time_limit:=60 real_time_factor:=0 output_dir:="$out" >"$T/$name.log" 2>&1 &
  local launch=$!
  pids+=("$launch")
  if ! wait_file "$out/mission.bag.active" 60; then
    bad "$name: the recording never started"; tail -30 "$T/$name.log"; kill -INT "$launch"; wait "$launch"; return
  fi
  sleep "$(echo "$delay" | sed 's/.$/.&/')"  # 0.5 .. 3.4 s into the mission
  local victim
  victim="$(child "$launch" "$name")"
  if [[ -z "$victim" ]]; then
    bad "$name: no such process under roslaunch"; kill -INT "$launch"; wait "$launch"; return
  fi
  kill -9 "$victim"
  faults=$((faults + 1))
  echo "killed $name (pid $victim) $(echo "$delay" | sed 's/.$/.&/') s after the recording started"
  # Every node of the launch is required: the launch ends by itself.
  local i
  for i in $(seq 600); do kill -0 "$launch" 2>/dev/null || break; sleep 0.1; done
  if kill -0 "$launch" 2>/dev/null; then
    bad "$name: the launch did not end after the kill"; kill -INT "$launch"
  fi
  wait "$launch"
  if check_outputs "$out" "$expect" "$reason"; then ok; else bad "$name: outputs"; tail -20 "$T/$name.log"; fi
}

kill_in_mission simulator aborted "interrupted"
kill_in_mission adk none ""
kill_in_mission record aborted "interrupted"

# An ADK killed and started again in the same graph, then the simulator killed: the second ADK
# says it started late, notices the dead simulator by its stalled clock, and writes `aborted`.
out="$T/restart"
roslaunch hameritt simulator.launch sim_config:="$scenario/sim_config.json" real_time_factor:=1 \
  cameras:=false >"$T/restart_sim.log" 2>&1 &
sim_launch=$!
pids+=("$sim_launch")
adk_args=(_mission:="$scenario/mission.json" _sim_config:="$scenario/sim_config.json"
          _output_dir:="$out" _clock_timeout:=3 _time_limit:=300)
rosrun hameritt adk "${adk_args[@]}" >"$T/adk1.log" 2>&1 &
adk1=$!
pids+=("$adk1")
# Once the simulator runs (real time), a random 3..5 s into the mission.
for _ in $(seq 120); do rosservice list 2>/dev/null | grep -q "^/simulator/step$" && break; sleep 0.5; done
sleep "$((RANDOM % 3 + 3))"
kill -9 "$adk1"
wait "$adk1" 2>/dev/null
faults=$((faults + 1))
echo "killed the ADK (pid $adk1); starting it again"
rosrun hameritt adk "${adk_args[@]}" >"$T/adk2.log" 2>&1 &
adk2=$!
pids+=("$adk2")
sleep "$((RANDOM % 3 + 4))"
if grep -q "started in a mission under way" "$T/adk2.log"; then ok; else
  bad "restart: the second ADK did not say it joined late"; tail -5 "$T/adk2.log"
fi
victim="$(child "$sim_launch" simulator)"
kill -9 "$victim"
faults=$((faults + 1))
echo "killed the simulator (pid $victim) under the restarted ADK"
for _ in $(seq 300); do kill -0 "$adk2" 2>/dev/null || break; sleep 0.1; done
if kill -0 "$adk2" 2>/dev/null; then
  bad "restart: the ADK did not end after the simulator died"; tail -5 "$T/adk2.log"
fi
wait "$adk2"
rc=$?
[[ $rc -eq 0 ]] && ok || bad "restart: the ADK exited $rc"
if check_outputs "$out" aborted "no new /clock.*simulator dead or stalled.*the ADK started at sim time" no
then ok; else bad "restart: outputs"; tail -5 "$T/adk2.log"; fi
wait "$sim_launch" 2>/dev/null

echo "seed $seed: $faults faults injected, $pass passed, $fail failed"
[[ $fail -eq 0 ]]
