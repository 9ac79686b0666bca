"""Re-tune SSS after the render, live. The passes of the last render with
SSS (Render with SSS, Apply SSS to Last Render, F12 or -f with the scene's
switch on), or of a multilayer EXR on a compositor Image node (a farm's
render: Scatter Image Node), stay decoded in the library (native.Frame),
per scene; a change of any SSS setting of the scene or of a
scattering material (Principled's Subsurface Weight, Radius, Scale, Base
Color; our own profile fields) scatters them again with the new scene
description, in memory, and pushes the pixels into an image that the
compositor's SSS Result node shows: no render, no file read or written.

Changes are gathered by a depsgraph handler (and our own settings' update
callbacks) and run once they settle (a slider being dragged scatters when
it pauses), in a worker thread so that the window stays responsive, the
result shown when it is done; undo and redo scatter again for the restored
settings. The passes are freed when the scene, the file
or the render goes away (another render of the scene, loading a file)."""
import json
import os
import threading
import time
from dataclasses import dataclass, field

import bpy
import numpy as np
from bpy.app.handlers import persistent

from . import native, nodes
from .analysis import analyse
from .description import method_name, scene_description
from .errors import SSSError
from .switch_off import assign_pass_indices

# How long settings must stay unchanged before a re-tune runs: a slider
# drag sends a change per redraw; its pauses scatter.
SETTLE_SECONDS = 0.08
# How long after its last re-tune a frame keeps the working memory for the
# next (70 - 150 MB at 1080p; made afresh it costs a third of a re-tune).
TRIM_SECONDS = 10.0


@dataclass
class Kept:
    """One scene's decoded passes and its last result."""
    frame: native.Frame
    view_layer: str
    combined: np.ndarray            # height x width x 4, rows top first
    description: str = ""           # the JSON it was last scattered with
    timings: dict = field(default_factory=dict)
    # A scene description read from a file (a farm's, beside its EXR):
    # re-tunes take its camera and materials with the open scene's method
    # and radius scale; None: the open scene's own description.
    fixed: dict = None
    # Per material, the scene radius scale its back light was rendered at.
    baked: dict = None
    # The live loop's scatter running in the background, if any.
    job: object = None              # _Job
    # When it last scattered (time.monotonic()), and whether the frame
    # still keeps that scatter's working memory.
    used: float = 0.0
    holds_memory: bool = False


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
        _discard(entry)     # its scatter reads the frame: not freed under it
        entry.frame.close()


def clear():
    for name in list(_kept):
        drop(name)


BAKED = "transmission_baked_scale"


def description(scene):
    """The scene description as the library reads it, computed without
    changing anything (pass indices as a render with SSS assigns them)."""
    found = analyse(scene)
    assign_pass_indices(found)
    return scene_description(scene, found)


def description_text(scene, baked=None):
    """What a re-tune scatters with: description() as JSON text. baked
    ({material name: radius scale}): the scale each material's back light
    was rendered at (a material not in it had none baked), which a
    re-tune cannot change; None: as the scene is now."""
    desc = description(scene)
    if baked is not None:
        for entry in desc["materials"]:
            entry.pop(BAKED, None)
            if entry["name"] in baked:
                entry[BAKED] = baked[entry["name"]]
    return json.dumps(desc, sort_keys=True)


def _entry_text(scene, entry):
    """What a re-tune of the entry scatters with."""
    if entry.fixed is None:
        return description_text(scene, entry.baked)
    desc = dict(entry.fixed)
    desc["radius_scale"] = float(entry.fixed.get("radius_scale", 1.0)) * \
        scene.sss.radius_scale
    desc["method"] = method_name(scene.sss.method)
    return json.dumps(desc, sort_keys=True)


