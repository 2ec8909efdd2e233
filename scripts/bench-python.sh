#!/usr/bin/env bash
# The Python module's cost (docs/benchmarks.md, "The Python module"): sim.run against `springy
# check` on the same scenes, idle and with a busy loop on the other core, and the cost of one
# Python call of sim.step(). Uses the build in build/ (scripts/build.sh).
#   scripts/bench-python.sh [ROUNDS]        ROUNDS: interleaved pairs per scene (default 7)
set -euo pipefail
cd "$(dirname "$0")/.."
rounds=${1:-7}
export PYTHONPATH=$PWD/build/python
py=/usr/bin/python3
bin=build/app/springy
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'); $(date -u)"
runs() {
  $py scripts/bench_python.py run $bin scenes/single_sphere.toml "$rounds"
  $py scripts/bench_python.py run $bin scenes/stack.toml "$rounds" 1
  $py scripts/bench_python.py run $bin scenes/jelly.toml "$rounds" 3
}
echo "-- idle"
runs
echo "-- busy (a loop on the other core)"
sh -c 'while :; do :; done' &
busy=$!
trap 'kill $busy 2>/dev/null' EXIT
runs
kill $busy
trap - EXIT
echo "-- the cost of a call"
$py scripts/bench_python.py step $bin scenes/single_sphere.toml 20000 5
