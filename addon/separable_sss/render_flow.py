"""SSS inside Blender's own render flow. With "Screen-space SSS" on for the
scene (Scene.sss.enabled), a render that runs on the main thread
(`blender -b shot.blend -f N`, `-a`, bpy.ops.render.render() from a
script) is scattered frame by frame, and Blender writes the frames, the
File Output nodes and the Render Result from the scattered image, in the
scene's own format and colour management.

Blender has no hook between rendering and compositing and runs no Python
inside the compositor, so:

- render_init: a copy of the scene (it shares the objects, materials and
  camera) is made to render the passes; in the scene's compositor every
  Render Layers node of the scene is muted and what it fed is fed from
  Image nodes reading the library's result for its view layer (the SSS
  layer's Combined and Alpha for Image and Alpha, the layer's own passes
  for the rest). A compositor without a live Render Layers node makes
  Blender's render of the scene a compositing-only one.
- render_pre, per frame: the scene is described at that frame (animated
  camera, radius, strength), the copy renders the frame's passes with
  material SSS switched off (and the back-light layer where transmission
  needs it), and the library scatters every view layer the compositor
  shows; the Image nodes read that frame's files.
- render_complete, render_cancel: the compositor, the materials and the
  scene are as before; the copy and the temporary files are removed.
- A frame that cannot be scattered stops the job: the message names the
  frame (and the pass), everything is restored and `blender -b` exits with
  status 1; no frame is written without SSS as if it had it.

Blender's own F12 renders in a job thread, where a second render cannot
start: the add-on binds F12 and Ctrl F12 to sss.render_frame, which with
the switch on renders in the foreground (operators.py); a render job that
starts anyway is left alone, and says so."""
import os
import shutil
import sys
import tempfile
import threading

import bpy
from bpy.app.handlers import persistent

from . import blender_compat as compat
from . import live, native, nodes, pipeline, transmission
from .switch_off import TAG, Undo, switched_off

# The render in progress, per scene name (handlers get nothing else).
_flows = {}
# The last failure, for the operator that started the render.
last_error = None
# Under blender -b a failed frame ends the process with status 1: Blender
# offers Python no other way to fail a render job.
EXIT_ON_FAILURE = bpy.app.background
# Copies whose render has ended: removing a scene inside a render handler
# crashes Blender, so they go at the next chance (see remove_leftovers).
_leftovers = []


def _say(scene, text):
    print(f"SSS: {scene.name}: {text}", flush=True)


def enabled(scene):
    return getattr(scene, "sss", None) is not None and scene.sss.enabled


