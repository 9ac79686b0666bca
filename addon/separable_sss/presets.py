"""Presets for the per-material SSS settings (Material.sss), through
Blender's own preset system: a menu, an add/remove operator, and the shipped
presets (presets/material/*.py, measured materials) copied into the user's
preset folder on register."""
import os
import shutil

import bpy
from bl_operators.presets import AddPresetBase

from .properties import SSSMaterialSettings

PRESET_SUBDIR = os.path.join("separable_sss", "material")
SHIPPED_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)),
                           "presets", "material")
# Names already installed once, kept in the user's preset folder so that a
# shipped preset the user deleted is not brought back on the next start.
# Dot files are not listed by the preset menu.
MARKER = ".separable_sss_shipped"

# The material a preset applies to: the Properties editor's material, else
# the active object's (the Node Editor sidebar has no context.material).
MATERIAL_DEFINE = ("material = getattr(bpy.context, 'material', None) or "
                   "bpy.context.object.active_material")

_fallback = False   # True when the shipped presets could not be installed


def context_material(context):
    """The material presets apply to, or None."""
    mat = getattr(context, "material", None)
    if mat is None and context.object is not None:
        mat = context.object.active_material
    return mat


def user_preset_dir(create=False):
    return bpy.utils.user_resource(
        'SCRIPTS', path=os.path.join("presets", PRESET_SUBDIR),
        create=create)


def install_shipped():
    """Copy each shipped preset into the user's preset folder once; a file
    already there is never overwritten. Returns the names copied."""
    target = user_preset_dir(create=True)
    if not target or not os.path.isdir(target):
        raise OSError("no user preset folder")
    marker = os.path.join(target, MARKER)
    done = set()
    if os.path.exists(marker):
        with open(marker, encoding="utf-8") as f:
            done = {line.strip() for line in f if line.strip()}
    copied = []
    for name in sorted(os.listdir(SHIPPED_DIR)):
        if not name.endswith(".py") or name in done:
            continue
        dst = os.path.join(target, name)
        if not os.path.exists(dst):
            shutil.copyfile(os.path.join(SHIPPED_DIR, name), dst)
            copied.append(name)
        done.add(name)
    with open(marker, "w", encoding="utf-8") as f:
        f.write("".join(name + "\n" for name in sorted(done)))
    return copied


class SSS_MT_material_presets(bpy.types.Menu):
    bl_label = "Presets"
    preset_subdir = PRESET_SUBDIR
    preset_operator = "script.execute_preset"

    def draw(self, _context):
        paths = bpy.utils.preset_paths(self.preset_subdir)
        if _fallback and os.path.isdir(SHIPPED_DIR):
            paths.append(SHIPPED_DIR)
        self.path_menu(
            paths, self.preset_operator,
            filter_ext=lambda ext: ext.lower() == ".py",
            display_name=lambda path: bpy.path.display_name(
                path, title_case=False))


class SSS_OT_material_preset_add(AddPresetBase, bpy.types.Operator):
    """Save the material's SSS settings as a preset, or remove one"""
    bl_idname = "sss.material_preset_add"
    bl_label = "Add SSS Material Preset"
    preset_menu = "SSS_MT_material_presets"
    preset_subdir = PRESET_SUBDIR
    preset_defines = [MATERIAL_DEFINE]
    # Every setting but the PropertyGroup's own name (register() fills
    # it once the schema's fields are added).
    preset_values = []

    @classmethod
    def poll(cls, context):
        mat = context_material(context)
        if mat is None or getattr(mat, "sss", None) is None:
            cls.poll_message_set("No active material")
            return False
        return True


classes = (SSS_MT_material_presets, SSS_OT_material_preset_add)


def register():
    global _fallback
    SSS_OT_material_preset_add.preset_values = [
        "material.sss." + key for key in SSSMaterialSettings.__annotations__]
    for cls in classes:
        bpy.utils.register_class(cls)
    try:
        install_shipped()
        _fallback = False
    except OSError as ex:
        # Read-only home, say: list the shipped folder in the menu instead.
        _fallback = True
        print("Separable SSS: presets not installed (%s); using %s"
              % (ex, SHIPPED_DIR))


def unregister():
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
