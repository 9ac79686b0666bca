"""Panels. The compositor sidebar's SSS tab: the everyday controls first
(the two actions, the scene's switch, the method, the scene's radius
scale), what scatters, the active material, and the rest in a closed
Advanced panel, as Cycles does. Material Properties > Screen-Space SSS:
the same per-material settings, with Transmission and Advanced as
sub-panels. Explanations live in tooltips; a panel line says what a
setting resolves to (a zero that means automatic shows its value)."""
import textwrap

import bpy

from . import live, nodes, pipeline, properties, transmission
from .presets import SSS_MT_material_presets
from .properties import method_items

# Labels longer than this are cut in a split layout (label left, field
# right) at the Properties editor's default width: such fields get the
# whole row instead.
SPLIT_LABEL_CHARS = 11


def _wrapped(layout, context, text, icon='NONE', lines=2):
    """A label wrapped to the region's width (sidebars are narrow), at most
    `lines` lines (the rest is cut with an ellipsis)."""
    region = getattr(context, "region", None)
    width = region.width if region is not None else 300
    scale = context.preferences.view.ui_scale
    chars = max(16, int((width - 50.0 * scale) / (7.5 * scale)))
    col = layout.column(align=True)
    wrapped = textwrap.wrap(text, chars) or [""]
    if len(wrapped) > lines:
        wrapped = textwrap.wrap(text, chars, max_lines=lines,
                                placeholder="...")
    for i, line in enumerate(wrapped):
        col.label(text=line, icon=icon if i == 0 else 'BLANK1')


def _prop(layout, data, name, split, text=None, **kwargs):
    """A property that is never cut short: where the label would not fit
    (an enum or path in the narrow sidebar, a long label in a split
    layout) it gets a line or the whole row of its own."""
    prop = data.bl_rna.properties[name]
    label = prop.name if text is None else text
    if prop.type == 'ENUM' or prop.subtype in {'DIR_PATH', 'FILE_PATH'}:
        if split and len(label) <= SPLIT_LABEL_CHARS:
            layout.prop(data, name, text=label, **kwargs)
            return
        col = layout.column(align=True)
        col.use_property_split = False
        col.label(text=label + ":")
        col.prop(data, name, text="", **kwargs)
        return
    if split and len(label) > SPLIT_LABEL_CHARS:
        row = layout.row()
        row.use_property_split = False
        row.prop(data, name, text=label, **kwargs)
        return
    layout.prop(data, name, text=label, **kwargs)


def _auto(layout, data, name, split, resolved):
    """An integer where 0 means automatic, with what it resolves to."""
    row = layout.row(align=True)
    _prop(row, data, name, split)
    if getattr(data, name) == 0:
        row.label(text="= %s" % resolved)


def _material(context, sidebar):
    if sidebar:
        obj = context.object
        return obj.active_material if obj is not None else None
    return getattr(context, "material", None)


def _no_fields(col, context):
    """Says why, where the library was not loaded when the add-on was
    enabled: the material settings then lack its fields."""
    if properties.library_error is None:
        return False
    _wrapped(col, context, properties.library_error, 'ERROR', lines=6)
    return True


def _has_sss(mat):
    return mat is not None and getattr(mat, "sss", None) is not None


# ------------------------------------------------------------- material

def draw_material_settings(layout, context, mat, split=True):
    """The everyday per-material block: presets, profile, strength, radius
    scale and the chosen profile's own fields. `split`: labels beside the
    fields (Properties editor); off in the narrow sidebar."""
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
    if _no_fields(col, context):
        return
    _prop(col, s, "profile", split)
    if s.profile == 'NONE':
        col.label(text="Not scattered", icon='INFO')
        return
    col.prop(s, "strength", slider=True)
    _prop(col, s, "radius_scale", split)
    if s.profile == 'BLENDER':
        _wrapped(col, context, "Radius and colour come from the material",
                 'INFO')
    elif s.profile == 'BURLEY':
        col.prop(s, "radius")
    elif s.profile == 'GAUSSIANS':
        col.prop(s, "gaussian_scale")
    elif s.profile == 'JIMENEZ':
        col.prop(s, "jimenez_width")
        col.prop(s, "jimenez_strength")
        col.prop(s, "jimenez_falloff")
    elif s.profile == 'NEAR_FAR':
        col.prop(s, "scatter_scale")
        _prop(col, s, "near_far_balance", split, slider=True)
        _prop(col, s, "near_sigma", split)
        _prop(col, s, "far_sigma", split)


