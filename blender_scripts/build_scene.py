"""Build small test and demo scenes procedurally and save them as .blend.

    blender -b --factory-startup --python-exit-code 1 \
        --python blender_scripts/build_scene.py -- --kind KIND --out SCENE.blend

KIND:
  demo   a head-sized object with a skin material, lit from the side and
         from behind (the demo)
  two    two scattering materials (skin, jade) and a plain one (floor),
         one of them driven by a texture through Base Color
  none   plain materials only: nothing scatters
  head   the demo's head with four times its Subsurface (8 cm red
         radius), so that scattering spans several pixels at 160x120
         (compare.py's first bundled scene)
  marble five small marble pieces (measured marble's scattering lengths)
         at depths from 10 to 36 cm, key light from the side and a back
         light (compare.py's second bundled scene)
  mixed  a skin sphere and a jade bangle (two profiles) behind a grey,
         non-scattering pillar, side and back light (the third)
  block  wax blocks with sharp edges and corners (no bevel), seen
         three faces at a time and lit across an edge: light enters one
         face and leaves the next (the sweep's fourth scene)
  slab   a thin (1.5 cm) random-walk skin slab facing the camera, lit only
         from behind (back-lit transmission's test)
  sphere an 8 cm skin sphere lit from the front and seen close up by an
         orthographic camera: a radius as large as the object (the sweep's
         fifth scene)
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

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__))), "addon"))
from separable_sss import blender_compat as compat  # noqa: E402


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="build_scene.py")
    p.add_argument("--kind", choices=("demo", "head", "two", "none", "marble", "mixed",
                                            "block", "slab", "sphere", "cup",
                                            "dome"), required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--size", type=int, default=64)
    p.add_argument("--samples", type=int, default=8)
    return p.parse_args(argv)


def material(name, **inputs):
    """A Principled BSDF material, in Blender 3.x's terms (base, subsurface,
    radius, subsurface_color, roughness), the same look on every version
    (blender_compat.set_principled)."""
    mat = bpy.data.materials.new(name)
    bsdf = compat.ensure_nodes(mat).nodes["Principled BSDF"]
    compat.set_principled(bsdf, **inputs)
    return mat


def assign(obj, mat):
    obj.data.materials.append(mat)
    return obj


def closed_parts(obj, name):
    """obj's mesh closed and each loose part made an object of its own,
    the largest keeping obj's name, the others called name; yields them,
    largest first, each selected and active as it is yielded.

    Suzanne's eyes are open caps set into holes of an open head. In one
    object the random walk leaves the skin through the caps and the holes,
    which darkens a ring round each eye: the Subsurface Scattering node's
    manual says Random Walk "works best for closed meshes. Overlapping
    faces and holes in the mesh can cause problems", and Cycles' commit
    that added it (D3054) that "geometry like eyes or mouth can darken the
    skin on the outside". A character's eyes are objects of their own, and
    so are these (docs/comparison.md, "The head's eyes")."""
    import bmesh
    mesh = bmesh.new()
    mesh.from_mesh(obj.data)
    bmesh.ops.holes_fill(mesh, edges=mesh.edges, sides=0)
    mesh.to_mesh(obj.data)
    mesh.free()
    select_only(obj)
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.mesh.separate(type="LOOSE")
    bpy.ops.object.mode_set(mode="OBJECT")
    parts = sorted(bpy.context.selected_objects,
                   key=lambda o: -len(o.data.polygons))
    base = obj.name
    for part in parts:  # out of the way of the names below
        part.name = "closed_parts"
    for i, part in enumerate(parts):
        part.name = base if i == 0 else f"{name}.{i}"
    for part in parts:
        select_only(part)
        yield part


def select_only(obj):
    for other in bpy.context.view_layer.objects:
        other.select_set(other == obj)
    bpy.context.view_layer.objects.active = obj


def clear(scene):
    for obj in list(scene.objects):
        if obj.type in ("MESH", "LIGHT"):
            bpy.data.objects.remove(obj, do_unlink=True)


def light(kind, name, energy, location, rotation=(0, 0, 0), size=0.5,
          target=None, angle=None):
    """A light at location, turned by rotation or aimed at target; size is
    an area light's, angle (degrees) a sun's."""
    data = bpy.data.lights.new(name, kind)
    data.energy = energy
    if kind == "AREA":
        data.size = size
    if angle is not None:
        data.angle = math.radians(angle)
    obj = bpy.data.objects.new(name, data)
    obj.location = location
    obj.rotation_euler = rotation
    bpy.context.scene.collection.objects.link(obj)
    if target is not None:
        aim(obj, target)
    return obj


def aim(obj, target):
    direction = Vector(target) - obj.location
    obj.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()


def place_camera(scene, location, target, lens):
    cam = scene.camera
    cam.location = location
    aim(cam, target)
    cam.data.lens = lens


def build_demo(scene, subsurface=0.02):
    skin = material("Skin", **{
        "base": (0.8, 0.55, 0.45, 1.0), "subsurface": subsurface,
        "radius": (1.0, 0.35, 0.2),
        "subsurface_color": (0.85, 0.45, 0.35, 1.0), "roughness": 0.45})
    bpy.ops.mesh.primitive_monkey_add(size=0.22, location=(0, 0, 0))
    for part in closed_parts(bpy.context.active_object, "Eye"):
        mod = part.modifiers.new("smooth", "SUBSURF")
        mod.levels = mod.render_levels = 2
        bpy.ops.object.shade_smooth()
        assign(part, skin)
    backdrop = material("Backdrop", **{"base": (0.05, 0.05, 0.06, 1),
                                       "roughness": 0.9})
    bpy.ops.mesh.primitive_plane_add(size=4, location=(0, 0.6, 0),
                                     rotation=(math.pi / 2, 0, 0))
    assign(bpy.context.active_object, backdrop)
    light("AREA", "Key", 12.0, (-0.7, -0.3, 0.2), size=0.3, target=(0, 0, 0))
    light("SPOT", "Back", 60.0, (0.15, 0.45, 0.1), target=(0, 0, 0))
    place_camera(scene, (0.0, -0.85, 0.02), (0, 0, 0), 85)


def build_two(scene, scatter=True):
    skin = material("Skin", **{
        "base": (0.8, 0.6, 0.5, 1.0),
        "subsurface": 0.5 if scatter else 0.0,
        "radius": (1.0, 0.4, 0.2),
        "subsurface_color": (0.9, 0.5, 0.4, 1.0)})
    jade = material("Jade", **{
        "base": (0.3, 0.7, 0.4, 1.0),
        "subsurface": 0.5 if scatter else 0.0,
        "radius": (0.3, 1.2, 0.6),
        "subsurface_color": (0.3, 0.8, 0.5, 1.0), "roughness": 0.2})
    # Jade's base colour comes from a texture: switching SSS off must then
    # insert a Mix node rather than set a value.
    tree = jade.node_tree
    noise = tree.nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = 8.0
    tree.links.new(noise.outputs["Color"],
                   tree.nodes["Principled BSDF"].inputs["Base Color"])
    floor = material("Floor", **{"base": (0.4, 0.4, 0.45, 1.0),
                                 "roughness": 0.3})
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


def random_walk(mat):
    """Cycles' random walk with the radius adapted to the colour (3.x's
    Random Walk, 4.x's Random Walk (Skin)): the method the calibration and
    the comparison were measured with."""
    compat.set_method(mat.node_tree.nodes["Principled BSDF"],
                      "RANDOM_WALK_SKIN")
    return mat


def smooth(obj, levels=0):
    if levels:
        mod = obj.modifiers.new("smooth", "SUBSURF")
        mod.levels = mod.render_levels = levels
    for poly in obj.data.polygons:
        poly.use_smooth = True
    return obj


def scale_scene(scene, s):
    """Scale every object, light and the camera about the origin by s.
    Area lights keep their irradiance (power x s^2); suns need nothing."""
    for obj in scene.objects:
        obj.location = obj.location * s
        if obj.type == "MESH":
            obj.scale = obj.scale * s
        elif obj.type == "LIGHT" and obj.data.type == "AREA":
            obj.data.size *= s
            obj.data.energy *= s * s
        elif obj.type == "LIGHT" and obj.data.type in ("POINT", "SPOT"):
            obj.data.energy *= s * s
            obj.data.shadow_soft_size *= s
    scene.camera.data.clip_start = min(scene.camera.data.clip_start,
                                       0.1 * s)


def build_marble(scene):
    """Small pieces of marble (spheres of 1.4 cm radius, a 2.4 cm cube, a
    cylinder: the size of beads and dice) at depths from 10 to 36 cm, under
    a hard key light and a back light. The marble has measured marble's
    diffusion lengths (1/sigma_tr = 8.5, 5.6, 4.0 mm for red, green, blue;
    Jensen et al. 2001), so at this size light scatters over about half an
    object's radius. The same world-space radius covers fewer pixels the
    farther the object is, so every method's depth handling shows."""
    marble = random_walk(material("Marble", **{
        "base": (0.83, 0.79, 0.75, 1.0), "subsurface": 0.0085,
        "radius": (1.0, 0.66, 0.47),
        "subsurface_color": (0.9, 0.88, 0.84, 1.0), "roughness": 0.25}))
    floor = material("Floor", **{"base": (0.12, 0.12, 0.13, 1.0),
                                 "roughness": 0.8})
    # Laid out at 25 times the size, then scaled down with the lights and
    # the camera (scale_scene): the layout reads in round numbers.
    shapes = (("sphere", (-1.3, -1.0, 0.35)), ("cube", (0.1, 0.2, 0.35)),
              ("sphere", (1.6, 1.8, 0.35)), ("cylinder", (-0.6, 3.2, 0.35)),
              ("sphere", (0.9, 5.0, 0.35)))
    for kind, loc in shapes:
        if kind == "sphere":
            bpy.ops.mesh.primitive_uv_sphere_add(radius=0.35, location=loc,
                                                 segments=48, ring_count=24)
        elif kind == "cube":
            bpy.ops.mesh.primitive_cube_add(size=0.6, location=loc,
                                            rotation=(0, 0, 0.6))
            bpy.context.active_object.modifiers.new("bevel", "BEVEL") \
                .width = 0.04
        else:
            bpy.ops.mesh.primitive_cylinder_add(radius=0.3, depth=0.7,
                                                location=loc, vertices=48)
        obj = bpy.context.active_object
        if kind != "cube":
            smooth(obj)
        assign(obj, marble)
    bpy.ops.mesh.primitive_plane_add(size=30, location=(0, 2, 0))
    assign(bpy.context.active_object, floor)
    # A small sun: hard shadows and terminators, where scattering shows.
    light("SUN", "Key", 4.0, (-4.0, -1.5, 2.5), target=(0, 1.5, 0.3),
          angle=1.0)
    light("AREA", "Back", 300.0, (1.5, 8.0, 1.2), size=1.5,
          target=(0, 1.5, 0.3))
    place_camera(scene, (0.0, -3.6, 1.2), (0.1, 1.5, 0.3), 40)
    scale_scene(scene, 0.04)


