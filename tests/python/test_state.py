"""The Python module against the command line: the same run to the bit, zero-copy views of the
state, the GIL released while stepping, and bad input as Python exceptions."""
import csv
import json
import threading
import time

import numpy as np
import pytest

import springy
from conftest import scene

SPHERE = scene("single_sphere")


def trace_row(sim, body):
    """A row of `springy check --trace` for the body now, formatted as check formats it."""
    m = body.measures()
    cx, cy, cz = m["centroid"]
    numbers = "".join(f",{v:.9g}" for v in (cx, cy, cz, m["volume"], m["kinetic"], m["gravitational"],
                                            m["elastic"], m["total"]))
    return f"{sim.name},{sim.time:.6f},{body.name}{numbers},{m['max_strain']:.6g},{m['contacts']}"


def test_a_drop_matches_check_to_the_bit(tmp_path, springy_cli):
    # The ball lands at 1.7 s and bounces; 3 s cover the impact.
    trace, records = tmp_path / "trace.csv", tmp_path / "check.json"
    springy_cli("check", SPHERE, "--duration", 3, "--trace", trace, "--json", records)
    with open(trace) as f:
        rows = [",".join(r) for r in list(csv.reader(f))[1:]]
    sim = springy.load(SPHERE, duration=3)
    ours = []
    for k in range(1, len(rows) + 1):
        sim.run(until=k / sim.fps)
        ours.append(trace_row(sim, sim.bodies[0]))
    assert len(rows) == 90
    assert ours == rows
    record = sim.check()
    theirs = json.loads(records.read_text())["scenes"][0]
    assert record.keys() == theirs.keys()
    for key in record:
        if key not in ("wall_s", "bodies"):
            assert record[key] == theirs[key], key
    assert record["status"] == "ok"
    # Every number of check's per-body record is written exactly (shortest round trip): equal
    # floats here are equal bits.
    assert record["bodies"] == theirs["bodies"]
    assert record["bodies"][0]["volume_min"] < 0.99  # it landed: squashed


def test_the_same_state_on_one_and_two_threads():
    hashes = []
    for threads in (1, 2):
        sim = springy.load(scene("stack"), duration=0.2, threads=threads)
        sim.run(until=0.2)
        hashes.append(sim.state_hash)
    assert hashes[0] == hashes[1]


def address(array):
    return array.__array_interface__["data"][0]


def test_views_are_the_state_without_a_copy():
    sim = springy.load(SPHERE)
    ball = sim.bodies[0]
    x, v = ball.positions, ball.velocities
    assert x.shape == (146, 3) and x.dtype == np.float64
    assert not x.flags.writeable and not v.flags.writeable
    start, where = x.copy(), address(x)
    sim.step(50)
    assert address(ball.positions) == where
    assert np.all(x[:, 1] < start[:, 1])  # the view itself shows the fall
    np.testing.assert_array_equal(x, sim.positions[:146])
    assert np.all(v[:, 1] < 0)
    with pytest.raises(ValueError):
        x[0, 0] = 1.0  # read-only: the state changes only through the checked setters
    # Setting the state copies into the same buffer: the view stays the state.
    ball.positions = start
    assert address(ball.positions) == where
    np.testing.assert_array_equal(x, start)
    ball.velocities = np.zeros((146, 3))
    assert np.all(v == 0)


def test_rest_positions_masses_faces_and_mesh_order():
    sim = springy.load(SPHERE)
    ball = sim.bodies[0]
    assert ball.name == "ball" and sim.body("ball") is ball
    np.testing.assert_array_equal(ball.rest_positions, ball.positions)
    assert ball.masses.sum() == pytest.approx(8.0, rel=1e-12)
    faces = ball.faces
    assert faces.shape == (288, 3) and faces.max() == 145  # 4 n^2 + 2 vertices, 8 n^2 faces (n = 6)
    # Outward: the faces' signed volume is the ball's.
    p = ball.rest_positions[faces]
    volume = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6
    assert volume == pytest.approx(ball.rest_volume, rel=1e-9)
    assert sorted(ball.mesh_order) == list(range(146))