def draw_material_transmission(layout, mat, split=True):
    """Back-lit transmission: the model and its fields."""
    s = mat.sss
    layout.use_property_split = split
    layout.use_property_decorate = False
    col = layout.column()
    if _no_fields(col, bpy.context):
        return
    col.active = s.profile != 'NONE'
    _prop(col, s, "transmission", split, text="Model")
    if s.transmission == 'OFF':
        return
    col.prop(s, "transmission_strength", slider=True)
    col.prop(s, "transmission_color", text="Color at Distance"
             if s.transmission == 'BEER_LAMBERT' else None)
    if s.transmission == 'JIMENEZ':
        _prop(col, s, "transmission_translucency", split, slider=True)
    elif s.transmission in {'BEER_LAMBERT', 'FAST'}:
        col.prop(s, "transmission_distance")
    if s.transmission == 'FAST':
        col.prop(s, "transmission_distortion", slider=True)
        col.prop(s, "transmission_power")
        col.prop(s, "transmission_scale")
        col.prop(s, "transmission_ambient")
    col.prop(s, "thickness_scale")


def draw_material_advanced(layout, context, mat, split=True):
    """What most materials never need: texturing, the radius meaning,
    energy matching, taps and the pass index."""
    s = mat.sss
    scene = context.scene
    layout.use_property_split = split
    layout.use_property_decorate = False
    col = layout.column()
    if _no_fields(col, context):
        return
    col.active = s.profile != 'NONE'
    _prop(col, s, "texturing", split)
    if s.profile in {'BLENDER', 'BURLEY'}:
        _prop(col, s, "mapping", split, text="Radius Meaning")
        if s.profile == 'BURLEY':
            sub = col.column()
            sub.active = s.mapping != 'CYCLES' and s.mapping != 'EEVEE'
            sub.prop(s, "albedo")
        _prop(col, s, "match_energy", split)
    _auto(col, s, "taps", split, "%d (scene's)" % scene.sss.taps)
    row = col.row(align=True)
    row.prop(mat, "pass_index")
    if mat.pass_index == 0:
        row.label(text="= free one")


class _MaterialPanel:
    """Shared by the sidebar's Active Material panels (sidebar = True) and
    Material Properties' (False)."""
    sidebar = False

    @classmethod
    def poll(cls, context):
        return _has_sss(_material(context, cls.sidebar))


class _PropertiesPanel:
    """Where Material Properties' panels live."""
    bl_space_type = 'PROPERTIES'
    bl_region_type = 'WINDOW'
    bl_context = "material"


class SSS_PT_material(_MaterialPanel, _PropertiesPanel, bpy.types.Panel):
    bl_label = "Screen-Space SSS"

    def draw(self, context):
        draw_material_settings(self.layout, context, context.material)


class SSS_PT_material_transmission(_MaterialPanel, _PropertiesPanel,
                                   bpy.types.Panel):
    bl_label = "Transmission"
    bl_parent_id = "SSS_PT_material"
    bl_options = {'DEFAULT_CLOSED'}

    def draw(self, context):
        draw_material_transmission(self.layout, context.material)


class SSS_PT_material_advanced(_MaterialPanel, _PropertiesPanel,
                               bpy.types.Panel):
    bl_label = "Advanced"
    bl_parent_id = "SSS_PT_material"
    bl_options = {'DEFAULT_CLOSED'}

    def draw(self, context):
        draw_material_advanced(self.layout, context, context.material)


# -------------------------------------------------------------- sidebar

class _SidebarPanel:
    bl_space_type = 'NODE_EDITOR'
    bl_region_type = 'UI'
    bl_category = "SSS"


def _draw_live(layout, context, scene):
    """Live Re-tune: whether the render's passes are kept, and the last
    re-tune's time or error."""
    entry = live.kept(scene)
    row = layout.row()
    row.prop(scene.sss, "live")
    if entry is None:
        row.label(text="(after Render with SSS)")
        return
    error = live.last_error.get(scene.name)
    if error:
        _wrapped(layout, context, "Live re-tune failed: " + error, 'ERROR')
    elif entry.timings:
        row.label(text="%dx%d, %.2f s" % (entry.frame.width,
                                          entry.frame.height,
                                          entry.timings.get("total", 0.0)))
    else:
        row.label(text="%dx%d kept" % (entry.frame.width,
                                       entry.frame.height))


class SSS_PT_node_main(_SidebarPanel, bpy.types.Panel):
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
        if nodes.image_node_file(
                getattr(context.space_data, "edit_tree", None) and
                context.space_data.edit_tree.nodes.active):
            col.operator("sss.scatter_image", icon='NODE_COMPOSITING')
        if live.kept(scene) is not None:
            col.operator("sss.save_result", icon='FILE_TICK')
        problem = pipeline.scene_problem(scene)
        if problem:
            _wrapped(layout, context, problem, 'ERROR')
        _draw_live(layout, context, scene)

        col = layout.column()
        col.prop(s, "enabled")
        _prop(col, s, "method", False, text="Method (speed or accuracy)")
        # What the method trades, in the library's words.
        summary = next((item[2] for item in method_items()
                        if item[0] == s.method), "")
        if summary:
            _wrapped(col, context, summary)
        col.prop(s, "radius_scale")


