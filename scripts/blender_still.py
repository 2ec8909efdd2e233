# A still of a springy export drawn by Blender (Cycles on the CPU, headless): the gallery's
# "Blender beside springy" picture (docs/export.md). Imports the .glb as docs/export.md tells a
# user to, sets springy's camera and light (given in springy's y-up axes) and renders one frame.
#
#   blender -b --factory-startup --python scripts/blender_still.py -- RUN.glb --fps 30 --frame 48 \
#       --camera 0 3 14 --target 0 1.5 0 --fov 60 --light 31.8 210 --size 1280 720 --out still.png
import argparse
import math
import sys

import bpy
from mathutils import Vector


def blender_axes(p):
    """springy's (x, y up, z) as Blender's z-up (x, -z, y)."""
    return Vector((p[0], -p[2], p[1]))


def main(argv):
    parser = argparse.ArgumentParser()
    parser.add_argument("glb")
    parser.add_argument("--fps", type=int, required=True)
    parser.add_argument("--frame", type=int, required=True)
    parser.add_argument("--camera", type=float, nargs=3, required=True)
    parser.add_argument("--target", type=float, nargs=3, required=True)
    parser.add_argument("--fov", type=float, default=60.0, help="vertical, degrees")
    parser.add_argument("--light", type=float, nargs=2, default=[31.8, 210.0], help="pitch down, yaw [degrees]")
    parser.add_argument("--size", type=int, nargs=2, default=[1280, 720])
    parser.add_argument("--samples", type=int, default=48)
    parser.add_argument("--out", required=True)
    args = parser.parse_args(argv)

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = args.fps, 1.0
    # Shading "Smooth": Debian 12's Blender 3.4.1 fails on the default ("Use Normal Data") with numpy 1.24.
    bpy.ops.import_scene.gltf(filepath=args.glb, import_shading="SMOOTH")
    scene.frame_set(args.frame)

    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    camera.location = blender_axes(args.camera)
    camera.rotation_euler = (blender_axes(args.target) - camera.location).to_track_quat("-Z", "Y").to_euler()
    camera.data.sensor_fit = "VERTICAL"
    camera.data.angle_y = math.radians(args.fov)
    scene.camera = camera

    # springy's light: a direction from its pitch (down) and yaw; a sun shines along it.
    pitch, yaw = math.radians(args.light[0]), math.radians(args.light[1])
    d = blender_axes((math.sin(yaw) * math.cos(pitch), -math.sin(pitch), math.cos(yaw) * math.cos(pitch)))
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    sun.data.energy = 4.0
    sun.data.angle = math.radians(2.0)
    sun.rotation_euler = d.to_track_quat("-Z", "Y").to_euler()
    scene.collection.objects.link(sun)
    world = bpy.data.worlds.new("sky")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.55, 0.62, 0.72, 1.0)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.6
    scene.world = world

    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = args.samples
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y = args.size
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    scene.render.filepath = args.out
    bpy.ops.render.render(write_still=True)


main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
