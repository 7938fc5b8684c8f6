#!/bin/bash
# hameritt_campaign end to end on a real single-node Slurm cluster started here (slurm-wlm and
# munge on localhost, generated slurm.conf, non-default ports; see slurm_cluster.sh):
#  1. the campaign (16 scenarios of all classes, 2 recorded 6 s missions) run unsharded with
#     `run --local`: the reference;
#  2. the same campaign in 4 shards submitted with `submit --slurm` (a 4-task job array); array
#     task 1 is cancelled (scancel) in the middle of its mission; `status` reports that unit
#     missing, `submit --slurm --resubmit-missing` resubmits only shard 1, which skips its
#     finished generation unit, clears the killed unit's work directory and completes it;
#  3. `merge`: the merged scenario files equal the reference's byte for byte, the manifests
#     equal field for field (`compare`: run-specific fields aside), every unit exists once,
#     and Python rosbag reads both bags.
# If Slurm cannot start here, the test says so loudly, still runs the sharded campaign locally
# (run --local --jobs 2) and compares it, and exits 77 (ctest: skipped), never a silent pass.
source "$(dirname "$0")/cli_lib.sh" campaign_slurm
source "$(dirname "$0")/slurm_cluster.sh"
export PATH="/usr/bin:/bin:/usr/sbin:/sbin:$PATH"
trap 'slurm_cluster_stop "$T/slurm"; rm -rf "$T"' EXIT
CAMP="$BIN/hameritt_campaign"
[[ -x "$CAMP" ]] || { echo "FAIL: $CAMP not built"; exit 1; }

config() {  # config SHARDS
  cat <<EOF
name: slurmtest
seed: 2026
classes: all
count: 16
shards: $1
missions:
  count: 2
  modes: [maneuver_only]
  time_limit: 6
  real_time_factor: 0
  record: true
  cameras: [down]
  timeout: 240
slurm:
  time: "00:10:00"
  cpus_per_task: 1
  mem: 1000M
EOF
}
config 1 >"$T/one.yaml"
config 4 >"$T/four.yaml"

echo "== 1. unsharded reference: run --local"
"$CAMP" plan "$T/one.yaml" --out "$T/one" >/dev/null && ok || bad "plan (1 shard)"
if "$CAMP" run "$T/one" --local >"$T/one.log" 2>&1; then ok; else
  bad "run --local (1 shard)"; cat "$T/one.log" "$T"/one/shard-*.local.log
fi
"$CAMP" merge "$T/one" >/dev/null && ok || bad "merge (1 shard)"

echo "== 2. 4 shards through Slurm"
"$CAMP" plan "$T/four.yaml" --out "$T/four" >/dev/null && ok || bad "plan (4 shards)"
C="$T/four"
slurm_ok=1
if ! slurm_cluster_start "$T/slurm"; then
  slurm_ok=0
  echo "################################################################################"
  echo "SKIPPED (Slurm): the single-node Slurm cluster could not start in this environment:"
  cat "$T/slurm/why.txt"
  echo "The Slurm submission, kill and resubmission case is NOT tested; running the 4 shards"
  echo "locally instead (run --local --jobs 2) for the merge comparison."
  echo "################################################################################"
  "$CAMP" run "$C" --local --jobs 2 >"$T/four.log" 2>&1 && ok || bad "run --local --jobs 2"
else
  sinfo
  out="$("$CAMP" submit "$C" --slurm)" && ok || bad "submit --slurm: $out"
  echo "$out"
  job="$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))[0]['job_id'])" \
         "$C/slurm/jobs.json")"
  grep -q -- "--array=0-3$" "$C/slurm/campaign-0.sbatch" && ok || bad "array spec"
  # Shard 1 holds gen-000001 and mission-000001-maneuver_only: cancel it mid-mission.
  killed=0
  for _ in $(seq 1 600); do
    log="$(ls "$C"/units/.work/mission-000001-maneuver_only@*/output/launch.log 2>/dev/null | head -1)"
    if [[ -n "$log" ]] && grep -q "process\[adk" "$log"; then
      sleep 2
      scancel "${job}_1" && killed=1
      echo "scancel ${job}_1 while the mission ran ($(grep -c . "$log") log lines)"
      break
    fi
    sleep 0.2
  done
  ((killed)) && ok || bad "never saw shard 1's mission running"
  "$CAMP" status "$C" --wait 300 >"$T/status1.txt"
  rc=$?
  cat "$T/status1.txt"
  [[ $rc -eq 3 ]] && ok || bad "status after the kill exited $rc, expected 3 (units missing)"
  grep -q "missing: mission-000001-maneuver_only (work dir present)" "$T/status1.txt" && ok ||
    bad "status does not list the killed unit with its stale work dir"
  [[ "$(grep -c "missing:" "$T/status1.txt")" == 1 ]] && ok || bad "other units missing too"
  [[ ! -e "$C/units/mission-000001-maneuver_only" ]] && ok || bad "the killed unit has output"
  # No process of the killed unit lingers (Slurm ended the whole task).
  sleep 1
  if ps -eo args | grep -v grep | grep -q "units/.work/mission-000001"; then
    bad "processes of the killed task are still running"; ps -eo pid,args | grep "units/.work" | grep -v grep
  else ok; fi
  out="$("$CAMP" submit "$C" --slurm --resubmit-missing)" && ok || bad "resubmit: $out"
  echo "$out"
  grep -q -- "--array=1$" "$C/slurm/campaign-1.sbatch" && ok || bad "resubmitted more than shard 1"
  "$CAMP" status "$C" --wait 300 && ok || bad "status after the resubmission: units missing"
  job2="$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))[1]['job_id'])" \
          "$C/slurm/jobs.json")"
  echo "-- resubmitted task's output:"
  cat "$C/slurm/${job2}_1.out"
  grep -q "gen-000001 already complete" "$C/slurm/${job2}_1.out" && ok ||
    bad "the resubmitted shard did not skip its finished unit"
  grep -q "removed the stale work directory mission-000001" "$C/slurm/${job2}_1.out" && ok ||
    bad "the resubmitted shard did not clear the killed unit's work dir"
  "$CAMP" submit "$C" --slurm --resubmit-missing | grep -q "nothing missing" && ok ||
    bad "a second resubmission found something missing"