def build_mixed(scene):
    """Two profiles (skin, jade) and a non-scattering pillar in front of
    both: scattering must not bleed across the pillar's silhouette. The
    jade is a bangle (a torus): a closed mesh, as the random walk needs
    (closed_parts). Scattering lengths are about a quarter of each
    object's thickness: the skin's red 11 cm on a 45 cm sphere, the jade's
    green 5.5 cm across the bangle's 22 cm band."""
    skin = random_walk(material("Skin", **{
        "base": (0.8, 0.55, 0.45, 1.0), "subsurface": 0.11,
        "radius": (1.0, 0.35, 0.2),
        "subsurface_color": (0.85, 0.45, 0.35, 1.0), "roughness": 0.45}))
    jade = random_walk(material("Jade", **{
        "base": (0.3, 0.7, 0.4, 1.0), "subsurface": 0.055,
        "radius": (0.3, 1.0, 0.5),
        "subsurface_color": (0.35, 0.8, 0.5, 1.0), "roughness": 0.2}))
    tree = skin.node_tree
    noise = tree.nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = 25.0
    bump = tree.nodes.new("ShaderNodeBump")
    bump.inputs["Strength"].default_value = 0.4
    bump.inputs["Distance"].default_value = 0.02
    tree.links.new(noise.outputs["Fac"], bump.inputs["Height"])
    tree.links.new(bump.outputs["Normal"],
                   tree.nodes["Principled BSDF"].inputs["Normal"])
    grey = material("Pillar", **{"base": (0.35, 0.35, 0.37, 1.0),
                                 "roughness": 0.6})
    floor = material("Floor", **{"base": (0.1, 0.1, 0.11, 1.0),
                                 "roughness": 0.8})
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.45, location=(-0.55, 0.3,
                                                                0.45),
                                         segments=48, ring_count=24)
    assign(smooth(bpy.context.active_object), skin)
    # Standing on its rim, turned 35 degrees from the camera.
    bpy.ops.mesh.primitive_torus_add(
        major_radius=0.32, minor_radius=0.11, major_segments=64,
        minor_segments=24, location=(0.5, 0.4, 0.43),
        rotation=(math.pi / 2, 0, math.radians(35)))
    assign(smooth(bpy.context.active_object), jade)
    bpy.ops.mesh.primitive_cylinder_add(radius=0.09, depth=1.6,
                                        location=(-0.12, -0.8, 0.8),
                                        vertices=32)
    assign(smooth(bpy.context.active_object), grey)
    bpy.ops.mesh.primitive_plane_add(size=20)
    assign(bpy.context.active_object, floor)
    # A small sun from the front right: the pillar's hard shadow crosses
    # the skin sphere; a weak back light rims both.
    light("SUN", "Key", 4.0, (1.8, -4.6, 2.5), target=(-0.55, 0.3, 0.45),
          angle=1.0)
    light("AREA", "Back", 80.0, (0.4, 2.6, 1.2), size=0.8,
          target=(0, 0.3, 0.45))
    place_camera(scene, (0.0, -2.5, 0.8), (0.0, 0.3, 0.45), 50)


