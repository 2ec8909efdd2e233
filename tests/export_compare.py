"""The export round trip's checks (tests/export_roundtrip.sh), run by Debian's /usr/bin/python3
with python3-vtk9 and numpy: what readers nobody in springy wrote make of its exports, against
what springy simulated (its trace) and against the mesh's own geometry.

  export_compare.py pvd RUN.pvd TRACE.csv FPS
      ParaView's way into the series: the .pvd collection (XML) names each body's .vtu per time,
      read by VTK's vtkXMLUnstructuredGridReader. Checks the times, the fields and their values.
  export_compare.py blender RUN.pvd POSITIONS.json [--height NAME FRAME Y]...
      Blender's positions (tests/blender_roundtrip.py) at its frames against the series' points,
      within 1e-5 of each body's (or moving collider's) size; with --height, the GLB object NAME's
      world matrix puts its origin at height Y at FRAME (within 1e-6 m).
  export_compare.py colliders RUN.pvd
      The moving colliders' series (group "colliders") read by VTK: a frame at each of the bodies'
      times, each a rigid motion of the first (every distance between two points kept), and moving.
Exit 0 when every check holds; 1 with a message naming the check, body and frame otherwise.
"""
import csv
import json
import math
import os
import sys
import xml.etree.ElementTree as ET

import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy

failures = []


def check(ok, what):
    if not ok:
        failures.append(what)
        print("FAILED: " + what)
    return ok


def read_series(pvd):
    """[(time, part, name, grid, group)] in the collection's order, each .vtu read by VTK."""
    root = ET.parse(pvd).getroot()
    assert root.get("type") == "Collection", pvd + " is not a VTK collection"
    series = []
    for ds in root.iter("DataSet"):
        reader = vtk.vtkXMLUnstructuredGridReader()
        path = os.path.join(os.path.dirname(pvd), ds.get("file"))
        reader.SetFileName(path)
        reader.Update()
        grid = reader.GetOutput()
        if grid.GetNumberOfPoints() == 0:
            raise SystemExit("FAILED: VTK read no points from " + path)
        series.append((float(ds.get("timestep")), int(ds.get("part")), ds.get("name"), grid, ds.get("group")))
    return series


def point_array(grid, name):
    a = grid.GetPointData().GetArray(name)
    return None if a is None else vtk_to_numpy(a)


def field(grid, name):
    a = grid.GetFieldData().GetArray(name)
    return None if a is None else a.GetValue(0)


def points(grid):
    return vtk_to_numpy(grid.GetPoints().GetData()).astype(np.float64)


def edges(grid):
    """The mesh's edges (i < j), from its triangles."""
    cells = vtk_to_numpy(grid.GetCells().GetConnectivityArray()).reshape(-1, 3)
    e = np.concatenate([cells[:, [0, 1]], cells[:, [1, 2]], cells[:, [2, 0]]])
    return np.unique(np.sort(e, axis=1), axis=0)


def by_body(series, group=""):
    """{part: {"name", "frames": [(time, grid)]}} of the bodies (group ""), or of the moving
    colliders (group "colliders")."""
    bodies = {}
    for t, part, name, grid, g in series:
        if g == group:
            bodies.setdefault(part, {"name": name, "frames": []})["frames"].append((t, grid))
    return bodies


def size_of(grid):
    p = points(grid)
    return float(np.linalg.norm(p.max(axis=0) - p.min(axis=0)))


