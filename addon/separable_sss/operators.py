"""Operators: render with SSS, apply SSS to the last render, remove the
compositor set-up, give scattering materials pass indices.

Rendering and loading the result run on the main thread; the library runs
in a worker thread while a modal timer keeps the UI alive and shows
progress. Headless (blender -b) everything runs in order, because modal
timers do not run there."""
import threading
import time

import bpy
from bpy.app.handlers import persistent
from bpy.props import BoolProperty, StringProperty

from . import blender_compat as compat
from . import live, native, nodes, pipeline, render_flow
from .switch_off import pass_indices, required_passes

# Only one run at a time: its worker thread, alive while the library runs
# (also after an Esc, until the library returns).
_worker = None


def _busy():
    return _worker is not None and _worker.is_alive()


def _one_line(ex):
    """An exception as one line for the report (never a traceback)."""
    lines = str(ex).strip().splitlines()
    first = lines[0] if lines else ""
    if isinstance(ex, pipeline.SSSError):
        return first or "SSS failed"
    return "Unexpected error: %s%s" % (type(ex).__name__,
                                       ": " + first if first else "")


def _done_text(job, image):
    path = job.output_exr if job.write else \
        "image '%s' (Save SSS Result writes it)" % image.name
    parts = [job.summary] if job.summary else []
    parts.append(pipeline.timings_text(job))
    if pipeline.methods_text(job):
        parts.append(pipeline.methods_text(job))
    return "SSS done (%s): %s" % ("; ".join(parts), path)


def _redraw(context):
    screen = getattr(context, "screen", None)
    if screen is None:
        return
    for area in screen.areas:
        if area.type in {'NODE_EDITOR', 'IMAGE_EDITOR', 'PROPERTIES'}:
            area.tag_redraw()


def _poll_common(cls, context):
    scene = context.scene
    if scene is None or getattr(scene, "sss", None) is None:
        cls.poll_message_set("No scene")
        return False
    if _busy():
        cls.poll_message_set("An SSS run is in progress")
        return False
    problem = pipeline.scene_problem(scene)
    if problem:
        cls.poll_message_set(problem)
        return False
    return True


def _missing_passes(layer):
    """The names of the passes the library needs that the view layer does
    not render (Render with SSS turns them on for its own render)."""
    if layer is None:
        return []
    try:
        needed = required_passes()
    except native.LibraryError:
        return []  # the run itself says what is wrong with the library
    return [layer.bl_rna.properties["use_pass_" + p].name
            for p in needed if not getattr(layer, "use_pass_" + p)]


# Per scene name, what its last render lacked (the Render Result keeps no
# list of its passes that Python can read): recorded as each render ends.
_last_render_missing = {}


@persistent
def _record_render(scene, *_args):
    _last_render_missing[scene.name] = {
        layer.name: _missing_passes(layer) for layer in scene.view_layers}


class _Run:
    """State shared with the worker thread: no bpy in here."""

    # The library's stages and the share of a frame's time each takes on
    # the bundled scenes (writing the EXR dominates): the bar moves by
    # what is done, not by the clock.
    STAGES = (("read", 0.3), ("scatter", 0.2), ("write", 0.5))
    STAGES_IN_MEMORY = (("read", 0.6), ("scatter", 0.4))

    def __init__(self, job):
        self.job = job
        self.stages = self.STAGES if job.write else self.STAGES_IN_MEMORY
        self.error = None
        self.started = time.monotonic()
        self.stage, self.done = "read", 0.0

    def progress(self, stage, done):
        """Called by the library on the worker thread."""
        self.stage, self.done = stage, done

    def fraction(self):
        """Share of the whole run done, 0..1."""
        total = 0.0
        for stage, weight in self.stages:
            if stage == self.stage:
                return total + weight * self.done
            total += weight
        return total

    def __call__(self):
        try:
            pipeline.scatter(self.job, progress=self.progress)
        except Exception as ex:   # reported on the main thread
            self.error = ex


