"""springy from Python: load a scene, step it, read and set its state as numpy arrays, check it,
render it, and run the command line's render, frames and study (docs/python.md).

    import springy
    sim = springy.load("scenes/single_sphere.toml", set={"body.0.mass": 4})
    sim.run(until=1.0)                 # releases the GIL; Ctrl-C stops it between frames
    ball = sim.bodies[0]
    ball.positions                     # (N, 3) float64, a read-only view of the state (no copy)
    record = sim.check()               # check --json's fields; a blow-up raises springy.Unstable
    image = sim.render(640, 360)       # (360, 640, 3) uint8, as `springy frames` draws it
"""

import csv as _csv
import json as _json
import math as _math
import os as _os

import numpy as _np

from . import _springy
from ._springy import Error, RenderError, Unstable

__all__ = ["load", "Simulation", "Body", "Error", "RenderError", "Unstable", "render_video", "frames",
           "study", "load_study", "integrators", "run_options"]


def _toml_value(key, value):
    """A Python value as the TOML text `--set KEY=VALUE` takes."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if _math.isnan(value):
            return "nan"
        if _math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)  # the shortest text that reads back to the same double
    if isinstance(value, str):
        return _json.dumps(value)  # a TOML basic string
    if isinstance(value, (list, tuple, _np.ndarray)):
        return "[" + ", ".join(_toml_value(key, v) for v in list(value)) + "]"
    if isinstance(value, _np.generic):
        return _toml_value(key, value.item())
    raise TypeError(f"set[{key!r}]: {type(value).__name__} is not a scene value "
                    "(a number, a string, a bool, or a list of them)")


def _settings(set):
    if set is None:
        return []
    if not isinstance(set, dict):
        raise TypeError("set: expected a dict of scene keys to values, e.g. {'body.0.mass': 4}")
    out = []
    for key, value in set.items():
        if not isinstance(key, str) or not key:
            raise TypeError(f"set: the key {key!r} is not a dotted scene key such as 'body.0.mass'")
        out.append(f"{key}={_toml_value(key, value)}")
    return out


def _option_text(name, value):
    """A run option's value as the command line's text (run/options.h reads it there and here)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, _np.integer)):
        return str(int(value))
    if isinstance(value, (float, _np.floating)):
        return repr(float(value))  # the shortest text that reads back to the same double
    if isinstance(value, str):
        return value
    raise TypeError(f"{name}: {type(value).__name__} is not an option value (a number, a string or a bool)")


def _options(options):
    """Keyword options of a run as {name: text}: None leaves an option at the scene's value."""
    return {name: _option_text(name, value) for name, value in options.items() if value is not None}


def run_options():
    """The options a run takes (load's keywords, the commands' options), as the command line's
    table lists them: [{name, flag, value, help, criterion, repeatable}]."""
    return _springy.run_options()


def _paths(scenes):
    if isinstance(scenes, (str, _os.PathLike)):
        return [_os.fspath(scenes)]
    return [_os.fspath(s) for s in scenes]


