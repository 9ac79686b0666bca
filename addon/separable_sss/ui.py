"""Panels: the SSS tab of the compositor's sidebar (scene settings, what
scatters, the active material) and a Screen-Space SSS panel in Material
Properties with the same per-material settings."""
import textwrap

import bpy

from . import nodes, pipeline, transmission
from .presets import SSS_MT_material_presets


def _wrapped(layout, context, text, icon='NONE'):
    """A label wrapped to the region's width (sidebars are narrow)."""
    region = getattr(context, "region", None)
    width = region.width if region is not None else 300
    scale = context.preferences.view.ui_scale
    chars = max(16, int((width - 50.0 * scale) / (7.5 * scale)))
    col = layout.column(align=True)
    for i, line in enumerate(textwrap.wrap(text, chars) or [""]):
        col.label(text=line, icon=icon if i == 0 else 'BLANK1')


def _scene_problem(scene):
    """Why Render with SSS is disabled, as one line, or None."""
    if scene.camera is None:
        return "The scene has no camera"
    if scene.render.engine != 'CYCLES':
        return "Render with Cycles: SSS needs its Material Index pass"
    return None


def _prop(layout, data, name, split):
    """A property; in the narrow sidebar (no split) an enum or path gets
    its label on a line of its own, so neither is cut short."""
    prop = data.bl_rna.properties[name]
    if split or (prop.type != 'ENUM' and prop.subtype not in
                 {'DIR_PATH', 'FILE_PATH'}):
        layout.prop(data, name)
        return
    col = layout.column(align=True)
    col.label(text=prop.name + ":")
    col.prop(data, name, text="")


def draw_material_settings(layout, context, mat, split=True):
    """The per-material block: presets, profile, strength, texturing and
    the fields of the chosen profile. `split`: labels beside the fields
    (Properties editor); off in the narrow sidebar."""
    s = mat.sss
    layout.context_pointer_set("material", mat)   # for the presets

    row = layout.row(align=True)
    row.menu(SSS_MT_material_presets.__name__,
             text=SSS_MT_material_presets.bl_label)
    row.operator("sss.material_preset_add", text="", icon='ADD')
    row.operator("sss.material_preset_add", text="",
                 icon='REMOVE').remove_active = True

    layout.use_property_split = split
    layout.use_property_decorate = False
    col = layout.column()
    _prop(col, s, "profile", split)
    if s.profile == 'NONE':
        _wrapped(col, context, "This material is left alone", 'INFO')
        return
    col.prop(s, "strength", slider=True)
    _prop(col, s, "texturing", split)

    col = layout.column()
    if s.profile == 'BLENDER':
        _prop(col, s, "mapping", split)
        _wrapped(col, context, "Radius and colour come from the material's "
                 "Subsurface inputs", 'INFO')
    elif s.profile == 'BURLEY':
        col.prop(s, "radius")
        _prop(col, s, "mapping", split)
        sub = col.column()
        sub.active = s.mapping in {'RANDOM_WALK', 'CYCLES_RANDOM_WALK',
                                   'CYCLES4_RANDOM_WALK', 'AUTO'}
        sub.prop(s, "albedo")
    elif s.profile == 'GAUSSIANS':
        col.prop(s, "gaussian_scale")
    elif s.profile == 'JIMENEZ':
        col.prop(s, "jimenez_width")
        col.prop(s, "jimenez_strength")
        col.prop(s, "jimenez_falloff")
    elif s.profile == 'NEAR_FAR':
        col.prop(s, "scatter_scale")
        col.prop(s, "near_far_balance", slider=True)
        col.prop(s, "near_sigma")
        col.prop(s, "far_sigma")
    col.prop(s, "radius_scale")
    if s.profile in {'BLENDER', 'BURLEY'}:
        col.prop(s, "match_energy")

    _draw_transmission(layout, context, s, split)

    col = layout.column()
    col.prop(s, "taps")
    col.prop(mat, "pass_index")
    if mat.pass_index == 0:
        _wrapped(col, context, "Pass index 0: a free one is given for the "
                 "time of each render", 'INFO')


def _draw_transmission(layout, context, s, split):
    """Back-lit transmission: the model and its fields."""
    col = layout.column()
    _prop(col, s, "transmission", split)
    if s.transmission == 'OFF':
        return
    if s.transmission == 'AUTO':
        _wrapped(col, context, "Auto: the Profile model for Random Walk "
                 "materials (measured against Cycles' random walk), off "
                 "for the others", 'INFO')
    col.prop(s, "transmission_strength", slider=True)
    col.prop(s, "transmission_color")
    if s.transmission == 'JIMENEZ':
        col.prop(s, "transmission_translucency", slider=True)
    elif s.transmission in {'BEER_LAMBERT', 'FAST'}:
        col.prop(s, "transmission_distance")
    if s.transmission == 'FAST':
        col.prop(s, "transmission_distortion", slider=True)
        col.prop(s, "transmission_power")
        col.prop(s, "transmission_scale")
        col.prop(s, "transmission_ambient")
    col.prop(s, "thickness_scale")


def _draw_backlight(layout, context, scene):
    """The scene's back-light layer: the setting, whether this render gets
    it and why, and what it costs."""
    s = scene.sss
    col = layout.column()
    _prop(col, s, "transmission_layer", False)
    col.prop(s, "transmission_samples")
    try:
        need, why = transmission.wanted(scene, pipeline.analyse(scene))
    except Exception as ex:
        need, why = False, "could not analyse the scene: %s" % ex
    if need:
        _wrapped(col, context, "Back-light layer on (%s), %d samples: %s"
                 % (why, transmission.layer_samples(scene),
                    transmission.COST_NOTE), 'LIGHT')
    else:
        _wrapped(col, context, "No back-light layer: " + why, 'INFO')


