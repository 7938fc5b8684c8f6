# Sourced by test scripts: a throw-away single-node Slurm cluster (Debian slurm-wlm + munge) in
# a temp dir. slurm_cluster_start DIR starts munged, slurmctld and slurmd on non-default ports
# with a generated slurm.conf, waits until sinfo shows the node idle, and exports SLURM_CONF.
# Returns non-zero (leaving DIR/why.txt) when the cluster cannot start. slurm_cluster_stop DIR
# stops every daemon it started, by pid; callers run it from an EXIT trap.

slurm_cluster_start() {
  local dir="$1"
  mkdir -p "$dir/state" "$dir/spool" "$dir/munge"
  chmod 700 "$dir/munge"
  local base=$((20000 + ($$ * 7) % 20000))
  local ctld_port=$base slurmd_port=$((base + 1))
  local cpus mem
  cpus="$(nproc)"
  mem=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 / 2 ))
  # munge: a private key, socket, pid and log file.
  if command -v mungekey >/dev/null; then
    mungekey --create --keyfile="$dir/munge/munge.key" --force >/dev/null 2>&1 ||
      dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
  else
    dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
  fi
  chmod 600 "$dir/munge/munge.key"
  if ! /usr/sbin/munged --force --key-file="$dir/munge/munge.key" \
       --socket="$dir/munge/munge.socket" --pid-file="$dir/munge/munged.pid" \
       --log-file="$dir/munge/munged.log" --seed-file="$dir/munge/munged.seed" 2>"$dir/munge/start.err"; then
    echo "munged did not start: $(cat "$dir/munge/start.err")" >"$dir/why.txt"
    return 1
  fi
  cat >"$dir/slurm.conf" <<CONF
ClusterName=hameritt_test
SlurmctldHost=localhost
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge/munge.socket
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
MinJobAge=300
KillWait=5
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=localhost Default=YES MaxTime=INFINITE State=UP
CONF
  export SLURM_CONF="$dir/slurm.conf"
  /usr/sbin/slurmctld -D -c -f "$dir/slurm.conf" >"$dir/slurmctld.out" 2>&1 &
  echo $! >"$dir/slurmctld.bgpid"
  /usr/sbin/slurmd -D -N localhost -f "$dir/slurm.conf" >"$dir/slurmd.out" 2>&1 &
  echo $! >"$dir/slurmd.bgpid"
  local i state=""
  for i in $(seq 1 60); do
    state="$(sinfo -h -N -o '%t' 2>/dev/null | head -1 || true)"
    [[ "$state" == idle ]] && return 0
    sleep 0.5
  done
  {
    echo "the node did not become idle within 30 s (sinfo state: '${state:-none}')"
    tail -5 "$dir/slurmctld.log" "$dir/slurmd.log" "$dir/slurmctld.out" "$dir/slurmd.out" 2>/dev/null
  } >"$dir/why.txt"
  return 1
}

slurm_cluster_stop() {
  local dir="$1" f pid
  for f in slurmd.bgpid slurmctld.bgpid; do
    [[ -f "$dir/$f" ]] || continue
    pid="$(cat "$dir/$f")"
    kill "$pid" 2>/dev/null || true
    for _ in $(seq 1 20); do kill -0 "$pid" 2>/dev/null || break; sleep 0.25; done
    kill -9 "$pid" 2>/dev/null || true
  done
  if [[ -f "$dir/munge/munged.pid" ]]; then
    kill "$(cat "$dir/munge/munged.pid")" 2>/dev/null || true
  fi
}
