"""Which scattering materials transmit light through thin parts, and
what lights them from behind: with how far the library says their light
reaches through them (native.transmission_reach), what decides if a
render needs the back-light layer (transmission.wanted). Reads the scene
only."""
import math

from mathutils import Vector

from . import blender_compat as compat

# A light counts as "behind" when the angle between the directions from the
# object to it and to the camera exceeds this (75 degrees: side lights
# that graze thin edges count, front lights do not).
BEHIND_COS = math.cos(math.radians(75.0))
# The world lights thin parts from behind when its colour x strength is at
# least this (luminance), or when its colour is textured.
WORLD_THRESHOLD = 0.1


def model(found):
    """The material's transmission model with Auto resolved: Profile for
    Random Walk materials (Burley profile, as the add-on maps them), off
    for the others."""
    s = found.material.sss
    if s.profile == "NONE":
        return "OFF"
    if s.transmission != "AUTO":
        return s.transmission
    walk = found.method.startswith("RANDOM_WALK") and \
        s.profile in ("BLENDER", "BURLEY")
    return "BURLEY" if walk else "OFF"


def transmitting(analysis):
    """The found materials whose transmission is on."""
    return [f for f in analysis.materials if model(f) != "OFF"]


def objects_with(scene, material):
    """The rendered objects that use material."""
    for obj in scene.objects:
        if obj.hide_render or not hasattr(obj, "material_slots"):
            continue
        if any(slot.material == material for slot in obj.material_slots):
            yield obj


def _centre(obj):
    corners = [obj.matrix_world @ Vector(c) for c in obj.bound_box]
    return sum(corners, Vector()) / len(corners)


def _world_is_bright(scene):
    world = scene.world
    if world is None:
        return False
    if not compat.uses_nodes(world):
        c = world.color
        return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2] >= \
            WORLD_THRESHOLD
    for node in world.node_tree.nodes:
        if node.type != "BACKGROUND":
            continue
        col, strength = node.inputs["Color"], node.inputs["Strength"]
        if col.is_linked or strength.is_linked:
            return True
        c = col.default_value
        lum = (0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]) * \
            strength.default_value
        if lum >= WORLD_THRESHOLD:
            return True
    return False


def lights_behind(scene, objects):
    """Names of what lights any of objects from behind (lights, "World");
    empty when nothing does."""
    if scene.camera is None or not objects:
        return []
    cam = scene.camera.matrix_world.translation
    names = []
    lights = [o for o in scene.objects if o.type == "LIGHT" and
              not o.hide_render and o.data.energy > 0.0]
    for obj in objects:
        centre = _centre(obj)
        to_cam = (cam - centre).normalized()
        for light in lights:
            if light.data.type == "SUN":
                to_light = (light.matrix_world.to_3x3() @
                            Vector((0.0, 0.0, 1.0))).normalized()
            else:
                to_light = (light.matrix_world.translation -
                            centre).normalized()
            if to_light.dot(to_cam) < BEHIND_COS and \
                    light.name not in names:
                names.append(light.name)
    if _world_is_bright(scene):
        names.append("World")
    return names