class SSS_PT_node_main(bpy.types.Panel):
    bl_space_type = 'NODE_EDITOR'
    bl_region_type = 'UI'
    bl_category = "SSS"
    bl_label = "Screen-Space SSS"

    @classmethod
    def poll(cls, context):
        space = context.space_data
        return (space is not None and space.type == 'NODE_EDITOR' and
                space.tree_type == 'CompositorNodeTree' and
                context.scene is not None and
                getattr(context.scene, "sss", None) is not None)

    def draw(self, context):
        layout = self.layout
        scene = context.scene
        s = scene.sss

        col = layout.column(align=True)
        col.scale_y = 1.3
        col.operator("sss.render", icon='RENDER_STILL')
        col.operator("sss.apply", icon='IMAGE_DATA')
        problem = _scene_problem(scene)
        if problem:
            _wrapped(layout, context, problem, 'ERROR')

        col = layout.column()
        _prop(col, s, "method", False)
        col.prop(s, "taps")
        col.prop(s, "radius_scale")
        _prop(col, s, "output_dir", False)
        col.prop(s, "enabled")
        _draw_backlight(layout, context, scene)

        col = layout.column(align=True)
        if s.last_result:
            col.label(text="Last result:")
            col.prop(s, "last_result", text="")
        if nodes.find_result(scene) is not None:
            col.operator("sss.remove_setup", icon='X')


class SSS_PT_node_found(bpy.types.Panel):
    bl_space_type = 'NODE_EDITOR'
    bl_region_type = 'UI'
    bl_category = "SSS"
    bl_label = "Found in Scene"
    bl_parent_id = "SSS_PT_node_main"

    def draw(self, context):
        layout = self.layout
        scene = context.scene
        # analyse() only walks the scene's materials: cheap enough for a
        # redraw, and nothing from an earlier redraw (which undo may have
        # freed) is kept.
        try:
            analysis = pipeline.analyse(scene)
        except Exception as ex:
            _wrapped(layout, context, "Could not analyse the scene: %s"
                     % ex, 'ERROR')
            return
        if not analysis.found:
            _wrapped(layout, context, "No material scatters: the render is "
                     "left alone", 'INFO')
        col = layout.column(align=True)
        for found in analysis.found:
            self._draw_found(col.box(), context, scene, found)
        for message in analysis.messages:
            _wrapped(layout, context, message, 'INFO')
        if analysis.found:
            layout.operator("sss.assign_pass_indices", icon='LINENUMBERS_ON')

    @staticmethod
    def _draw_found(box, context, scene, found):
        s = found.material.sss
        row = box.row()
        row.label(text=found.name, icon='MATERIAL')
        row.label(text="Index %d" % found.pass_index if found.pass_index
                  else "Index auto")
        col = box.column(align=True)
        col.label(text=s.bl_rna.properties["profile"].enum_items[
            s.profile].name)
        if s.profile in {'BLENDER', 'BURLEY'}:
            radius = found.radius if s.profile == 'BLENDER' else s.radius
            col.label(text="Radius %s mm" % " / ".join(
                "%.3g" % (r * 1000.0) for r in radius))
        try:
            px = pipeline.kernel_pixels(scene, found)
        except Exception:
            return
        if not px:
            col.label(text="Kernel size unknown")
        elif px < 1.0:
            col.label(text="Kernel %.1f px: hardly visible" % px,
                      icon='INFO')
        else:
            col.label(text="Kernel radius %.1f px" % px)


class SSS_PT_node_material(bpy.types.Panel):
    bl_space_type = 'NODE_EDITOR'
    bl_region_type = 'UI'
    bl_category = "SSS"
    bl_label = "Active Material"
    bl_parent_id = "SSS_PT_node_main"

    def draw(self, context):
        layout = self.layout
        obj = context.object
        mat = obj.active_material if obj is not None else None
        if mat is None:
            _wrapped(layout, context, "Select an object with a material to "
                     "edit its SSS settings", 'INFO')
            return
        layout.label(text=mat.name, icon='MATERIAL')
        draw_material_settings(layout, context, mat, split=False)


class SSS_PT_material(bpy.types.Panel):
    bl_space_type = 'PROPERTIES'
    bl_region_type = 'WINDOW'
    bl_context = "material"
    bl_label = "Screen-Space SSS"

    @classmethod
    def poll(cls, context):
        mat = getattr(context, "material", None)
        return mat is not None and getattr(mat, "sss", None) is not None

    def draw(self, context):
        draw_material_settings(self.layout, context, context.material)


class SSS_PT_render(bpy.types.Panel):
    """The scene's switch where renders are set up."""
    bl_space_type = 'PROPERTIES'
    bl_region_type = 'WINDOW'
    bl_context = "render"
    bl_label = "Screen-Space SSS"
    bl_options = {'DEFAULT_CLOSED'}

    @classmethod
    def poll(cls, context):
        return getattr(context.scene, "sss", None) is not None

    def draw_header(self, context):
        self.layout.prop(context.scene.sss, "enabled", text="")

    def draw(self, context):
        s = context.scene.sss
        col = self.layout.column()
        col.active = s.enabled
        _prop(col, s, "method", False)
        col.prop(s, "radius_scale")


classes = (SSS_PT_node_main, SSS_PT_node_found, SSS_PT_node_material,
           SSS_PT_material, SSS_PT_render)

register, unregister = bpy.utils.register_classes_factory(classes)
