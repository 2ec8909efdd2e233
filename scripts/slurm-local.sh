#!/usr/bin/env bash
# A single-node Slurm cluster on this machine, for tests and trying `springy sweep --slurm`:
#   bash scripts/slurm-local.sh start DIR   # munged, slurmctld, slurmd; prints "export SLURM_CONF=..."
#   bash scripts/slurm-local.sh stop DIR    # stops every daemon that start left running
# Everything lives in DIR: a fresh munge key, a minimal slurm.conf (one node: this host, all its
# cores; no cgroups, no accounting), the daemons' state, logs and pid files. No systemd: the
# daemons are started directly, as root (slurmd runs jobs as their users). Ports are picked free.
# Needs the Debian packages munge, slurmctld, slurmd and slurm-client (scripts/install-deps.sh).
set -euo pipefail
usage() { echo "usage: $0 start|stop DIR" >&2; exit 2; }
[ $# -eq 2 ] || usage
dir=$(realpath -m "$2")

stop() {
  local name pidfile pid i
  for name in slurmd slurmctld munged; do
    pidfile=$dir/run/$name.pid
    [ -s "$pidfile" ] || continue
    pid=$(cat "$pidfile")
    kill -TERM "$pid" 2>/dev/null || { rm -f "$pidfile"; continue; }
    for i in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$pid" 2>/dev/null || true
    rm -f "$pidfile"
  done
}

# A TCP port on 127.0.0.1 that nothing listens on.
free_port() {
  local port
  while :; do
    port=$((20000 + RANDOM % 30000))
    (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null || { echo "$port"; return; }
  done
}

start() {
  if [ "$(id -u)" != 0 ]; then echo "$0: needs root (slurmd starts jobs as their users)" >&2; exit 1; fi
  local tool
  for tool in munged mungekey slurmctld slurmd sbatch sinfo; do
    command -v "$tool" >/dev/null || { echo "$0: $tool is not installed (bash scripts/install-deps.sh)" >&2; exit 1; }
  done
  mkdir -p "$dir"/{munge,run,log,state,spool}
  chmod 700 "$dir/munge"
  rm -f "$dir/munge/munge.key"
  mungekey --create --keyfile="$dir/munge/munge.key"
  chmod 600 "$dir/munge/munge.key"
  # --force: the socket directory may be below a world-writable /tmp.
  munged --force --key-file="$dir/munge/munge.key" --socket="$dir/munge/munge.socket" \
    --pid-file="$dir/run/munged.pid" --log-file="$dir/log/munged.log" --seed-file="$dir/munge/munged.seed"
  local host cores ctld_port d_port
  host=$(hostname -s)
  cores=$(nproc)
  ctld_port=$(free_port)
  d_port=$(free_port)
  while [ "$d_port" = "$ctld_port" ]; do d_port=$(free_port); done
  cat >"$dir/slurm.conf" <<EOF
# Written by scripts/slurm-local.sh: one node, this host, for tests.
ClusterName=springy-local
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$d_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool/slurmd-%n
SlurmctldPidFile=$dir/run/slurmctld.pid
SlurmdPidFile=$dir/run/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SwitchType=switch/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MinJobAge=300
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cores State=UNKNOWN
PartitionName=local Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
  export SLURM_CONF=$dir/slurm.conf
  slurmctld -f "$SLURM_CONF" -i
  slurmd -f "$SLURM_CONF"
  # Ready when the node is idle (at most 30 s).
  local i state=""
  for i in $(seq 300); do
    state=$(sinfo -h -N -o %T 2>/dev/null || true)
    [ "$state" = idle ] && { echo "export SLURM_CONF=$SLURM_CONF"; return; }
    sleep 0.1
  done
  echo "$0: the node did not become idle in 30 s (state: '${state}'); logs in $dir/log" >&2
  tail -n 20 "$dir"/log/*.log >&2 || true
  stop
  exit 1
}

case $1 in
  start) start ;;
  stop) stop ;;
  *) usage ;;
esac