class Body:
    """One body of a simulation. Its vertices are in springy's order (along the body's longest
    side); `mesh_order` maps them back to the mesh file's: positions[mesh_order] lists them in
    the file's order. Views stay valid as long as the simulation and change as it steps."""

    def __init__(self, sim, index):
        self._sim = sim
        self.index = index
        info = sim._core.body_info(index)
        self.name = info["name"]
        self.mass = info["mass"]
        self.rest_volume = info["rest_volume"]
        self.rest_size = info["rest_size"]
        self.open = info["open"]
        self.vertex_count = info["vertex_count"]

    def __repr__(self):
        return f"<springy.Body {self.index} '{self.name}': {self.vertex_count} vertices>"

    @property
    def positions(self):
        """(N, 3) float64, a read-only view of the state: set it with `body.positions = array`."""
        return self._sim._core.positions(self.index)

    @positions.setter
    def positions(self, value):
        self._sim._core.set_positions(value, self.index)

    @property
    def velocities(self):
        """(N, 3) float64, a read-only view of the state: set it with `body.velocities = array`."""
        return self._sim._core.velocities(self.index)

    @velocities.setter
    def velocities(self, value):
        self._sim._core.set_velocities(value, self.index)

    @property
    def rest_positions(self):
        """(N, 3) float64, read-only: the shape the struts and hinges hold at rest."""
        return self._sim._core.rest_positions(self.index)

    @property
    def masses(self):
        """(N,) float64, read-only: each vertex's mass [kg]."""
        return self._sim._core.masses(self.index)

    @property
    def faces(self):
        """(F, 3) uint32, a copy: the simulated surface's triangles, outward, as indices into positions."""
        return self._sim._core.faces(self.index)

    @property
    def mesh_order(self):
        """(N,) uint32: positions[mesh_order[k]] is the mesh file's vertex k."""
        return self._sim._core.mesh_order(self.index)

    def measures(self):
        """The body now: centroid, momentum, energies [J], volume, size, max_strain, contacts (its
        vertices touching a collider or a body), ..."""
        return self._sim._core.measures(self.index)


class Simulation:
    """A scene loaded as `springy check` loads it, stepped as check steps it (the same frames,
    the same monitor, the same bits). Made by springy.load()."""

    def __init__(self, core):
        self._core = core
        self.bodies = [Body(self, i) for i in range(core.body_count)]

    def __repr__(self):
        try:
            now = f"t = {self.time:g} s, {self.integrator}"
        except RuntimeError:  # another thread's call holds it (docs/python.md): no clock to read
            now = "busy"
        return f"<springy.Simulation '{self.name}': {len(self.bodies)} bodies, {now}>"

    # The state and the clock.
    time = property(lambda self: self._core.time, doc="simulated time [s]")
    dt = property(lambda self: self._core.dt, doc="the step [s] (the adaptive step's last)")
    steps = property(lambda self: self._core.steps, doc="steps taken")
    force_evaluations = property(lambda self: self._core.force_evaluations)
    integrator = property(lambda self: self._core.integrator)
    substeps = property(lambda self: self._core.substeps)
    duration = property(lambda self: self._core.duration, doc="the scene's duration [s]")
    fps = property(lambda self: self._core.fps, doc="the scene's frame rate: run() checks at each frame")
    threads = property(lambda self: self._core.threads)
    name = property(lambda self: self._core.name, doc="the scene's name")
    state_hash = property(lambda self: self._core.state_hash,
                          doc="FNV-1a of the state's bits: equal hashes, bit-identical states")

    @property
    def positions(self):
        """(V, 3) float64, every body's vertices in model order; a read-only view."""
        return self._core.positions()

    @positions.setter
    def positions(self, value):
        self._core.set_positions(value)

    @property
    def velocities(self):
        """(V, 3) float64, every body's vertices in model order; a read-only view."""
        return self._core.velocities()

    @velocities.setter
    def velocities(self, value):
        self._core.set_velocities(value)

    def body(self, name):
        """The body named `name`."""
        for b in self.bodies:
            if b.name == name:
                return b
        raise KeyError(f"{name!r}: the scene's bodies are " + ", ".join(repr(b.name) for b in self.bodies))

    def step(self, n=1, check=True):
        """n steps of the integrator (adaptive: n accepted steps), then the monitor's check
        (check=False leaves it out). Releases the GIL. Raises Unstable."""
        self._core.step(n, check)

    def run(self, until):
        """Steps through each frame time up to `until` [s] (the monitor checks at each, as in
        `springy check`), then to `until`. Releases the GIL; Ctrl-C stops it between frames.
        Raises Unstable with the body, time and message when the monitor stops the run."""
        self._core.run(float(until))

    def check(self, min_volume=None, end_volume=None, end_at_rest=None):
        """Runs to the scene's end and returns check --json's record of the run as a dict (path,
        scene, status, failed_body, message, integrator, dt, substeps, duration, wall_s, bodies:
        body, steps, time,
        max_strain, max_penetration, volume_min, volume_end, kinetic, gravitational, elastic,
        at_rest). The criteria default to load()'s; a failed one gives status "failed"; an
        instability raises Unstable."""
        criteria = _options({"min_volume": min_volume, "end_volume": end_volume, "end_at_rest": end_at_rest})
        return _json.loads(self._core.check(criteria))

    def render(self, width=None, height=None, overlay=True, shadows=True, antialias=True):
        """The scene at this instant as `springy frames` draws it: an (H, W, 3) uint8 array.
        width and height default to the scene's [render] size."""
        return self._core.render(width, height, overlay, shadows, antialias)


