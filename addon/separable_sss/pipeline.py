"""The add-on's pipeline: analyse the scene, render with material SSS
switched off, save the passes as a multilayer EXR with the scene
description beside it, run the library (the same code path as the `sss`
command), and bring the result back as an image. Functions that touch bpy
run on the main thread; scatter() does not touch bpy and may run in a
worker thread."""
import json
import math
import os
import re
import tempfile
from dataclasses import dataclass, field

import bpy

from . import analysis, native, transmission
from . import blender_compat as compat
from .analysis import Analysis, Found, analyse  # noqa: F401
from .switch_off import switched_off

METHOD_CODES = {"SEPARABLE": 0, "REFERENCE": 3}


class SSSError(Exception):
    """A failure to show the user as one line."""


@dataclass
class Job:
    input_exr: str
    output_exr: str
    scene_json: str
    layer: str = ""
    radius_scale: float = 1.0  # times the description's own
    timings: dict = field(default_factory=dict)
    summary: str = ""


def output_dir(scene):
    """The folder for passes and results: the scene's setting, else a
    per-user temporary folder."""
    path = bpy.path.abspath(scene.sss.output_dir) if scene.sss.output_dir \
        else os.path.join(tempfile.gettempdir(), "separable_sss")
    try:
        os.makedirs(path, exist_ok=True)
        probe = tempfile.NamedTemporaryFile(dir=path, prefix=".sss-probe-")
        probe.close()
    except OSError as e:
        raise SSSError(f"output folder {path} is not writable: "
                       f"{e.strerror or e}") from None
    return path


def _safe(name):
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name) or "scene"


def paths_for(scene, frame):
    base = os.path.join(output_dir(scene),
                        f"{_safe(scene.name)}_{frame:04d}")
    return base + "_passes.exr", base + "_sss.exr", base + "_scene.json"


# ------------------------------------------------------------- description

# The Radius Meaning choices (properties.MAPPINGS) by their scene.json names.
MAPPING_NAMES = {"CYCLES": "cycles", "EEVEE": "eevee",
                 "RANDOM_WALK": "random-walk",
                 "CYCLES_RANDOM_WALK": "cycles-random-walk",
                 "CYCLES4_RANDOM_WALK": "cycles4-random-walk"}


def _material_entry(found):
    s = found.material.sss
    # Principled v2's Subsurface Weight mixes the diffuse and subsurface
    # lobes: it scales how much of the light is scattered.
    entry = {"pass_index": found.pass_index, "name": found.name,
             "strength": s.strength * found.weight,
             "texturing": "post" if s.texturing == "POST" else
             "pre-and-post"}
    if s.taps:
        entry["taps"] = s.taps
    scale = s.radius_scale
    if s.profile in ("BLENDER", "BURLEY"):
        # Measured (blender_scripts/calibrate.py, csrc/sss_calibration.c):
        # how Cycles' random walk widens with the colour and what energy it
        # returns, per method and Blender version. The Burley profile
        # follows Random Walk (Skin), the walk 3.x has.
        walk = compat.WALK_CALIBRATION.get(
            "RANDOM_WALK_SKIN" if s.profile == "BURLEY" else found.method)
        if s.mapping != "AUTO":
            mapping = MAPPING_NAMES[s.mapping]
        elif walk:
            mapping = walk[0]
        else:
            mapping = "random-walk" if found.method.startswith(
                "RANDOM_WALK") else "cycles"
        radius = found.radius if s.profile == "BLENDER" else tuple(s.radius)
        albedo = (found.albedo or found.color) if s.profile == "BLENDER" \
            else tuple(s.albedo)
        entry.update(profile="burley",
                     radius=[float(r) * scale for r in radius],
                     mapping=mapping,
                     albedo=[min(max(float(a), 0.0), 1.0) for a in albedo])
        if s.match_energy and walk:
            entry["calibration"] = walk[1]
    elif s.profile == "GAUSSIANS":
        entry.update(profile="gaussians", scale=s.gaussian_scale * scale)
    elif s.profile == "JIMENEZ":
        entry.update(profile="jimenez", width=s.jimenez_width * scale,
                     strength_rgb=list(s.jimenez_strength),
                     falloff=list(s.jimenez_falloff))
    elif s.profile == "NEAR_FAR":
        entry.update(profile="near-far",
                     scatter_scale=s.scatter_scale * scale,
                     balance=s.near_far_balance,
                     near_sigma=list(s.near_sigma),
                     far_sigma=list(s.far_sigma))
    if s.profile != "NONE":
        entry.update(transmission.material_fields(found))
    return entry


