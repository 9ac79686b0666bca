"""The add-on's pipeline: analyse the scene, render with material SSS
switched off, save the passes as a multilayer EXR with the scene
description beside it, run the library (the same code path as the `sss`
command), and bring the result back as an image. Functions that touch bpy
run on the main thread; scatter() does not touch bpy and may run in a
worker thread."""
import math
import os
import re
import tempfile
import time
from dataclasses import dataclass, field

import bpy
import numpy as np

from . import analysis, live, native, nodes, preferences, transmission
from . import blender_compat as compat
from .analysis import Analysis, Found, analyse  # noqa: F401
from .description import (camera_pixels_per_metre,  # noqa: F401
                          library_material, scene_description,
                          write_description)
from .errors import SSSError
from .switch_off import switched_off


@dataclass
class Job:
    input_exr: str
    output_exr: str
    scene_json: str
    layer: str = ""
    radius_scale: float = 1.0  # times the description's own
    timings: dict = field(default_factory=dict)
    summary: str = ""
    # What scatter() read and made, kept by finish() for live re-tunes.
    frame: object = None            # native.Frame
    combined: object = None         # numpy height x width x 4
    # Whether scatter() writes output_exr (scripts and farms want the
    # file); the operators show the result in memory instead, and Save
    # SSS Result writes it when wanted.
    write: bool = True


def output_path(scene):
    """The folder for passes and results: the scene's setting, else the
    add-on's default (Preferences), else a per-user temporary folder
    (nothing is created)."""
    prefs = preferences.get()
    for path in (scene.sss.output_dir, prefs.output_dir if prefs else ""):
        if path:
            return bpy.path.abspath(path)
    return os.path.join(tempfile.gettempdir(), "separable_sss")


def output_dir(scene):
    """output_path(), created and checked writable."""
    path = output_path(scene)
    try:
        os.makedirs(path, exist_ok=True)
        probe = tempfile.NamedTemporaryFile(dir=path, prefix=".sss-probe-")
        probe.close()
    except OSError as e:
        raise SSSError(f"output folder {path} is not writable: "
                       f"{e.strerror or e}") from None
    return path


def safe_name(name):
    """A scene or layer name as it appears in the add-on's file names."""
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name) or "scene"


def paths_for(scene, frame):
    base = os.path.join(output_dir(scene),
                        f"{safe_name(scene.name)}_{frame:04d}")
    return base + "_passes.exr", base + "_sss.exr", base + "_scene.json"


# ------------------------------------------------------------- description

# ----------------------------------------------------------------- render

def scene_problem(scene):
    """Why the scene cannot be rendered with SSS, as one sentence, or None:
    what the operators' poll, the sidebar and every run say."""
    if scene.camera is None:
        return "The scene has no camera"
    if scene.render.engine != "CYCLES":
        return (f"{scene.render.engine.title()} renders have no Material "
                "Index pass: switch the render engine to Cycles")
    return None


def check_scene(scene):
    """Raises SSSError with scene_problem's sentence, if any."""
    problem = scene_problem(scene)
    if problem:
        raise SSSError(problem[0].lower() + problem[1:])


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


def check_library():
    """Fails before a long render, not after it, if libsss is missing."""
    try:
        native.library()
    except native.LibraryError as e:
        raise SSSError(str(e)) from None


def prepare_render(context):
    """Renders the current frame with material SSS off and restores the
    scene; returns the job for scatter()."""
    scene = context.scene
    check_scene(scene)
    check_library()
    found = analyse(scene)
    inp, out, desc = paths_for(scene, scene.frame_current)
    with switched_off(scene, found) as undo:
        # The compositor would only show the previous SSS result again.
        undo.set(scene.render, "use_compositing", False)
        # SSS_TEST_FAIL=cancel: as if the artist pressed Esc (which a
        # headless test cannot; every other failure is injected from the
        # test side, tests/blender/faults.py).
        status = {"CANCELLED"} if os.environ.get("SSS_TEST_FAIL") == \
            "cancel" else bpy.ops.render.render()
        if status != {"FINISHED"}:
            raise SSSError("the render was cancelled; nothing was changed")
        save_passes(scene, inp)
        write_description(scene, found, desc)
    summary = f"{len(found.materials)} scattering material(s)"
    if transmission.transmitting(found):
        need, why = transmission.wanted(scene, found)
        summary += f"; back-light layer {'on' if need else 'off'}, {why}"
    return Job(inp, out, desc, context.view_layer.name, summary=summary)


