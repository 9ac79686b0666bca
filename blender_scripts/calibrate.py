"""Measure how Cycles' random-walk SSS differs from the plain diffuse lobe
that libsss blurs, on flat slabs, headless:

    blender -b --factory-startup --python-exit-code 1 \\
        --python blender_scripts/calibrate.py -- --out DIR \\
        [--part energy,edge,texture,crease,shape] [--samples 128] [--size 64]
        [--radii 0.05,0.2] [--method RANDOM_WALK_SKIN]

energy: a large thick box (2 x 2 m face, 1 m deep) faces an orthographic
  camera that sees only the middle 0.2 m of its face, under a uniform white
  world (strength 1, no lamps; --light sun: a sun at normal incidence
  instead). Per render three albedos (one per colour channel: Base Color =
  Subsurface Color = (a, b, c), Subsurface 1, Subsurface Radius (r, r, r),
  Specular 0, or --specular) are rendered with the random walk and with
  Subsurface 0 (the add-on's SSS-off render). The mean Combined over the
  central half of the frame of one divided by the other is the energy
  ratio RW / diffuse (ratio_diffuse: the same of the diffuse passes, which
  differs from it only with a specular layer) of
  that albedo; the diffuse side is A exactly under the white world (a
  check). --view-angles turns the box about its vertical axis so that the
  camera sees the face at those angles from its normal (the random walk's
  energy depends on it from Blender 4.0). Written to DIR/energy.csv.
edge: the same box under a sun at normal incidence, half of it shadowed by
  a plate that only casts shadows (invisible to camera and to indirect
  rays): random walk against the SSS-off render scattered by libsss with
  each Burley radius mapping (cycles, eevee, random-walk,
  cycles-random-walk, cycles4-random-walk) and with what the add-on
  asks for the method on this Blender ("measured": mapping and energy
  calibration). Edge profiles
  are averaged along the edge, normalised by their lit plateau, and
  compared (RMSE over the profile); the Burley d that fits the random walk
  best is also searched (numerically integrated edge response). Written to
  DIR/edge.csv and DIR/edge_profiles.csv.
texture: the box with a striped Base Color (a checker texture) under the
  sun, random walk against SSS-off + libsss with post and pre-and-post
  texturing. Written to DIR/texture.csv.
crease: the box's top edge (a sharp 90-degree convex edge) seen at 45
  degrees (--crease-view: the angle between the camera's axis and the
  top face's normal; the front face is seen at 90 degrees less) by the
  orthographic camera, its front face under a sun at
  normal incidence (--crease-sun: its rays leaning that many degrees
  towards the edge) and its top face unlit (the sun grazes it): the random
  walk against the SSS-off render scattered by libsss with this Blender's
  measured mapping and calibration, without the crease term (scene
  "crease": 0), with it (1), and with the blur stopped at the edge but
  nothing carried over (2: what the term of a walk whose blur stops
  there is fitted against: the walk's gain on the top face, its loss on
  the front face), per row of the frame (t: metres along each face from
  the edge, negative on the front face), over the scattered front face's
  plateau, every image less its specular reflection (--specular). Written
  to DIR/crease_METHOD.csv.
shape: a sphere of radius 4 cm (128 x 64 segments, smooth) seen head-on by
  an orthographic camera 12 cm wide, under a sun along the view, with the
  radius r = x a for each x of SHAPE_X (x: the radius times the sphere's
  mean curvature 1/a), and the box under the same sun: the random walk
  over SSS off in the middle 10 % of the frame (--size / 10 pixels square)
  of the sphere, divided by the box's, is what a convex surface adds to
  the flat slab's gain (the shape table of csrc/sss_calibration.c); the
  same over the sphere's whole visible side (gain_whole) is what the walk
  returns there at all once its light spreads over the whole object
  (--shape-x: which x).
  Written to DIR/shape_METHOD.csv.

Everything is Cycles on the CPU with denoising and adaptive sampling off,
clamping off, seed 1 (SSS off) and 2 (random walk).
"""
import argparse
import csv
import json
import math
import os
import sys
import time

import bpy
from mathutils import Vector

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, ".."))
sys.path.insert(0, os.path.join(ROOT, "addon"))
sys.path.insert(0, HERE)