def scene_description(scene, found):
    """The JSON the library reads (docs/scene.md)."""
    cam = scene.camera.data
    return {
        "version": 1,
        "camera": {
            "type": "ORTHO" if cam.type == "ORTHO" else "PERSP",
            "lens": cam.lens, "sensor_width": cam.sensor_width,
            "sensor_height": cam.sensor_height,
            "sensor_fit": cam.sensor_fit,
            "shift_x": cam.shift_x, "shift_y": cam.shift_y,
            "ortho_scale": cam.ortho_scale,
            "clip_start": cam.clip_start, "clip_end": cam.clip_end,
            "pixel_aspect_x": scene.render.pixel_aspect_x,
            "pixel_aspect_y": scene.render.pixel_aspect_y,
        },
        "unit_scale": scene.unit_settings.scale_length or 1.0,
        # In the description, not beside it: `sss` on this file gives
        # the add-on's result.
        "radius_scale": scene.sss.radius_scale,
        "method": scene.sss.method.lower().replace("_", "-"),
        "taps": scene.sss.taps | 1,
        "materials": [_material_entry(f) for f in found.found],
    }


def write_description(scene, found, path):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(scene_description(scene, found), f, indent=2)
    os.replace(tmp, path)


# ----------------------------------------------------------------- render

def _check_scene(scene):
    if scene.camera is None:
        raise SSSError("the scene has no camera")
    if scene.render.engine != "CYCLES":
        raise SSSError(f"{scene.render.engine.title()} renders have no "
                       "Material Index pass; render with Cycles")


def save_passes(scene, path):
    """Saves the Render Result (every view layer and pass) as a 32-bit
    multilayer EXR, restoring the output settings it touches."""
    result = bpy.data.images.get("Render Result")
    if result is None:
        raise SSSError("there is no render result yet: render first")
    settings = scene.render.image_settings
    saved = compat.image_settings_state(settings)
    try:
        compat.set_multilayer_exr(settings)
        result.save_render(path, scene=scene)
    finally:
        compat.restore_image_settings(settings, saved)
    if not os.path.exists(path):
        raise SSSError(f"Blender did not write {path} (no render result "
                       "yet?)")


def _check_library():
    """Fails before a long render, not after it, if libsss is missing."""
    try:
        native.library()
    except native.LibraryError as e:
        raise SSSError(str(e)) from None


def prepare_render(context):
    """Renders the current frame with material SSS off and restores the
    scene; returns the job for scatter()."""
    scene = context.scene
    _check_scene(scene)
    _check_library()
    found = analyse(scene)
    inp, out, desc = paths_for(scene, scene.frame_current)
    with switched_off(scene, found) as undo:
        # The compositor would only show the previous SSS result again.
        undo.set(scene.render, "use_compositing", False)
        fail = os.environ.get("SSS_TEST_FAIL")
        if fail == "render":
            raise SSSError("injected failure (SSS_TEST_FAIL=render)")
        # SSS_TEST_FAIL=cancel: as if the artist pressed Esc.
        status = {"CANCELLED"} if fail == "cancel" else \
            bpy.ops.render.render()
        if status != {"FINISHED"}:
            raise SSSError("the render was cancelled; nothing was changed")
        save_passes(scene, inp)
        write_description(scene, found, desc)
    return Job(inp, out, desc, context.view_layer.name,
               summary=f"{len(found.found)} scattering material(s)")