def build_block(scene):
    """Two wax blocks with sharp (unbevelled) edges and corners: a 40 cm
    cube turned 35 degrees from the camera and a 16 cm thick bar beside
    it, so that three faces of each show. A hard key light from above and
    to the left lights the top faces and one side each; the other sides
    see only the world and the floor, so the light the random walk carries
    round an edge, from a lit face to a dark one, is most of what they
    show. The wax scatters over about a tenth of the cube's side (red
    4 cm) and a quarter of the bar's thickness."""
    wax = random_walk(material("Wax", **{
        "base": (0.85, 0.75, 0.55, 1.0), "subsurface": 0.04,
        "radius": (1.0, 0.7, 0.45),
        "subsurface_color": (0.9, 0.75, 0.5, 1.0), "roughness": 0.35}))
    floor = material("Floor", **{"base": (0.1, 0.1, 0.11, 1.0),
                                 "roughness": 0.8})
    bpy.ops.mesh.primitive_cube_add(size=0.4, location=(-0.22, 0.2, 0.2),
                                    rotation=(0, 0, math.radians(35)))
    assign(bpy.context.active_object, wax)
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.3, -0.05, 0.13),
                                    rotation=(0, 0, math.radians(-20)))
    bar = bpy.context.active_object
    bar.scale = (0.16, 0.5, 0.26)
    assign(bar, wax)
    bpy.ops.mesh.primitive_plane_add(size=20)
    assign(bpy.context.active_object, floor)
    light("SUN", "Key", 4.0, (-2.0, -1.2, 3.0), target=(0, 0.1, 0.2),
          angle=1.0)
    place_camera(scene, (0.35, -1.9, 1.05), (0.0, 0.1, 0.17), 50)


