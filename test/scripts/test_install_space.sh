#!/usr/bin/env bash
# The package as a ROS user builds and installs it: a scratch catkin workspace with the package
# in src/hameritt, `catkin_make` and `catkin_make install` in a clean environment, then the
# workspace's source, build and devel spaces are removed and everything runs from the install
# space alone: rospack finds share/hameritt, the installed data equals the checkout's, the tools
# (hameritt_validate, hameritt_generate, hameritt_summary, hameritt_map, hameritt_world,
# hameritt_campaign, cot_listen.py) work on the installed scenario and config, and a short
# `roslaunch hameritt mission.launch` ends with metrics.json written. strace is the judge of
# "alone": no tool opens, stats or executes a file of the checkout or of the workspace outside
# its install space (negative control: a run told to read the checkout's config is caught); the
# mission executes the installed nodes, and roslaunch hands them files of the install space.
#
# ccache: the workspace's build space is $SRC/build-workspace and the workspace builds with
# Ninja, which runs the compiler there; its devel space is build-workspace/devel and the generated
# headers lie in build-workspace/generated. The compiler then sees the same paths relative to its
# working directory as in the checkout's own build in $SRC/build (../src, ../include,
# devel/include, generated), and with that build in the cache the workspace's compile is mostly
# cache hits.
source "$(dirname "$0")/cli_lib.sh" install_space
export PATH="/usr/bin:/bin:/usr/sbin:/sbin:$PATH"

R="$(cd "$SRC" && pwd -P)"
S="$R/build-workspace"
W="$S/ws"
I="$W/install"
JOBS="${HAMERITT_JOBS:-$(nproc)}"

# A clean environment: no devel space of the checkout sourced (no underlay to chain to), ROS
# logs in the scratch directory.
clean_env=(env -i HOME="$HOME" PATH=/usr/bin:/bin:/usr/sbin:/sbin LANG=C.UTF-8
  PYTHONNOUSERSITE=1 ROS_HOME="$T/ros_home" CCACHE_BASEDIR="$R" CCACHE_NOHASHDIR=1
  CCACHE_STATSLOG="$T/ccache_stats.log")
[[ -n "${CCACHE_DIR:-}" ]] && clean_env+=(CCACHE_DIR="$CCACHE_DIR")
[[ -n "${XDG_CACHE_HOME:-}" ]] && clean_env+=(XDG_CACHE_HOME="$XDG_CACHE_HOME")

# ------------------------------------------------------------------ the workspace
rm -rf "$S"
mkdir -p "$W/src"
ln -s "$R" "$W/src/hameritt"
cmake_args=(-DCMAKE_BUILD_TYPE=Release -DPYTHON_EXECUTABLE=/usr/bin/python3
  -DCATKIN_ENABLE_TESTING=OFF -DCATKIN_DEVEL_PREFIX="$S/devel")
if command -v ccache >/dev/null 2>&1; then
  cmake_args+=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
fi
catkin_make=(catkin_make -C "$W" --build "$S" --use-ninja "${cmake_args[@]}" -j"$JOBS")

echo "== catkin_make in $W"
if "${clean_env[@]}" "${catkin_make[@]}" >"$T/catkin_make.log" 2>&1; then
  ok
else
  bad "catkin_make"; tail -40 "$T/catkin_make.log"
fi
echo "== catkin_make install"
if "${clean_env[@]}" "${catkin_make[@]}" install >"$T/install.log" 2>&1; then
  ok
else
  bad "catkin_make install"; tail -40 "$T/install.log"
fi
if [[ $fail -ne 0 ]]; then
  echo "test_install_space: $pass passed, $fail failed (build; left in $S)"
  exit 1
fi