class Flow:
    """One render of one scene with SSS: its copy, its files, its changes
    to the compositor (undone by close)."""

    def __init__(self, scene):
        self.scene = scene
        self.copy = None
        self.folder = tempfile.mkdtemp(prefix="render-",
                                       dir=pipeline.output_dir(scene))
        self.tree_undo = Undo()
        self.layers = []     # view layer names the compositor shows
        self.images = {}     # view layer name -> its result image
        self.done = set()    # frames whose results are on disk
        self.first, self.keep_first = None, True
        self.failed = False
        self.render_layers = []
        self.denoise = False
        # The last frame's decoded passes and result for the view layer
        # the compositor shows first: kept for live re-tunes (live.py)
        # when the render completes.
        self.kept = None

    # -- files
    def passes_path(self, frame):
        return os.path.join(self.folder, f"passes_{frame:04d}.exr")

    def result_path(self, layer, frame):
        return os.path.join(self.folder,
                            f"{pipeline.safe_name(layer)}_{frame:04d}.exr")

    # -- set-up
    def open(self):
        scene = self.scene
        pipeline.check_scene(scene)
        pipeline.check_library()
        copy = scene.copy()
        copy.name = f"{scene.name} (SSS passes)"
        self.copy = copy
        copy.render.use_compositing = False
        copy.render.use_sequencer = False
        compat.set_multilayer_exr(copy.render.image_settings)
        # The scene's denoiser applies to the scattered image (_rewire):
        # Cycles' own would denoise only Combined, which the recombination
        # does not use, so the copy stores OIDN's albedo and normal instead.
        self.denoise = scene.render.engine == 'CYCLES' and \
            scene.cycles.use_denoising
        if self.denoise:
            copy.cycles.use_denoising = False
            for layer in copy.view_layers:
                layer.cycles.denoising_store_passes = True
        self.tree_undo.set(scene.render, "use_compositing", True)
        tree = compat.compositor_tree(scene)
        if tree is None:  # Blender's default: Render Layers to Composite
            tree = compat.compositor_tree(scene, create=True)
            self.tree_undo.add(lambda: compat.remove_compositor(scene, tree))
        self.tree = tree
        self.render_layers = [
            n for n in tree.nodes
            if n.bl_idname == "CompositorNodeRLayers" and not n.mute and
            (n.scene is None or n.scene == scene)]
        self.layers = sorted({n.layer for n in self.render_layers})
        if self.denoise and any(n.bl_idname == "CompositorNodeDenoise" and
                                not n.mute for n in tree.nodes):
            self.denoise = False  # the artist denoises in the compositor
        if not self.layers:
            raise pipeline.SSSError("the compositor shows no view layer of "
                                    "this scene")
        self.first = scene.frame_current
        self.frame(self.first)
        for node in self.render_layers:
            self._rewire(node)
        self._follow_old_setup()

    def _follow_old_setup(self):
        """Render with SSS's result node, if one is left in the tree,
        shows this render's result too, never an old one."""
        node = nodes.find_result(self.scene)
        if node is None:
            return
        view_layer = bpy.context.view_layer
        layer = view_layer.name if view_layer and \
            view_layer.name in self.layers else self.layers[0]
        multilayer = node.image is not None and node.image.type == 'MULTILAYER'
        old = (node.image, node.layer if multilayer else None,
               node.frame_start, node.frame_offset, node.frame_duration)
        # Where its image went: an in-memory result (Render with SSS,
        # a live re-tune) leaves by the Image socket, a file's by the SSS
        # layer's Combined, which is what this render's file shows.
        tree = self.tree
        went = [(link.from_socket.identifier, link.to_socket)
                for out in node.outputs for link in out.links]

        def restore(n=node, o=old, went=went):
            n.image = o[0]
            if o[1]:
                n.layer = o[1]
            n.frame_start, n.frame_offset, n.frame_duration = o[2:]
            for ident, to in went:
                source = next((s for s in n.outputs if s.identifier == ident),
                              None)
                if source is not None and not any(
                        link.from_socket == source for link in to.links):
                    tree.links.new(source, to)
        self.tree_undo.add(restore)
        node.image = self.images[layer]
        node.layer = nodes.RESULT_LAYER
        source = node.outputs.get(nodes.RESULT_PASS)
        for _, to in went:
            if source is not None and not any(
                    link.from_socket == source for link in to.links):
                tree.links.new(source, to)
        self._follow_frames(node)

    def _result_nodes(self, node):
        """Two Image nodes on the layer's result: its SSS layer and its
        own passes."""
        tree, undo = self.tree, self.tree_undo
        image = self.images.get(node.layer)
        if image is None:
            path = self.result_path(node.layer, self.scene.frame_current)
            image = bpy.data.images.load(path, check_existing=False)
            image.source = 'SEQUENCE'
            self.images[node.layer] = image
        made = []
        for dy, layer in ((0, nodes.RESULT_LAYER), (-260, node.layer)):
            im = tree.nodes.new("CompositorNodeImage")
            undo.add(lambda im=im: tree.nodes.remove(im))
            im.label = TAG
            im.image = image
            im.location = (node.location.x, node.location.y + dy)
            im.layer = layer
            self._follow_frames(im)
            made.append(im)
        return made

    def _follow_frames(self, node):
        """The Image node reads the file numbered as the scene's frame."""
        start = min(self.scene.frame_start, self.scene.frame_current, 1)
        node.frame_start = start
        node.frame_offset = start - 1
        node.frame_duration = 1048574 - start

    def _denoised(self, node, sss, own):
        """The scattered image through a Denoise node with the layer's
        albedo and normal: what the scene's denoiser asks for (measured:
        docs/denoising.md)."""
        tree, undo = self.tree, self.tree_undo
        dn = tree.nodes.new("CompositorNodeDenoise")
        undo.add(lambda: tree.nodes.remove(dn))
        dn.label = TAG
        dn.location = (node.location.x + 200, node.location.y)
        compat.set_denoise_hdr(dn)
        tree.links.new(sss.outputs["Combined"], dn.inputs["Image"])
        for name in ("Normal", "Albedo"):
            aux = own.outputs.get("Denoising " + name)
            if aux is not None:
                tree.links.new(aux, dn.inputs[name])
        return dn.outputs[0]

    def _rewire(self, node):
        tree, undo = self.tree, self.tree_undo
        sss, own = self._result_nodes(node)
        image = self._denoised(node, sss, own) if self.denoise else \
            sss.outputs.get("Combined")
        for link in list(tree.links):
            if link.from_node != node:
                continue
            name, target = link.from_socket.name, link.to_socket
            if name in ("Image", "Alpha"):
                source = image if name == "Image" else sss.outputs.get(
                    "Alpha")
            else:
                source = own.outputs.get(name)
            original = link.from_socket
            tree.links.remove(link)
            undo.add(lambda o=original, t=target: tree.links.new(o, t))
            if source is None:
                _say(self.scene, f"the compositor's {name} of view layer "
                     f"{node.layer} is not in the result; left unlinked")
                continue
            new = tree.links.new(source, target)
            undo.add(lambda n=new: tree.links.remove(n))
        undo.set(node, "mute", True)

    # -- per frame
    def frame(self, frame):
        """Renders the frame's passes with SSS off and scatters every
        shown view layer into its result file."""
        if frame in self.done:
            if frame == self.first:
                self.keep_first = False  # reached: it may go after this
            return
        scene, copy = self.scene, self.copy
        # Blender updates the original data (what the description reads:
        # camera, radii, strengths) only after render_pre: evaluate the
        # frame now, for both scenes.
        scene.frame_set(frame)
        copy.frame_set(frame)
        found = pipeline.analyse(scene)
        if transmission.transmitting(found):
            need, why = transmission.wanted(scene, found)
            _say(scene, f"frame {frame}: back-light layer "
                 f"{'on' if need else 'off'}, {why}")
        desc = os.path.join(self.folder, f"scene_{frame:04d}.json")
        with switched_off(copy, found):
            pipeline.write_description(scene, found, desc)
            copy.render.filepath = self.passes_path(frame)
            status = bpy.ops.render.render(write_still=True,
                                           scene=copy.name)
        passes = self.passes_path(frame)
        if status != {'FINISHED'} or not os.path.exists(passes):
            raise pipeline.SSSError(f"frame {frame}: the passes were not "
                                    "rendered")
        for layer in self.layers:
            job = pipeline.Job(passes, self.result_path(layer, frame), desc,
                               layer)
            try:
                pipeline.scatter(job)
            except pipeline.SSSError as e:
                raise pipeline.SSSError(f"frame {frame}: {e}") from None
            if layer == self.layers[0]:
                self.keep(layer, job)
            _say(scene, f"frame {frame}, view layer {layer}: "
                 f"{pipeline.timings_text(job)}")
        os.remove(passes)
        # The results of the frame before go; the first frame's stay until
        # the render reaches it (open renders the scene's current frame,
        # which an animation may reach later).
        keep = {self.first} if self.keep_first else set()
        for old in self.done - keep:
            for layer in self.layers:
                _remove(self.result_path(layer, old))
        self.done = {frame} | keep

    def keep(self, layer, job):
        """Holds the frame's passes for live re-tunes, freeing the last."""
        if self.kept is not None:
            self.kept[1].close()
        self.kept = (layer, job.frame, job.combined)
        job.frame = job.combined = None

    def write_passes(self, frame):
        """A multilayer EXR output holds only the composite after a
        compositing-only render: the frame's passes (every shown view
        layer's, and its SSS layer: SSS for the first, SSS-NAME for the
        others) join it, written over Blender's file atomically."""
        path = bpy.path.abspath(self.scene.render.frame_path(frame=frame))
        if not os.path.exists(path):
            return
        first = self.layers[0]
        with native.Exr(self.result_path(first, frame)) as out, \
                native.Exr(path) as written:
            # A view layer already named SSS-NAME would be replaced by
            # NAME's result: refused, as the library refuses one named SSS.
            taken = {layer for layer, *_ in out.passes()}
            result = nodes.RESULT_LAYER
            for layer in self.layers[1:]:
                if f"{result}-{layer}" in taken:
                    raise pipeline.SSSError(
                        f"frame {frame}: view layer '{result}-{layer}' has "
                        f"the name of view layer '{layer}''s SSS result, "
                        "which would replace it; rename it")
            out.copy_layer(written, "Composite")
            for layer in self.layers[1:]:
                with native.Exr(self.result_path(layer, frame)) as other:
                    out.copy_layer(other, layer)
                    out.copy_layer(other, result, f"{result}-{layer}")
            out.write(path)

    def blank(self):
        """After a failure: the compositor gets nothing from this scene's
        view layers for the rest of the render."""
        self.failed = True
        for node in self.render_layers:
            if not node.mute:
                self.tree_undo.set(node, "mute", True)
        for image in self.images.values():
            image.filepath = os.path.join(self.folder, "failed_####.exr")

    # -- tear-down
    def close(self, completed=False):
        """Puts the compositor back; after a completed render the last
        frame's passes stay decoded for live re-tunes."""
        if self.kept is not None:
            layer, frame, combined = self.kept
            self.kept = None
            if completed and not self.failed:
                live.keep(self.scene, layer, frame, combined)
            else:
                frame.close()
        errors = self.tree_undo.run()
        for image in self.images.values():
            try:
                bpy.data.images.remove(image)
            except ReferenceError:  # already gone
                pass
        if self.copy is not None and self.copy.name in bpy.data.scenes:
            _leftovers.append(self.copy.name)
        shutil.rmtree(self.folder, ignore_errors=True)
        if errors:
            _say(self.scene, "could not restore the compositor exactly: " +
                 "; ".join(errors))


