"""Scene analysis: which materials scatter, with what radius and colour,
and which passes the render needs. Reads the scene only."""
from dataclasses import dataclass, field

import bpy

from . import blender_compat as compat
from .blender_compat import principled_input


@dataclass
class Found:
    """One scattering material."""
    material: bpy.types.Material
    name: str
    pass_index: int
    node: bpy.types.Node          # the Principled or Subsurface node
    radius: tuple                 # metres per channel
    color: tuple                  # the scattering colour
    method: str                   # BURLEY, RANDOM_WALK, RANDOM_WALK_SKIN
    linked_factor: bool = False   # the SSS switch is driven by a texture
    # The albedo Cycles' random walk uses: the Principled BSDF's diffuse
    # colour (socket values; a texture's pixels come in through DiffCol).
    albedo: tuple = None
    # How much of the diffuse lobe scatters: Principled v2's Subsurface
    # Weight (1 for 3.x's Subsurface factor and the Subsurface node).
    weight: float = 1.0
    # The index and roughness of the surface 4.x's plain Random Walk
    # enters through.
    walk_ior: float = 1.5
    walk_roughness: float = 0.5


@dataclass
class Analysis:
    materials: list = field(default_factory=list)  # Found, each scattering one
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


def _principled_notes(mat, sss, switch):
    """What the analysis cannot follow, for the panel and the report."""
    notes = []
    if switch in sss.linked:
        notes.append(f"{mat.name}: {switch} is driven by a texture; it "
                     "scatters everywhere with its full radius")
    other = [n for n in sss.linked if n != switch and n != "Base Color"]
    if other:
        notes.append(f"{mat.name}: {', '.join(other)} driven by links; "
                     "their unlinked values are used")
    if abs(sss.ior - 1.4) > 1e-3 or abs(sss.anisotropy) > 1e-3:
        notes.append(f"{mat.name}: Subsurface IOR {sss.ior:.3g} and "
                     f"Anisotropy {sss.anisotropy:.3g} are ignored (the "
                     "calibration assumes 1.4 and 0)")
    return notes


def analyse(scene):
    """What scatters in this scene and what the render must provide."""
    result = Analysis()
    unit = scene.unit_settings.scale_length or 1.0
    for mat in scene_materials(scene):
        if not compat.uses_nodes(mat):
            continue
        settings = getattr(mat, "sss", None)
        for node in mat.node_tree.nodes:
            if node.type == "EMISSION" or (
                    node.type == "BSDF_PRINCIPLED" and
                    _input_value(node, compat.PRINCIPLED["emission_strength"])
                    and (_is_linked(node, compat.PRINCIPLED["emission"]) or
                         any(_input_value(node, compat.PRINCIPLED["emission"])
                             [:3]))):
                result.emits = True
            if node.type in ("BSDF_GLASS", "BSDF_REFRACTION") or (
                    node.type == "BSDF_PRINCIPLED" and
                    (_is_linked(node, compat.PRINCIPLED["transmission"]) or
                     _input_value(node, compat.PRINCIPLED["transmission"])
                     > 0)):
                result.transmits = True
        if settings is not None and settings.profile == "NONE":
            continue
        for node in mat.node_tree.nodes:
            found = None
            if node.type == "BSDF_PRINCIPLED":
                sss = compat.principled_sss(node)
                if sss.weight <= 0.0:
                    continue
                switch = compat.PRINCIPLED["subsurface"]
                found = Found(mat, mat.name, mat.pass_index, node,
                              tuple(v * unit for v in sss.radius),
                              sss.color, compat.method(node),
                              switch in sss.linked, sss.albedo, sss.weight,
                              sss.walk_ior, sss.walk_roughness)
                result.messages.extend(_principled_notes(mat, sss, switch))
            elif node.type == "SUBSURFACE_SCATTERING":
                scale = node.inputs["Scale"].default_value
                r = node.inputs["Radius"].default_value
                found = Found(mat, mat.name, mat.pass_index, node,
                              tuple(v * scale * unit for v in r),
                              tuple(node.inputs["Color"].default_value[:3]),
                              compat.method(node))
                found.albedo = found.color
                ior = node.inputs.get("IOR")  # 4.x: what the walk enters
                if ior is not None:
                    found.walk_ior = min(max(float(ior.default_value),
                                             1.01), 3.8)
                rough = node.inputs.get("Roughness")
                if rough is not None:
                    found.walk_roughness = min(max(float(
                        rough.default_value), 0.0), 1.0)
            if found:
                result.materials.append(found)
                break  # one profile per material
    return result


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
