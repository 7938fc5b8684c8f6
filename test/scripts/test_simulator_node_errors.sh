#!/usr/bin/env bash
# The simulator node on bad input: a clear error naming the file and field, exit code 1, never
# a crash or a hang. Runs its own roscore on a free port.
set -u
BIN="${HAMERITT_BIN_DIR:?}"
SRC="${HAMERITT_SOURCE_DIR:?}"
T="$(mktemp -d /tmp/hameritt_simerr.XXXXXX)"
port="$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')"
export ROS_MASTER_URI="http://127.0.0.1:$port"
roscore -p "$port" >"$T/roscore.log" 2>&1 &
core=$!
trap 'kill $core 2>/dev/null; wait $core 2>/dev/null; rm -rf "$T"' EXIT
for _ in $(seq 100); do rosparam list >/dev/null 2>&1 && break; sleep 0.1; done
pass=0
fail=0

# run NAME PATTERN ARGS...: the node must exit 1 within 60 s with PATTERN in its output.
run() {
  local name="$1" pattern="$2"
  shift 2
  local out rc
  out="$(timeout 60 "$BIN/simulator" "$@" 2>&1)"
  rc=$?
  if [[ $rc -ne 1 ]]; then
    fail=$((fail + 1)); echo "FAIL $name: exit $rc, expected 1: $out"
  elif [[ ! "$out" =~ $pattern ]]; then
    fail=$((fail + 1)); echo "FAIL $name: output does not match /$pattern/: $out"
  else
    pass=$((pass + 1))
  fi
}

S="$SRC/scenarios/default/sim_config.json"
run missing_param "~sim_config: required parameter" __name:=sim_a
run missing_file "$T/nope.json: cannot open" __name:=sim_b _sim_config:="$T/nope.json"
printf '{"schema": "hameritt/sim_config",' >"$T/truncated.json"
run malformed "$T/truncated.json: malformed JSON" __name:=sim_c _sim_config:="$T/truncated.json"
/usr/bin/python3 - "$S" "$T" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
a = json.loads(json.dumps(s)); a["uav"]["altitude"]["max"] = "high"
json.dump(a, open(sys.argv[2] + "/wrongtype.json", "w"))
b = json.loads(json.dumps(s)); b["world"]["params"]["street_width"] = 11.0
json.dump(b, open(sys.argv[2] + "/otherworld.json", "w"))
c = json.loads(json.dumps(s)); c["entities"][0]["trajectory"] = [[0, 0, 0, 0, 0], [0, 1, 1, 0, 0]]
json.dump(c, open(sys.argv[2] + "/badtraj.json", "w"))
PY
run wrong_type "wrongtype.json.*uav.altitude.max.*number" __name:=sim_d _sim_config:="$T/wrongtype.json"
run fingerprint "otherworld.json: world.fingerprint" __name:=sim_e _sim_config:="$T/otherworld.json"
run trajectory "badtraj.json.*entities.*trajectory" __name:=sim_f _sim_config:="$T/badtraj.json"
run bad_rate "~publish_rate_hz" __name:=sim_g _sim_config:="$S" _publish_rate_hz:=300.0
run bad_physics "physics_rate_hz" __name:=sim_h _sim_config:="$S" _physics_rate_hz:=-5.0
run bad_urdf "$T/none.urdf" __name:=sim_i _sim_config:="$S" _urdf:="$T/none.urdf"
run bad_record_depth "~record_depth: expected 16UC1 \\(millimetres\\) or 32FC1 \\(metres\\), got 16UC2" \
  __name:=sim_j _sim_config:="$S" _record_depth:=16UC2
run bad_png_level "~record_png_level: expected -1 \\(off\\) or a zlib level 0..9, got 12" \
  __name:=sim_k _sim_config:="$S" _record_png_level:=12
run bad_autopilot "~autopilot: expected internal, px4 or ardupilot, got 'betaflight'" \
  __name:=sim_l _sim_config:="$S" _autopilot:=betaflight
run autopilot_lockstep "~autopilot px4 with /lockstep true: not supported" \
  __name:=sim_m _sim_config:="$S" _autopilot:=px4 _lockstep:=true
run bad_rotor_layout "~rotor_layout: expected a permutation of 0,1,2,3" \
  __name:=sim_n _sim_config:="$S" _autopilot:=px4 _rotor_layout:=0,1,1,3
run bad_gcs_udp "~gcs_udp: expected IPV4:PORT, got nowhere" \
  __name:=sim_o _sim_config:="$S" _gcs_udp:=nowhere

echo "$pass passed, $fail failed"
[[ $fail -eq 0 ]]
