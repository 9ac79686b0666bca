"""Presses F12 in a real Blender window (under Xvfb, started with
--enable-event-simulate), once with the scene's Screen-space SSS on and
once off, and saves each Render Result: the add-on's key binding must
scatter the first and leave the second to Blender.

    blender --factory-startup --enable-event-simulate --python f12.py -- \
        SCENE.blend OUT_DIR
"""
import os
import sys

import bpy

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "addon"))
blend, out = sys.argv[sys.argv.index("--") + 1:][:2]
import separable_sss  # noqa: E402

separable_sss.register()
bpy.ops.wm.open_mainfile(filepath=blend)
steps = [True, False]


def press():
    scene = bpy.context.scene
    scene.sss.enabled = steps[0]
    win = bpy.context.window_manager.windows[0]
    win.event_simulate(type='MOUSEMOVE', value='NOTHING', x=300, y=300)
    win.event_simulate(type='F12', value='PRESS')
    win.event_simulate(type='F12', value='RELEASE')
    bpy.app.timers.register(save, first_interval=1.0)


def save():
    if bpy.app.is_job_running('RENDER'):
        return 0.5
    from separable_sss import render_flow
    name = "on" if steps.pop(0) else "off"
    path = os.path.join(out, name + ".png")
    bpy.data.images["Render Result"].save_render(path)
    print(f"F12 {name}: saved {path}; error {render_flow.last_error}; "
          f"scenes {len(bpy.data.scenes)}", flush=True)
    if steps:
        bpy.app.timers.register(press, first_interval=0.5)
    else:
        bpy.ops.wm.quit_blender()
    return None


bpy.app.timers.register(press, first_interval=2.0)
