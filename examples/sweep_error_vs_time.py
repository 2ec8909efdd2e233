#!/usr/bin/env python3
"""Sweeps one material key of a scene and plots error against run time (springy's Python API).

For each value of the key, the scene is run at a few step sizes (dt / substeps) and once at a
much finer one, the reference. The error of a run is the largest distance of any vertex from its
place in the reference at any frame, as a fraction of the body's size; its cost is the wall
time its steps took. Each value gives one curve of the work-precision plot: how much run time
an accuracy costs, and how that changes with the material.

    PYTHONPATH=build/python python3 examples/sweep_error_vs_time.py \
        --scene scenes/single_sphere.toml --key body.0.strut_period --values 0.05 0.07 0.1

writes sweep.png (log-log, one curve per value) and sweep.csv (every run).
"""
import argparse
import csv
import time

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import springy  # noqa: E402


def trajectory(scene, key, value, substeps, duration, integrator):
    """Every vertex at every frame, the wall time the steps took, and the first body's size."""
    sim = springy.load(scene, set={key: value}, substeps=substeps, duration=duration, integrator=integrator,
                       threads=1, quiet=True)
    frames = max(1, round(duration * sim.fps))
    x = np.empty((frames, *sim.positions.shape))
    wall = 0.0
    for k in range(frames):
        start = time.perf_counter()
        sim.run(until=(k + 1) / sim.fps)
        wall += time.perf_counter() - start
        x[k] = sim.positions  # a copy of the view
    return x, wall, sim.bodies[0].rest_size, sim.dt


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default="scenes/single_sphere.toml")
    parser.add_argument("--key", default="body.0.strut_period", help="the scene key swept (as --set takes it)")
    parser.add_argument("--values", type=float, nargs="+", default=[0.05, 0.07, 0.1])
    parser.add_argument("--substeps", type=int, nargs="+", default=[1, 2, 4, 8])
    parser.add_argument("--reference", type=int, default=32, help="substeps of the reference run")
    parser.add_argument("--duration", type=float, default=2.5, help="seconds simulated (the scene's by default: 2.5)")
    parser.add_argument("--integrator", default=None, help="the scene's by default")
    parser.add_argument("--output", default="sweep.png")
    parser.add_argument("--csv", default="sweep.csv")
    args = parser.parse_args()

    rows = []
    fig, ax = plt.subplots(figsize=(6.4, 4.4), dpi=120)
    for value in args.values:
        reference, _, size, _ = trajectory(args.scene, args.key, value, args.reference, args.duration, args.integrator)
        walls, errors = [], []
        for substeps in args.substeps:
            try:
                x, wall, _, dt = trajectory(args.scene, args.key, value, substeps, args.duration, args.integrator)
            except springy.Unstable as e:  # a step too long for this material: a point the plot leaves out
                print(f"{args.key} = {value:g}, {substeps} substeps: unstable ({e.body_name} at {e.time:.3f} s)")
                rows.append((value, substeps, "", "", "", "unstable"))
                continue
            error = np.linalg.norm(x - reference, axis=2).max() / size
            walls.append(wall)
            errors.append(error)
            rows.append((value, substeps, dt, error, wall, "ok"))
            print(f"{args.key} = {value:g}, {substeps} substeps (dt {dt:.3g} s): error {error:.3g} of the size, "
                  f"{wall:.3f} s")
        ax.loglog(walls, errors, "o-", label=f"{args.key.split('.')[-1]} = {value:g}")
    ax.set_xlabel("run time [s]")
    ax.set_ylabel("largest vertex error / body size")
    ax.set_title(f"{args.scene.split('/')[-1]}: error against run time")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(args.output)
    with open(args.csv, "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(["value", "substeps", "dt", "error", "wall", "status"])
        out.writerows(rows)
    print(f"wrote {args.output} and {args.csv}")


if __name__ == "__main__":
    main()
