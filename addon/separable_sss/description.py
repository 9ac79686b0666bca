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


# The material schema's fields (native.material_fields(), the library's
# table) become the entry's keys through these rules; a new field needs
# none of its own.

# The fields the add-on works out itself instead of offering them as
# settings: the calibration follows Match Energy, the baked scale the
# back-light layer (_with_baked), the walk's surface the material's IOR,
# Specular IOR Level and Roughness (_burley), thin_reflectance Match Energy
# where the library measured the walk's thin parts (native.thin_measured).
DERIVED = ("transmission_baked_scale", "calibration", "thin_reflectance",
           "walk_ior", "walk_roughness")

# The setting a field is stored as where it is not the field's member
# (the name .blend files and presets already hold).
PROPERTY_NAMES = {"burley_mapping": "mapping"}

# The fields the material's Radius Scale multiplies: its lengths and the
# profiles' own scale factors.
SCALED = ("radius", "gaussian_scale", "jimenez_width", "scatter_scale",
          "transmission_distance")


def property_name(member):
    """The material setting (Material.sss) that holds a field."""
    return PROPERTY_NAMES.get(member, member)


def identifier(name):
    """A library name as a setting's choice ("pre-and-post" ->
    "PRE_AND_POST"); library_name() is its inverse."""
    return name.upper().replace("-", "_")


def library_name(choice):
    return choice.lower().replace("_", "-")


def _setting(s, member, field):
    """One field's value as the material's setting holds it, in the
    library's terms (an enum by its name), within the field's range where
    it has an upper bound."""
    value = getattr(s, property_name(member))
    if field["type"] == "enum":
        return library_name(value)
    if field["type"] == "int":
        return int(value)
    values = [float(v) for v in value] if field["type"] == "rgb" \
        else [float(value)]
    if field["hi"] < 1e30 and not field["lo_open"]:
        values = [min(max(v, field["lo"]), field["hi"]) for v in values]
    return values if field["type"] == "rgb" else values[0]


def material_entry(found):
    """One entry of the description's material table: every field of the
    library's schema that the material's profile reads (transmission's
    only while it transmits), from its setting, then what the add-on
    resolves (Auto choices, From Material, radius scale, weight)."""
    s = found.material.sss
    profile = "burley" if s.profile == "BLENDER" else library_name(s.profile)
    kind = native.profiles()[profile]
    model = lighting.model(found)
    fields = native.material_fields()
    entry = {"pass_index": found.pass_index, "name": found.name,
             "profile": profile}
    for member, field in fields.items():
        if member in DERIVED or field["profile"] not in (-1, kind) or \
                (field["transmits"] and model == "OFF"):
            continue
        entry[field["key"]] = _setting(s, member, field)
    # Principled v2's Subsurface Weight mixes the diffuse and subsurface
    # lobes: it scales how much of the light is scattered.
    entry["strength"] *= found.weight
    entry["transmission"] = library_name(model)
    if not entry["taps"]:
        del entry["taps"]          # the profile's own (the scene's; 17)
    scale = s.radius_scale
    for member in SCALED:
        key = fields[member]["key"]
        if key in entry:
            entry[key] = [v * scale for v in entry[key]] if isinstance(
                entry[key], list) else entry[key] * scale
    if profile == "burley":
        _burley(found, entry, fields)
    return entry


def _burley(found, entry, fields):
    """The Burley fields the add-on resolves: From Material's radius and
    colour, the Auto radius meaning and the energy calibration.
    Measured (blender_scripts/calibrate.py, csrc/sss_calibration.c): how
    Cycles' random walk widens with the colour and what energy it
    returns, per method and Blender version. The Burley profile follows
    Random Walk (Skin), the walk 3.x has."""
    s = found.material.sss
    walk = compat.WALK_CALIBRATION.get(
        "RANDOM_WALK_SKIN" if s.profile == "BURLEY" else found.method)
    if s.mapping == "AUTO":
        entry["mapping"] = walk[0] if walk else "random-walk" if \
            found.method.startswith("RANDOM_WALK") else "cycles"
    if s.profile == "BLENDER":
        entry["radius"] = [float(r) * s.radius_scale for r in found.radius]
        albedo = fields["albedo"]
        entry["albedo"] = [min(max(float(a), albedo["lo"]), albedo["hi"])
                           for a in (found.albedo or found.color)]
    if s.match_energy and walk:
        entry["calibration"] = walk[1]
        # Where libsss measured how much light thin parts lit from the
        # front lose through their back (csrc/sss_thin.c), Match Energy
        # takes all of that loss, read from the back-light layer's
        # thickness (docs/transmission.md, "Thin parts lit from the
        # front").
        if _thin_measured(entry):
            entry["thin_reflectance"] = 1.0
        # 4.x's plain Random Walk enters through the material's own
        # surface, and its energy follows that surface's index and
        # roughness.
        entry["walk_ior"] = found.walk_ior
        entry["walk_roughness"] = found.walk_roughness


def _thin_measured(entry):
    """native.thin_measured, False for an entry the library refuses (the
    scatter names the bad field)."""
    try:
        return native.thin_measured(entry)
    except native.LibraryError:
        return False


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