def prepare_last_render(context):
    """Uses the existing Render Result (rendered with the passes the
    library needs) instead of rendering again."""
    scene = context.scene
    check_scene(scene)
    check_library()
    found = analyse(scene)
    inp, out, desc = paths_for(scene, scene.frame_current)
    # Pass indices must be those the render used: assign them the same way
    # (and put everything back) to describe the materials.
    with switched_off(scene, found, backlight=False):
        write_description(scene, found, desc)
    save_passes(scene, inp)
    return Job(inp, out, desc, context.view_layer.name,
               summary=f"{len(found.materials)} scattering material(s)")


def scatter(job, progress=None):
    """Runs the library on the job's files: reads the passes (kept in
    job.frame for live re-tunes), scatters them and writes the result.
    No bpy: thread-safe. progress(stage, done): where the frame is
    ("read", "scatter", "write", each from 0 to 1)."""
    def told(stage):
        if progress is None:
            return None
        return lambda done: progress(stage, done)

    timings = {}
    frame = None
    try:
        with native.Scene(job.scene_json) as scene:
            radius_scale = job.radius_scale
            if progress is not None:
                progress("read", 0.0)
            started = time.perf_counter()
            frame = native.Frame(job.input_exr, job.layer or None,
                                 progress=told("read"))
            timings["read"] = time.perf_counter() - started
            combined = np.empty((frame.height, frame.width, 4), np.float32)
            light = np.empty((frame.height, frame.width, 3), np.float32) \
                if job.write else None
            timings.update(frame.scatter(scene, combined, light,
                                         radius_scale=radius_scale,
                                         progress=progress))
            if job.write:
                if progress is not None:
                    progress("write", 0.0)
                started = time.perf_counter()
                frame.write(job.output_exr, combined, light,
                            progress=told("write"))
                timings["write"] = time.perf_counter() - started
    except native.LibraryError as e:
        if frame is not None:
            frame.close()
        raise SSSError(str(e)) from None
    job.timings = timings
    job.frame, job.combined = frame, combined
    return job


def finish(context, job):
    """Shows the result in the compositor, the frame kept for live
    re-tunes: the file scatter() wrote, loaded as an image, or (job.write
    off) the pixels pushed into the scene's in-memory image."""
    scene = context.scene
    entry = None
    if job.frame is not None:
        entry = live.keep(scene, job.layer, job.frame, job.combined)
        job.frame = job.combined = None
    if not job.write:
        return live.show(scene, entry)
    name = os.path.basename(job.output_exr)
    image = bpy.data.images.get(name)
    if image is not None and bpy.path.abspath(image.filepath) == \
            job.output_exr:
        image.reload()
    else:
        image = bpy.data.images.load(job.output_exr, check_existing=False)
        image.name = name
    scene.sss.last_result = job.output_exr
    nodes.ensure_setup(scene, image)
    return image


def save_result(scene, path):
    """Writes the scene's kept frame with its current result as the `sss`
    command does (every input channel and the SSS layer, atomically):
    scattered once more with the description it is shown with, for the
    diffuse light the compositor's image does not hold."""
    entry = live.kept(scene)
    if entry is None:
        raise SSSError("no SSS result is kept for this scene: render with "
                       "SSS first")
    if not entry.description:
        raise SSSError("the kept result has not been scattered yet")
    combined = np.empty_like(entry.combined)
    light = np.empty(combined.shape[:2] + (3,), np.float32)
    try:
        with native.Scene(text=entry.description) as desc:
            entry.frame.scatter(desc, combined, light)
        entry.frame.write(path, combined, light)
    except native.LibraryError as e:
        raise SSSError(str(e)) from None
    scene.sss.last_result = path
    return path


def timings_text(job):
    t = job.timings
    text = f"read {t.get('read', 0):.2f} s, SSS {t.get('scatter', 0):.2f} s"
    return text + (f", write {t['write']:.2f} s" if "write" in t else "")


def methods_text(job):
    """The method each material ran ("Skin: disk, Wax: separable"): what
    the Auto method chose, frame by frame."""
    methods = job.timings.get("methods") or {}
    return ", ".join(f"{name}: {m}" for name, m in sorted(methods.items()))


def support_metres(scene, found):
    """How far the material's profile reaches, as the library uses it."""
    return native.material_support(library_material(scene, found)) * \
        scene.sss.radius_scale


def kernel_pixels(scene, found):
    """Expected kernel half-width in pixels at the current resolution, at
    the distance of the material's nearest object."""
    distance = analysis.nearest_distance(scene, found.material)
    if not distance:
        return 0.0
    px = support_metres(scene, found) * \
        camera_pixels_per_metre(scene, distance)
    return round(px, 1) if math.isfinite(px) else 0.0