class _SSSRunBase:
    """Shared by Render with SSS and Apply SSS to Last Render: subclasses
    define prepare(context) -> pipeline.Job (main thread)."""
    # An undo step: the run changes the compositor and the scene's result.
    bl_options = {'REGISTER', 'UNDO'}
    prepare = None  # subclasses: prepare(context) -> pipeline.Job

    def _prepare(self, context):
        """The job, its result shown in memory (no file written)."""
        job = self.prepare(context)
        job.write = False
        return job

    def _nothing_to_do(self, context):
        """A scene where nothing scatters is left alone, and we say so."""
        if pipeline.analyse(context.scene).materials:
            return False
        self.report({'WARNING'}, "No material scatters: nothing to do; "
                    "the render is left alone")
        return True

    # -- headless, or called from a script: everything in order
    def execute(self, context):
        try:
            if self._nothing_to_do(context):
                return {'CANCELLED'}
            job = self._prepare(context)
            pipeline.scatter(job)
            image = pipeline.finish(context, job)
        except Exception as ex:
            self.report({'ERROR'}, _one_line(ex))
            return {'CANCELLED'}
        self.report({'INFO'}, _done_text(job, image))
        return {'FINISHED'}

    # -- interactive: the library runs in a worker thread
    def invoke(self, context, _event):
        global _worker
        if bpy.app.background or context.window is None:
            return self.execute(context)
        try:
            if self._nothing_to_do(context):
                return {'CANCELLED'}
            job = self._prepare(context)
        except Exception as ex:
            self.report({'ERROR'}, _one_line(ex))
            return {'CANCELLED'}
        self._scene_name = context.scene.name
        self._run = _Run(job)
        _worker = threading.Thread(target=self._run, name="sss-scatter",
                                   daemon=True)
        _worker.start()
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.modal_handler_add(self)
        wm.progress_begin(0, 100)
        self._status(context, "Scattering (Esc: stop waiting)")
        return {'RUNNING_MODAL'}

    def modal(self, context, event):
        if event.type == 'ESC' and event.value == 'PRESS':
            self._cleanup(context)
            self.report({'WARNING'}, "SSS: stopped waiting; the running "
                        "library call finishes in the background and its "
                        "result is not loaded")
            return {'CANCELLED'}
        if event.type != 'TIMER':
            return {'PASS_THROUGH'}
        if _worker is not None and _worker.is_alive():
            run = self._run
            context.window_manager.progress_update(
                int(100.0 * run.fraction()))
            self._status(context, "%s %d %% (%.1f s; Esc: stop waiting)" % (
                {"read": "Reading the passes", "scatter": "Scattering",
                 "write": "Writing the result"}.get(run.stage, run.stage),
                int(100.0 * run.done), time.monotonic() - run.started))
            return {'PASS_THROUGH'}
        self._cleanup(context)
        if self._run.error is not None:
            self.report({'ERROR'}, _one_line(self._run.error))
            return {'CANCELLED'}
        return self._finish(context)

    def cancel(self, context):
        # Window closed or file loaded while running.
        self._cleanup(context)

    def _finish(self, context):
        scene = bpy.data.scenes.get(self._scene_name)
        if scene is None:
            self.report({'ERROR'}, "SSS: the scene %r is gone; its result "
                        "was not shown" % self._scene_name)
            return {'CANCELLED'}
        try:
            if scene == context.scene:
                image = pipeline.finish(context, self._run.job)
            else:   # the user switched scenes meanwhile
                with context.temp_override(scene=scene):
                    image = pipeline.finish(bpy.context, self._run.job)
        except Exception as ex:
            self.report({'ERROR'}, _one_line(ex))
            return {'CANCELLED'}
        self.report({'INFO'}, _done_text(self._run.job, image))
        _redraw(context)
        return {'FINISHED'}

    def _status(self, context, text):
        workspace = getattr(context, "workspace", None)
        if workspace is not None:
            workspace.status_text_set("SSS: " + text)

    def _cleanup(self, context):
        wm = context.window_manager
        timer = getattr(self, "_timer", None)
        if timer is not None:
            wm.event_timer_remove(timer)
            self._timer = None
        wm.progress_end()
        workspace = getattr(context, "workspace", None)
        if workspace is not None:
            workspace.status_text_set(None)


class SSS_OT_render(_SSSRunBase, bpy.types.Operator):
    """Render the current frame with material SSS off, scatter its diffuse
    light with the library and show the result in the compositor"""
    bl_idname = "sss.render"
    bl_label = "Render with SSS"

    @classmethod
    def poll(cls, context):
        return _poll_common(cls, context)

    def prepare(self, context):
        return pipeline.prepare_render(context)


