#!/usr/bin/env python3
"""Not a test: times `springy render scenes/single_sphere.toml` end to end, BEFORE (a springy
binary built from an older commit) against AFTER, interleaved run by run so that both see the
same machine load. Prints medians per configuration: end-to-end frames/s, the per-stage ms that
`springy render` prints, and CPU seconds per frame (user + system, all threads).

Usage: tests/render/bench_video.py BEFORE_BINARY AFTER_BINARY [runs=3] [duration_s=4]
"""
import os, re, resource, statistics, subprocess, sys, tempfile

before, after = sys.argv[1], sys.argv[2]
runs = int(sys.argv[3]) if len(sys.argv) > 3 else 3
duration = sys.argv[4] if len(sys.argv) > 4 else "4"
scene = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scenes", "single_sphere.toml")
configs = [
    ("720p AA shadows", ["--width", "1280", "--height", "720"]),
    ("720p shadows", ["--width", "1280", "--height", "720", "--no-antialias"]),
    ("720p AA", ["--width", "1280", "--height", "720", "--no-shadows"]),
    ("720p plain", ["--width", "1280", "--height", "720", "--no-antialias", "--no-shadows"]),
    ("1080p AA shadows", ["--width", "1920", "--height", "1080"]),
    ("1080p plain", ["--width", "1920", "--height", "1080", "--no-antialias", "--no-shadows"]),
]
pat = re.compile(r"\(([\d.]+) frames/s\); per frame: simulate ([\d.]+) ms, render ([\d.]+) ms, "
                 r"read back ([\d.]+) ms, convert ([\d.]+) ms, encode ([\d.]+) ms")
fields = ["fps", "simulate", "render", "readback", "convert", "encode", "cpu_ms"]
results = {}
with tempfile.TemporaryDirectory() as out:
    for r in range(runs):
        for name, flags in configs:
            for which, binary in (("before", before), ("after", after)):
                t0 = resource.getrusage(resource.RUSAGE_CHILDREN)
                p = subprocess.run([binary, "render", scene, "--duration", duration, *flags, "-o",
                                    os.path.join(out, "v.mp4")], capture_output=True, text=True, check=True)
                t1 = resource.getrusage(resource.RUSAGE_CHILDREN)
                m = pat.search(p.stdout)
                frames = int(re.search(r": (\d+) frames", p.stdout).group(1))
                cpu = (t1.ru_utime - t0.ru_utime + t1.ru_stime - t0.ru_stime) * 1000.0 / frames
                row = [float(x) for x in m.groups()] + [cpu]
                results.setdefault((name, which), []).append(row)
                print(f"run {r + 1} {name:18s} {which:6s} " +
                      " ".join(f"{f}={v:.1f}" for f, v in zip(fields, row)), flush=True)

print("\nmedians of", runs, "runs; ms per frame except fps; cpu_ms = CPU time of all threads per frame")
print("| configuration | version | frames/s | simulate | render | read back | convert | encode | CPU ms/frame |")
print("|---|---|---|---|---|---|---|---|---|")
for name, _ in configs:
    med = {}
    for which in ("before", "after"):
        rows = results[(name, which)]
        med[which] = [statistics.median(col) for col in zip(*rows)]
        print(f"| {name} | {which} | " + " | ".join(f"{v:.1f}" for v in med[which]) + " |")
    print(f"| {name} | after/before | {med['after'][0] / med['before'][0]:.2f}x | | "
          f"{med['after'][2] / med['before'][2]:.2f}x | | | | {med['after'][6] / med['before'][6]:.2f}x |")
