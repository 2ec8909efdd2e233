"""Bad values handed to the Python module (issue 63, part D): refused as the command line refuses
them, with its words, naming the body and the vertex; a failed simulation goes on once its state
is set; one call at a time on a simulation."""
import threading

import numpy as np
import pytest

import springy
from conftest import scene

SPHERE = scene("single_sphere")
STACK = scene("stack")


def cli_error(springy_cli, *args):
    """The command line's message for a refused command: its stderr's first line (exit non-zero)."""
    r = springy_cli(*args, check=False)
    assert r.returncode != 0, r.stdout + r.stderr
    return r.stderr.splitlines()[0]


# --- The state's setters: finite, in bounds, no body set onto a point -------------------------

def test_a_position_of_1e308_is_refused_naming_the_body_and_the_vertex():
    sim = springy.load(SPHERE, quiet=True)
    ball = sim.bodies[0]
    before = sim.state_hash
    bad = ball.rest_positions.copy()
    bad[7, 1] = 1e308
    with pytest.raises(ValueError, match=r"^body 0 'ball': positions\[7, 1\] is 1e\+308: "
                                         r"a coordinate must be within 1e6 m of the origin$"):
        ball.positions = bad
    bad[7, 1] = -2e6  # beyond the bound, far below overflow
    with pytest.raises(ValueError, match=r"positions\[7, 1\] is -2e\+06"):
        ball.positions = bad
    assert sim.state_hash == before, "a refused value leaves the state as it was"
    sim.step(10)
    assert sim.steps == 10 and np.all(np.isfinite(ball.positions))


def test_a_body_set_onto_one_point_is_refused():
    sim = springy.load(SPHERE, quiet=True)
    before = sim.state_hash
    with pytest.raises(ValueError, match=r"^body 0 'ball': positions: vertices \d+ and \d+, joined by a strut, are both "
                                         r"at \(0, 0, 0\): a strut's ends must be apart"):
        sim.bodies[0].positions = np.zeros((146, 3))
    with pytest.raises(ValueError, match=r"^sim\.positions: body 0 'ball', vertices \d+ and \d+, joined by a strut"):
        sim.positions = np.full((146, 3), 2.5)
    assert sim.state_hash == before


def test_the_whole_states_setters_name_the_body_and_its_vertex():
    sim = springy.load(STACK, quiet=True, threads=1)
    ball = sim.body("ball 2")
    first = sum(b.vertex_count for b in sim.bodies[:ball.index])  # its vertex 0 in the whole state
    before = sim.state_hash
    x = sim.positions.copy()
    x[first + 5, 2] = np.nan
    with pytest.raises(ValueError, match=rf"^sim\.positions\[{first + 5}, 2\] \(body 2 'ball 2', vertex 5\) is nan: "
                                         r"every value must be finite$"):
        sim.positions = x
    v = np.zeros_like(x)
    v[first + 3, 0] = -1e300
    with pytest.raises(ValueError, match=rf"^sim\.velocities\[{first + 3}, 0\] \(body 2 'ball 2', vertex 3\) is "
                                         r"-1e\+300: a velocity must be within 1e6 m/s on each axis$"):
        sim.velocities = v
    v[first + 3, 0] = -np.inf
    with pytest.raises(ValueError, match=r"\(body 2 'ball 2', vertex 3\) is -inf: every value must be finite"):
        sim.velocities = v
    assert sim.state_hash == before
    # Negative and large (but bounded) velocities are velocities.
    v[first + 3, 0] = -9e5
    sim.velocities = v
    assert sim.velocities[first + 3, 0] == -9e5


# --- After Unstable: setting the state forgets the failure -----------------------------------

def test_setting_the_state_after_unstable_lets_it_step_on():
    sim = springy.load(SPHERE, integrator="explicit_euler", dt=1 / 30, substeps=1, quiet=True)
    with pytest.raises(springy.Unstable):
        sim.run(until=5)
    failed_at = sim.time
    with pytest.raises(springy.Unstable):
        sim.step()  # the refused state is not stepped
    assert sim.render(64, 48).shape == (48, 64, 3)  # but it can be looked at
    ball = sim.bodies[0]
    ball.positions = ball.rest_positions + [0, 2, 0]
    ball.velocities = np.zeros((ball.vertex_count, 3))
    lifted = ball.measures()["centroid"][1]
    sim.step(3)  # the docs' way on: set the state, step (the monitor watches again from here)
    assert sim.time == pytest.approx(failed_at + 3 / 30)
    assert np.all(np.isfinite(ball.positions))
    assert ball.measures()["centroid"][1] < lifted, "it falls"