def test_the_gil_is_released_while_stepping():
    sim = springy.load(scene("stack"), duration=2, threads=1)
    ticks = []
    running = threading.Event()

    def count():
        while running.is_set():
            ticks.append(time.perf_counter())

    sim.step(2)  # warm
    running.set()
    counter = threading.Thread(target=count)
    counter.start()
    time.sleep(0.01)
    start = time.perf_counter()
    sim.step(1000, check=False)  # one call (about 0.9 s here): no return to Python until it ends
    end = time.perf_counter()
    running.clear()
    counter.join()
    during = [t for t in ticks if start < t < end]
    assert end - start > 0.2, "the call should take long enough to see"
    # Held, the GIL would let the counter run only when the call returns.
    assert len(during) > 1000
    assert during[-1] - during[0] > 0.8 * (end - start)


def test_bad_input_raises_clear_exceptions():
    sim = springy.load(SPHERE)
    ball = sim.bodies[0]
    with pytest.raises(ValueError, match=r"expected shape \(146, 3\), got \(145, 3\)"):
        ball.positions = np.zeros((145, 3))
    with pytest.raises(ValueError, match=r"expected shape \(146, 3\), got \(438,\)"):
        ball.velocities = np.zeros(438)
    bad = ball.positions.copy()
    bad[7, 2] = np.nan
    with pytest.raises(ValueError, match=r"positions\[7, 2\] is nan: every value must be finite"):
        ball.positions = bad
    with pytest.raises(TypeError, match="real numbers"):
        ball.positions = np.full((146, 3), "a")
    with pytest.raises(IndexError, match="the scene has 1 bodies"):
        sim._core.positions(3)
    with pytest.raises(KeyError, match="'ball'"):
        sim.body("nothing")
    with pytest.raises(ValueError, match="finite"):
        sim.run(until=float("nan"))
    with pytest.raises(ValueError, match="n must be 0 or more"):
        sim.step(-1)
    with pytest.raises(springy.Error, match="masss"):
        springy.load(SPHERE, set={"body.0.masss": 4})
    with pytest.raises(springy.Error, match="no_such_scene.toml"):
        springy.load("no_such_scene.toml")
    with pytest.raises(springy.Error, match="--integrator: 'rk5'"):
        springy.load(SPHERE, integrator="rk5")
    with pytest.raises(TypeError, match=r"set\['body.0.mass'\]: dict"):
        springy.load(SPHERE, set={"body.0.mass": {}})
    with pytest.raises(ValueError, match="even"):
        sim.render(101, 64)
    # None of it touched the simulation.
    assert sim.time == 0 and sim.steps == 0
    np.testing.assert_array_equal(ball.positions, ball.rest_positions)
    sim.run(until=0.1)
    assert sim.time == pytest.approx(0.1, abs=1e-3)


def test_settings_reach_the_scene():
    heavy = springy.load(SPHERE, set={"body.0.mass": 4.0, "scene.duration": 2})
    assert heavy.bodies[0].mass == pytest.approx(4.0)
    assert heavy.duration == 2
    # Without an index a key is set on every body, as --set body.KEY=VALUE does.
    every = springy.load(SPHERE, set={"body.mass": 2, "body.position": [0.0, 30, 0.0]})
    assert every.bodies[0].mass == pytest.approx(2.0)
    assert every.bodies[0].measures()["centroid"][1] == pytest.approx(30.0, abs=1e-9)


def test_a_blow_up_raises_unstable_with_the_body_and_time():
    sim = springy.load(SPHERE, integrator="explicit_euler", dt=1 / 30, substeps=1)
    with pytest.raises(springy.Unstable) as caught:
        sim.run(until=5)
    e = caught.value
    assert e.body == 0 and e.body_name == "ball"
    assert 0 < e.time <= 5 and e.step > 0
    assert "ball" in e.message and str(e) == e.message
    assert not e.criterion
    with pytest.raises(springy.Unstable):
        sim.step()  # the state is what the monitor refused
    # check() raises it with check's record of the failed run.
    with pytest.raises(springy.Unstable) as caught:
        springy.load(SPHERE, integrator="explicit_euler", dt=1 / 30, substeps=1).check()
    record = caught.value.record
    assert record["status"] == "failed" and record["failed_body"] == "ball"
    assert record["message"] == caught.value.message and record["bodies"][0]["body"] == "ball"
    # A criterion is a check's status, as check --json reports it.
    record = springy.load(SPHERE, duration=3).check(min_volume=0.99)
    assert record["status"] == "failed" and "volume" in record["message"]


def test_quiet_drops_the_advisors_notes(capfd):
    # A step over the stable limit: the advisor warns on stderr, as the command line does.
    springy.load(SPHERE, dt=0.03)
    assert "stable" in capfd.readouterr().err
    springy.load(SPHERE, dt=0.03, quiet=True)
    assert capfd.readouterr().err == ""
