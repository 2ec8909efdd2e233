"""Ctrl-C from Python: a long sim.run or render_video stops within a frame with
KeyboardInterrupt, and the video's temporary file is removed."""
import os
import signal
import subprocess
import sys
import time

from conftest import scene

SCRIPT = """
import sys, time, springy
sim = springy.load(sys.argv[1], threads=1, quiet=True)
print("ready", flush=True)
start = time.perf_counter()
try:
    if sys.argv[2] == "run":
        sim.run(until=sim.duration)
    else:
        springy.render_video(sys.argv[1], sys.argv[3], width=320, height=180)
except KeyboardInterrupt:
    print(f"interrupted at t = {sim.time:.3f} s after {time.perf_counter() - start:.2f} s", flush=True)
    sys.exit(0)
print("finished", flush=True)
"""


def interrupt(tmp_path, what):
    out = tmp_path / "video.mp4"
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    p = subprocess.Popen([sys.executable, "-c", SCRIPT, scene("stack"), what, str(out)], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, env=env)
    assert p.stdout.readline().strip() == "ready"
    time.sleep(1.0)
    sent = time.perf_counter()
    p.send_signal(signal.SIGINT)
    stdout, stderr = p.communicate(timeout=60)
    return p.returncode, stdout, stderr, time.perf_counter() - sent, out


def test_ctrl_c_stops_a_run_between_frames(tmp_path):
    status, stdout, stderr, after, _ = interrupt(tmp_path, "run")
    assert status == 0, stderr
    assert stdout.startswith("interrupted at t = "), stdout
    assert after < 5  # the stack's frames take about 0.3 s each here
    t = float(stdout.split("t = ")[1].split(" s")[0])
    assert 0 < t < 12


def test_ctrl_c_stops_render_video_and_leaves_no_file(tmp_path):
    status, stdout, stderr, after, out = interrupt(tmp_path, "video")
    assert status == 0, stderr
    assert stdout.startswith("interrupted"), stdout + stderr
    assert after < 10
    assert os.listdir(tmp_path) == [], os.listdir(tmp_path)  # neither the video nor its temporary file