# --- One call at a time on a simulation ------------------------------------------------------

def test_a_second_thread_is_refused_while_run_holds_the_simulation():
    def loaded():
        return springy.load(STACK, duration=0.2, threads=1, quiet=True)

    sim = loaded()
    vertices = sim.positions.shape[0]
    errors, seen = [], []
    worker = threading.Thread(target=lambda: sim.run(until=0.05))
    worker.start()
    # run() holds the simulation from its first line to its return; read until it does.
    while worker.is_alive() and not seen:
        try:
            sim.state_hash
        except RuntimeError as e:
            seen.append(e)
    assert seen, "run() ended before it was seen holding the simulation"
    for call in (lambda: sim.step(), lambda: sim.run(until=0.1), lambda: sim.check(),
                 lambda: setattr(sim, "velocities", np.zeros((vertices, 3))), lambda: sim.render(64, 48),
                 lambda: sim.bodies[0].measures(), lambda: sim.time, lambda: sim.positions):
        try:
            call()
        except RuntimeError as e:
            errors.append(str(e))
    worker.join()
    assert len(errors) == 8, errors
    assert str(seen[0]).startswith("simulation busy: run() is in progress on another thread (sim.state_hash refused")
    assert errors and all(e.startswith("simulation busy: run() is in progress on another thread") for e in errors)
    # Nothing touched it meanwhile: the same state as the same run alone.
    alone = loaded()
    alone.run(until=0.05)
    assert sim.time == alone.time and sim.state_hash == alone.state_hash
    sim.step()  # free again


# --- Options and the study's numbers: the command line's checks and words --------------------

@pytest.mark.parametrize("name, value", [
    ("dt", float("nan")), ("dt", -1.0), ("duration", -5), ("duration", float("inf")), ("tolerance", float("nan")),
    ("substeps", 0), ("iterations", 0), ("threads", 0), ("min_volume", float("nan")), ("end_volume", 2),
    ("integrator", "rk5"), ("threads", 2.5),
])
def test_load_refuses_what_check_refuses_with_its_words(springy_cli, name, value):
    flag = "--" + name.replace("_", "-")
    text = repr(value) if isinstance(value, float) else str(value)
    said = cli_error(springy_cli, "check", SPHERE, flag, text)
    with pytest.raises(springy.Error) as caught:
        springy.load(SPHERE, quiet=True, **{name: value})
    assert str(caught.value) == said


def test_checks_criteria_are_the_command_lines(springy_cli):
    sim = springy.load(SPHERE, duration=0.1, quiet=True)
    for name, value in (("min_volume", float("nan")), ("end_volume", -0.5), ("min_volume", 1.5)):
        said = cli_error(springy_cli, "check", SPHERE, "--" + name.replace("_", "-"), repr(value))
        with pytest.raises(springy.Error) as caught:
            sim.check(**{name: value})
        assert str(caught.value) == said
    assert sim.time == 0, "a refused criterion runs nothing"


@pytest.mark.parametrize("kind, given, args", [
    ("accuracy", {"repeats": 0}, ["--repeats", "0"]),
    ("accuracy", {"repeats": 1001}, ["--repeats", "1001"]),
    ("accuracy", {"repeats": 2.5}, ["--repeats", "2.5"]),
    ("contact", {"max_duration": float("nan")}, ["--max-duration", "nan"]),
    ("contact", {"max_duration": -5}, ["--max-duration", "-5"]),
    ("contact", {"max_duration": 0}, ["--max-duration", "0"]),
    ("precision", {}, []),
])
def test_study_refuses_what_the_command_line_refuses_with_its_words(springy_cli, tmp_path, kind, given, args):
    # --quick and one small scene: a value let through runs a short study, not the default one.
    out = tmp_path / "study"
    said = cli_error(springy_cli, "study", kind, "--quick", "--scenes", SPHERE, "-o", out, *args)
    with pytest.raises(springy.Error) as caught:
        springy.study(kind, out, scenes=[SPHERE], quick=True, **given)
    assert str(caught.value) == said
    assert not out.exists(), "a refused study writes nothing"
