"""Screenshots of the add-on's panels in a real Blender window, for the docs:
the compositor's SSS tab after Render with SSS, the same with every panel
open, and Material Properties > Screen-Space SSS. Run under Xvfb (make
screenshots does) by a Blender that opens windows:

    xvfb-run -a -s "-screen 0 1920x1080x24" blender --factory-startup \\
        --enable-event-simulate --python scripts/ui_screenshots.py -- \\
        SCENE.blend OUT_DIR

Writes OUT_DIR/ui-sidebar.png and ui-material.png as an artist first
sees them, ui-compositor.png, and with --open after OUT_DIR
ui-sidebar-open.png and ui-material-open.png with every sub-panel open;
prints the sidebar's width. Blender 3.4 has no
Python access to a sidebar's active tab, so the SSS tab is chosen the way
an artist can: Ctrl+Wheel over the tabs (it is the last one)."""
import os
import sys

import bpy
import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(ROOT, "addon"))
os.environ.setdefault("SSS_LIB", os.path.join(ROOT, "build", "libsss.so"))
args = sys.argv[sys.argv.index("--") + 1:]
blend, out = args[:2]
# --open: every sub-panel open, the shots named ui-*-open.png
SUFFIX = "-open" if "--open" in args[2:] else ""
import separable_sss  # noqa: E402
from separable_sss import blender_compat as compat  # noqa: E402
from separable_sss import ui  # noqa: E402

separable_sss.register()
state = {}


def log(*a):
    print("ui_screenshots:", *a, flush=True)


def window():
    return bpy.context.window_manager.windows[0]


def region(area, kind):
    return next(r for r in area.regions if r.type == kind)


def wheel(area_region, times, down=True, ctrl=False):
    win = window()
    x = area_region.x + area_region.width - 8 if ctrl else \
        area_region.x + area_region.width // 2
    y = area_region.y + area_region.height // 2
    win.event_simulate(type='MOUSEMOVE', value='NOTHING', x=x, y=y)
    for _ in range(times):
        win.event_simulate(type='WHEELDOWNMOUSE' if down else 'WHEELUPMOUSE',
                           value='PRESS', ctrl=ctrl, x=x, y=y)


def set_up():
    """The Layout workspace with its 3D view turned into the compositor,
    the sidebar open; the splash screen closed; the head's material
    active."""
    win = window()
    win.event_simulate(type='MOUSEMOVE', value='NOTHING', x=200, y=200)
    win.event_simulate(type='ESC', value='PRESS')
    win.event_simulate(type='ESC', value='RELEASE')
    for area in win.screen.areas:
        if area.type == 'VIEW_3D':
            area.type = 'NODE_EDITOR'
            area.ui_type = 'CompositorNodeTree'
            area.spaces[0].show_region_ui = True
            state["nodes"] = area
        elif area.type == 'PROPERTIES':
            state["props"] = area
    scene = bpy.context.scene
    head = next((o for o in scene.objects if o.type == 'MESH' and
                 o.active_material and o.active_material.sss.profile !=
                 'NONE' and "Head" in o.name), None) or next(
        o for o in scene.objects if o.type == 'MESH' and o.active_material)
    bpy.context.view_layer.objects.active = head
    head.select_set(True)
    log("active object", head.name, "material", head.active_material.name)
    bpy.app.timers.register(run_sss, first_interval=1.0)


def run_sss():
    """Render with SSS as its button does, then pick the SSS tab."""
    with bpy.context.temp_override(window=window(), area=state["nodes"]):
        status = bpy.ops.sss.render('EXEC_DEFAULT', True)
    log("Render with SSS:", status)
    wheel(region(state["nodes"], 'UI'), 8, ctrl=True)
    bpy.app.timers.register(shoot_sidebar, first_interval=1.5)