import numpy as np  # noqa: E402
from separable_sss import blender_compat as compat  # noqa: E402
from separable_sss import native  # noqa: E402
from exr_io import read_exr, rgb, single  # noqa: E402
from script_cli import run_main, script_argv  # noqa: E402

ALBEDO_SETS = ((0.05, 0.1, 0.2), (0.3, 0.4, 0.5), (0.6, 0.7, 0.8),
               (0.85, 0.9, 0.95), (0.98, 0.99, 1.0))
VIEW = 0.2   # metres of slab face the camera sees
SPECULAR = 0.0   # the measured material's specular input (--specular)
ROUGHNESS = 0.5  # and its roughness (--roughness)
MEASURED_IOR = 1.5   # and its IOR (4.x's default)
SHAPE_RADIUS = 0.04   # the shape part's sphere, metres
SHAPE_X = (0.01, 0.03, 0.1, 0.3, 1.0, 3.0, 10.0, 30.0, 100.0)


def log(*a):
    print("calibrate:", *a, flush=True)


def parse_args():
    argv = script_argv()
    p = argparse.ArgumentParser(prog="calibrate.py")
    p.add_argument("--out", required=True)
    p.add_argument("--part", default="energy,edge,texture",
                   help="any of energy, edge, texture, crease, shape")
    p.add_argument("--samples", type=int, default=128)
    p.add_argument("--size", type=int, default=64)
    p.add_argument("--radii", default="0.05")
    p.add_argument("--method", default="RANDOM_WALK_SKIN",
                   choices=compat.METHODS,
                   help="by Blender 4.x's names (3.x's Random Walk is "
                   "RANDOM_WALK_SKIN, its Fixed Radius RANDOM_WALK)")
    p.add_argument("--light", default="world", choices=("world", "sun"))
    p.add_argument("--sun-angle", type=float, default=0.0,
                   help="energy with --light sun: degrees from the normal")
    p.add_argument("--view-angles", default="0",
                   help="energy: degrees between the camera's axis and the "
                   "face's normal (the box is turned about its vertical "
                   "axis), comma-separated")
    p.add_argument("--view", type=float, default=0.2,
                   help="metres of the face the camera sees")
    p.add_argument("--crease-view", type=float, default=45.0,
                   help="crease: degrees between the camera's axis and the "
                   "unlit top face's normal")
    p.add_argument("--crease-sun", type=float, default=0.0,
                   help="crease: degrees the sun's rays lean from the lit "
                   "front face's normal towards the edge (0 to 80; the top "
                   "face stays unlit)")
    p.add_argument("--albedos", help="override: a,b,c;d,e,f")
    p.add_argument("--specular", type=float, default=compat.SPECULAR_OFF,
                   help="the Principled BSDF's Specular IOR Level (3.x: "
                   "Specular); by default none. From 4.0 plain Random "
                   "Walk enters through an interface of the index it "
                   "makes (at 0.5 the IOR, 1.5)")
    p.add_argument("--roughness", type=float, default=0.5,
                   help="the Principled BSDF's Roughness (from 4.0 it "
                   "also shapes how plain Random Walk enters)")
    p.add_argument("--shape-x", default=",".join(f"{x:g}" for x in SHAPE_X),
                   help="shape: the radii over the sphere's radius")
    args = p.parse_args(argv)
    args.part = args.part.split(",")
    args.radii = [float(x) for x in args.radii.split(",")]
    args.shape_x = [float(x) for x in args.shape_x.split(",")]
    try:
        args.view_angles = [float(x) for x in args.view_angles.split(",")]
    except ValueError as e:
        p.error(f"--view-angles: {e}")
    if not all(0.0 <= a < 90.0 for a in args.view_angles):
        p.error("--view-angles: each in [0, 90) degrees")
    if not 0.0 <= args.crease_sun <= 80.0:
        p.error(f"--crease-sun {args.crease_sun}: from 0 to 80 degrees")
    if not 5.0 <= args.crease_view <= 85.0:
        p.error(f"--crease-view {args.crease_view}: from 5 to 85 degrees "
                "(both faces seen)")
    if not 0.0 <= args.specular <= 1.0:
        p.error(f"--specular {args.specular:g}: from 0 to 1")
    if not 0.0 <= args.roughness <= 1.0:
        p.error(f"--roughness {args.roughness:g}: from 0 to 1")
    args.out = os.path.abspath(args.out)
    global VIEW, SPECULAR, ROUGHNESS
    VIEW = args.view
    SPECULAR = args.specular
    ROUGHNESS = args.roughness
    return args