class SSS_OT_apply(_SSSRunBase, bpy.types.Operator):
    """Scatter the diffuse light of the existing render (it must hold the
    diffuse, depth and material index passes) without rendering again"""
    bl_idname = "sss.apply"
    bl_label = "Apply SSS to Last Render"

    @classmethod
    def poll(cls, context):
        if not _poll_common(cls, context):
            return False
        if bpy.data.images.get("Render Result") is None:
            cls.poll_message_set("There is no render yet: render first, "
                                 "or use Render with SSS")
            return False
        # The passes of a render with SSS are kept: a re-tune needs no
        # more (the render with the switch on rendered them on a copy).
        layer = context.view_layer
        entry = live.kept(context.scene)
        if entry is not None and layer is not None and \
                entry.view_layer == layer.name:
            return True
        # Unknown (a render before the add-on was on): tried, and the
        # library names what is missing.
        missing = _last_render_missing.get(context.scene.name, {}).get(
            layer.name if layer is not None else "")
        if missing:
            cls.poll_message_set("The render lacks %s: use Render with "
                                 "SSS, or enable them in View Layer "
                                 "Properties and render again"
                                 % ", ".join(missing))
            return False
        return True

    def prepare(self, context):
        return pipeline.prepare_last_render(context)

    def _retune(self, context):
        """With the render's passes kept (live.py), scatters them again
        with the current settings, in memory; None when none are kept."""
        scene = context.scene
        entry = live.kept(scene)
        layer = context.view_layer
        if entry is None or (layer is not None and
                             entry.view_layer != layer.name):
            return None
        try:
            timings = live.retune(scene, force=True)
        except Exception as ex:
            self.report({'ERROR'}, _one_line(ex))
            return {'CANCELLED'}
        methods = ", ".join(f"{name}: {m}" for name, m in
                            sorted(timings.get("methods", {}).items()))
        self.report({'INFO'}, "SSS re-tuned from the render's kept passes "
                    "(SSS %.2f s, in all %.2f s%s)" % (
                        timings["scatter"], timings["total"],
                        "; " + methods if methods else ""))
        _redraw(context)
        return {'FINISHED'}

    def execute(self, context):
        return self._retune(context) or super().execute(context)

    def invoke(self, context, event):
        return self._retune(context) or super().invoke(context, event)


class SSS_OT_remove_setup(bpy.types.Operator):
    """Remove the SSS nodes from the compositor; the Render Layers image
    goes back into the Composite output"""
    bl_idname = "sss.remove_setup"
    bl_label = "Remove SSS Nodes"
    bl_options = {'REGISTER', 'UNDO'}

    @classmethod
    def poll(cls, context):
        scene = context.scene
        if scene is None or nodes.find_result(scene) is None:
            cls.poll_message_set("There are no SSS nodes in the compositor")
            return False
        return True

    def execute(self, context):
        try:
            count = nodes.remove_setup(context.scene)
        except Exception as ex:
            self.report({'ERROR'}, _one_line(ex))
            return {'CANCELLED'}
        self.report({'INFO'}, "Removed %d SSS node(s)" % count)
        return {'FINISHED'}


class SSS_OT_assign_pass_indices(bpy.types.Operator):
    """Give every scattering material a pass index of its own (renders do
    this for the time of the render only): keeps indices stable for farm
    renders with a hand-written scene description"""
    bl_idname = "sss.assign_pass_indices"
    bl_label = "Assign Pass Indices"
    bl_options = {'REGISTER', 'UNDO'}

    @classmethod
    def poll(cls, context):
        if context.scene is None or getattr(context.scene, "sss",
                                            None) is None:
            cls.poll_message_set("No scene")
            return False
        return True

    def execute(self, context):
        try:
            found = pipeline.analyse(context.scene)
        except Exception as ex:
            self.report({'ERROR'}, _one_line(ex))
            return {'CANCELLED'}
        if not found.materials:
            self.report({'WARNING'}, "No material scatters")
            return {'CANCELLED'}
        changed = []
        for mat, index in pass_indices(found).items():
            if mat.pass_index != index:
                mat.pass_index = index
                changed.append("%s: %d" % (mat.name, index))
        if changed:
            self.report({'INFO'}, "Pass indices: " + ", ".join(changed))
        else:
            self.report({'INFO'}, "Every scattering material already has "
                        "a pass index of its own")
        return {'FINISHED'}


