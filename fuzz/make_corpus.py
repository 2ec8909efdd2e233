#!/usr/bin/env python3
"""Regenerates the committed seed corpus fuzz/corpus/{scene,mesh} (fuzz/README.md).

scene: the repository's scenes/*.toml and tests/data/**/*.toml.
motion: the scenes among those where something moves on its own (a motion table, pin_motion,
       pin_release, [[attach]]), and small ones (MOTION_SEEDS) that use every motion and attach key.
set:   --set inputs (a byte choosing the scene, then one setting a line; fuzz/fuzz_inputs.h).
mesh:  tests/data/meshes/*, a small sphere (icosphere, 162 vertices, 320 triangles) as ASCII and
       binary PLY, OFF, binary STL and OBJ, a tetrahedron as GLB, COLLADA and 3DS, and truncated
       cuts of some of them; each packed as a fuzz_mesh input (fuzz/mesh_input.py).
Deterministic: running it again gives the same bytes. Run from anywhere:
  python3 fuzz/make_corpus.py
"""
import base64
import json
import math
import pathlib
import shutil
import struct
import sys

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
from mesh_input import pack  # noqa: E402

FUZZ = pathlib.Path(__file__).resolve().parent
ROOT = FUZZ.parent


def icosphere(level):
    t = (1 + math.sqrt(5)) / 2
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
             (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    verts = [tuple(c / math.sqrt(sum(x * x for x in v)) for c in v) for v in verts]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
             (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
             (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(level):
        cache = {}

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                p = [(x + y) / 2 for x, y in zip(verts[a], verts[b])]
                n = math.sqrt(sum(x * x for x in p))
                verts.append(tuple(x / n for x in p))
                cache[key] = len(verts) - 1
            return cache[key]

        new = []
        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            new += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new
    return [tuple(round(x, 6) for x in v) for v in verts], faces


TETRA_V = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]
TETRA_F = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]


def ply_ascii(v, f):
    head = f"ply\nformat ascii 1.0\nelement vertex {len(v)}\nproperty float x\nproperty float y\nproperty float z\n" \
           f"element face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n"
    body = "".join(f"{x:g} {y:g} {z:g}\n" for x, y, z in v) + "".join(f"3 {a} {b} {c}\n" for a, b, c in f)
    return (head + body).encode()


def ply_binary(v, f):
    head = f"ply\nformat binary_little_endian 1.0\nelement vertex {len(v)}\nproperty float x\nproperty float y\n" \
           f"property float z\nelement face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n".encode()
    return head + b"".join(struct.pack("<3f", *p) for p in v) + b"".join(struct.pack("<B3i", 3, *t) for t in f)


def off(v, f):
    return (f"OFF\n{len(v)} {len(f)} 0\n" + "".join(f"{x:g} {y:g} {z:g}\n" for x, y, z in v) +
            "".join(f"3 {a} {b} {c}\n" for a, b, c in f)).encode()


def normal(v, t):
    a, b, c = (v[i] for i in t)
    u = [b[k] - a[k] for k in range(3)]
    w = [c[k] - a[k] for k in range(3)]
    n = (u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0])
    length = math.sqrt(sum(x * x for x in n)) or 1.0
    return tuple(x / length for x in n)


def stl_binary(v, f):
    out = b"springy fuzz corpus: binary STL".ljust(80, b" ") + struct.pack("<I", len(f))
    for t in f:
        out += struct.pack("<12fH", *normal(v, t), *v[t[0]], *v[t[1]], *v[t[2]], 0)
    return out


def obj(v, f):
    lines = [f"v {x:g} {y:g} {z:g}" for x, y, z in v]
    lines += ["f " + " ".join(str(i + 1) for i in t) for t in f]
    return ("# springy fuzz corpus\no sphere\n" + "\n".join(lines) + "\n").encode()