def keep(scene, view_layer, frame, combined, fixed=None):
    """Keeps a frame read for a render with SSS (pipeline.scatter) or from
    a file, and its result (None: to be scattered), replacing what the
    scene held. A render's back light stays at the radius it was rendered
    with (the library refuses another scene radius scale for it)."""
    drop(scene.name)
    scattered = combined is not None
    if scattered:
        # the render's scatter left its working memory in the frame: a
        # render may never be re-tuned, so it goes now (the first re-tune
        # makes it again; render handlers may run off the main thread, so
        # no timer is set here)
        frame.trim()
    else:
        combined = np.zeros((frame.height, frame.width, 4), np.float32)
    entry = Kept(frame, view_layer, combined, fixed=fixed)
    if fixed is None:
        entry.baked = {m["name"]: m[BAKED]
                       for m in description(scene)["materials"] if BAKED in m}
        if scattered:
            entry.description = description_text(scene, entry.baked)
    _kept[scene.name] = entry
    return entry


def description_beside(path):
    """The scene description a farm (or the add-on) wrote beside an EXR:
    NAME_scene.json for NAME_passes.exr, else NAME.json; None if none."""
    stem = os.path.splitext(path)[0]
    names = [stem + ".json"]
    if stem.endswith("_passes"):
        names.insert(0, stem[:-len("_passes")] + "_scene.json")
    for name in names:
        if os.path.isfile(name):
            return name
    return None


def keep_file(scene, path, layer=None):
    """Reads a multilayer EXR's passes (a farm's render) for live
    re-tunes, with the description beside it (description_beside) or,
    without one, the open scene's camera and materials; scatters and
    shows it. Returns (entry, description path or None). Raises
    SSSError."""
    desc_path = description_beside(path)
    fixed = None
    if desc_path is not None:
        try:
            with open(desc_path, encoding="utf-8") as f:
                fixed = json.load(f)
        except (OSError, ValueError) as e:
            raise SSSError(f"{desc_path}: {e}") from None
        if not isinstance(fixed, dict):
            raise SSSError(f"{desc_path}: not a scene description")
    elif scene.camera is None:
        raise SSSError(f"{os.path.basename(path)} has no scene description "
                       "beside it and the scene has no camera to describe")
    try:
        frame = native.Frame(path, layer)
    except native.LibraryError as e:
        if layer is None or e.name != "SSS_ERR_MISSING_PASS":
            raise SSSError(str(e)) from None
        try:    # the node's layer has no passes: the file's first that has
            frame = native.Frame(path, None)
        except native.LibraryError as e2:
            raise SSSError(str(e2)) from None
    entry = keep(scene, frame.layer, frame, None, fixed)
    try:
        retune(scene, force=True)
    except SSSError:
        drop(scene.name)
        raise
    return entry, desc_path


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
    _discard(entry)         # this scatter supersedes a background one
    started = time.perf_counter()
    text = _entry_text(scene, entry)
    if text == entry.description and not force:
        return {}
    try:
        with native.Scene(text=text) as desc:
            timings = entry.frame.scatter(desc, entry.combined)
    except native.LibraryError as e:
        raise SSSError(str(e)) from None
    entry.description = text
    _used(entry)
    show(scene, entry)
    timings["total"] = time.perf_counter() - started
    entry.timings = timings
    last_error.pop(scene.name, None)
    return timings


class _Job:
    """The live loop's scatter in a worker thread: the library releases
    the interpreter while it works, so Blender's window stays responsive
    (a large frame can take seconds). It writes its own buffer; the main
    thread shows it once done (_finish)."""

    def __init__(self, entry, text):
        self.text = text
        self.started = time.perf_counter()
        self.combined = np.empty_like(entry.combined)
        self.timings = self.error = None
        self.desc = native.Scene(text=text)   # parsed here: errors now
        self.thread = threading.Thread(target=self._run, args=(entry.frame,),
                                       name="sss-live", daemon=True)
        self.thread.start()

    def _run(self, frame):
        try:
            self.timings = frame.scatter(self.desc, self.combined)
        except Exception as ex:  # reported on the main thread
            self.error = ex


def _used(entry):
    """Notes a scatter of the entry's frame: its working memory is kept
    until TRIM_SECONDS pass without another (_settled)."""
    entry.used = time.monotonic()
    entry.holds_memory = True
    if not bpy.app.timers.is_registered(_settled):
        bpy.app.timers.register(_settled, first_interval=TRIM_SECONDS)


