"""Live re-tune in a real Blender window, for the docs: Render with SSS on
the head scene, the compositor's backdrop showing the result, then the
material's radius scale changed step by step the way a dragged slider
changes it (one change per redraw; the add-on's depsgraph handler and its
timer do the rest, as in any session), and the backdrop shot before and
after. Run under Xvfb (make screenshots does) by a Blender that opens
windows:

    xvfb-run -a -s "-screen 0 1280x720x24" blender --factory-startup \\
        --enable-event-simulate --python scripts/live_screenshot.py -- \\
        SCENE.blend OUT_DIR

Writes OUT_DIR/live-before.png, OUT_DIR/live-after.png and
OUT_DIR/live.png (the two side by side); prints the live re-tunes' times
and how much the backdrop changed."""
import os
import sys

import bpy
import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(ROOT, "addon"))
os.environ.setdefault("SSS_LIB", os.path.join(ROOT, "build", "libsss.so"))
args = sys.argv[sys.argv.index("--") + 1:]
blend, out = args[:2]
import separable_sss  # noqa: E402
from separable_sss import live, pipeline  # noqa: E402

separable_sss.register()
state = {"steps": [0.9, 0.8, 0.7, 0.6, 0.5, 0.4], "times": []}


def log(*a):
    print("live_screenshot:", *a, flush=True)


def window():
    return bpy.context.window_manager.windows[0]


def set_up():
    """The 3D view becomes the compositor with its backdrop."""
    win = window()
    win.event_simulate(type='MOUSEMOVE', value='NOTHING', x=200, y=200)
    win.event_simulate(type='ESC', value='PRESS')
    win.event_simulate(type='ESC', value='RELEASE')
    for area in win.screen.areas:
        if area.type == 'VIEW_3D':
            area.type = 'NODE_EDITOR'
            area.ui_type = 'CompositorNodeTree'
            space = area.spaces[0]
            space.show_backdrop = True
            space.show_region_ui = False
            state["nodes"] = area
    bpy.app.timers.register(run_sss, first_interval=1.0)


def run_sss():
    # Less noise than the panels' shots need: the change is the point.
    bpy.context.scene.cycles.samples = 64
    with bpy.context.temp_override(window=window(), area=state["nodes"]):
        status = bpy.ops.sss.render('EXEC_DEFAULT', True)
    log("Render with SSS:", status)
    area = state["nodes"]
    region = next(r for r in area.regions if r.type == 'WINDOW')
    space = area.spaces[0]
    render = bpy.context.scene.render
    width = render.resolution_x * render.resolution_percentage / 100.0
    height = render.resolution_y * render.resolution_percentage / 100.0
    space.backdrop_zoom = 0.95 * min(region.width / width,
                                     region.height / height)
    space.backdrop_offset = (0.0, 0.0)
    # The nodes out of the way: the backdrop stays where it is.
    with bpy.context.temp_override(window=window(), area=area,
                                   region=region):
        bpy.ops.view2d.pan(deltax=-4000, deltay=0)
    bpy.app.timers.register(shoot_before, first_interval=2.0)


def shoot(name):
    path = os.path.join(out, name)
    with bpy.context.temp_override(window=window(), area=state["nodes"]):
        bpy.ops.screen.screenshot_area(filepath=path)
    shot = bpy.data.images.load(path)
    w, h = shot.size
    pixels = np.array(shot.pixels[:], dtype=np.float32).reshape(h, w, 4)
    bpy.data.images.remove(shot)
    log("wrote", path)
    return pixels


def viewer():
    """The compositor's Viewer image (what the backdrop draws)."""
    image = bpy.data.images.get("Viewer Node")
    if image is None or not image.has_data:
        return None
    return np.array(image.pixels[:], dtype=np.float32)


def shoot_before():
    state["before"] = shoot("live-before.png")
    state["viewer"] = viewer()
    found = pipeline.analyse(bpy.context.scene).materials
    state["material"] = found[0].material
    bpy.app.timers.register(drag, first_interval=0.2)


def drag():
    """One slider step per call, as a drag sends them."""
    if state["steps"]:
        state["material"].sss.radius_scale = state["steps"].pop(0)
        return 0.03
    bpy.app.timers.register(settled, first_interval=1.5)
    return None


def settled():
    entry = live.kept(bpy.context.scene)
    log("live re-tune after the drag: %.3f s (SSS %.3f s), error: %s" % (
        entry.timings.get("total", -1.0), entry.timings.get("scatter", -1.0),
        live.last_error.get(bpy.context.scene.name)))
    after = shoot("live-after.png")
    before = state["before"]
    now = viewer()
    if now is not None and state["viewer"] is not None and \
            now.shape == state["viewer"].shape:
        log("viewer image: largest change %.4f" % np.abs(
            now - state["viewer"]).max())
    log("backdrop pixels changed: %.1f %%" % (100.0 * np.mean(
        np.abs(after - before).max(axis=-1) > 2.0 / 255.0)))
    both = np.concatenate([before, np.ones((before.shape[0], 8, 4),
                                            np.float32), after], axis=1)
    h, w = both.shape[0] // 2 * 2, both.shape[1] // 2 * 2   # half size
    both = both[:h, :w].reshape(h // 2, 2, w // 2, 2, 4).mean(axis=(1, 3))
    h, w = both.shape[:2]
    image = bpy.data.images.new("live", w, h, alpha=True)
    image.pixels.foreach_set(both.ravel())
    image.filepath_raw = os.path.join(out, "live.png")
    image.file_format = 'PNG'
    image.save()
    log("wrote", image.filepath_raw)
    bpy.ops.wm.quit_blender()


os.makedirs(out, exist_ok=True)
bpy.ops.wm.open_mainfile(filepath=blend)
bpy.app.timers.register(set_up, first_interval=2.0)