# ---------------------------------------------------------------- scene

def reset():
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    scene = bpy.context.scene
    cam_data = bpy.data.cameras.new("Cam")
    cam_data.type = "ORTHO"
    cam_data.ortho_scale = VIEW
    cam = bpy.data.objects.new("Cam", cam_data)
    scene.collection.objects.link(cam)
    cam.location = (0, -5, 0)
    cam.rotation_euler = (math.pi / 2, 0, 0)
    scene.camera = cam
    return scene


def measured_material(name):
    """A Principled BSDF with the specular of --specular (by default none)
    and the roughness of --roughness (0.5), pass index 1: what every part
    measures."""
    mat = bpy.data.materials.new(name)
    mat.pass_index = 1
    bsdf = compat.ensure_nodes(mat).nodes["Principled BSDF"]
    compat.principled_input(bsdf, "specular").default_value = SPECULAR
    compat.principled_input(bsdf, "roughness").default_value = ROUGHNESS
    compat.principled_input(bsdf, "ior").default_value = MEASURED_IOR
    return mat


def slab(scene, turn=0.0):
    """The box: face at y = 0 towards the camera, 6 x 6 m, 4 m deep, turned
    by `turn` degrees about the vertical axis through the face's middle."""
    mat = measured_material("Slab")
    mesh = bpy.data.meshes.new("Slab")
    obj = bpy.data.objects.new("Slab", mesh)
    scene.collection.objects.link(obj)
    import bmesh
    bm = bmesh.new()
    bmesh.ops.create_cube(bm, size=1.0)
    bmesh.ops.scale(bm, vec=(6.0, 4.0, 6.0), verts=bm.verts)
    bmesh.ops.translate(bm, vec=(0, 2.0, 0), verts=bm.verts)
    bm.to_mesh(mesh)
    bm.free()
    mesh.materials.append(mat)
    obj.rotation_euler = (0.0, 0.0, math.radians(turn))
    return obj, mat


def world(scene, strength):
    if scene.world is None:
        scene.world = bpy.data.worlds.new("World")
    bg = compat.ensure_nodes(scene.world).nodes["Background"]
    bg.inputs["Color"].default_value = (1, 1, 1, 1)
    bg.inputs["Strength"].default_value = strength


def sun(scene, direction=(0, 1, 0), strength=3.0):
    data = bpy.data.lights.new("Sun", "SUN")
    data.energy = strength
    data.angle = math.radians(0.05)
    obj = bpy.data.objects.new("Sun", data)
    scene.collection.objects.link(obj)
    obj.rotation_euler = Vector(direction).to_track_quat("-Z", "Y") \
        .to_euler()
    return obj


def occluder(scene):
    """A plate in front of the left half of the face that only casts
    shadows: the edge runs along z at x = 0."""
    mesh = bpy.data.meshes.new("Plate")
    obj = bpy.data.objects.new("Plate", mesh)
    scene.collection.objects.link(obj)
    mesh.from_pydata([(-9, -.05, -9), (0, -.05, -9), (0, -.05, 9),
                      (-9, -.05, 9)],
                     [], [(0, 1, 2, 3)])
    for attr in ("visible_camera", "visible_diffuse", "visible_glossy",
                 "visible_transmission", "visible_volume_scatter"):
        setattr(obj, attr, False)
    return obj


def setup_render(scene, args, out_path):
    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x = r.resolution_y = args.size
    r.resolution_percentage = 100
    r.use_compositing = False
    r.use_sequencer = False
    c = scene.cycles
    c.device = "CPU"
    c.samples = args.samples
    c.use_denoising = False
    c.use_adaptive_sampling = False
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.filter_width = 0.01  # point-sampled pixels: edges stay sharp
    layer = scene.view_layers[0]
    for name in ("diffuse_direct", "diffuse_indirect", "diffuse_color",
                 "glossy_direct", "glossy_indirect", "glossy_color", "z",
                 "material_index"):
        setattr(layer, "use_pass_" + name, True)


