#!/usr/bin/env python3
"""Not a test: times `springy render scenes/single_sphere.toml` end to end with several springy
binaries (built from older commits, and the current one), interleaved run by run so that all see
the same machine load. Prints medians per configuration: end-to-end frames/s, the per-stage ms
that `springy render` prints, and CPU seconds per frame (user + system, all threads), and each
binary's ratio to the first.

Usage: tests/render/bench_video.py BINARY BINARY... [runs=3] [duration_s=4] [default]
A binary may be given as LABEL=PATH. "default": only the default configuration (1280x720,
shadows, FXAA); otherwise six (720p and 1080p, shadows and anti-aliasing on and off).
"""
import os, re, resource, statistics, subprocess, sys, tempfile

args = sys.argv[1:]
only_default = "default" in args
args = [a for a in args if a != "default"]
numbers = [a for a in args if re.fullmatch(r"[\d.]+", a)]
binaries = [(a.split("=", 1) if "=" in a else (a, a)) for a in args if a not in numbers]
if len(binaries) < 2:
    sys.exit(__doc__)
runs = int(numbers[0]) if numbers else 3
duration = numbers[1] if len(numbers) > 1 else "4"
scene = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scenes", "single_sphere.toml")
configs = [
    ("720p AA shadows", ["--width", "1280", "--height", "720"]),
    ("720p shadows", ["--width", "1280", "--height", "720", "--no-antialias"]),
    ("720p AA", ["--width", "1280", "--height", "720", "--no-shadows"]),
    ("720p plain", ["--width", "1280", "--height", "720", "--no-antialias", "--no-shadows"]),
    ("1080p AA shadows", ["--width", "1920", "--height", "1080"]),
    ("1080p plain", ["--width", "1920", "--height", "1080", "--no-antialias", "--no-shadows"]),
]
if only_default:
    configs = configs[:1]
pat = re.compile(r"\(([\d.]+) frames/s\); per frame: simulate ([\d.]+) ms, render ([\d.]+) ms, "
                 r"read back ([\d.]+) ms, convert ([\d.]+) ms, encode ([\d.]+) ms")
fields = ["fps", "simulate", "render", "readback", "convert", "encode", "cpu_ms"]
results = {}
with tempfile.TemporaryDirectory() as out:
    for r in range(runs):
        for name, flags in configs:
            for which, binary in binaries:
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
    for which, _ in binaries:
        rows = results[(name, which)]
        med[which] = [statistics.median(col) for col in zip(*rows)]
        print(f"| {name} | {which} | " + " | ".join(f"{v:.1f}" for v in med[which]) + " |")
    first = binaries[0][0]
    for which, _ in binaries[1:]:
        print(f"| {name} | {which}/{first} | {med[which][0] / med[first][0]:.2f}x | | "
              f"{med[which][2] / med[first][2]:.2f}x | | | | {med[which][6] / med[first][6]:.2f}x |")
