"""One list of run options (run/options.h): every option the command line's run commands take is
one the Python module takes, by the same name, checked the same way."""
import re

import pytest

import springy
from conftest import scene

SPHERE = scene("single_sphere")

# The options of check, export and report that write files or pick a format: what the command does
# with a run, not how the run goes.
OUTPUTS = {"--help", "--trace", "--json", "--junit", "--export", "--export-format", "--output", "--format",
           "--fps", "--width", "--height", "--sweep", "--x", "--y", "--study", "--crf", "--preset", "--no-overlay",
           "--no-shadows", "--no-antialias", "--times", "--sheet", "--sheet-only", "--keep-volume"}

# A value each option takes on the single sphere (iterations needs vbd: given with it below).
SAMPLES = {"integrator": "verlet", "dt": 0.001, "tolerance": 1e-3, "iterations": 4, "substeps": 2,
           "duration": 0.1, "threads": 1, "min_volume": 0.5, "end_volume": 0.5, "end_at_rest": True}

# What each option changes, seen from Python (a criterion: the run that fails it).
EFFECTS = {
    "integrator": lambda sim: sim.integrator == "verlet",
    "dt": lambda sim: sim.dt == 0.001 / sim.substeps,
    "tolerance": lambda sim: sim.integrator == "verlet_adaptive",
    "iterations": lambda sim: sim.integrator == "vbd",
    "substeps": lambda sim: sim.substeps == 2,
    "duration": lambda sim: sim.duration == 0.1,
    "threads": lambda sim: sim.threads == 1,
    # A falling ball keeps its volume: half of it passes.
    "min_volume": lambda sim: sim.check()["status"] == "ok",
    "end_volume": lambda sim: sim.check()["status"] == "ok",
    # The ball falls for 0.1 s: not at rest, so the criterion fails the run.
    "end_at_rest": lambda sim: sim.check()["status"] == "failed",
}


def flags(springy_cli, command):
    """The long options `springy COMMAND --help` lists."""
    text = springy_cli(command, "--help").stdout
    return set(re.findall(r"(?:^|[ ,])(--[a-z][a-z0-9-]*)", text, re.M))


@pytest.mark.parametrize("command", ["check", "export", "report", "render", "frames", "suggest"])
def test_every_run_option_of_the_command_line_is_one_of_python(springy_cli, command):
    table = {row["flag"]: row for row in springy.run_options()}
    listed = flags(springy_cli, command)
    assert "--integrator" in listed and "--set" in listed  # the walk reads the help at all
    for flag in sorted(listed - OUTPUTS):
        assert flag in table, f"springy {command} {flag} is not in the run options' table, so Python lacks it"
        assert table[flag]["name"] == flag[2:].replace("-", "_")


def test_python_takes_each_option_and_runs_with_it():
    for row in springy.run_options():
        name = row["name"]
        if name == "set":
            sim = springy.load(SPHERE, set={"body.0.mass": 4}, quiet=True)
            assert sim.bodies[0].mass == 4
            continue
        options = {"duration": 0.1, "integrator": "vbd"} if name == "iterations" else {"duration": 0.1}
        options[name] = SAMPLES[name]
        sim = springy.load(SPHERE, quiet=True, **options)
        sim.run(until=0.05)
        assert sim.time == pytest.approx(0.05, abs=0.002), name
        assert EFFECTS[name](sim), name


def test_vbd_with_its_sweeps_runs_from_python():
    sim = springy.load(SPHERE, integrator="vbd", iterations=4, duration=0.2, quiet=True)
    assert sim.integrator == "vbd"
    record = sim.check()
    assert record["status"] == "ok" and record["integrator"] == "vbd"
    assert record["bodies"][0]["steps"] > 0


def test_a_bad_option_gets_the_command_lines_message():
    with pytest.raises(springy.Error, match=r"--iterations must be between 1 and 1000"):
        springy.load(SPHERE, integrator="vbd", iterations=0)
    with pytest.raises(springy.Error, match=r"--threads must be between 1 and 256"):
        springy.load(SPHERE, threads=300)
    with pytest.raises(springy.Error, match=r"--dt must be a positive finite number of seconds"):
        springy.load(SPHERE, dt=float("nan"))
    with pytest.raises(springy.Error, match=r"add --integrator vbd"):
        springy.load(SPHERE, iterations=4)
    with pytest.raises(springy.Error, match=r"--min-volume must be a fraction from 0 to 1"):
        springy.load(SPHERE, min_volume=2)
    with pytest.raises(TypeError, match=r"'bogus' is not an option of a run; they are: integrator, "):
        springy.load(SPHERE, bogus=1)


def test_the_same_messages_from_the_command_line(springy_cli):
    r = springy_cli("check", SPHERE, "--threads", "300", check=False)
    assert r.returncode != 0 and "--threads must be between 1 and 256" in r.stderr
    r = springy_cli("check", SPHERE, "--iterations", "0", "--integrator", "vbd", check=False)
    assert r.returncode != 0 and "--iterations must be between 1 and 1000" in r.stderr
