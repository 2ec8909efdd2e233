#!/usr/bin/env python3
"""The Python module's cost against the command line's (scripts/bench-python.sh runs it; results
in docs/benchmarks.md, "The Python module").

run:  `springy check SCENE --threads 1 --json` (its record's wall_s: the run, frame by frame under
      the monitor) against springy.load(SCENE, threads=1).run(until=the last frame), the same
      frames and monitor from Python; ROUNDS rounds, the two interleaved in each, medians.
step: the cost of one Python call of sim.step(): N calls of step(1) against one step(N) on the
      same scene, (T_calls - T_one) / N, with and without the monitor's check after each call.
"""
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import springy


def check_wall(binary, scene, extra):
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "r.json")
        subprocess.run([binary, "check", scene, "--threads", "1", "--json", out, *extra], check=True,
                       capture_output=True)
        with open(out) as f:
            return json.load(f)["scenes"][0]["wall_s"]


def python_wall(scene, duration):
    kwargs = {"duration": duration} if duration else {}
    sim = springy.load(scene, threads=1, **kwargs)
    end = round(sim.duration * sim.fps) / sim.fps
    start = time.perf_counter()
    sim.run(until=end)
    return time.perf_counter() - start


def main():
    mode, binary = sys.argv[1], sys.argv[2]
    if mode == "run":
        scene, rounds = sys.argv[3], int(sys.argv[4])
        duration = float(sys.argv[5]) if len(sys.argv) > 5 else None
        extra = ["--duration", str(duration)] if duration else []
        cli, py = [], []
        for i in range(rounds):  # interleaved, the order alternating
            pair = [lambda: cli.append(check_wall(binary, scene, extra)), lambda: py.append(python_wall(scene, duration))]
            for f in (pair if i % 2 == 0 else reversed(pair)):
                f()
        c, p = statistics.median(cli), statistics.median(py)
        print(f"{os.path.basename(scene)}{' --duration ' + str(duration) if duration else ''}: check {c:.4f} s "
              f"(range {min(cli):.4f}-{max(cli):.4f}), sim.run {p:.4f} s (range {min(py):.4f}-{max(py):.4f}), "
              f"ratio {p / c:.3f}")
    elif mode == "step":
        scene, n, rounds = sys.argv[3], int(sys.argv[4]), int(sys.argv[5])
        results = {True: [], False: []}
        one = {True: [], False: []}
        for _ in range(rounds):
            for check in (False, True):
                sim = springy.load(scene, threads=1)
                sim.step(10, check)
                start = time.perf_counter()
                for _ in range(n):
                    sim.step(1, check)
                calls = time.perf_counter() - start
                sim = springy.load(scene, threads=1)
                sim.step(10, check)
                start = time.perf_counter()
                sim.step(n, False)
                if check:
                    sim.step(0, True)
                single = time.perf_counter() - start
                results[check].append((calls - single) / n * 1e6)
                one[check].append(single / n * 1e6)
        for check in (False, True):
            print(f"{os.path.basename(scene)}: step(1, check={check}) costs {statistics.median(results[check]):.2f} us "
                  f"more per call than a step inside step({n}) ({statistics.median(one[check]):.2f} us a step; "
                  f"range {min(results[check]):.2f}-{max(results[check]):.2f} us)")


if __name__ == "__main__":
    main()
