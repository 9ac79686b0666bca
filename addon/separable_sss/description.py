"""The scene description the library reads (docs/scene.md): camera, unit
scale, method and quality, the scene's radius scale and one entry per
scattering material, with its radius mapping, energy calibration and
transmission. The one place the add-on turns its settings into the
library's keys: the pipeline, the render flow, the scripts and the test
scenes all write it through here."""
import json
import os

from . import blender_compat as compat
from . import lighting, native


def method_name(identifier):
    """The library's name for a Method choice ("SEPARABLE_EXACT" ->
    "separable-exact"; properties builds the choices from the names)."""
    return identifier.lower().replace("_", "-")


MODELS = {"OFF": "off", "BURLEY": "burley", "JIMENEZ": "jimenez",
          "BEER_LAMBERT": "beer-lambert", "FAST": "fast"}


def _transmission_fields(found):
    """The scene-description keys of a material's transmission."""
    s = found.material.sss
    kind = lighting.model(found)
    if kind == "OFF":
        return {"transmission": "off"}
    return {
        "transmission": MODELS[kind],
        "transmission_strength": s.transmission_strength,
        "transmission_color": [min(max(float(c), 0.0), 1.0)
                               for c in s.transmission_color],
        "transmission_distance": s.transmission_distance * s.radius_scale,
        "transmission_translucency": s.transmission_translucency,
        "transmission_distortion": s.transmission_distortion,
        "transmission_power": s.transmission_power,
        "transmission_scale": s.transmission_scale,
        "transmission_ambient": s.transmission_ambient,
        "thickness_scale": s.thickness_scale,
    }


# The Radius Meaning choices (properties.MAPPINGS) by their scene.json names.
MAPPING_NAMES = {"CYCLES": "cycles", "EEVEE": "eevee",
                 "RANDOM_WALK": "random-walk",
                 "CYCLES_RANDOM_WALK": "cycles-random-walk",
                 "CYCLES4_RANDOM_WALK": "cycles4-random-walk"}


def material_entry(found):
    """One entry of the description's material table."""
    s = found.material.sss
    # Principled v2's Subsurface Weight mixes the diffuse and subsurface
    # lobes: it scales how much of the light is scattered.
    entry = {"pass_index": found.pass_index, "name": found.name,
             "strength": s.strength * found.weight,
             "texturing": "post" if s.texturing == "POST" else
             "pre-and-post"}
    if s.taps:
        entry["taps"] = s.taps
    scale = s.radius_scale
    if s.profile in ("BLENDER", "BURLEY"):
        # Measured (blender_scripts/calibrate.py, csrc/sss_calibration.c):
        # how Cycles' random walk widens with the colour and what energy it
        # returns, per method and Blender version. The Burley profile
        # follows Random Walk (Skin), the walk 3.x has.
        walk = compat.WALK_CALIBRATION.get(
            "RANDOM_WALK_SKIN" if s.profile == "BURLEY" else found.method)
        if s.mapping != "AUTO":
            mapping = MAPPING_NAMES[s.mapping]
        elif walk:
            mapping = walk[0]
        else:
            mapping = "random-walk" if found.method.startswith(
                "RANDOM_WALK") else "cycles"
        radius = found.radius if s.profile == "BLENDER" else tuple(s.radius)
        albedo = (found.albedo or found.color) if s.profile == "BLENDER" \
            else tuple(s.albedo)
        entry.update(profile="burley",
                     radius=[float(r) * scale for r in radius],
                     mapping=mapping,
                     albedo=[min(max(float(a), 0.0), 1.0) for a in albedo])
        if s.match_energy and walk:
            entry["calibration"] = walk[1]
    elif s.profile == "GAUSSIANS":
        entry.update(profile="gaussians", scale=s.gaussian_scale * scale)
    elif s.profile == "JIMENEZ":
        entry.update(profile="jimenez", width=s.jimenez_width * scale,
                     strength_rgb=list(s.jimenez_strength),
                     falloff=list(s.jimenez_falloff))
    elif s.profile == "NEAR_FAR":
        entry.update(profile="near-far",
                     scatter_scale=s.scatter_scale * scale,
                     balance=s.near_far_balance,
                     near_sigma=list(s.near_sigma),
                     far_sigma=list(s.far_sigma))
    if s.profile != "NONE":
        entry.update(_transmission_fields(found))
    return entry


def camera_entry(scene):
    """The description's camera (docs/scene.md)."""
    cam = scene.camera.data
    return {
        "type": "ORTHO" if cam.type == "ORTHO" else "PERSP",
        "lens": cam.lens, "sensor_width": cam.sensor_width,
        "sensor_height": cam.sensor_height,
        "sensor_fit": cam.sensor_fit,
        "shift_x": cam.shift_x, "shift_y": cam.shift_y,
        "ortho_scale": cam.ortho_scale,
        "clip_start": cam.clip_start, "clip_end": cam.clip_end,
        "pixel_aspect_x": scene.render.pixel_aspect_x,
        "pixel_aspect_y": scene.render.pixel_aspect_y,
    }


def unit_scale(scene):
    return scene.unit_settings.scale_length or 1.0


def camera_pixels_per_metre(scene, distance):
    """Horizontal pixels per metre at a view distance (scene units) at the
    scene's render size, as the library projects it (csrc/sss_camera.c)."""
    render = scene.render
    scale = render.resolution_percentage / 100.0
    return native.camera_pixels_per_metre(
        camera_entry(scene), unit_scale(scene),
        max(1, int(render.resolution_x * scale)),
        max(1, int(render.resolution_y * scale)), distance)


def scene_description(scene, found):
    """The JSON the library reads (docs/scene.md)."""
    return {
        "version": 1,
        "camera": camera_entry(scene),
        "unit_scale": unit_scale(scene),
        # In the description, not beside it: `sss` on this file gives
        # the add-on's result.
        "radius_scale": scene.sss.radius_scale,
        "method": method_name(scene.sss.method),
        "taps": scene.sss.taps | 1,
        "materials": [_with_baked(scene, f, material_entry(f))
                      for f in found.materials],
    }


def slab(scene, found):
    """The library's diffusion slab (sigma_tr, a, zb per channel, metres
    at radius scale 1) when the back-light layer bakes this material's
    attenuation into its light (transmission.py, PROP_MODE 2): the burley
    model on a Burley profile, every channel with a medium. None
    otherwise."""
    s = found.material.sss
    if lighting.model(found) != "BURLEY" or not s.thickness_scale > 0.0 \
            or not scene.sss.radius_scale > 0.0:
        return None
    params = native.transmission_slab(library_material(scene, found))
    if params is None or not all(a > 0.0 for a in params[1]):
        return None
    return params


def _with_baked(scene, found, entry):
    """The library must know which back light already crossed the part at
    this radius scale: it refuses to scale that light's radius (sss
    --radius-scale)."""
    if slab(scene, found):
        entry["transmission_baked_scale"] = scene.sss.radius_scale
    return entry


def write_description(scene, found, path):
    """Writes the description atomically (a temporary file, renamed)."""
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(scene_description(scene, found), f, indent=2)
    os.replace(tmp, path)


def library_material(scene, found):
    """The material's description entry with its tap count resolved, for
    questions to the library about it."""
    entry = material_entry(found)
    return dict(entry, taps=entry.get("taps") or scene.sss.taps | 1)
