"""Scene analysis: which materials scatter, with what radius and colour,
and which passes the render needs. Reads the scene only."""
from dataclasses import dataclass, field

import bpy

from .blender_compat import PRINCIPLED, principled_input


@dataclass
class Found:
    """One scattering material."""
    material: bpy.types.Material
    name: str
    pass_index: int
    node: bpy.types.Node          # the Principled or Subsurface node
    radius: tuple                 # metres per channel (radius x factor)
    color: tuple                  # Subsurface Color (or the SSS node's)
    method: str                   # BURLEY, RANDOM_WALK, ...
    linked_factor: bool = False   # Subsurface driven by a texture
    # The albedo Cycles' random walk uses: the Principled BSDF's diffuse
    # colour mix(Base Color, Subsurface Color, Subsurface) (the socket
    # values; a texture's pixels come in through DiffCol instead).
    albedo: tuple = None


@dataclass
class Analysis:
    found: list = field(default_factory=list)
    emits: bool = False
    transmits: bool = False
    messages: list = field(default_factory=list)


def scene_materials(scene):
    """Materials on renderable objects of the scene, each once."""
    seen = []
    for obj in scene.objects:
        if obj.hide_render or not hasattr(obj, "material_slots"):
            continue
        for slot in obj.material_slots:
            mat = slot.material
            if mat and mat not in seen:
                seen.append(mat)
    return seen


def _input_value(node, name):
    sock = node.inputs.get(name)
    return None if sock is None else sock.default_value


def _is_linked(node, name):
    sock = node.inputs.get(name)
    return bool(sock and sock.is_linked)


def _scatters(node):
    """(factor, linked) for a Principled node's Subsurface input."""
    sock = principled_input(node, "subsurface")
    if sock.is_linked:
        return 1.0, True
    return float(sock.default_value), False


def analyse(scene):
    """What scatters in this scene and what the render must provide."""
    result = Analysis()
    unit = scene.unit_settings.scale_length or 1.0
    for mat in scene_materials(scene):
        if not mat.use_nodes or not mat.node_tree:
            continue
        settings = getattr(mat, "sss", None)
        for node in mat.node_tree.nodes:
            if node.type == "EMISSION" or (
                    node.type == "BSDF_PRINCIPLED" and
                    _input_value(node, PRINCIPLED["emission_strength"]) and
                    (_is_linked(node, PRINCIPLED["emission"]) or
                     any(_input_value(node, PRINCIPLED["emission"])[:3]))):
                result.emits = True
            if node.type in ("BSDF_GLASS", "BSDF_REFRACTION") or (
                    node.type == "BSDF_PRINCIPLED" and
                    (_is_linked(node, PRINCIPLED["transmission"]) or
                     _input_value(node, PRINCIPLED["transmission"]) > 0)):
                result.transmits = True
        if settings is not None and settings.profile == "NONE":
            continue
        for node in mat.node_tree.nodes:
            found = None
            if node.type == "BSDF_PRINCIPLED":
                factor, linked = _scatters(node)
                if factor <= 0.0:
                    continue
                r = principled_input(node, "subsurface_radius").default_value
                sscol = tuple(principled_input(node, "subsurface_color")
                              .default_value[:3])
                base = principled_input(node, "base").default_value[:3]
                found = Found(mat, mat.name, mat.pass_index, node,
                              tuple(v * factor * unit for v in r),
                              sscol, node.subsurface_method, linked,
                              tuple(b + (c - b) * factor
                                    for b, c in zip(base, sscol)))
                if linked:
                    result.messages.append(
                        f"{mat.name}: Subsurface is driven by a texture; "
                        "its full radius is used")
            elif node.type == "SUBSURFACE_SCATTERING":
                scale = node.inputs["Scale"].default_value
                r = node.inputs["Radius"].default_value
                found = Found(mat, mat.name, mat.pass_index, node,
                              tuple(v * scale * unit for v in r),
                              tuple(node.inputs["Color"].default_value[:3]),
                              node.falloff)
                found.albedo = found.color
            if found:
                result.found.append(found)
                break  # one profile per material
    return result


def camera_pixels_per_metre(scene, distance):
    """Horizontal pixels per metre at a view distance (Blender's sensor
    fit rules, as in csrc/sss_camera.c)."""
    cam = scene.camera.data
    render = scene.render
    scale = render.resolution_percentage / 100.0
    w = render.resolution_x * scale
    h = render.resolution_y * scale
    ax, ay = render.pixel_aspect_x, render.pixel_aspect_y
    fit = cam.sensor_fit
    if fit == "AUTO":
        fit = "HORIZONTAL" if ax * w >= ay * h else "VERTICAL"
    viewfac = w if fit == "HORIZONTAL" else (ay / ax) * h
    unit = scene.unit_settings.scale_length or 1.0
    if cam.type == "ORTHO":
        return viewfac / (cam.ortho_scale * unit)
    sensor = cam.sensor_height if cam.sensor_fit == "VERTICAL" else \
        cam.sensor_width
    return viewfac * cam.lens / (sensor * distance * unit)


def nearest_distance(scene, material):
    """Distance from the camera to the nearest object using material."""
    if scene.camera is None:
        return None
    cam_pos = scene.camera.matrix_world.translation
    distance = None
    for obj in scene.objects:
        if any(s.material == material for s in
               getattr(obj, "material_slots", [])):
            d = (obj.matrix_world.translation - cam_pos).length
            distance = d if distance is None else min(distance, d)
    return distance
