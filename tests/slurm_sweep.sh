#!/usr/bin/env bash
# ctest slurm_sweep: an 8-task sweep through a real Slurm cluster equals the local runner's, bit
# for bit. Starts a single-node cluster on localhost (scripts/slurm-local.sh: munged, slurmctld,
# slurmd, a config written into a temporary directory, no systemd), submits the sweep with
# `springy sweep --slurm` (a job array and a gather job after it), waits for the gather with a time
# limit, and compares the manifest, the tables and the map with a local run's. Every daemon it
# started is stopped on any exit (trap), and by a watchdog should the test itself be killed.
# Fails, never skips, without root or Slurm: scripts/install-deps.sh installs it.
# usage: slurm_sweep.sh SPRINGY SOURCE_DIR
set -euo pipefail
springy=$1
source_dir=$2
work=$(mktemp -d /tmp/springy-slurm-test.XXXXXX)
cluster=$work/cluster

cleanup() {
  local status=$?
  bash "$source_dir/scripts/slurm-local.sh" stop "$cluster" || status=1
  [ $status -eq 0 ] && rm -rf "$work" || echo "slurm_sweep: kept $work for a look" >&2
  exit $status
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM
# Should this script be killed outright (SIGKILL: a ctest timeout), a watchdog stops the daemons.
( while kill -0 $$ 2>/dev/null; do sleep 1; done; bash "$source_dir/scripts/slurm-local.sh" stop "$cluster" ) \
  >/dev/null 2>&1 </dev/null &

fail() { echo "slurm_sweep: FAILED: $*" >&2; exit 1; }

unset SLURM_CONF
eval "$(bash "$source_dir/scripts/slurm-local.sh" start "$cluster")"
[ -n "${SLURM_CONF:-}" ] || fail "the cluster did not start"

# Eight tasks: dt x stiffness over a short drop (it lands at 0.7 s).
cat >"$work/grid.toml" <<EOF
scenes = ["$source_dir/scenes/single_sphere.toml"]
command = "check"
args = ["--min-volume", "0.95"]
[set]
duration = 1.2
"body.position" = [0.0, 8.0, 0.0]
[grid]
dt = [0.002, 0.004]
body.strut_period = [0.04, 0.07, 0.1, 0.2]
EOF

cd "$work"
"$springy" sweep grid.toml -o local >local.out || fail "the local sweep failed: $(cat local.out)"
t0=$SECONDS
"$springy" sweep grid.toml -o slurm --slurm --max-running 4 >submit.out || fail "sweep --slurm failed"
grep -q "submitted job array" submit.out || fail "no job array submitted: $(cat submit.out)"
read -r _ array < <(grep '^array ' slurm/slurm/jobs)
read -r _ gather < <(grep '^gather ' slurm/slurm/jobs)

# Wait for both jobs to leave the queue (at most 120 s).
deadline=$((SECONDS + 120))
while [ -n "$(squeue -h -j "$array,$gather" 2>/dev/null)" ]; do
  [ $SECONDS -lt $deadline ] || { squeue >&2; fail "the jobs did not finish in 120 s"; }
  sleep 0.5
done
echo "slurm_sweep: the jobs took $((SECONDS - t0)) s"
[ -f slurm/table.csv ] || fail "the gather job wrote no table: $(cat slurm/logs/gather.log 2>/dev/null)"

# Slurm ran every task (each its own log, %4a), and the gather after them.
for i in 0 1 2 3 4 5 6 7; do
  grep -q "^task $i: " "slurm/logs/000$i.log" || fail "no log of task $i from Slurm"
done
grep -q "8 tasks, .* 0 missing" slurm/logs/gather.log || fail "gather: $(cat slurm/logs/gather.log)"
# The same tasks, the same results, byte for byte.
for f in manifest.jsonl table.csv table.json map-single_sphere.png; do
  cmp "local/$f" "slurm/$f" || fail "$f differs between the local runner and Slurm"
done
# Not a vacuous match: the grid has both passing and failing points.
grep -q ',ok,' local/table.csv && grep -q ',failed,' local/table.csv || fail "expected ok and failed points: $(cat local/table.csv)"

# Stop the cluster here and check that no daemon it started is left.
pids=$(cat "$cluster"/run/*.pid)
bash "$source_dir/scripts/slurm-local.sh" stop "$cluster"
for pid in $pids; do
  ! kill -0 "$pid" 2>/dev/null || fail "daemon $pid still running after stop"
done
echo "slurm_sweep: 8 tasks through Slurm equal the local runner's ($((SECONDS)) s)"
