"""Build small test and demo scenes procedurally and save them as .blend.

    blender -b --factory-startup --python-exit-code 1 \
        --python blender_scripts/build_scene.py -- --kind KIND --out SCENE.blend

KIND:
  demo   a head-sized object with a skin material, lit from the side and
         from behind (the demo)
  two    two scattering materials (skin, jade) and a plain one (floor),
         one of them driven by a texture through Base Color
  none   plain materials only: nothing scatters
Rendering is Cycles at low resolution and samples; denoising and light
clamping are off so Blender's Combined is exactly the sum of its passes.
"""
import argparse
import math
import os
import sys
import traceback

import bpy
from mathutils import Vector


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="build_scene.py")
    p.add_argument("--kind", choices=("demo", "two", "none"), required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--size", type=int, default=64)
    p.add_argument("--samples", type=int, default=8)
    return p.parse_args(argv)


def material(name, **inputs):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    for key, value in inputs.items():
        bsdf.inputs[key].default_value = value
    return mat


def assign(obj, mat):
    obj.data.materials.append(mat)
    return obj


def clear(scene):
    for obj in list(scene.objects):
        if obj.type in ("MESH", "LIGHT"):
            bpy.data.objects.remove(obj, do_unlink=True)


def light(kind, name, energy, location, rotation, size=0.5):
    data = bpy.data.lights.new(name, kind)
    data.energy = energy
    if kind == "AREA":
        data.size = size
    obj = bpy.data.objects.new(name, data)
    obj.location = location
    obj.rotation_euler = rotation
    bpy.context.scene.collection.objects.link(obj)
    return obj


def aim(obj, target):
    direction = Vector(target) - obj.location
    obj.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()


def build_demo(scene):
    skin = material("Skin", **{
        "Base Color": (0.8, 0.55, 0.45, 1.0), "Subsurface": 0.02,
        "Subsurface Radius": (1.0, 0.35, 0.2),
        "Subsurface Color": (0.85, 0.45, 0.35, 1.0), "Roughness": 0.45})
    bpy.ops.mesh.primitive_monkey_add(size=0.22, location=(0, 0, 0))
    head = bpy.context.active_object
    mod = head.modifiers.new("smooth", "SUBSURF")
    mod.levels = mod.render_levels = 2
    bpy.ops.object.shade_smooth()
    assign(head, skin)
    backdrop = material("Backdrop", **{"Base Color": (0.05, 0.05, 0.06, 1),
                                       "Roughness": 0.9})
    bpy.ops.mesh.primitive_plane_add(size=4, location=(0, 0.6, 0),
                                     rotation=(math.pi / 2, 0, 0))
    assign(bpy.context.active_object, backdrop)
    light("AREA", "Key", 12.0, (-0.7, -0.3, 0.2), (0, 0, 0), 0.3)
    aim(scene.objects["Key"], (0, 0, 0))
    light("SPOT", "Back", 60.0, (0.15, 0.45, 0.1), (0, 0, 0))
    aim(scene.objects["Back"], (0, 0, 0))
    cam = scene.camera
    cam.location = (0.0, -0.85, 0.02)
    aim(cam, (0, 0, 0))
    cam.data.lens = 85


def build_two(scene, scatter=True):
    skin = material("Skin", **{
        "Base Color": (0.8, 0.6, 0.5, 1.0),
        "Subsurface": 0.5 if scatter else 0.0,
        "Subsurface Radius": (1.0, 0.4, 0.2),
        "Subsurface Color": (0.9, 0.5, 0.4, 1.0)})
    jade = material("Jade", **{
        "Base Color": (0.3, 0.7, 0.4, 1.0),
        "Subsurface": 0.5 if scatter else 0.0,
        "Subsurface Radius": (0.3, 1.2, 0.6),
        "Subsurface Color": (0.3, 0.8, 0.5, 1.0), "Roughness": 0.2})
    # Jade's base colour comes from a texture: switching SSS off must then
    # insert a Mix node rather than set a value.
    tree = jade.node_tree
    noise = tree.nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = 8.0
    tree.links.new(noise.outputs["Color"],
                   tree.nodes["Principled BSDF"].inputs["Base Color"])
    floor = material("Floor", **{"Base Color": (0.4, 0.4, 0.45, 1.0),
                                 "Roughness": 0.3})
    bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, location=(-1.1, 0, 1))
    bpy.ops.object.shade_smooth()
    assign(bpy.context.active_object, skin)
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.8, location=(1.1, 0.3,
                                                               0.8))
    bpy.ops.object.shade_smooth()
    assign(bpy.context.active_object, jade)
    bpy.ops.mesh.primitive_plane_add(size=20)
    assign(bpy.context.active_object, floor)
    light("SUN", "Sun", 3.0, (0, 0, 5), (0.9, 0.3, 2.4))


def main():
    args = parse_args()
    scene = bpy.context.scene
    clear(scene)
    if args.kind == "demo":
        build_demo(scene)
    else:
        build_two(scene, scatter=args.kind == "two")
    scene.world.use_nodes = True
    scene.world.node_tree.nodes["Background"].inputs["Color"] \
        .default_value = (0.02, 0.025, 0.03, 1.0)
    render = scene.render
    render.engine = "CYCLES"
    render.resolution_x = render.resolution_y = args.size
    render.resolution_percentage = 100
    scene.cycles.device = "CPU"
    scene.cycles.samples = args.samples
    scene.cycles.use_denoising = False
    scene.cycles.sample_clamp_direct = 0.0
    scene.cycles.sample_clamp_indirect = 0.0
    scene.cycles.seed = 1
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(args.out))
    print("build_scene: wrote", args.out)


try:
    main()
except Exception:
    traceback.print_exc()
    sys.exit(1)