# Every compile went through ccache: its counts for this workspace add up to the objects built.
objects="$(find "$S" -path "$W" -prune -o -name '*.o' -print | wc -l)"
read -r hits misses < <("${clean_env[@]}" ccache --show-log-stats -v 2>/dev/null | /usr/bin/python3 -c '
import re, sys
text = sys.stdin.read()
def count(label):
    m = re.search(r"^\s*%s:\s+(\d+)" % label, text, re.M)
    return int(m.group(1)) if m else 0
print(count("Hits"), count("Misses"))')
if command -v ccache >/dev/null 2>&1; then
  [[ $objects -gt 0 && $((hits + misses)) -eq $objects ]] && ok ||
    bad "ccache counted $hits hits + $misses misses for $objects objects"
  echo "workspace compile: $objects objects, ccache $hits hits, $misses misses"
fi

# The source tree (as the workspace knows it), the build and the devel space go away.
rm "$W/src/hameritt"
find "$S" -mindepth 1 -maxdepth 1 ! -name ws -exec rm -rf {} +

# inst CMD...: CMD in a clean environment with only the install space sourced, in $T.
inst() {
  (cd "$T" && "${clean_env[@]}" ROS_MASTER_URI="http://localhost:$port" /bin/bash -c \
    'cmd=("$@"); set --; source "$0/setup.bash"; exec "${cmd[@]}"' "$I" "$@")
}
# traced NAME CMD...: inst CMD under strace (file opens, stats and executions) into $T/NAME.trace.
# STRACE_CALLS overrides the system calls traced.
traced() {
  local name="$1"
  shift
  inst strace -f -qq --seccomp-bpf -e trace="${STRACE_CALLS:-execve,open,openat,stat,newfstatat,access,readlink}" \
    -o "$T/$name.trace" "$@"
}
port=$((14000 + $$ % 2000))

echo "== the install space"
share="$(inst rospack find hameritt)"
[[ "$share" == "$I/share/hameritt" ]] && ok || bad "rospack find hameritt: '$share', expected $I/share/hameritt"
rpp="$(inst printenv ROS_PACKAGE_PATH)"
/usr/bin/python3 - "$rpp" "$R" "$I" <<'PY' && ok || bad "ROS_PACKAGE_PATH: $rpp"
import os, sys
rpp, checkout, install = sys.argv[1:]
entries = [e for e in rpp.split(":") if e]
assert any(e.rstrip("/") == install + "/share" for e in entries), entries
for e in entries:
    p = os.path.normpath(e)
    assert not p.startswith(checkout + "/") or p.startswith(install + "/"), e
PY
for d in launch config scenarios models; do
  diff -r "$R/$d" "$I/share/hameritt/$d" >"$T/diff_$d" && ok || bad "share/hameritt/$d differs: $(head -5 "$T/diff_$d")"
done
diff -r "$R/include/hameritt" "$I/include/hameritt" | grep -v "^Only in $I/include/hameritt: [A-Za-z]*\.h$" \
  >"$T/diff_include" && bad "include/hameritt differs: $(head -5 "$T/diff_include")" || ok
missing=0
for m in "$R"/msg/*.msg "$R"/srv/*.srv; do
  [[ -f "$I/include/hameritt/$(basename "${m%.*}").h" ]] || { missing=1; bad "no installed header for $m"; }
done
[[ $missing -eq 0 ]] && ok
for p in hameritt_generate hameritt_validate hameritt_world hameritt_summary hameritt_check_path \
         hameritt_map hameritt_render hameritt_export hameritt_campaign cot_listen.py hameritt_tak_check \
         scenario_generator simulator planner path_player adk coverage_search_client \
         color_shape_detector cop tak_bridge; do
  [[ -x "$I/lib/hameritt/$p" ]] && ok || bad "$p not installed in lib/hameritt"
done

echo "== the tools, from the install space alone"
D="$I/share/hameritt/scenarios/default"
traced validate "$I/lib/hameritt/hameritt_validate" "$D/mission.json" "$D/sim_config.json" >"$T/validate.out" 2>&1 &&
  ok || bad "hameritt_validate: $(cat "$T/validate.out")"
cls="$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["class"])' "$D/mission.json")"
seed="$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["seed"])' "$D/mission.json")"
id="$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["scenario_id"])' "$D/mission.json")"
# The installed config regenerates the installed scenario byte for byte.
traced generate "$I/lib/hameritt/hameritt_generate" --class "$cls" --scenario-seed "$seed" --out "$T/regen" --quiet &&
  ok || bad "hameritt_generate"
cmp -s "$D/mission.json" "$T/regen/$id/mission.json" && ok || bad "regenerated mission.json differs"
cmp -s "$D/sim_config.json" "$T/regen/$id/sim_config.json" && ok || bad "regenerated sim_config.json differs"
traced summary "$I/lib/hameritt/hameritt_summary" "$D" >"$T/summary.out" 2>&1 && grep -q "^objective" "$T/summary.out" &&
  ok || bad "hameritt_summary: $(head -5 "$T/summary.out")"
traced map "$I/lib/hameritt/hameritt_map" "$D" --out "$T/map.png" && ok || bad "hameritt_map"
[[ "$(head -c 8 "$T/map.png" 2>/dev/null | od -An -tx1 | tr -d ' \n')" == "89504e470d0a1a0a" ]] && ok ||
  bad "hameritt_map wrote no PNG"
traced world "$I/lib/hameritt/hameritt_world" --out "$T/world.json" && ok || bad "hameritt_world"
traced validate_world "$I/lib/hameritt/hameritt_validate" "$T/world.json" >/dev/null && ok || bad "the installed world does not validate"
cat >"$T/campaign.yaml" <<'EOF'
name: install_space
seed: 7
classes: all
count: 3
shards: 1
missions:
  count: 0
EOF
traced campaign_plan rosrun hameritt hameritt_campaign plan "$T/campaign.yaml" --out "$T/campaign" \
  >"$T/campaign.log" 2>&1 && ok || bad "hameritt_campaign plan: $(tail -5 "$T/campaign.log")"
traced campaign_run rosrun hameritt hameritt_campaign run "$T/campaign" --local >>"$T/campaign.log" 2>&1 &&
  ok || bad "hameritt_campaign run: $(tail -5 "$T/campaign.log")"
traced campaign_merge rosrun hameritt hameritt_campaign merge "$T/campaign" >>"$T/campaign.log" 2>&1 &&
  ok || bad "hameritt_campaign merge: $(tail -5 "$T/campaign.log")"
n="$(/usr/bin/python3 -c 'import json,sys; print(len(json.load(open(sys.argv[1]))["scenarios"]))' \
  "$T/campaign/merged/manifest.json" 2>/dev/null)"
[[ "$n" == 3 ]] && ok || bad "the campaign merged $n scenarios, expected 3"
traced cot_listen rosrun hameritt cot_listen.py --help >/dev/null && ok || bad "rosrun hameritt cot_listen.py --help"
# The renderer reads the installed meshes (the simulator renders with the same library).
traced render "$I/lib/hameritt/hameritt_render" --sim-config "$D/sim_config.json" --time 0 \
  --camera down --out "$T/render" >"$T/render.out" 2>&1 && ok || bad "hameritt_render: $(tail -3 "$T/render.out")"
grep -q "\"$I/share/hameritt/models/meshes/[a-z_0-9]*\.obj\"" "$T/render.trace" && ok || bad "no installed mesh was read"

echo "== roslaunch hameritt mission.launch, from the install space alone"
out="$T/mission"
# Every file the launch hands to a node lies in the install space (roslaunch's own view).
inst roslaunch --dump-params hameritt mission.launch >"$T/params.yaml" 2>&1 && ok || bad "roslaunch --dump-params"
/usr/bin/python3 - "$T/params.yaml" "$R" "$I" <<'PY' && ok || bad "launch parameters name files outside the install space"
import sys, yaml
params, checkout, install = yaml.safe_load(open(sys.argv[1])), sys.argv[2], sys.argv[3]
files = {k: v for k, v in params.items() if isinstance(v, str) and v.startswith("/") and "." in v}
bad = {k: v for k, v in files.items() if v.startswith(checkout + "/") and not v.startswith(install + "/")}
assert not bad, bad
assert any(k.endswith("/urdf") and v.startswith(install + "/share/hameritt/models/") for k, v in files.items()), files
print("launch parameters: %d files, all in the install space" % len(files))
PY
# Executions only: tracing every file opened slows the graph enough, on a loaded machine, for
# the ADK's stall watchdog to end the mission (the tools above are traced in full).
if STRACE_CALLS=execve traced mission timeout 300 roslaunch -p "$port" hameritt mission.launch time_limit:=4 \
     real_time_factor:=0 output_dir:="$out" >"$T/launch.log" 2>&1; then ok; else
  bad "roslaunch exited non-zero or timed out"; tail -40 "$T/launch.log"
fi
/usr/bin/python3 - "$out/metrics.json" "$D/mission.json" <<'PY' && ok || bad "metrics.json"
import json, sys
m = json.load(open(sys.argv[1]))
mission = json.load(open(sys.argv[2]))
assert m["scenario_id"] == mission["scenario_id"], (m["scenario_id"], mission["scenario_id"])
assert m["outcome"] in ("success", "timeout"), (m["outcome"], m.get("reason"))
# The ADK ends the mission when it sees the limit passed: on a loaded machine, after it.
assert m["end_time"] >= 4.0 - 1e-6 or m["outcome"] == "success", m["end_time"]
assert m["outcome"] == "success" or m["reason"] == "time limit 4 s reached", m["reason"]
print("metrics.json: %s, outcome %s at %.2f s" % (m["scenario_id"], m["outcome"], m["end_time"]))
PY

# ------------------------------------------------------------------ strace, the judge
# judge TRACE...: no file of the checkout (or of the workspace outside its install space) opened,
# looked at or executed; prints the files of the install space used.
judge() {
  /usr/bin/python3 - "$R" "$I" "$@" <<'PY'
import os, re, sys
checkout, install, traces = sys.argv[1], sys.argv[2], sys.argv[3:]
path_re = re.compile(r'^\d+\s+(\w+)\((?:AT_FDCWD, |\d+, )?"([^"]*)"')
bad, used = [], set()
for t in traces:
    for line in open(t, errors="replace"):
        m = path_re.match(line)
        if not m:
            continue
        call, p = m.groups()
        p = os.path.normpath(p) if os.path.isabs(p) else p
        if p.startswith(install + "/"):
            used.add(os.path.relpath(p, install).split("/")[0])
        elif p == install or install.startswith(p + "/"):
            continue  # the install space or an ancestor (resolving its path)
        elif p == checkout or p.startswith(checkout + "/"):
            bad.append("%s: %s %s" % (os.path.basename(t), call, p))
for b in bad[:10]:
    print("  read outside the install space:", b)
print("  install space dirs used:", " ".join(sorted(used)))
sys.exit(1 if bad or not used else 0)
PY
}
judge "$T"/*.trace && ok || bad "a program reached outside the install space"
# The mission ran the installed nodes.
for n in simulator adk planner coverage_search_client color_shape_detector; do
  grep -q "execve(\"$I/lib/hameritt/$n\"" "$T/mission.trace" && ok || bad "the installed $n did not run"
done

# Negative control: a tool pointed at the checkout's config is caught by the judge.
inst strace -f -qq -e trace=openat -o "$T/control.trace.x" env HAMERITT_CONFIG_DIR="$R/config" \
  "$I/lib/hameritt/hameritt_world" --out "$T/world2.json" && ok || bad "control: hameritt_world with the checkout's config"
judge "$T/control.trace.x" >/dev/null && bad "the judge missed a read of the checkout" || ok

echo "test_install_space: $pass passed, $fail failed"
if [[ $fail -eq 0 ]]; then
  rm -rf "$S"
else
  echo "workspace left in $S"
fi
[[ $fail -eq 0 ]]
