"""Animation renders (Render Animation, `blender -b scene.blend -a`): when
Scene.sss.use_animation is on, the render runs with material SSS switched
off and multilayer EXR output, and each written frame gets its SSS result
beside it (NAME_sss.exr) with a line printed per frame. Everything is
restored when the render completes or is cancelled."""
import os

import bpy
from bpy.app.handlers import persistent

from . import blender_compat as compat
from . import pipeline
from .analysis import analyse
from .switch_off import switched_off

# Per-render state: the open switch-off block and the saved output
# settings, keyed by scene name (handlers get no other place to keep it).
_active = {}


def _enabled(scene):
    return getattr(scene, "sss", None) is not None and \
        scene.sss.use_animation and scene.camera is not None


@persistent
def on_init(scene, *_):
    if not _enabled(scene) or scene.name in _active:
        return
    analysis = analyse(scene)
    if not analysis.found:
        print(f"SSS: {scene.name}: no material scatters; frames are left "
              "alone")
        return
    try:
        desc = os.path.join(pipeline.output_dir(scene),
                            f"{pipeline._safe(scene.name)}_scene.json")
    except pipeline.SSSError as e:
        print(f"SSS: {scene.name}: {e}; frames are left alone", flush=True)
        return
    # Adding a view layer once the render has started is not safe: frames
    # rendered with -a get no back-light layer (no transmission).
    block = switched_off(scene, analysis, backlight=False)
    block.__enter__()
    settings = scene.render.image_settings
    saved = compat.image_settings_state(settings)
    compat.set_multilayer_exr(settings)
    pipeline.write_description(scene, analysis, desc)
    _active[scene.name] = (block, saved, desc)


@persistent
def on_write(scene, *_):
    state = _active.get(scene.name)
    if state is None:
        return
    frame_file = scene.render.frame_path(frame=scene.frame_current)
    root, ext = os.path.splitext(frame_file)
    job = pipeline.Job(frame_file, root + "_sss" + ext, state[2],
                       bpy.context.view_layer.name, scene.sss.radius_scale)
    try:
        pipeline.scatter(job)
        print(f"SSS: frame {scene.frame_current}: {job.output_exr} "
              f"({pipeline.timings_text(job)})", flush=True)
    except pipeline.SSSError as e:
        print(f"SSS: frame {scene.frame_current}: error: {e}", flush=True)


@persistent
def on_end(scene, *_):
    state = _active.pop(scene.name, None)
    if state is None:
        return
    block, saved, _ = state
    settings = scene.render.image_settings
    compat.restore_image_settings(settings, saved)
    block.__exit__(None, None, None)


HANDLERS = ((bpy.app.handlers.render_init, on_init),
            (bpy.app.handlers.render_write, on_write),
            (bpy.app.handlers.render_complete, on_end),
            (bpy.app.handlers.render_cancel, on_end))


def register():
    for handlers, fn in HANDLERS:
        if fn not in handlers:
            handlers.append(fn)


def unregister():
    for handlers, fn in HANDLERS:
        if fn in handlers:
            handlers.remove(fn)