def build_slab(scene):
    """A thin skin slab (1.5 cm) facing the camera, lit only from behind by
    an area light: its front glows only through transmission."""
    skin = random_walk(material("Skin", **{
        "base": (0.8, 0.55, 0.45, 1.0), "subsurface": 0.02,
        "radius": (1.0, 0.5, 0.25),
        "subsurface_color": (0.85, 0.45, 0.35, 1.0), "roughness": 0.6}))
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0, 0, 0))
    slab = bpy.context.active_object
    slab.scale = (0.3, 0.015, 0.3)
    assign(slab, skin)
    light("AREA", "Back", 30.0, (0.0, 0.5, 0.0), size=0.4, target=(0, 0, 0))
    place_camera(scene, (0.0, -1.0, 0.0), (0, 0, 0), 50)


def build_shell(scene, cup):
    """The slab's skin, 1.5 cm thick, bent into half a sphere's shell of
    6 cm outer radius and lit only from behind: the cup shows the camera
    its inside (the inside of an ear), the dome its outside. Back-lit
    curved thin parts measured by measure_transmission.py
    (docs/transmission.md, "Glow between facing parts")."""
    import bmesh
    build_slab(scene)
    skin = bpy.data.materials["Skin"]
    bpy.data.objects.remove(bpy.data.objects["Cube"], do_unlink=True)
    mesh = bpy.data.meshes.new("Shell")
    bm = bmesh.new()
    bmesh.ops.create_uvsphere(bm, u_segments=64, v_segments=32,
                              radius=0.06)
    side = 1.0 if cup else -1.0  # the half away from the camera, or near
    bmesh.ops.delete(bm, geom=[v for v in bm.verts if side * v.co.y < -1e-7],
                     context="VERTS")
    bm.to_mesh(mesh)
    bm.free()
    shell = bpy.data.objects.new("Shell", mesh)
    scene.collection.objects.link(shell)
    solid = shell.modifiers.new("thickness", "SOLIDIFY")
    solid.thickness = 0.015
    solid.offset = -1.0  # inwards: the outer radius stays 6 cm
    solid.use_even_offset = True
    for poly in mesh.polygons:
        poly.use_smooth = True
    assign(shell, skin)
    place_camera(scene, (0.0, -0.3, 0.0), (0, 0, 0), 50)  # fills the frame