class SSS_PT_node_found(_SidebarPanel, bpy.types.Panel):
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
        if not analysis.materials:
            layout.label(text="No material scatters", icon='INFO')
        col = layout.column(align=True)
        for found in analysis.materials:
            self._draw_found(col.box(), scene, found)
        for message in analysis.messages:
            _wrapped(layout, context, message, 'INFO')

    @staticmethod
    def _draw_found(box, scene, found):
        s = found.material.sss
        col = box.column(align=True)
        col.label(text=found.name, icon='MATERIAL')
        profile = s.bl_rna.properties["profile"].enum_items[s.profile].name
        col.label(text=profile)
        if s.profile in {'BLENDER', 'BURLEY'}:
            radius = found.radius if s.profile == 'BLENDER' else s.radius
            col.label(text="Radius %s mm" % " / ".join(
                "%.2g" % (r * 1000.0) for r in radius))
        try:
            px = pipeline.kernel_pixels(scene, found)
        except Exception:
            return
        if not px:
            col.label(text="Blur size unknown")
        elif px < 1.0:
            col.label(text="Blur under a pixel: hardly visible", icon='INFO')
        else:
            col.label(text="Blurs up to %d px here" % round(px))


class SSS_PT_node_material(_MaterialPanel, _SidebarPanel, bpy.types.Panel):
    bl_label = "Active Material"
    bl_parent_id = "SSS_PT_node_main"
    sidebar = True

    @classmethod
    def poll(cls, context):
        return True     # says what to do when there is no material

    def draw(self, context):
        layout = self.layout
        mat = _material(context, True)
        if not _has_sss(mat):
            _wrapped(layout, context, "Select an object with a material",
                     'INFO')
            return
        layout.label(text=mat.name, icon='MATERIAL')
        draw_material_settings(layout, context, mat, split=False)


class SSS_PT_node_material_transmission(_MaterialPanel, _SidebarPanel,
                                        bpy.types.Panel):
    bl_label = "Transmission"
    bl_parent_id = "SSS_PT_node_material"
    bl_options = {'DEFAULT_CLOSED'}
    sidebar = True

    def draw(self, context):
        draw_material_transmission(self.layout, _material(context, True),
                                   split=False)


class SSS_PT_node_material_advanced(_MaterialPanel, _SidebarPanel,
                                    bpy.types.Panel):
    bl_label = "Advanced"
    bl_parent_id = "SSS_PT_node_material"
    bl_options = {'DEFAULT_CLOSED'}
    sidebar = True

    def draw(self, context):
        draw_material_advanced(self.layout, context,
                               _material(context, True), split=False)


def _draw_backlight(layout, context, scene):
    """The scene's back-light layer: the setting, its samples, and whether
    the next render gets it."""
    s = scene.sss
    col = layout.column()
    _prop(col, s, "transmission_layer", False)
    _auto(col, s, "transmission_samples", False,
          transmission.layer_samples(scene))
    try:
        need, why = transmission.wanted(scene, pipeline.analyse(scene))
    except Exception as ex:
        need, why = False, "cannot tell: %s" % ex
    _wrapped(col, context, ("Next render: on, " if need else
                            "Next render: off, ") + why,
             'LIGHT' if need else 'INFO')


class SSS_PT_node_advanced(_SidebarPanel, bpy.types.Panel):
    """The scene's rarely changed settings, a panel of its own below the
    main one (the material's Advanced is inside Active Material)."""
    bl_label = "Advanced"
    bl_options = {'DEFAULT_CLOSED'}

    @classmethod
    def poll(cls, context):
        return SSS_PT_node_main.poll(context)

    def draw(self, context):
        layout = self.layout
        scene = context.scene
        s = scene.sss
        col = layout.column()
        if not _no_fields(col, context):
            col.prop(s, "taps")
        _prop(col, s, "output_dir", False)
        if not s.output_dir:
            _wrapped(col, context, "Empty: " + pipeline.output_path(scene))
        _draw_backlight(layout, context, scene)

        col = layout.column(align=True)
        if s.last_result:
            col.label(text="Last result:")
            col.prop(s, "last_result", text="")
        if pipeline.analyse(scene).materials:
            col.operator("sss.assign_pass_indices", icon='LINENUMBERS_ON')
        if nodes.find_result(scene) is not None:
            col.operator("sss.remove_setup", icon='X')


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
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        col = layout.column()
        col.active = s.enabled
        _prop(col, s, "method", True)
        _prop(col, s, "radius_scale", True)


classes = (SSS_PT_node_main, SSS_PT_node_found, SSS_PT_node_material,
           SSS_PT_node_material_transmission, SSS_PT_node_material_advanced,
           SSS_PT_node_advanced, SSS_PT_material,
           SSS_PT_material_transmission, SSS_PT_material_advanced,
           SSS_PT_render)

register, unregister = bpy.utils.register_classes_factory(classes)