def shoot(area, name, crop=None, half=False):
    """A screenshot of the area; crop: (x0, x1) or (x0, x1, y0, y1) pixels
    of it to keep (y up from the bottom), half: scaled to half size."""
    path = os.path.join(out, name.replace(".png", SUFFIX + ".png"))
    with bpy.context.temp_override(window=window(), area=area):
        bpy.ops.screen.screenshot_area(filepath=path)
    if crop or half:
        shot = bpy.data.images.load(path)
        w, h = shot.size
        pixels = np.array(shot.pixels[:], dtype=np.float32).reshape(h, w, 4)
        bpy.data.images.remove(shot)
        if crop:
            y0, y1 = crop[2:] if len(crop) == 4 else (0, h)
            pixels = pixels[max(0, y0):min(h, y1),
                            max(0, crop[0]):min(w, crop[1])]
        if half:
            h2, w2 = pixels.shape[0] // 2 * 2, pixels.shape[1] // 2 * 2
            pixels = pixels[:h2, :w2].reshape(h2 // 2, 2, w2 // 2, 2, 4) \
                .mean(axis=(1, 3))
        h, w = pixels.shape[:2]
        image = bpy.data.images.new(name, w, h, alpha=True)
        image.pixels.foreach_set(pixels.ravel())
        image.filepath_raw = path
        image.file_format = 'PNG'
        image.save()
        bpy.data.images.remove(image)
    log("wrote", path)


def shoot_sidebar():
    ui = region(state["nodes"], 'UI')
    log("sidebar width", ui.width, "px, window",
        window().width, "x", window().height)
    area = state["nodes"]
    shoot(area, "ui-sidebar.png", crop=(ui.x - area.x,
                                        ui.x - area.x + ui.width))
    bpy.app.timers.register(shoot_properties, first_interval=0.5)


def open_sub_panels():
    """--open: the closed-by-default panels registered open before anything
    is drawn, as an artist would open them (Blender 3.4 has no Python
    access to a panel's open state)."""
    for cls in ui.classes:
        if 'DEFAULT_CLOSED' in getattr(cls, "bl_options", ()) and \
                cls is not ui.SSS_PT_render:
            bpy.utils.unregister_class(cls)
            cls.bl_options = set(cls.bl_options) - {'DEFAULT_CLOSED'}
            bpy.utils.register_class(cls)


def shoot_properties():
    area = state["props"]
    area.spaces[0].context = 'MATERIAL'
    bpy.app.timers.register(scroll_properties, first_interval=0.5)


def scroll_properties():
    # The add-on's panel is the last of the material tab.
    wheel(region(state["props"], 'WINDOW'), 60)
    bpy.app.timers.register(shoot_material, first_interval=1.0)


def shoot_material():
    win = window()      # no tooltip in the picture
    win.event_simulate(type='MOUSEMOVE', value='NOTHING', x=5, y=5)
    bpy.app.timers.register(shoot_material_now, first_interval=1.0)


def shoot_material_now():
    shoot(state["props"], "ui-material.png")
    space = state["nodes"].spaces[0]
    space.show_region_ui = False
    space.show_backdrop = False
    with bpy.context.temp_override(window=window(), area=state["nodes"],
                                   region=region(state["nodes"], 'WINDOW')):
        bpy.ops.node.view_all()
    bpy.app.timers.register(shoot_compositor, first_interval=1.5)


def node_box(area):
    """The compositor's nodes' bounding box in the area's pixels, with a
    margin: (x0, x1, y0, y1), y up."""
    win = region(area, 'WINDOW')
    tree = compat.compositor_tree(bpy.context.scene)
    xs, ys = [], []
    for node in tree.nodes:
        x, y = node.location
        w, h = node.dimensions
        for px, py in ((x, y), (x + w, y - h)):
            rx, ry = win.view2d.view_to_region(px, py, clip=False)
            xs.append(rx + win.x - area.x)
            ys.append(ry + win.y - area.y)
    m = 30
    return (int(min(xs)) - m, int(max(xs)) + m, int(min(ys)) - m,
            int(max(ys)) + m)


def shoot_compositor():
    if not SUFFIX:
        shoot(state["nodes"], "ui-compositor.png",
              crop=node_box(state["nodes"]))
    tree = compat.compositor_tree(bpy.context.scene)
    log("nodes selected after the run:",
        [n.name for n in tree.nodes if n.select])
    bpy.ops.wm.quit_blender()


os.makedirs(out, exist_ok=True)
if SUFFIX:
    open_sub_panels()
bpy.ops.wm.open_mainfile(filepath=blend)
bpy.app.timers.register(set_up, first_interval=2.0)