def compare_pvd(pvd, trace_csv, fps):
    series = read_series(pvd)
    bodies = by_body(series)
    trace = {}
    with open(trace_csv) as f:
        for row in csv.DictReader(f):
            trace.setdefault(row["body"], []).append(row)
    dt = 1.0 / fps
    for part, body in sorted(bodies.items()):
        name, frames = body["name"], body["frames"]
        rows = trace.get(name)
        if not check(rows is not None, f"body {name}: not in the trace"):
            continue
        # The trace has a row per frame after the first instant; the series has the first too.
        check(len(frames) == len(rows) + 1, f"body {name}: {len(frames)} frames in the series, "
              f"{len(rows) + 1} in the run")
        for k, (t, grid) in enumerate(frames):
            # Frame k is the state at the step nearest to k / fps: its simulated time.
            check(abs(t - k * dt) <= 0.5 * dt, f"body {name} frame {k}: time {t}, expected {k * dt} "
                  "within half a frame")
            check(abs(field(grid, "TimeValue") - t) < 1e-9, f"body {name} frame {k}: TimeValue differs from the pvd's")
            for array, comps in (("velocity", 3), ("strain", 1), ("contact", 1), ("pinned", 1)):
                a = point_array(grid, array)
                if check(a is not None, f"body {name} frame {k}: no point field '{array}'"):
                    shape = (grid.GetNumberOfPoints(),) if comps == 1 else (grid.GetNumberOfPoints(), comps)
                    check(a.shape == shape and np.all(np.isfinite(a)), f"body {name} frame {k}: '{array}' "
                          f"has shape {a.shape}, expected {shape}, or is not finite")
        size = size_of(frames[0][1])
        mass = point_array(frames[0][1], "mass")
        first = points(frames[0][1])
        e = edges(frames[0][1])
        rest = np.linalg.norm(first[e[:, 1]] - first[e[:, 0]], axis=1)
        for k, row in enumerate(rows, start=1):
            t, grid = frames[k]
            check(abs(float(row["time"]) - t) < 1e-6, f"body {name} frame {k}: trace time {row['time']}, series {t}")
            volume = field(grid, "volume")
            if check(volume is not None, f"body {name} frame {k}: no field 'volume'"):
                check(abs(volume - float(row["volume"])) <= 1e-8 * abs(volume) + 1e-12,
                      f"body {name} frame {k}: volume {volume}, trace {row['volume']}")
            p = points(grid)
            if mass is not None:
                # The simulated mesh itself: its mass-weighted centroid is the trace's.
                c = (p * mass[:, None]).sum(axis=0) / mass.sum()
                ct = np.array([float(row["centroid_x"]), float(row["centroid_y"]), float(row["centroid_z"])])
                check(np.linalg.norm(c - ct) <= 1e-7 * size, f"body {name} frame {k}: centroid {c}, trace {ct}")
                # Velocity: the kinetic energy it gives is the trace's.
                v = point_array(grid, "velocity")
                kinetic = 0.5 * float((mass * (v * v).sum(axis=1)).sum())
                check(abs(kinetic - float(row["kinetic"])) <= 1e-7 * abs(kinetic) + 1e-12,
                      f"body {name} frame {k}: kinetic energy of the velocities {kinetic}, trace {row['kinetic']}")
                # Strain: the largest |l - l0| / l0 of the edges at each vertex, l0 at the first
                # instant (every body starts at its rest shape; its struts are its edges).
                length = np.linalg.norm(p[e[:, 1]] - p[e[:, 0]], axis=1)
                s = np.abs(length - rest) / rest
                expected = np.zeros(len(p))
                np.maximum.at(expected, e[:, 0], s)
                np.maximum.at(expected, e[:, 1], s)
                got = point_array(grid, "strain")
                check(np.max(np.abs(got - expected)) <= 1e-5 * max(1e-3, expected.max()),
                      f"body {name} frame {k}: strain differs from the edges' by {np.max(np.abs(got - expected))}")
                check(abs(float(row["max_strain"]) - expected.max()) <= 1e-4 * max(1e-3, expected.max()),
                      f"body {name} frame {k}: largest strain {expected.max()}, trace {row['max_strain']}")
            # Pinned vertices never move; the others of a falling body do.
            pinned = point_array(grid, "pinned").astype(bool)
            check(np.all(np.abs(p[pinned] - first[pinned]) <= 1e-12 * max(1.0, size)),
                  f"body {name} frame {k}: a pinned vertex moved")
        # Touching: the bodies of the test's scene meet only the ground (y = 0), apart from each
        # other: a body that reaches the ground touches it at some frame, and a vertex well above
        # the body's lowest never touches.
        reached = touched_any = False
        for k, (t, grid) in enumerate(frames):
            p, contact = points(grid), point_array(grid, "contact").astype(bool)
            low = p[:, 1] - p[:, 1].min()
            reached = reached or p[:, 1].min() < 0.01 * size
            touched_any = touched_any or contact.any()
            check(not np.any(contact & (low > 0.25 * size)), f"body {name} frame {k}: a vertex "
                  f"{low[contact].max() if contact.any() else 0:.3g} m above the body's lowest touches")
        check(touched_any == reached, f"body {name}: {'reaches' if reached else 'never reaches'} the ground, "
              f"{'touches' if touched_any else 'never touches'}")
        touched = any(point_array(g, "contact").any() for _, g in frames)
        print(f"  {name}: {len(frames)} frames, {frames[0][1].GetNumberOfPoints()} points, size {size:.3g}, "
              f"{'touches' if touched else 'never touches'}, "
              f"{int(point_array(frames[0][1], 'pinned').sum())} pinned")
    return bodies


def compare_colliders(pvd):
    series = read_series(pvd)
    times = [t for t, _ in next(iter(by_body(series).values()))["frames"]]
    colliders = by_body(series, "colliders")
    check(len(colliders) > 0, f"{pvd}: a moving collider's series")
    for part, collider in sorted(colliders.items()):
        name, frames = collider["name"], collider["frames"]
        check([t for t, _ in frames] == times, f"{name}: a frame at each of the bodies' {len(times)} times")
        first = points(frames[0][1])
        size = size_of(frames[0][1])
        pairs = np.linalg.norm(first[:, None, :] - first[None, :, :], axis=2)
        moved = 0.0
        for k, (t, grid) in enumerate(frames):
            check(abs(field(grid, "TimeValue") - t) < 1e-9, f"{name} frame {k}: TimeValue differs from the pvd's")
            p = points(grid)
            if not check(p.shape == first.shape, f"{name} frame {k}: {p.shape} points, the first frame {first.shape}"):
                continue
            d = np.linalg.norm(p[:, None, :] - p[None, :, :], axis=2)
            check(np.abs(d - pairs).max() <= 1e-9 * size, f"{name} frame {k}: not a rigid motion of the first frame")
            moved = max(moved, float(np.abs(p - first).max()))
        check(moved > 1e-3 * size, f"{name}: moves ({moved:.3g} m at most)")
        print(f"  {name}: {len(frames)} frames, {len(first)} points, size {size:.3g}, moves {moved:.3g} m at most")


