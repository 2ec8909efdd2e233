#!/usr/bin/env python3
"""Converts between mesh files and fuzz_mesh inputs (one byte choosing the extension, then the
file's bytes; the order is kMeshExtensions in fuzz/fuzz_inputs.h).

  fuzz/mesh_input.py pack FILE.EXT INPUT        a mesh file -> a fuzz_mesh input (corpus entry)
  fuzz/mesh_input.py unpack INPUT DEST          a fuzz_mesh input (e.g. a crash file) -> DEST.EXT
"""
import pathlib
import sys

# Same order as kMeshExtensions in fuzz/fuzz_inputs.h.
EXTENSIONS = ["ply", "obj", "stl", "off", "gltf", "glb", "3ds", "dae", "fbx"]


def pack(data: bytes, extension: str) -> bytes:
    return bytes([EXTENSIONS.index(extension.lower())]) + data


def unpack(data: bytes) -> tuple[bytes, str]:
    if not data:
        raise ValueError("an empty input is no mesh file")
    return data[1:], EXTENSIONS[data[0] % len(EXTENSIONS)]


def main() -> int:
    if len(sys.argv) != 4 or sys.argv[1] not in ("pack", "unpack"):
        print(__doc__, file=sys.stderr)
        return 2
    source, dest = pathlib.Path(sys.argv[2]), pathlib.Path(sys.argv[3])
    if sys.argv[1] == "pack":
        dest.write_bytes(pack(source.read_bytes(), source.suffix[1:]))
        print(dest)
    else:
        data, extension = unpack(source.read_bytes())
        out = dest.with_name(dest.name + "." + extension)
        out.write_bytes(data)
        print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
