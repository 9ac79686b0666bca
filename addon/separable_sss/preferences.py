"""The add-on's Preferences: which libsss to use and where results go by
default, with what is loaded now."""
import bpy
from bpy.props import StringProperty

from . import native


def _addon_name():
    """The add-on's module name as Blender knows it: "separable_sss" for
    the legacy add-on, "bl_ext.REPO.separable_sss" for the extension."""
    return __package__


def get(context=None):
    """The preferences, or None where Blender has none for the add-on (it
    is imported without being enabled, as scripts do)."""
    context = context or bpy.context
    addon = context.preferences.addons.get(_addon_name())
    return addon.preferences if addon is not None else None


def _library_changed(self, _context):
    native.set_preferred_path(bpy.path.abspath(self.library_path))


class SSSPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    library_path: StringProperty(
        name="Library", subtype='FILE_PATH', default="",
        update=_library_changed,
        description="The library (libsss.so, .dll or .dylib) to use "
        "instead of the one the add-on carries (empty: the add-on's own; "
        "$SSS_LIB still comes first). Takes effect when Blender starts "
        "again")
    output_dir: StringProperty(
        name="Default Output Folder", subtype='DIR_PATH', default="",
        description="Where passes and results go when a scene sets no "
        "folder of its own (empty: a temporary folder)")

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(self, "library_path")
        layout.prop(self, "output_dir")
        col = layout.column(align=True)
        try:
            native.library()
            col.label(text="Loaded: libsss %s, %s" % (
                native.version(), native.loaded_path()), icon='CHECKMARK')
        except native.LibraryError as ex:
            col.label(text="Not loaded: %s" % ex, icon='ERROR')


def register():
    bpy.utils.register_class(SSSPreferences)
    prefs = get()
    if prefs is not None:
        native.set_preferred_path(bpy.path.abspath(prefs.library_path))


def unregister():
    bpy.utils.unregister_class(SSSPreferences)