def build_sphere(scene):
    """An 8 cm skin sphere lit from the front, seen by an orthographic
    camera close up: at large radius scales (make sweep at 100-1000x: 1 to
    10 m of red radius) the light spreads over the whole object, where no
    light may be created."""
    skin = random_walk(material("Skin", **{
        "base": (0.8, 0.55, 0.45, 1.0), "subsurface": 0.01,
        "radius": (1.0, 0.35, 0.2),
        "subsurface_color": (0.85, 0.45, 0.35, 1.0), "roughness": 0.5}))
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.04, segments=64,
                                         ring_count=32, location=(0, 0, 0))
    bpy.ops.object.shade_smooth()
    assign(bpy.context.active_object, skin)
    light("AREA", "Key", 3.0, (-0.15, -0.4, 0.15), size=0.15,
          target=(0, 0, 0))
    place_camera(scene, (0.0, -0.5, 0.0), (0, 0, 0), 50)
    scene.camera.data.type = "ORTHO"
    scene.camera.data.ortho_scale = 0.12


def main():
    args = parse_args()
    scene = bpy.context.scene
    clear(scene)
    if args.kind == "demo":
        build_demo(scene)
    elif args.kind == "head":
        build_demo(scene, subsurface=0.08)
        random_walk(bpy.data.materials["Skin"])
    elif args.kind == "marble":
        build_marble(scene)
    elif args.kind == "mixed":
        build_mixed(scene)
    elif args.kind == "block":
        build_block(scene)
    elif args.kind == "slab":
        build_slab(scene)
    elif args.kind == "sphere":
        build_sphere(scene)
    elif args.kind in ("cup", "dome"):
        build_shell(scene, cup=args.kind == "cup")
    else:
        build_two(scene, scatter=args.kind == "two")
    compat.ensure_nodes(scene.world).nodes["Background"].inputs["Color"] \
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