class SSS_OT_scatter_image(bpy.types.Operator):
    """Scatter the passes of the multilayer EXR on the active Image node (a
    farm's render) with the scene description beside it, or the scene's
    camera and materials, and keep them for live re-tunes"""
    bl_idname = "sss.scatter_image"
    bl_label = "Scatter Image Node"
    bl_options = {'REGISTER', 'UNDO'}

    @classmethod
    def poll(cls, context):
        scene = context.scene
        if scene is None or getattr(scene, "sss", None) is None:
            cls.poll_message_set("No scene")
            return False
        tree = compat.compositor_tree(scene)
        node = tree.nodes.active if tree is not None else None
        if nodes.image_node_file(node) is None:
            cls.poll_message_set("Make an Image node with a multilayer EXR "
                                 "of render passes the active node")
            return False
        return True

    def execute(self, context):
        scene = context.scene
        node = compat.compositor_tree(scene).nodes.active
        path = nodes.image_node_file(node)
        layer = getattr(node, "layer", "") or None
        try:
            entry, desc = live.keep_file(scene, path, layer)
        except Exception as ex:
            self.report({'ERROR'}, _one_line(ex))
            return {'CANCELLED'}
        self.report({'INFO'}, "SSS: %s (layer %s) scattered with %s in "
                    "%.2f s; kept for live re-tunes" % (
                        bpy.path.basename(path), entry.frame.layer,
                        bpy.path.basename(desc) if desc else
                        "the scene's camera and materials",
                        entry.timings.get("total", 0.0)))
        _redraw(context)
        return {'FINISHED'}


class SSS_OT_save_result(bpy.types.Operator):
    """Write the SSS result the compositor shows as a multilayer EXR: the
    render's passes with the layer SSS (Combined, DiffLight), as the sss
    command writes it"""
    bl_idname = "sss.save_result"
    bl_label = "Save SSS Result"

    filepath: StringProperty(subtype='FILE_PATH')
    filter_glob: StringProperty(default="*.exr", options={'HIDDEN'})

    @classmethod
    def poll(cls, context):
        entry = live.kept(context.scene)
        if entry is None or not entry.description:
            cls.poll_message_set("No SSS result is kept: render with SSS "
                                 "first")
            return False
        return True

    def invoke(self, context, _event):
        if not self.filepath:
            scene = context.scene
            self.filepath = pipeline.paths_for(scene, scene.frame_current)[1]
        context.window_manager.fileselect_add(self)
        return {'RUNNING_MODAL'}

    def execute(self, context):
        path = bpy.path.abspath(self.filepath)
        if not path.lower().endswith(".exr"):
            path += ".exr"
        try:
            pipeline.save_result(context.scene, path)
        except Exception as ex:
            self.report({'ERROR'}, _one_line(ex))
            return {'CANCELLED'}
        self.report({'INFO'}, "SSS result written to %s" % path)
        return {'FINISHED'}


class SSS_OT_render_frame(bpy.types.Operator):
    """Render the active scene (F12; Ctrl F12: the animation). With the
    scene's Screen-space SSS on, the render runs in the foreground so that
    it can be scattered; otherwise it is Blender's own render"""
    bl_idname = "sss.render_frame"
    bl_label = "Render"
    bl_options = {'REGISTER'}

    animation: BoolProperty(name="Animation", default=False)

    def execute(self, context):
        scene = context.scene
        if not render_flow.enabled(scene) and \
                not render_flow.old_setup_shows(scene):
            return bpy.ops.render.render('INVOKE_DEFAULT', use_viewport=True,
                                         animation=self.animation)
        render_flow.last_error = None
        status = bpy.ops.render.render('EXEC_DEFAULT',
                                       animation=self.animation,
                                       write_still=False)
        render_flow.remove_leftovers()
        if render_flow.last_error:
            self.report({'ERROR'}, _one_line(render_flow.last_error))
            return {'CANCELLED'}
        if context.window is not None and not bpy.app.background:
            bpy.ops.render.view_show('INVOKE_DEFAULT')
        return status


classes = (SSS_OT_render, SSS_OT_apply, SSS_OT_remove_setup,
           SSS_OT_assign_pass_indices, SSS_OT_scatter_image,
           SSS_OT_save_result, SSS_OT_render_frame)

_register_classes, _unregister_classes = \
    bpy.utils.register_classes_factory(classes)
_keymap_items = []


def register():
    _register_classes()
    bpy.app.handlers.render_post.append(_record_render)
    # F12 and Ctrl F12 through the operator above, where Blender has a
    # window (no key configuration exists under blender -b).
    kc = bpy.context.window_manager.keyconfigs.addon
    if kc is None:
        return
    km = kc.keymaps.new(name="Screen", space_type='EMPTY')
    for ctrl in (False, True):
        item = km.keymap_items.new("sss.render_frame", 'F12', 'PRESS',
                                   ctrl=ctrl)
        item.properties.animation = ctrl
        _keymap_items.append((km, item))


def unregister():
    if _record_render in bpy.app.handlers.render_post:
        bpy.app.handlers.render_post.remove(_record_render)
    for km, item in _keymap_items:
        km.keymap_items.remove(item)
    _keymap_items.clear()
    _unregister_classes()
