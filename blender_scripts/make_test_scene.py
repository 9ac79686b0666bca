"""Build and render a tiny Cycles test scene with every pass libsss reads.

    blender -b --factory-startup --python-exit-code 1 \
        --python blender_scripts/make_test_scene.py -- --out DIR [--size 64] [--samples 4]

Writes into DIR:
  render.exr     render-output naming (ViewLayer.DiffDir.R ...), float, ZIP
  render_half.exr  the same passes as half floats, PIZ
  fileout.exr    File Output node naming (DiffDir.R, Depth.V ...), float
  scene.json     the add-on's scene description (addon/separable_sss/
                 description.py)

The scene: a subsurface sphere (pass index 1), a glossy floor (2), a glass
sphere (3, so the transmission passes are not empty), an emissive cube
(index 0: never scattered), a sun and a coloured world (the Env pass).
Light clamping and denoising are off so that Blender's Combined is exactly
the sum of its passes.
"""
import argparse
import os
import shutil
import sys
import traceback

import bpy

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__))), "addon"))
import separable_sss  # noqa: E402
from separable_sss import analysis, description  # noqa: E402
from separable_sss import blender_compat as compat  # noqa: E402


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="make_test_scene.py")
    p.add_argument("--out", required=True)
    p.add_argument("--size", type=int, default=64)
    p.add_argument("--samples", type=int, default=4)
    return p.parse_args(argv)


def principled(name, pass_index, transmission=0.0, **inputs):
    """A Principled BSDF material in 3.x's terms, the same look on every
    version (blender_compat.set_principled)."""
    mat = bpy.data.materials.new(name)
    mat.pass_index = pass_index
    bsdf = compat.ensure_nodes(mat).nodes["Principled BSDF"]
    compat.set_principled(bsdf, **inputs)
    compat.principled_input(bsdf, "transmission").default_value = \
        transmission
    return mat


def add_object(op, material, **kwargs):
    op(**kwargs)
    obj = bpy.context.active_object
    obj.data.materials.append(material)
    bpy.ops.object.shade_smooth()
    return obj


def build_scene(size, samples):
    scene = bpy.context.scene
    for obj in list(scene.objects):
        if obj.type == "MESH":
            bpy.data.objects.remove(obj, do_unlink=True)

    skin = principled("Skin", 1, base=(0.8, 0.6, 0.5, 1.0), subsurface=0.4,
                      radius=(0.3, 0.12, 0.06),
                      subsurface_color=(0.9, 0.5, 0.4, 1.0), roughness=0.5)
    floor = principled("Floor", 2, base=(0.3, 0.35, 0.4, 1.0),
                       roughness=0.25)
    glass = principled("Glass", 3, base=(0.9, 0.95, 1.0, 1.0),
                       transmission=1.0, roughness=0.05)
    lamp = bpy.data.materials.new("Lamp")
    nodes = compat.ensure_nodes(lamp).nodes
    nodes.remove(nodes["Principled BSDF"])
    emit = nodes.new("ShaderNodeEmission")
    emit.inputs["Color"].default_value = (1.0, 0.8, 0.3, 1.0)
    emit.inputs["Strength"].default_value = 4.0
    lamp.node_tree.links.new(emit.outputs[0],
                             nodes["Material Output"].inputs["Surface"])

    add_object(bpy.ops.mesh.primitive_uv_sphere_add, skin, radius=1.0,
               location=(0, 0, 1.0), segments=48, ring_count=24)
    add_object(bpy.ops.mesh.primitive_plane_add, floor, size=20,
               location=(0, 0, 0))
    add_object(bpy.ops.mesh.primitive_uv_sphere_add, glass, radius=0.6,
               location=(1.6, 1.2, 0.6))
    add_object(bpy.ops.mesh.primitive_cube_add, lamp, size=0.5,
               location=(-1.5, 1.0, 0.25))

    sun = next((o for o in scene.objects if o.type == "LIGHT"), None)
    sun.data.type = "SUN"
    sun.data.energy = 3.0
    sun.rotation_euler = (0.9, 0.3, 2.4)

    world = scene.world
    background = compat.ensure_nodes(world).nodes["Background"]
    background.inputs["Color"].default_value = (0.05, 0.08, 0.12, 1.0)

    render = scene.render
    render.engine = "CYCLES"
    render.resolution_x = size
    render.resolution_y = size
    render.resolution_percentage = 100
    render.film_transparent = False
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.samples = samples
    cycles.use_denoising = False
    cycles.sample_clamp_direct = 0.0
    cycles.sample_clamp_indirect = 0.0
    cycles.seed = 1

    layer = scene.view_layers[0]
    for name in ("diffuse_direct", "diffuse_indirect", "diffuse_color",
                 "glossy_direct", "glossy_indirect", "glossy_color",
                 "transmission_direct", "transmission_indirect",
                 "transmission_color", "emit", "environment", "z",
                 "material_index", "position"):
        setattr(layer, "use_pass_" + name, True)
    return scene


def add_file_output(scene, base):
    """A multilayer File Output node: passes named without a layer."""
    tree = compat.compositor_tree(scene, create=True)
    rl = next(n for n in tree.nodes if n.type == "R_LAYERS")
    out = tree.nodes.new("CompositorNodeOutputFile")
    out.format.file_format = "OPEN_EXR_MULTILAYER"
    out.format.color_depth = "32"
    out.format.exr_codec = "ZIP"
    out.base_path = base
    out.file_slots.clear()
    sockets = {"Image": "Combined"}
    for s in rl.outputs:
        if s.enabled and s.name not in ("Image", "Alpha", "Noisy Image"):
            sockets[s.name] = s.name
    for socket, slot in sockets.items():
        out.file_slots.new(slot)
        tree.links.new(rl.outputs[socket], out.inputs[slot])


def main():
    args = parse_args()
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    scene = build_scene(args.size, args.samples)
    add_file_output(scene, os.path.join(out, "fileout_"))

    settings = scene.render.image_settings
    settings.file_format = "OPEN_EXR_MULTILAYER"
    settings.color_depth = "32"
    settings.exr_codec = "ZIP"
    scene.render.filepath = os.path.join(out, "render")
    scene.render.use_file_extension = True
    scene.frame_set(1)
    bpy.ops.render.render(write_still=True)
    shutil.move(os.path.join(out, "fileout_0001.exr"),
                os.path.join(out, "fileout.exr"))

    # The same render saved again as half floats with PIZ.
    settings.color_depth = "16"
    settings.exr_codec = "PIZ"
    bpy.data.images["Render Result"].save_render(
        os.path.join(out, "render_half.exr"), scene=scene)

    # The add-on's own description of the scene, as a render with it
    # would write.
    separable_sss.register()
    try:
        found = analysis.analyse(scene)
        for f in found.materials:
            # Burley with the Principled BSDF's own Subsurface Radius and
            # Color read as a mean free path, no energy calibration and no
            # transmission: a plain blur whose energy the tests can check.
            s = f.material.sss
            s.profile = "BURLEY"
            s.radius = compat.principled_sss(f.node).radius
            s.albedo = compat.principled_sss(f.node).color
            s.mapping = "RANDOM_WALK"
            s.match_energy = False
            s.transmission = "OFF"
        description.write_description(scene, found,
                                      os.path.join(out, "scene.json"))
    finally:
        separable_sss.unregister()
    print("make_test_scene: wrote", out)


try:
    main()
except Exception:
    traceback.print_exc()
    sys.exit(1)