def _trim_idle(now, again):
    """Frees the working memory of frames not re-tuned for TRIM_SECONDS;
    again(seconds) for those that will be."""
    for name, entry in _kept.items():
        if not entry.holds_memory or entry.job is not None or \
                name in _pending:
            continue
        left = TRIM_SECONDS - (now - entry.used)
        if left > 0.0:
            again(left)
        else:
            entry.frame.trim()
            entry.holds_memory = False


def _discard(entry):
    """Waits for the entry's background scatter and drops its result."""
    if entry.job is not None:
        entry.job.thread.join()
        entry.job.desc.close()
        entry.job = None


def _start(scene, entry):
    """Starts a background re-tune when the settings changed since the
    last one; returns whether one runs. Raises SSSError (a description
    the library refuses)."""
    text = _entry_text(scene, entry)
    if text == entry.description:
        return False
    try:
        entry.job = _Job(entry, text)
    except native.LibraryError as e:
        entry.description = text       # not tried again until it changes
        raise SSSError(str(e)) from None
    return True


def _finish(scene, entry):
    """Shows a finished background re-tune (main thread); False while it
    runs."""
    job = entry.job
    if job is None:
        return True
    if job.thread.is_alive():
        return False
    entry.job = None
    job.desc.close()
    entry.description = job.text
    _used(entry)
    if job.error is not None:
        error = job.error
        raise SSSError(str(error)) if isinstance(
            error, native.LibraryError) else error
    entry.combined = job.combined
    show(scene, entry)
    job.timings["total"] = time.perf_counter() - job.started
    entry.timings = job.timings
    last_error.pop(scene.name, None)
    return True


# ------------------------------------------------------------- handlers

# What a depsgraph update must touch to change the description: the scene
# (its SSS settings, the camera it points at), a material or its nodes, a
# camera.
_WATCHED = (bpy.types.Scene, bpy.types.Material, bpy.types.ShaderNodeTree,
            bpy.types.Camera)


def _report(name, ex):
    last_error[name] = str(ex).strip().splitlines()[0] if str(ex) \
        else type(ex).__name__
    print(f"SSS: {name}: live re-tune failed: {last_error[name]}",
          flush=True)


POLL_SECONDS = 0.03   # how often a running background re-tune is looked at


def _settled():
    """Timer: shows the background re-tunes that finished and starts one
    for every scene whose changes have settled (a scene whose re-tune
    still runs starts its next one after it); runs again while any waits
    or runs."""
    now = time.monotonic()
    wait = None

    def again(seconds):
        nonlocal wait
        wait = seconds if wait is None else min(wait, seconds)

    for name, entry in list(_kept.items()):
        scene = bpy.data.scenes.get(name)
        if entry.job is None or scene is None:
            continue
        try:
            if not _finish(scene, entry):
                again(POLL_SECONDS)
        except Exception as ex:  # shown in the panel; the loop goes on
            _report(name, ex)
    for name, changed_at in list(_pending.items()):
        left = SETTLE_SECONDS - (now - changed_at)
        if left > 0.0:
            again(left)
            continue
        scene = bpy.data.scenes.get(name)
        entry = _kept.get(name)
        if scene is None or entry is None:
            _pending.pop(name, None)
            drop(name)
            continue
        if entry.job is not None:
            again(POLL_SECONDS)   # after the running one
            continue
        _pending.pop(name, None)
        if not scene.sss.live:
            continue
        try:
            if _start(scene, entry):
                again(POLL_SECONDS)
        except Exception as ex:
            _report(name, ex)
    _trim_idle(now, again)
    return wait


def schedule(scene_name):
    """A change to scatter once settings settle."""
    first = not _pending
    _pending[scene_name] = time.monotonic()
    if first:
        # registered, it may only be waiting to trim a frame's memory
        if bpy.app.timers.is_registered(_settled):
            bpy.app.timers.unregister(_settled)
        bpy.app.timers.register(_settled, first_interval=SETTLE_SECONDS)


def changed(owner):
    """A setting of ours changed on a scene or material (its update
    callback, properties.py): Blender's depsgraph does not report those."""
    if isinstance(owner, bpy.types.Scene):
        names = [owner.name]
    else:           # a material: any scene may show it
        names = list(_kept)
    for name in names:
        scene = bpy.data.scenes.get(name)
        if name in _kept and scene is not None and scene.sss.live:
            schedule(name)


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