def compare_blender(pvd, positions_json, heights=()):
    series = read_series(pvd)
    with open(positions_json) as f:
        blender = json.load(f)
    print(f"  Blender {blender['blender']}")
    compare_blender_bodies(by_body(series), blender)
    compare_blender_colliders(by_body(series, "colliders"), blender)
    for name, frame, y in heights:
        at = blender.get("glb_placement", {}).get(name, {}).get(frame)
        if check(at is not None, f"glb: no placement of {name} at frame {frame}"):
            check(abs(at[1] - float(y)) <= 1e-6, f"glb {name} frame {frame}: its world matrix puts it at height "
                  f"{at[1]:.9g}, expected {y}")
            print(f"  glb {name} frame {frame}: at height {at[1]:.9g} (expected {y})")


def compare_blender_colliders(colliders, blender):
    """Each moving collider as Blender has it: the OBJ's object NAME (no spaces) under its own
    Mesh Cache, the GLB's object NAME placed by its animation; against the series' points."""
    for source in ("obj", "glb"):
        objects = blender.get(source, {})
        for part, collider in sorted(colliders.items()):
            name = collider["name"].replace(" ", "") if source == "obj" else collider["name"]
            if not check(name in objects, f"{source}: no object named {name} (has {sorted(objects)})"):
                continue
            size = size_of(collider["frames"][0][1])
            for frame, got in objects[name].items():
                expected = points(collider["frames"][int(frame)][1])
                got = np.array(got)
                if check(got.shape == expected.shape, f"{source} {name} frame {frame}: {got.shape} points, "
                         f"the series has {expected.shape}"):
                    err = float(np.abs(got - expected).max())
                    check(err <= 1e-5 * size, f"{source} {name} frame {frame}: Blender's vertices differ from "
                          f"springy's by {err:.3g} m, over 1e-5 of its size {size:.3g} m")
                    print(f"  {source} {name} frame {frame}: largest difference {err:.2g} m = {err / size:.2g} of its size")


def compare_blender_bodies(bodies, blender):
    order = sorted(bodies)
    for source in ("obj", "glb"):
        if source not in blender:
            continue
        objects = blender[source]
        for frame in next(iter(objects.values())).keys():
            k = int(frame)
            expected = {part: points(bodies[part]["frames"][k][1]) for part in order}
            if source == "obj":
                # One object: the bodies' points one after another, in the bodies' order.
                got_all = np.array(objects["springy"][frame]) if check("springy" in objects, "obj: no object 'springy'") \
                    else None
                if got_all is None:
                    continue
                got, at = {}, 0
                for part in order:
                    n = len(expected[part])
                    got[part] = got_all[at:at + n]
                    at += n
                check(at == len(got_all), f"obj frame {k}: {len(got_all)} points, the bodies have {at}")
            else:
                got = {}
                for part in order:
                    name = bodies[part]["name"]
                    if check(name in objects, f"glb: no object named {name} (has {sorted(objects)})"):
                        got[part] = np.array(objects[name][frame])
            for part in order:
                if part not in got:
                    continue
                name = bodies[part]["name"]
                size = size_of(bodies[part]["frames"][0][1])
                if not check(got[part].shape == expected[part].shape,
                             f"{source} {name} frame {k}: {got[part].shape} points, the series has {expected[part].shape}"):
                    continue
                err = float(np.abs(got[part] - expected[part]).max())
                check(err <= 1e-5 * size, f"{source} {name} frame {k}: Blender's vertices differ from springy's by "
                      f"{err:.3g} m, over 1e-5 of the body's size {size:.3g} m")
                print(f"  {source} {name} frame {k}: largest difference {err:.2g} m = {err / size:.2g} of its size")


def main():
    mode = sys.argv[1]
    if mode == "pvd":
        compare_pvd(sys.argv[2], sys.argv[3], float(sys.argv[4]))
    elif mode == "blender":
        rest = sys.argv[4:]
        heights = [tuple(rest[i + 1:i + 4]) for i in range(0, len(rest), 4) if rest[i] == "--height"]
        compare_blender(sys.argv[2], sys.argv[3], heights)
    elif mode == "colliders":
        compare_colliders(sys.argv[2])
    else:
        raise SystemExit("usage: export_compare.py pvd|blender|colliders ...")
    if failures:
        print(f"{len(failures)} checks failed")
        sys.exit(1)


main()