def set_material(mat, colour, radius, subsurface, method):
    """Base and scattering colour `colour`, the radius r in metres for
    subsurface > 0 (Radius x Subsurface, or x Scale from 4.0), and the
    method by 4.x's name."""
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    compat.set_method(bsdf, method)
    compat.set_principled(
        bsdf, base=(*colour, 1.0), subsurface_color=(*colour, 1.0),
        subsurface=subsurface,
        radius=(radius / subsurface,) * 3 if subsurface > 0 else (1.0,) * 3)


def render_to(scene, path, seed):
    scene.cycles.seed = seed
    t0 = time.perf_counter()
    if bpy.ops.render.render() != {"FINISHED"}:
        raise RuntimeError("render failed")
    seconds = time.perf_counter() - t0
    compat.set_multilayer_exr(scene.render.image_settings)
    bpy.data.images["Render Result"].save_render(path, scene=scene)
    return read_exr(path), seconds


def glossy(ch):
    """The specular layer's reflection in a render (0 without one)."""
    return (rgb(ch, "GlossDir") + rgb(ch, "GlossInd")) * rgb(ch, "GlossCol")


def walk_and_off(scene, mat, albedo, radius, args, name):
    """Renders the material with the random walk (seed 2) and with
    Subsurface 0 (seed 1, kept as work/NAME_off_TAG.exr for libsss): the
    two Combined images less their specular reflection (none but with
    --specular; the same in both, and not what scatters) and the SSS-off
    render's path."""
    tag = f"{radius}_{albedo[0]}"
    set_material(mat, albedo, radius, 1.0, args.method)
    rw, _ = render_to(scene, os.path.join(args.out, "work",
                                          f"{name}_rw_{tag}.exr"), 2)
    set_material(mat, albedo, radius, 0.0, args.method)
    inp = os.path.join(args.out, "work", f"{name}_off_{tag}.exr")
    off, _ = render_to(scene, inp, 1)
    return (rgb(rw, "Combined") - glossy(rw), rgb(off, "Combined") -
            glossy(off), inp)


def albedo_sets(args):
    if args.albedos:
        return [tuple(float(v) for v in s.split(",")) for s in
                args.albedos.split(";")]
    return ALBEDO_SETS


# --------------------------------------------------------------- energy