def _remove(path):
    try:
        os.remove(path)
    except OSError:
        pass


def _fail(scene, flow, error):
    """Stops the job. Under -b: everything restored, then the process
    exits with status 1. In a session (Blender offers no way to cancel a
    render from Python) the rest of the render composites nothing, so no
    frame passes for a scattered one, and the operator reports the error;
    the end of the render restores everything."""
    global last_error
    last_error = error
    _say(scene, f"error: {error}")
    if flow is None or EXIT_ON_FAILURE:
        if flow is not None:
            _flows.pop(scene.name, None)
            flow.close()
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(1)
    flow.blank()


def _ours(scene):
    return any(f.copy is not None and f.copy.name == scene.name
               for f in _flows.values())


def _old_setup(scene):
    """(tree, Composite input, Render Layers node) when the Composite is
    fed by the set-up Render with SSS left in the compositor and a Render
    Layers node could feed it instead; else None."""
    tree = compat.compositor_tree(scene)
    if tree is None or nodes.find_result(scene) is None:
        return None
    composite = compat.composite_input(tree, create=False)
    if composite is None or not composite.is_linked or \
            not composite.links[0].from_node.get(nodes.ROLE_KEY):
        return None
    layers = next((n for n in tree.nodes
                   if n.bl_idname == "CompositorNodeRLayers" and not n.mute),
                  None)
    return (tree, composite, layers) if layers is not None else None