fi

echo "== 3. merge and compare with the unsharded run"
"$CAMP" merge "$C" && ok || bad "merge (4 shards)"
diff -r "$T/one/merged/scenarios" "$C/merged/scenarios" >/dev/null && ok ||
  bad "merged scenario files differ from the unsharded run's"
cmp -s "$T/one/merged/world.json" "$C/merged/world.json" && ok || bad "world.json differs"
"$CAMP" compare "$T/one/merged/manifest.json" "$C/merged/manifest.json" && ok ||
  bad "the manifests differ"
[[ -z "$(ls "$C/units/.work")" ]] && ok || bad "work dirs left: $(ls "$C/units/.work")"
/usr/bin/python3 - "$C" "$slurm_ok" <<'PY'
import json, os, sys
import rosbag
c, slurm_ok = sys.argv[1], sys.argv[2] == "1"
m = json.load(open(os.path.join(c, "merged", "manifest.json")))
plan = json.load(open(os.path.join(c, "plan.json")))
fails = []
units = sorted(d for d in os.listdir(os.path.join(c, "units")) if not d.startswith("."))
if units != sorted(u["id"] for u in plan["units"]):
    fails.append("unit directories %s are not exactly the plan's" % units)
ids = [s["id"] for s in m["scenarios"]]
if len(ids) != 16 or len(set(ids)) != 16 or [s["index"] for s in m["scenarios"]] != list(range(16)):
    fails.append("scenarios: %d ids, %d distinct" % (len(ids), len(set(ids))))
if len(os.listdir(os.path.join(c, "merged", "scenarios"))) != 16:
    fails.append("merged/scenarios does not hold 16 scenarios")
if [e["unit"] for e in m["missions"]] != ["mission-000000-maneuver_only", "mission-000001-maneuver_only"]:
    fails.append("missions: %r" % [e["unit"] for e in m["missions"]])
if slurm_ok and sorted({e["job"].split("_")[0] for e in m["missions"]}) == [""]:
    fails.append("the missions did not run in Slurm jobs")
if m["run"]["shards"] != 4:
    fails.append("run.shards %r" % m["run"]["shards"])
for e in m["missions"]:
    met = json.load(open(os.path.join(c, e["metrics_path"])))
    if met["outcome"] != e["outcome"] or met["scenario_id"] != e["scenario_id"]:
        fails.append("%s: the manifest disagrees with metrics.json" % e["unit"])
    if e["time_limit"] != 6.0 or e["end_time"] is None:
        fails.append("%s: time_limit %r end_time %r" % (e["unit"], e["time_limit"], e["end_time"]))
    bag_path = os.path.join(c, e["bag_path"])
    if os.path.getsize(bag_path) != e["bag_size"]:
        fails.append("%s: bag_size %r, file %d" % (e["unit"], e["bag_size"], os.path.getsize(bag_path)))
    bag = rosbag.Bag(bag_path)
    topics = {t: v.message_count for t, v in bag.get_type_and_topic_info().topics.items()}
    bag.close()
    if topics.get("/uav/odom", 0) < 200 or topics.get("/uav/camera/down/boxes", 0) < 30:
        fails.append("%s: bag topics %r" % (e["unit"], topics))
    if "/uav/camera/front/boxes" in topics:
        fails.append("%s: cameras: [down] but the front camera was recorded" % e["unit"])
    logs = os.path.join(c, "units", e["unit"], "ros_log")
    if not os.path.isdir(logs) or not os.listdir(logs):
        fails.append("%s: no ROS log in its own ROS_LOG_DIR" % e["unit"])
s = m["summary"]
if s["missions"] != 2 or sum(x["missions"] for x in s["by_class_and_mode"]) != 2:
    fails.append("summary %r" % s)
print(json.dumps({k: s[k] for k in ("missions", "outcomes", "success_rate", "koz_violations",
                                     "bag_bytes")}))
if fails:
    print("FAIL:\n  " + "\n  ".join(fails)); sys.exit(1)
print("merged manifest: %d units exactly once, 16 scenarios, 2 missions with readable bags"
      % len(units))
PY
[[ $? -eq 0 ]] && ok || bad "merged manifest checks"

echo "$pass passed, $fail failed"
((fail == 0)) || exit 1
if ((slurm_ok == 0)); then
  echo "SKIPPED (Slurm): only the local part ran; the Slurm case did not (see above)"
  exit 77
fi