def part_energy(args):
    rows = []
    for radius, view_angle, albedo in (
            (r, v, a) for r in args.radii for v in args.view_angles
            for a in albedo_sets(args)):
        scene = reset()
        _, mat = slab(scene, view_angle)
        if args.light == "world":
            world(scene, 1.0)
        else:
            world(scene, 0.0)
            t = math.radians(args.sun_angle)
            sun(scene, (math.sin(t), math.cos(t), 0.0))
        setup_render(scene, args, None)
        n = args.size
        win = (slice(n // 4, 3 * n // 4), slice(n // 4, 3 * n // 4))
        out = {}
        for label, sub in (("off", 0.0), ("rw", 1.0)):
            set_material(mat, albedo, radius, sub, args.method)
            path = os.path.join(args.out, "work",
                                f"energy_{label}_{radius}_"
                                f"{albedo[0]}.exr")
            ch, sec = render_to(scene, path, 1 if label == "off" else 2)
            comb = rgb(ch, "Combined")[win]
            diff = (rgb(ch, "DiffDir") + rgb(ch, "DiffInd"))[win] * \
                rgb(ch, "DiffCol")[win]
            out[label] = (comb.reshape(-1, 3), diff.reshape(-1, 3), sec)
        for c in range(3):
            off = out["off"][0][:, c]
            rw = out["rw"][0][:, c]
            ratio = rw.mean() / off.mean()
            # Standard error of the ratio from pixel scatter.
            se = ratio * math.hypot(rw.std() / rw.mean(),
                                    off.std() / max(off.mean(), 1e-9)) \
                / math.sqrt(rw.size)
            # With a specular layer Combined holds its reflection too;
            # the diffuse passes (where Cycles puts the walk's light) are
            # what the library scales.
            ratio_diffuse = out["rw"][1][:, c].mean() / max(
                out["off"][1][:, c].mean(), 1e-9)
            row = dict(method=args.method, light=args.light,
                       sun_angle=args.sun_angle, specular=args.specular,
                       roughness=args.roughness,
                       ratio_diffuse=float(ratio_diffuse),
                       view_angle=view_angle, radius=radius, albedo=albedo[c],
                       off=float(off.mean()), rw=float(rw.mean()),
                       ratio=float(ratio), stderr=float(se),
                       rw_diffpasses=float(out["rw"][1][:, c].mean()),
                       seconds_off=out["off"][2],
                       seconds_rw=out["rw"][2])
            rows.append(row)
            log(f"energy r={radius} view {view_angle:g} A="
                f"{albedo[c]:.3f}: off "
                f"{row['off']:.4f} rw {row['rw']:.4f} ratio "
                f"{ratio:.4f} +- {se:.4f} ({out['rw'][2]:.1f} s)")
    name = f"energy_{args.method.lower()}_{args.light}" + (
        f"{args.sun_angle:g}" if args.light == "sun" else "") + ".csv"
    write_csv(os.path.join(args.out, name), rows)


def write_csv(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    log("wrote", path)


# ---------------------------------------------------------- edge, texture

def scene_json(path, albedo, radius, mapping, texturing="post",
               calibration=None, **top):
    """One Burley material as libsss's scene file; `top`: top-level keys
    over the defaults (method, taps, ...). The surface the walk enters
    through is the measured material's (--specular, --roughness)."""
    mat = {"pass_index": 1, "profile": "burley",
           "radius": [radius] * 3, "mapping": mapping,
           "albedo": [float(a) for a in albedo], "texturing": texturing,
           "walk_ior": compat.walk_ior(MEASURED_IOR, SPECULAR),
           "walk_roughness": ROUGHNESS}
    if calibration:
        mat["calibration"] = calibration
    desc = {"version": 1,
            "camera": {"type": "ORTHO", "ortho_scale": VIEW,
                       "sensor_width": 36, "sensor_height": 24,
                       "sensor_fit": "AUTO", "lens": 50,
                       "pixel_aspect_x": 1, "pixel_aspect_y": 1},
            "unit_scale": 1.0, "method": "separable-exact", "taps": 65,
            "materials": [mat], **top}
    with open(path, "w") as f:
        json.dump(desc, f)


def scatter(inp, desc, out):
    with native.Scene(desc) as sc:
        sc.process(inp, out)
    ch = read_exr(out)
    return rgb(ch, "SSS.Combined")


def edge_response(x, d):
    """Share of a Burley (shape d) profile's mass on the lit side, at
    signed distance x (metres; x > 0 lit) from a straight shadow edge."""
    r = d * np.geomspace(1e-4, 40.0, 4000)
    pdf = (np.exp(-r / d) + np.exp(-r / (3 * d))) / (4 * d)  # 2 pi r R(r)
    dr = np.gradient(r)
    out = []
    for xi in np.atleast_1d(x):
        a = abs(xi)
        beyond = np.where(r > a, np.arccos(np.clip(a / r, -1, 1)) / np.pi,
                          0.0)
        tail = float(np.sum(pdf * beyond * dr))
        out.append(1.0 - tail if xi >= 0 else tail)
    return np.array(out)


def profile_along(img, n):
    """Mean over the rows of the middle half: one value per column."""
    return img[n // 4:3 * n // 4].mean(axis=0)


def part_edge(args):
    rows, prof_rows = [], []
    native.library()  # fail early, before the renders
    for radius in args.radii:
        for albedo in albedo_sets(args):
            scene = reset()
            _, mat = slab(scene)
            world(scene, 0.0)
            sun(scene)
            occluder(scene)
            setup_render(scene, args, None)
            n = args.size
            rw, off, inp = walk_and_off(scene, mat, albedo, radius, args,
                                        "edge")
            # Pixel centres in metres, x = 0 at the edge (frame centre).
            px = (np.arange(n) + 0.5) / n * VIEW - VIEW / 2
            prw = profile_along(rw, n)
            poff = profile_along(off, n)
            results = {}
            # Every mapping alone, and "measured": what the add-on asks
            # for this method on this Blender (mapping and calibration).
            measured = compat.WALK_CALIBRATION.get(args.method)
            for mapping in ("cycles", "eevee", "random-walk",
                            "cycles-random-walk", "cycles4-random-walk") + \
                    (("measured",) if measured else ()):
                desc = inp.replace(".exr", f"_{mapping}.json")
                if mapping == "measured":
                    scene_json(desc, albedo, radius, measured[0],
                               calibration=measured[1])
                else:
                    scene_json(desc, albedo, radius, mapping)
                img = scatter(inp, desc, inp.replace(".exr",
                                                     f"_{mapping}_sss.exr"))
                results[mapping] = profile_along(img, n)
            for c in range(3):
                lit = poff[-n // 8:, c].mean()
                lit_rw = prw[-n // 8:, c].mean()
                # Everything over the SSS-off render's lit plateau (flat
                # and exact): energy differences count too.
                ref = prw[:, c] / lit
                row = dict(method=args.method, radius=radius,
                           albedo=albedo[c], lit_off=float(lit),
                           lit_rw=float(lit_rw),
                           energy_ratio=float(lit_rw / lit))
                for mapping, prof in results.items():
                    p = prof[:, c] / lit
                    row["rmse_" + mapping] = float(np.sqrt(np.mean(
                        (p - ref) ** 2)))
                # Best-fitting Burley d, in units of the radius.
                best = None
                for f in np.geomspace(0.01, 1.0, 121):
                    model = edge_response(px, f * radius)
                    k = float(model @ ref / (model @ model))  # energy
                    e = float(np.sqrt(np.mean((k * model - ref) ** 2)))
                    if best is None or e < best[1]:
                        best = (f, e)
                row["d_fit_over_r"] = float(best[0])
                row["rmse_fit"] = best[1]
                a = albedo[c]
                # The older mappings' d / r, as the library has them.
                for key in ("cycles", "eevee", "random-walk"):
                    row["d_over_r_" + key.replace("-", "_")] = \
                        native.burley_d({"profile": "burley",
                                         "radius": [1.0] * 3,
                                         "mapping": key,
                                         "albedo": [a] * 3})[0]
                rows.append(row)
                log("edge", {k: (round(v, 4) if isinstance(v, float) else v)
                             for k, v in row.items()})
                for i in range(n):
                    prof_rows.append(dict(
                        radius=radius, albedo=a, x=float(px[i]),
                        rw=float(ref[i]),
                        off=float(poff[i, c] / lit),
                        **{m: float(results[m][i, c] / lit)
                           for m in results}))
    write_csv(os.path.join(args.out, f"edge_{args.method.lower()}.csv"),
              rows)
    write_csv(os.path.join(args.out, "edge_profiles.csv"), prof_rows)


def part_texture(args):
    """Stripes of Base Color 4 px wide under the sun: which texturing
    mode's blur of colour matches the random walk."""
    rows = []
    for radius in args.radii:
        scene = reset()
        _, mat = slab(scene)
        world(scene, 0.0)
        sun(scene)
        setup_render(scene, args, None)
        tree = mat.node_tree
        bsdf = tree.nodes["Principled BSDF"]
        checker = tree.nodes.new("ShaderNodeTexChecker")
        checker.inputs["Color1"].default_value = (0.9, 0.8, 0.7, 1)
        checker.inputs["Color2"].default_value = (0.3, 0.15, 0.1, 1)
        checker.inputs["Scale"].default_value = 1.0 / (VIEW / 8)
        # Object coordinates: stripes along x only (z scaled to 0).
        coords = tree.nodes.new("ShaderNodeTexCoord")
        sep = tree.nodes.new("ShaderNodeMapping")
        sep.inputs["Scale"].default_value = (1.0, 0.0, 0.0)
        tree.links.new(coords.outputs["Object"], sep.inputs["Vector"])
        tree.links.new(sep.outputs["Vector"], checker.inputs["Vector"])
        set_material(mat, (0.5, 0.5, 0.5), radius, 1.0, args.method)
        for sock in ("Base Color", "Subsurface Color"):
            if sock in bsdf.inputs:
                tree.links.new(checker.outputs["Color"], bsdf.inputs[sock])
        rw, _ = render_to(scene, os.path.join(args.out, "work",
                                              f"tex_rw_{radius}.exr"), 2)
        rw = rgb(rw, "Combined")
        compat.principled_input(bsdf, "subsurface").default_value = 0.0
        inp = os.path.join(args.out, "work", f"tex_off_{radius}.exr")
        offch, _ = render_to(scene, inp, 1)
        off = rgb(offch, "Combined")
        n = args.size
        win = (slice(n // 4, 3 * n // 4), slice(n // 8, 7 * n // 8))
        mean_col = rgb(offch, "DiffCol")[win].reshape(-1, 3).mean(axis=0)
        res = {"no-sss": off}
        # This Blender's measured mapping and calibration for the method.
        mapping, calibration = compat.WALK_CALIBRATION.get(
            args.method, ("cycles", None))
        for tex in ("post", "pre-and-post"):
            for cal in (None, calibration) if calibration else (None,):
                desc = inp.replace(".exr", f"_{tex}_{cal}.json")
                scene_json(desc, mean_col, radius, mapping, tex, cal)
                try:
                    res[f"{tex}{'+cal' if cal else ''}"] = scatter(
                        inp, desc, inp.replace(".exr", f"_{tex}_{cal}_o.exr"))
                except Exception as e:  # library without calibration
                    log(f"{tex} {cal}: {e}")
        for name, img in res.items():
            d = img[win] - rw[win]
            rows.append(dict(method=args.method, radius=radius, mode=name,
                             rmse=float(np.sqrt(np.mean(d ** 2))),
                             rel_mae=float(np.abs(d).sum() /
                                           np.abs(rw[win]).sum()),
                             mean_ratio=float(img[win].mean() /
                                              rw[win].mean())))
            log("texture", rows[-1])
    write_csv(os.path.join(args.out, f"texture_{args.method.lower()}.csv"),
              rows)

# --------------------------------------------------------------- crease

def edge_camera(scene, degrees=45.0):
    """The orthographic camera looking down on the box's top front edge
    (y = 0, z = 3), which runs across the frame's middle, its axis
    `degrees` from the top face's normal: the unlit top face above the
    edge, the lit front face below."""
    cam = scene.camera
    a = math.radians(degrees)
    d = math.sqrt(50.0)   # as far as at 45 degrees, (0, -5, 8)
    cam.location = (0.0, -d * math.sin(a), 3.0 + d * math.cos(a))
    cam.rotation_euler = (a, 0.0, 0.0)


def part_crease(args):
    rows = []
    native.library()
    mapping, calibration = compat.WALK_CALIBRATION.get(
        args.method, ("cycles", None))
    n = args.size
    for radius in args.radii:
        for albedo in albedo_sets(args):
            scene = reset()
            edge_camera(scene, args.crease_view)
            _, mat = slab(scene)
            world(scene, 0.0)
            lean = math.radians(args.crease_sun)
            sun(scene, (0.0, math.cos(lean), math.sin(lean)))
            setup_render(scene, args, None)
            rw, off, inp = walk_and_off(scene, mat, albedo, radius, args,
                                        "crease")
            # Without the crease term, with it as the library ships it,
            # and with the blur stopped at the edge but nothing carried
            # over (what the term is fitted against, for the walks whose
            # blur stops there).
            images = []
            shine = glossy(read_exr(inp))  # the off render's, in each
            for crease in (0, 1, 2):
                desc = inp.replace(".exr", f"_crease{crease}.json")
                scene_json(desc, albedo, radius, mapping,
                           calibration=calibration, method="separable",
                           taps=33, crease=crease)
                images.append(scatter(inp, desc, desc.replace(
                    ".json", "_sss.exr")) - shine)
            ours, creased, stopped = images
            # Rows top to bottom: the top face, then the front face; one
            # value per row over the middle half of the columns.
            cols = slice(n // 4, 3 * n // 4)
            prw, pours, poff, pcrease, pstop = (
                img[:, cols].mean(axis=1)
                for img in (rw, ours, off, creased, stopped))
            # Screen metres from the edge (frame middle), up positive; t
            # along the face: u / cos(view) on the top face, u / sin(view)
            # on the front face.
            u = (n / 2 - (np.arange(n) + 0.5)) / n * VIEW
            a = math.radians(args.crease_view)
            t = np.where(u > 0, u / math.cos(a), u / math.sin(a))
            lit = pours[-n // 8:].mean(axis=0)
            bd = native.burley_d({"profile": "burley", "radius": [radius] * 3,
                                  "mapping": mapping,
                                  "albedo": list(albedo)})
            for i in range(n):
                for c in range(3):
                    rows.append(dict(method=args.method, radius=radius,
                                     albedo=albedo[c], d=bd[c],
                                     view=args.crease_view,
                                     sun=args.crease_sun,
                                     t=float(t[i]),
                                     rw=float(prw[i, c] / lit[c]),
                                     ours=float(pours[i, c] / lit[c]),
                                     crease=float(pcrease[i, c] / lit[c]),
                                     stopped=float(pstop[i, c] / lit[c]),
                                     off=float(poff[i, c] / lit[c])))
            log(f"crease r={radius} A={albedo}: done")
    write_csv(os.path.join(args.out, f"crease_{args.method.lower()}.csv"),
              rows)


# ---------------------------------------------------------------- shape

def sphere(scene, radius):
    """A smooth sphere of `radius` metres at the origin."""
    mat = measured_material("Sphere")
    bpy.ops.mesh.primitive_uv_sphere_add(radius=radius, segments=128,
                                         ring_count=64, location=(0, 0, 0))
    obj = bpy.context.active_object
    for poly in obj.data.polygons:
        poly.use_smooth = True
    obj.data.materials.append(mat)
    return obj, mat


def middle_ratio(scene, mat, albedo, radius, args, tag):
    """Random walk over SSS off, per channel: in the middle of the frame,
    and over every pixel of the object (its whole visible side)."""
    n = args.size
    k = max(2, n // 10)
    win = (slice((n - k) // 2, (n + k) // 2),) * 2
    means, whole = {}, {}
    for label, sub in (("off", 0.0), ("rw", 1.0)):
        set_material(mat, albedo, radius, sub, args.method)
        path = os.path.join(args.out, "work", f"shape_{tag}_{label}.exr")
        ch, _ = render_to(scene, path, 1 if label == "off" else 2)
        img = rgb(ch, "Combined")
        means[label] = img[win].reshape(-1, 3).mean(axis=0)
        seen = single(ch, "Depth") < 1e9
        whole[label] = img[seen].mean(axis=0)
    return (means["rw"] / np.maximum(means["off"], 1e-12),
            whole["rw"] / np.maximum(whole["off"], 1e-12))


def part_shape(args):
    global VIEW
    rows = []
    for albedo in albedo_sets(args):
        VIEW = 0.2
        scene = reset()
        _, mat = slab(scene)
        world(scene, 0.0)
        sun(scene, (0.0, 1.0, 0.0))
        setup_render(scene, args, None)
        flat = middle_ratio(scene, mat, albedo, 0.05, args, "slab")[0]
        VIEW = 3.0 * SHAPE_RADIUS
        for x in args.shape_x:
            scene = reset()
            _, mat = sphere(scene, SHAPE_RADIUS)
            world(scene, 0.0)
            sun(scene, (0.0, 1.0, 0.0))
            setup_render(scene, args, None)
            ratio, whole = middle_ratio(scene, mat, albedo,
                                        x * SHAPE_RADIUS, args, f"{x:g}")
            for c in range(3):
                rows.append(dict(method=args.method, x=x, albedo=albedo[c],
                                 sphere=float(ratio[c]), slab=float(flat[c]),
                                 gain=float(ratio[c] / flat[c]),
                                 sphere_whole=float(whole[c]),
                                 gain_whole=float(whole[c] / flat[c])))
                log(f"shape x={x:g} A={albedo[c]:.3f}: sphere "
                    f"{ratio[c]:.4f} slab {flat[c]:.4f} gain "
                    f"{ratio[c] / flat[c]:.4f}; over its visible side "
                    f"{whole[c]:.4f}, gain {whole[c] / flat[c]:.4f}")
    write_csv(os.path.join(args.out, f"shape_{args.method.lower()}.csv"),
              rows)


def main():
    args = parse_args()
    os.makedirs(os.path.join(args.out, "work"), exist_ok=True)
    os.environ.setdefault("SSS_LIB", os.path.join(ROOT, "build",
                                                  "libsss.so"))
    t0 = time.perf_counter()
    if "energy" in args.part:
        part_energy(args)
    if "edge" in args.part:
        part_edge(args)
    if "texture" in args.part:
        part_texture(args)
    if "crease" in args.part:
        part_crease(args)
    if "shape" in args.part:
        part_shape(args)
    log(f"done in {time.perf_counter() - t0:.0f} s")


run_main(main)
