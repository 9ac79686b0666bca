"""Re-tune SSS after the render, live. The passes of the last render with
SSS (Render with SSS, Apply SSS to Last Render) stay decoded in the library
(native.Frame), per scene; a change of any SSS setting of the scene or of a
scattering material (Principled's Subsurface Weight, Radius, Scale, Base
Color; our own profile fields) scatters them again with the new scene
description, in memory, and pushes the pixels into an image that the
compositor's SSS Result node shows: no render, no file read or written.

Changes are gathered by a depsgraph handler and run once they settle (a
slider being dragged scatters when it pauses); undo and redo scatter again
for the restored settings. The passes are freed when the scene, the file
or the render goes away (another render of the scene, loading a file)."""
import json
import time
from dataclasses import dataclass, field

import bpy
import numpy as np
from bpy.app.handlers import persistent

from . import native, nodes
from .analysis import analyse
from .description import scene_description
from .errors import SSSError
from .switch_off import assign_pass_indices

# How long settings must stay unchanged before a re-tune runs: a slider
# drag sends a change per redraw; its pauses scatter.
SETTLE_SECONDS = 0.08


@dataclass
class Kept:
    """One scene's decoded passes and its last result."""
    frame: native.Frame
    view_layer: str
    combined: np.ndarray            # height x width x 4, rows top first
    description: str = ""           # the JSON it was last scattered with
    timings: dict = field(default_factory=dict)


_kept = {}        # scene name -> Kept
_pending = {}     # scene name -> time of the last change not yet scattered
last_error = {}   # scene name -> the last live re-tune's error, for the UI


def image_name(scene):
    return f"SSS {scene.name}"


def kept(scene):
    """The scene's decoded passes, or None."""
    return _kept.get(scene.name) if scene is not None else None


def drop(scene_name):
    """Frees a scene's passes (its image stays, as a plain image)."""
    entry = _kept.pop(scene_name, None)
    _pending.pop(scene_name, None)
    last_error.pop(scene_name, None)
    if entry is not None:
        entry.frame.close()


def clear():
    for name in list(_kept):
        drop(name)


def description_text(scene):
    """The scene description as the library reads it, computed without
    changing anything (pass indices as a render with SSS assigns them):
    what a re-tune scatters with."""
    found = analyse(scene)
    assign_pass_indices(found)
    return json.dumps(scene_description(scene, found), sort_keys=True)


def keep(scene, view_layer, frame, combined):
    """Keeps a frame read for a render with SSS (pipeline.scatter) and its
    result, replacing what the scene held."""
    drop(scene.name)
    _kept[scene.name] = Kept(frame, view_layer, combined,
                             description_text(scene))


def _push(scene, combined):
    """The pixels into the scene's in-memory result image (float, scene
    linear, premultiplied like the render's), created or resized as
    needed; returns the image."""
    height, width = combined.shape[:2]
    name = image_name(scene)
    image = bpy.data.images.get(name)
    if image is not None and (tuple(image.size) != (width, height) or
                              image.source != 'GENERATED' or
                              not image.is_float):
        bpy.data.images.remove(image)
        image = None
    if image is None:
        image = bpy.data.images.new(name, width, height, alpha=True,
                                    float_buffer=True)
    image.alpha_mode = 'PREMUL'
    # Blender's rows go bottom up, the file's top down.
    image.pixels.foreach_set(np.ascontiguousarray(combined[::-1]).ravel())
    image.update()
    return image


def show(scene, entry):
    """Shows the entry's result in the scene's compositor."""
    image = _push(scene, entry.combined)
    nodes.ensure_setup(scene, image)
    return image


def retune(scene, force=False):
    """Scatters the scene's kept passes with its current settings and shows
    the result. Returns the timings ({"scatter", "total", "methods"}),
    {} when nothing changed since the last scatter (unless force), or
    None when the scene holds no passes. Raises SSSError."""
    entry = kept(scene)
    if entry is None:
        return None
    started = time.perf_counter()
    text = description_text(scene)
    if text == entry.description and not force:
        return {}
    try:
        with native.Scene(text=text) as desc:
            timings = entry.frame.scatter(desc, entry.combined)
    except native.LibraryError as e:
        raise SSSError(str(e)) from None
    entry.description = text
    show(scene, entry)
    timings["total"] = time.perf_counter() - started
    entry.timings = timings
    last_error.pop(scene.name, None)
    return timings


# ------------------------------------------------------------- handlers

# What a depsgraph update must touch to change the description: the scene
# (its SSS settings, the camera it points at), a material or its nodes, a
# camera.
_WATCHED = (bpy.types.Scene, bpy.types.Material, bpy.types.ShaderNodeTree,
            bpy.types.Camera)


def _settled():
    """Timer: re-tunes every scene whose changes have settled; runs
    again while some have not."""
    now = time.monotonic()
    wait = None
    for name, changed in list(_pending.items()):
        left = SETTLE_SECONDS - (now - changed)
        if left > 0.0:
            wait = left if wait is None else min(wait, left)
            continue
        _pending.pop(name, None)
        scene = bpy.data.scenes.get(name)
        if scene is None or name not in _kept:
            drop(name)
            continue
        if not scene.sss.live:
            continue
        try:
            retune(scene)
        except Exception as ex:  # shown in the panel; the loop goes on
            last_error[name] = str(ex).strip().splitlines()[0] if str(ex) \
                else type(ex).__name__
            print(f"SSS: {name}: live re-tune failed: {last_error[name]}",
                  flush=True)
    return wait


def schedule(scene_name):
    """A change to scatter once settings settle."""
    first = not _pending
    _pending[scene_name] = time.monotonic()
    if first and not bpy.app.timers.is_registered(_settled):
        bpy.app.timers.register(_settled, first_interval=SETTLE_SECONDS)


@persistent
def _on_depsgraph(scene, depsgraph):
    for name in [n for n in _kept if n not in bpy.data.scenes]:
        drop(name)          # the scene is gone
    if scene is None or scene.name not in _kept or not scene.sss.live:
        return
    for update in depsgraph.updates:
        if isinstance(update.id, _WATCHED):
            schedule(scene.name)
            return


@persistent
def _on_undo(*_args):
    for name in list(_kept):
        scene = bpy.data.scenes.get(name)
        if scene is not None and scene.sss.live:
            schedule(name)


@persistent
def _on_render(scene, *_args):
    # A new render replaces the Render Result: its passes are not these
    # (a render with SSS keeps its own once it is scattered).
    if scene is not None:
        drop(scene.name)


@persistent
def _on_load(*_args):
    clear()


_HANDLERS = (("depsgraph_update_post", _on_depsgraph),
             ("undo_post", _on_undo), ("redo_post", _on_undo),
             ("render_init", _on_render), ("load_pre", _on_load))


def register():
    for name, fn in _HANDLERS:
        getattr(bpy.app.handlers, name).append(fn)


def unregister():
    for name, fn in _HANDLERS:
        handlers = getattr(bpy.app.handlers, name)
        if fn in handlers:
            handlers.remove(fn)
    if bpy.app.timers.is_registered(_settled):
        bpy.app.timers.unregister(_settled)
    clear()