def old_setup_shows(scene):
    """Whether a render with the switch off would composite an old SSS
    result (the F12 operator then renders in the foreground, where
    on_init can prevent it)."""
    return _old_setup(scene) is not None


def _unhook_old_setup(scene):
    """With the switch off, a render shows what Blender renders, never
    the result Render with SSS left on the Composite: for the render, the
    Composite takes the Render Layers image again (put back afterwards).
    Returns the undo, or None when there is nothing to do."""
    found = _old_setup(scene)
    if found is None:
        return None
    tree, composite, layers = found
    undo = Undo()
    source = composite.links[0].from_socket
    tree.links.remove(composite.links[0])
    undo.add(lambda: tree.links.new(source, composite))
    link = tree.links.new(layers.outputs["Image"], composite)
    undo.add(lambda: tree.links.remove(link))
    return undo


# Renders with the switch off whose Composite was unhooked from an old
# result (scene name -> undo).
_unhooked = {}


@persistent
def on_init(scene, *_):
    global last_error
    if _ours(scene) or scene.name in _flows:
        return
    if not enabled(scene):
        if threading.current_thread() is threading.main_thread() and \
                scene.name not in _unhooked:
            undo = _unhook_old_setup(scene)
            if undo is not None:
                _unhooked[scene.name] = undo
                _say(scene, "Screen-space SSS is off: the Composite shows "
                     "this render, not the last SSS result")
        return
    if threading.current_thread() is not threading.main_thread():
        _say(scene, "a render job in the background cannot be scattered "
             "(a second render cannot start there); render with F12 from "
             "the add-on's key binding, Render with SSS or blender -b")
        return
    last_error = None
    if not pipeline.analyse(scene).materials:
        _say(scene, "no material scatters; the render is left alone")
        return
    try:
        flow = Flow(scene)
    except pipeline.SSSError as e:
        return _fail(scene, None, e)
    _flows[scene.name] = flow
    try:
        flow.open()
    except Exception as e:  # noqa: BLE001 - every failure stops the job
        _fail(scene, flow, e)


