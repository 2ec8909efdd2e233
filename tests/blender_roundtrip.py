# Blender's side of the export round trip (tests/export_roundtrip.sh): loads springy's exports
# with Blender's own importers and modifiers, the way docs/export.md tells a user to, and writes
# the vertex positions Blender evaluates at the frames asked for, as JSON, in springy's
# coordinates (y up), for the test to compare with what springy simulated.
#
#   blender -b --factory-startup --python tests/blender_roundtrip.py -- \
#       --obj RUN.obj --pc2 RUN.pc2 --glb RUN.glb --fps 30 --frames 0 5 10 --out positions.json
#
# OBJ + PC2: File > Import > Wavefront (.obj) with its defaults (-Z forward, Y up), then a Mesh
# Cache modifier on the object: format PC2, the file, the rest as it is.
# GLB: File > Import > glTF 2.0, Shading "Smooth" (see below), the rest as it is; the scene's frame rate set to the run's first,
# so frame k is the run's frame k.
# A collider or prop that moves is an object of its own: in the OBJ with its own cache
# (RUN.collider0.pc2 for the object collider0), in the GLB placed by its node's animation; the
# GLB's objects' world placements (the origin's place, y up) are written too ("glb_placement").
import argparse
import json
import sys

import bpy
import mathutils


def yup(m, co):
    """A vertex of `m`'s object in world space, back in springy's y-up axes (Blender is z-up)."""
    p = m @ co
    return [p.x, p.z, -p.y]


def sample(objects, frames):
    """{object name: {frame: [[x, y, z], ...]}} as Blender evaluates them (modifiers, shape keys)."""
    scene = bpy.context.scene
    out = {o.name: {} for o in objects}
    for f in frames:
        scene.frame_set(f)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        for o in objects:
            ev = o.evaluated_get(depsgraph)
            mesh = ev.to_mesh()
            out[o.name][str(f)] = [yup(ev.matrix_world, v.co) for v in mesh.vertices]
            ev.to_mesh_clear()
    return out


def placements(objects, frames):
    """{object name: {frame: [x, y, z]}}: where each object's world matrix puts its origin (y up)."""
    scene = bpy.context.scene
    out = {o.name: {} for o in objects}
    for f in frames:
        scene.frame_set(f)
        for o in objects:
            out[o.name][str(f)] = yup(o.matrix_world, mathutils.Vector((0.0, 0.0, 0.0)))
    return out


def empty_scene(fps):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = fps
    scene.render.fps_base = 1.0


def main(argv):
    parser = argparse.ArgumentParser()
    parser.add_argument("--obj")
    parser.add_argument("--pc2")
    parser.add_argument("--glb")
    parser.add_argument("--fps", type=int, required=True)
    parser.add_argument("--frames", type=int, nargs="+", required=True)
    parser.add_argument("--out", required=True)
    args = parser.parse_args(argv)
    result = {"blender": bpy.app.version_string}

    if args.obj:
        empty_scene(args.fps)
        bpy.ops.wm.obj_import(filepath=args.obj, forward_axis="NEGATIVE_Z", up_axis="Y")
        meshes = [o for o in bpy.context.scene.objects if o.type == "MESH"]
        for o in meshes:
            cache = o.modifiers.new("springy", "MESH_CACHE")
            cache.cache_format = "PC2"
            # The bodies' object takes RUN.pc2; a moving collider's object, its own RUN.NAME.pc2.
            cache.filepath = args.pc2 if o.name == "springy" else args.pc2[:-len(".pc2")] + "." + o.name + ".pc2"
            # The rest as it is: start frame 0, axes +Y forward, +Z up (no change: the importer
            # keeps the file's coordinates in the mesh and turns y up into z up with the object's
            # rotation, which applies to the cache's points too).
        result["obj"] = sample(meshes, args.frames)

    if args.glb:
        empty_scene(args.fps)
        # Shading "Smooth": the default, "Use Normal Data", fails in Debian 12's Blender 3.4.1 with
        # its numpy 1.24 (the importer's np.bool, removed from numpy in 1.24).
        bpy.ops.import_scene.gltf(filepath=args.glb, import_shading="SMOOTH")
        meshes = [o for o in bpy.context.scene.objects if o.type == "MESH"]
        result["glb"] = sample(meshes, args.frames)
        result["glb_placement"] = placements(meshes, args.frames)
        result["glb_frame_range"] = [bpy.context.scene.frame_start, bpy.context.scene.frame_end]

    with open(args.out, "w") as f:
        json.dump(result, f)


main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