def glb(v, f):
    data = b"".join(struct.pack("<3f", *p) for p in v) + b"".join(struct.pack("<3H", *t) for t in f)
    data += b"\0" * (-len(data) % 4)
    gltf = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]}],
            "buffers": [{"byteLength": len(data)}],
            "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 12 * len(v)},
                            {"buffer": 0, "byteOffset": 12 * len(v), "byteLength": 6 * len(f)}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": len(v), "type": "VEC3",
                           "min": [0, 0, 0], "max": [1, 1, 1]},
                          {"bufferView": 1, "componentType": 5123, "count": 3 * len(f), "type": "SCALAR"}]}
    js = json.dumps(gltf, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    chunks = struct.pack("<I4s", len(js), b"JSON") + js + struct.pack("<I4s", len(data), b"BIN\0") + data
    return struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks


def collada(v, f):
    pos = " ".join(f"{c:g}" for p in v for c in p)
    idx = " ".join(str(i) for t in f for i in t)
    return f"""<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>Y_UP</up_axis></asset>
  <library_geometries>
    <geometry id="tetra" name="tetra"><mesh>
      <source id="tetra-pos"><float_array id="tetra-pos-array" count="{3 * len(v)}">{pos}</float_array>
        <technique_common><accessor source="#tetra-pos-array" count="{len(v)}" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
        </accessor></technique_common></source>
      <vertices id="tetra-vtx"><input semantic="POSITION" source="#tetra-pos"/></vertices>
      <triangles count="{len(f)}"><input semantic="VERTEX" source="#tetra-vtx" offset="0"/><p>{idx}</p></triangles>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="scene"><node id="node"><instance_geometry url="#tetra"/></node></visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
""".encode()


def three_ds(v, f):
    def chunk(cid, payload):
        return struct.pack("<HI", cid, 6 + len(payload)) + payload

    verts = chunk(0x4110, struct.pack("<H", len(v)) + b"".join(struct.pack("<3f", *p) for p in v))
    faces = chunk(0x4120, struct.pack("<H", len(f)) + b"".join(struct.pack("<4H", *t, 0) for t in f))
    obj = chunk(0x4000, b"tetra\0" + chunk(0x4100, verts + faces))
    return chunk(0x4D4D, chunk(0x0002, struct.pack("<I", 3)) + chunk(0x3D3D, obj))


def write(path, data):
    path.write_bytes(data)
    return len(data)


# Small scenes that use every motion and attachment key (scenes/README.md), for fuzz_motion.
BALL = """[[body]]
name = "{name}"
shape = "icosphere"
subdivisions = 1
radius = 0.3
position = {position}
mass = 1.0
"""
MOTION_SEEDS = {
    "attach_springs_to_moving_bar": """[scene]
duration = 1.0
dt = 0.002
""" + BALL.format(name="ball", position="[0, 1, 0]") + """
[[triangles]]
name = "bar"
quads = [[[-0.5, 1.5, -0.1], [-0.5, 1.5, 0.1], [0.5, 1.5, 0.1], [0.5, 1.5, -0.1]]]
[triangles.motion]
keys = [[0, 0, 0, 0], [0.02, 0.1, 0, 0], [0.04, 0.1, 0.1, 0]]
interpolation = "cubic"

[[attach]]
body = "ball"
points = [[0, 1.3, 0]]
to = "bar"
period = 0.5
decay = 2.0
release = 0.03
""",
    "attach_hard_and_two_bodies": """[scene]
dt = 0.001
""" + BALL.format(name="a", position="[0, 1, 0]") + BALL.format(name="b", position="[1, 1, 0]") + """
[[triangles]]
name = "hook"
quads = [[[-0.2, 1.4, -0.2], [-0.2, 1.4, 0.2], [0.2, 1.4, 0.2], [0.2, 1.4, -0.2]]]
[triangles.motion]
spin = 90
axis = [0, 1, 0]
centre = [0, 0, 0]

[[attach]]
body = "a"
points = [[0, 1.3, 0]]
to = "hook"

[[attach]]
body = "b"
points = [[0.7, 1, 0]]
to = "a"
period = 0.2
release = 0.01
""",
    "cloth_pin_track": """[scene]
dt = 0.001
[[body]]
name = "cloth"
shape = "cloth"
size = [0.5, 0.5]
resolution = [4, 4]
position = [0, 1, 0]
mass = 0.1
pin_side = "top"
pin_release = 0.015
[body.pin_motion]
oscillate = [0.1, 0.0, 0.05]
frequency = 20
phase = 45
""",
    "oscillating_plane_and_prop": """[scene]
dt = 0.002
""" + BALL.format(name="ball", position="[0, 0.35, 0]") + """
[[plane]]
point = [0, 0, 0]
normal = [0, 1, 0]
[plane.motion]
oscillate = [0, 0.05, 0]
frequency = 10

[[prop]]
shape = "box"
center = [0, 1, 0]
size = [0.2, 0.2, 0.2]
[prop.motion]
keys = [[0, 0, 0, 0], [1, 0, 1, 0]]
spin = 30
""",
}

# --set seeds: the byte choosing the scene (fuzz/fuzz_inputs.h kSetScenes), then the settings.
SET_SEEDS = {
    "single_sphere_mass": (0, "body.mass=2.0\nscene.duration=0.5"),
    "spheres_first_body": (1, "body.0.strut_period=0.02\nenvironment.drag=0.1"),
    "press_motion_keys": (2, "triangles.0.motion.keys=[[0, 0, 0, 0], [1, 0, -0.5, 0]]"),
    "cape_pin": (3, "body.pin_release=1.0\nbody.pin_motion.spin=90"),
    "pile_integrator": (4, "scene.integrator=\"vbd\"\nscene.iterations=4"),
    "bunny_new_table": (5, "render.camera.fov=40\nnew.table.key=1"),
    "shaker_frequency": (7, "triangles.motion.frequency=5.0"),
    "drape_array": (8, "body.0.color=[1, 0, 0]"),
}

MOVING_KEYS = ("motion", "pin_motion", "pin_release", "[[attach]]")


def main():
    scene_dir, mesh_dir = FUZZ / "corpus" / "scene", FUZZ / "corpus" / "mesh"
    motion_dir, set_dir = FUZZ / "corpus" / "motion", FUZZ / "corpus" / "set"
    for d in (scene_dir, mesh_dir, motion_dir, set_dir):
        shutil.rmtree(d, ignore_errors=True)
        d.mkdir(parents=True)
    total = 0
    for src in sorted(ROOT.glob("scenes/*.toml")) + sorted(ROOT.glob("tests/data/**/*.toml")):
        name = "_".join(src.relative_to(ROOT).with_suffix("").parts)
        total += write(scene_dir / name, src.read_bytes())
        if any(key in src.read_text() for key in MOVING_KEYS):
            total += write(motion_dir / name, src.read_bytes())
    for name, text in MOTION_SEEDS.items():
        total += write(motion_dir / name, text.encode())
    for name, (scene, settings) in SET_SEEDS.items():
        total += write(set_dir / name, bytes([scene]) + settings.encode())

    def mesh(name, data, ext):
        nonlocal total
        total += write(mesh_dir / name, pack(data, ext))

    for src in sorted(ROOT.glob("tests/data/meshes/*")):
        mesh("tests_" + src.stem + "_" + src.suffix[1:], src.read_bytes(), src.suffix[1:])
    sv, sf = icosphere(2)
    ascii_ply, binary_ply = ply_ascii(sv, sf), ply_binary(sv, sf)
    mesh("sphere_ascii_ply", ascii_ply, "ply")
    mesh("sphere_binary_ply", binary_ply, "ply")
    mesh("sphere_off", off(sv, sf), "off")
    mesh("sphere_binary_stl", stl_binary(sv, sf), "stl")
    mesh("sphere_obj", obj(sv, sf), "obj")
    mesh("tetra_glb", glb(TETRA_V, TETRA_F), "glb")
    mesh("tetra_dae", collada(TETRA_V, TETRA_F), "dae")
    mesh("tetra_3ds", three_ds(TETRA_V, TETRA_F), "3ds")
    mesh("tetra_ascii_ply", ply_ascii(TETRA_V, TETRA_F), "ply")
    # Truncated cuts: in the vertex list and in the face list of both PLYs, and of OFF and STL.
    ascii_header = ascii_ply.index(b"end_header\n") + len(b"end_header\n")
    binary_header = binary_ply.index(b"end_header\n") + len(b"end_header\n")
    mesh("cut_ascii_ply_vertices", ascii_ply[:ascii_header + 200], "ply")
    mesh("cut_ascii_ply_faces", ascii_ply[:len(ascii_ply) - 100], "ply")
    mesh("cut_binary_ply_vertices", binary_ply[:binary_header + 12 * 50 + 5], "ply")
    mesh("cut_binary_ply_faces", binary_ply[:len(binary_ply) - 30], "ply")
    mesh("cut_off", off(sv, sf)[:300], "off")
    mesh("cut_binary_stl", stl_binary(sv, sf)[:84 + 50 * 10 + 20], "stl")
    print(f"fuzz corpus: {len(list(scene_dir.iterdir()))} scenes, {len(list(mesh_dir.iterdir()))} meshes, "
          f"{len(list(motion_dir.iterdir()))} moving scenes, {len(list(set_dir.iterdir()))} --set inputs, {total} bytes")


if __name__ == "__main__":
    main()