def prepare_last_render(context):
    """Uses the existing Render Result (rendered with the passes the
    library needs) instead of rendering again."""
    scene = context.scene
    _check_scene(scene)
    _check_library()
    found = analyse(scene)
    inp, out, desc = paths_for(scene, scene.frame_current)
    # Pass indices must be those the render used: assign them the same way
    # (and put everything back) to describe the materials.
    with switched_off(scene, found, backlight=False):
        write_description(scene, found, desc)
    save_passes(scene, inp)
    return Job(inp, out, desc, context.view_layer.name,
               summary=f"{len(found.found)} scattering material(s)")


def scatter(job):
    """Runs the library on the job's files. No bpy: thread-safe."""
    try:
        with native.Scene(job.scene_json) as scene:
            radius_scale = job.radius_scale
            if os.environ.get("SSS_TEST_FAIL") == "library":
                radius_scale = -1.0  # the library refuses it: a real error
            job.timings = scene.process(job.input_exr, job.output_exr,
                                        radius_scale=radius_scale,
                                        layer=job.layer or None)
    except native.LibraryError as e:
        raise SSSError(str(e)) from None
    return job


def finish(context, job):
    """Loads the result as an image and wires it into the compositor."""
    from . import nodes
    name = os.path.basename(job.output_exr)
    image = bpy.data.images.get(name)
    if image is not None and bpy.path.abspath(image.filepath) == \
            job.output_exr:
        image.reload()
    else:
        image = bpy.data.images.load(job.output_exr, check_existing=False)
        image.name = name
    context.scene.sss.last_result = job.output_exr
    nodes.ensure_setup(context.scene, image)
    return image


def timings_text(job):
    t = job.timings
    return (f"read {t.get('read', 0):.2f} s, SSS {t.get('scatter', 0):.2f} s,"
            f" write {t.get('write', 0):.2f} s")


def cycles_rw_d_over_radius(a):
    """Mirror of csrc/sss_calibration.c: Burley d over the radius for
    Cycles' random walk at albedo a: its mean free path over Burley's
    searchlight fit, at least 0.032 below albedo 0.995."""
    d = transmission.rw_mfp_over_radius(a) / (1.9 - a + 3.5 * (a - 0.8) ** 2)
    return max(d, 0.032) if a < 0.995 else d


def support_metres(scene, found):
    """How far the material's profile reaches, as the library will use it
    (mirrors csrc/sss_profile.c): Burley 16 d, Gaussians where all but
    1e-5 of the mass lies (4.8 sigma), Jimenez 2 or 3 kernel units."""
    entry = _material_entry(found)
    profile = entry["profile"]
    if profile == "burley":
        r = entry["radius"]
        if entry["mapping"] == "cycles":
            d = [x / (4 * math.pi) for x in r]
        elif entry["mapping"] == "eevee":
            d = [x * 0.0459101 for x in r]
        elif entry["mapping"] == "random-walk":
            d = [x / (3.5 + 100 * (a - 0.33) ** 4)
                 for x, a in zip(r, entry["albedo"])]
        else:
            d = [x * cycles_rw_d_over_radius(a)
                 for x, a in zip(r, entry["albedo"])]
        metres = 16 * max(d)
    elif profile == "gaussians":
        metres = 4.8 * math.sqrt(7.41) * 1e-3 * entry["scale"]
    elif profile == "jimenez":
        taps = entry.get("taps") or scene.sss.taps
        metres = (3 if taps > 20 else 2) * entry["width"] / 3
    else:
        sigma = max(max(entry["near_sigma"]), max(entry["far_sigma"]))
        metres = 4.8 * sigma * 1e-3 * entry["scatter_scale"]
    return metres * scene.sss.radius_scale


def kernel_pixels(scene, found):
    """Expected kernel half-width in pixels at the current resolution, at
    the distance of the material's nearest object."""
    distance = analysis.nearest_distance(scene, found.material)
    if not distance:
        return 0.0
    px = support_metres(scene, found) * \
        analysis.camera_pixels_per_metre(scene, distance)
    return round(px, 1) if math.isfinite(px) else 0.0