def _step(scene, do):
    """do(flow) for the scene's running render; a failure stops the job."""
    flow = _flows.get(scene.name)
    if flow is None or flow.failed:
        return
    try:
        do(flow)
    except Exception as e:  # noqa: BLE001 - every failure stops the job
        _fail(scene, flow, e)


@persistent
def on_pre(scene, *_):
    _step(scene, lambda flow: flow.frame(scene.frame_current))


@persistent
def on_write(scene, *_):
    if compat.is_multilayer_exr(scene.render.image_settings):
        _step(scene, lambda flow: flow.write_passes(scene.frame_current))


def _end(scene, completed):
    undo = _unhooked.pop(scene.name, None)
    if undo is not None:
        undo.run()
    flow = _flows.pop(scene.name, None)
    if flow is not None:
        flow.close(completed)
        if not bpy.app.background:
            bpy.app.timers.register(remove_leftovers, first_interval=0.1)


@persistent
def on_complete(scene, *_):
    _end(scene, True)


@persistent
def on_cancel(scene, *_):
    _end(scene, False)


@persistent
def remove_leftovers(*_):
    """Removes the copies of renders that have ended (never saved with
    the file: this runs before every save, too)."""
    if _flows:
        return 0.5  # a render is running: later
    while _leftovers:
        scene = bpy.data.scenes.get(_leftovers.pop())
        if scene is not None:
            bpy.data.scenes.remove(scene)
    return None


@persistent
def on_load(*_):
    """A new file: the old file's copies went with it."""
    _leftovers.clear()


HANDLERS = ((bpy.app.handlers.render_init, on_init),
            (bpy.app.handlers.render_pre, on_pre),
            (bpy.app.handlers.render_write, on_write),
            (bpy.app.handlers.render_complete, on_complete),
            (bpy.app.handlers.render_cancel, on_cancel),
            (bpy.app.handlers.save_pre, remove_leftovers),
            (bpy.app.handlers.load_pre, on_load))


def register():
    for handlers, fn in HANDLERS:
        if fn not in handlers:
            handlers.append(fn)


def unregister():
    for handlers, fn in HANDLERS:
        if fn in handlers:
            handlers.remove(fn)
