"""Screen-space subsurface scattering for Blender render passes: renders
with material SSS switched off, scatters the diffuse light with libsss and
brings the result back into the compositor."""

bl_info = {
    "name": "Separable SSS",
    "author": "libsss developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Node Editor > Sidebar > SSS; Material Properties",
    "description": "Fast screen-space subsurface scattering as a "
                   "post-process on Cycles render passes",
    "category": "Compositing",
}

if "bpy" in locals():
    import importlib
    for _m in (blender_compat, native, errors, analysis,  # noqa: F821
               lighting, description, transmission,  # noqa: F821
               switch_off, nodes, live, pipeline, preferences,  # noqa: F821
               properties, presets, operators, ui, render_flow):  # noqa: F821
        importlib.reload(_m)

import bpy  # noqa: E402,F401

from . import (analysis, blender_compat, description,  # noqa: E402
               errors, lighting, live, native, nodes, operators, pipeline,
               preferences, presets, properties, render_flow, switch_off,
               transmission, ui)

_modules = (preferences, properties, presets, operators, ui, render_flow,
            live)


def register():
    for module in _modules:
        module.register()


def unregister():
    for module in reversed(_modules):
        module.unregister()