def load(path, set=None, quiet=False, auto_substeps=False, **options):
    """Loads a scene file as `springy check` does: `set` sets scene keys first, as --set KEY=VALUE
    ({"body.0.mass": 4, "environment.drag": 0.1}); the keywords are the command line's run options
    (run_options(): integrator, dt, substeps, tolerance, iterations, duration, threads, min_volume,
    end_volume, end_at_rest; substeps="auto" or auto_substeps=True as --substeps auto), checked as
    the command line checks them. quiet=True drops the advisor's and the bodies' notes on stderr
    (the step it chose, a proxy). A bad file, key or option raises springy.Error naming it."""
    if auto_substeps:
        options["substeps"] = "auto"
    core = _springy.Simulation(_os.fspath(path), _settings(set), _options(options), bool(quiet))
    return Simulation(core)


def render_video(scenes, output, set=None, width=None, height=None, fps=None, crf=None, overlay=True, shadows=True,
                 antialias=True, **options):
    """`springy render SCENES -o OUTPUT` with the same options (the run options as load's
    keywords); the same video. Raises springy.Error with the command's message when it fails."""
    _springy.render_video(_paths(scenes), _os.fspath(output), _settings(set), _options(options), width, height, fps,
                          crf, overlay, shadows, antialias)


def frames(scenes, output=".", times=None, sheet=False, sheet_only=False, set=None, width=None, height=None,
           overlay=True, shadows=True, antialias=True, **options):
    """`springy frames SCENES -o OUTPUT --times ...` with the same options; the same PNGs."""
    if times is None:
        times = ""
    elif not isinstance(times, str):
        times = ",".join(repr(float(t)) for t in times)
    _springy.frames(_paths(scenes), _os.fspath(output), times, bool(sheet), bool(sheet_only), _settings(set),
                    _options(options), width, height, overlay, shadows, antialias)


def _column(values):
    """A CSV column as a numpy array: float64 where every cell is a number, else str."""
    try:
        return _np.array([float(v) if v != "" else _math.nan for v in values], dtype=_np.float64)
    except ValueError:
        return _np.array(values, dtype=str)


def load_study(directory):
    """A study's tables (every .csv `springy study` wrote in `directory`) as
    {table: {column: numpy array}}: e.g. load_study("docs")["accuracy"]["error"]."""
    tables = {}
    for name in sorted(_os.listdir(directory)):
        if not name.endswith(".csv"):
            continue
        with open(_os.path.join(directory, name), newline="") as f:
            rows = list(_csv.reader(f))
        if not rows:
            continue
        header, body = rows[0], rows[1:]
        tables[name[:-4]] = {col: _column([r[i] if i < len(r) else "" for r in body]) for i, col in enumerate(header)}
    return tables


def study(kind, output="study", scenes=(), quick=False, repeats=3, max_duration=None):
    """`springy study KIND -o OUTPUT` (accuracy, contact or stability), then its tables as
    load_study(OUTPUT) reads them. repeats and max_duration are --repeats and --max-duration
    (None: the whole of each scene), checked as the command line checks them."""
    _springy.study(kind, _os.fspath(output), _paths(scenes), bool(quick), _option_text("repeats", repeats),
                   None if max_duration is None else _option_text("max_duration", max_duration))
    return load_study(output)


def integrators():
    """The integrators' names, as --integrator takes them."""
    return _springy.integrators()
