"""Settings stored in the .blend: per material (Material.sss) and per scene
(Scene.sss). The material's are the add-on's own few (profile, radius scale,
energy matching) plus one per field of the library's material schema
(sss_material_field), made from it when the add-on is enabled: its default,
range, help and unit (metres for radii and widths, mm for Gaussian
sigmas)."""
import bpy
from bpy.props import (BoolProperty, EnumProperty, FloatProperty,
                       FloatVectorProperty, IntProperty, PointerProperty,
                       StringProperty)

from . import live, native
from .description import DERIVED, identifier, property_name

PROFILES = [
    ("BLENDER", "From Material",
     "Burley from the material's own Subsurface Radius and Color", 0),
    ("BURLEY", "Burley", "Burley normalized diffusion with the radius below",
     1),
    ("GAUSSIANS", "Sum of Gaussians",
     "d'Eon's six-Gaussian skin profile, scaled", 2),
    ("JIMENEZ", "Jimenez Separable",
     "Jimenez's artist-friendly separable kernel", 3),
    ("NEAR_FAR", "Near/Far Gaussians",
     "Two Gaussians: a tight near and a wide far one", 4),
    ("NONE", "Off", "Do not scatter this material", 5),
]

# The Method choices come from the library, which names its methods; the
# list is kept here because Blender reads a dynamic enum's strings after
# the call that made them has returned.
_method_items = []


def method_items(_self=None, _context=None):
    """[(IDENTIFIER, Label, summary, value)] of the library's methods
    ("separable-exact" is SEPARABLE_EXACT, "Separable Exact"); empty while
    the library cannot be loaded (the operators say why)."""
    if not _method_items:
        try:
            _method_items.extend(
                (name.upper().replace("-", "_"),
                 name.replace("-", " ").title(), summary, value)
                for value, (name, summary) in enumerate(native.methods()))
        except native.LibraryError:
            return []
    return _method_items


BACKLIGHT_LAYER = [
    ("AUTO", "Auto", "Render the back-light layer when a transmitting "
     "material is lit from behind (a light past 75 degrees from the "
     "camera, or a bright world)", 0),
    ("ALWAYS", "Always", "Whenever a scattering material transmits", 1),
    ("NEVER", "Never", "No transmission", 2),
]


class SSSMaterialSettings(bpy.types.PropertyGroup):
    """The add-on's own settings; register() adds one property per field
    of the library's material schema (field_properties)."""
    profile: EnumProperty(name="Profile", items=PROFILES, default="BLENDER")
    radius_scale: FloatProperty(
        name="Radius Scale", min=0.0, soft_max=10.0, default=1.0,
        description="Multiplies this material's scattering distances (the "
        "scene's Scene Radius Scale multiplies every material's)")
    match_energy: BoolProperty(
        name="Match Energy", default=True,
        description="Scale the scattered light per colour channel by the "
        "random walk's measured reflectance over the diffuse lobe's, for "
        "the colour, the angle each pixel is seen at and how curved the "
        "surface is there (Random Walk materials and the Burley profile)")


# Enum fields: the choices the add-on adds before the library's (resolved by
# description.py and lighting.py; the first is the default) and what is
# added to a library value to give the value stored in .blend files.
ENUM_EXTRAS = {
    "burley_mapping": (1, [
        ("AUTO", "Auto", "What this Blender's Cycles does with the radius "
         "for Random Walk materials (and the Burley profile), Cycles' "
         "Burley otherwise", 0)]),
    "transmission": (0, [
        ("AUTO", "Auto", "Profile for Random Walk materials (measured "
         "against Cycles' random walk), off for the others", 5)]),
}

# Labels and tooltips of the library's enum names where the name alone
# says too little; any other name is shown title-cased with the field's
# help.
ENUM_TEXT = {
    ("burley_mapping", "cycles"): ("Cycles Burley", "d = radius / 4 pi"),
    ("burley_mapping", "eevee"): ("EEVEE", "d = 0.0459 radius"),
    ("burley_mapping", "random-walk"): (
        "Mean Free Path",
        "The radius is the diffuse mean free path (Christensen-Burley)"),
    ("burley_mapping", "cycles-random-walk"): (
        "Cycles Random Walk",
        "What Cycles' random walk (3.x's Random Walk, 4.x's Random Walk "
        "(Skin)) does with the radius, as measured on slabs: its mean free "
        "path through Jensen's dipole, then Burley's fit"),
    ("burley_mapping", "cycles4-random-walk"): (
        "Cycles 4 Random Walk",
        "What the Random Walk of Cycles 4.x and 5.x does with the radius, "
        "as measured on slabs (narrower for dark colours)"),
    ("texturing", "post"): (
        "Post-Scatter",
        "Blur the light, multiply by the colour after: crisp texture"),
    ("texturing", "pre-and-post"): (
        "Pre- and Post-Scatter",
        "Square root of the colour before and after: texture bleeds a "
        "little"),
    ("transmission", "off"): ("Off",
                              "No light through thin parts from behind"),
    ("transmission", "burley"): (
        "Profile", "Burley profiles: the share of the light entering the "
        "back that leaves by the front, from diffusion in the random "
        "walk's own medium (per sample, along the real paths); Gaussian "
        "sums: their mass beyond the thickness"),
    ("transmission", "jimenez"): (
        "Jimenez", "Jimenez et al. 2010: d'Eon's skin Gaussians through "
        "s = t 8.25 (1 - translucency) / width"),
    ("transmission", "beer-lambert"): (
        "Beer-Lambert", "The colour seen through the given distance: "
        "colour ^ (thickness / distance)"),
    ("transmission", "fast"): (
        "Fast (GDC 2011)", "pow(N.V (1 - distortion), power) x scale + "
        "ambient, fading out at the distance: an artist model"),
}

NO_UPPER_BOUND = 1e30  # sss_field_info.hi for "no upper bound"


def enum_items(member, field):
    """[(IDENTIFIER, label, tooltip, value)]: the add-on's extra choices,
    then the library's names (sss_material_field_name)."""
    offset, extras = ENUM_EXTRAS.get(member, (0, []))
    items = list(extras)
    for name, value in field["names"]:
        label, tip = ENUM_TEXT.get(
            (member, name),
            (name.replace("-", " ").title(), _sentence(field["help"])))
        items.append((identifier(name), label, tip, value + offset))
    return items


def _sentence(text):
    return text[:1].upper() + text[1:]


def _label(field):
    """The field's label, from its key: "transmission_color" -> "Color",
    "strength_rgb" -> "Strength", "near_sigma" -> "Near Sigma (mm)" (a
    help that starts with "mm" gives the unit)."""
    key = field["key"]
    if key != "transmission" and key.startswith("transmission_"):
        key = key[len("transmission_"):]
    if key.endswith("_rgb"):
        key = key[:-len("_rgb")]
    label = key.replace("_", " ").title()
    return label + " (mm)" if field["help"].startswith("mm") else label


def field_property(member, field):
    """The bpy property of one field of the library's material schema:
    its default, range and help; a help starting with "metres" makes it
    a length (shown in the scene's units)."""
    kind, default = field["type"], field["default"]
    keywords = {"name": _label(field),
                "description": _sentence(field["help"])}
    if kind == "enum":
        items = enum_items(member, field)
        extras = ENUM_EXTRAS.get(member, (0, []))[1]
        keywords["default"] = extras[0][0] if extras else next(
            identifier(n) for n, v in field["names"] if v == int(default))
        return EnumProperty(items=items, **keywords)
    lo, hi = field["lo"], field["hi"]
    if kind == "int":
        return IntProperty(min=int(lo) + field["lo_open"],
                           max=min(int(hi), 2**31 - 1), default=int(default),
                           **keywords)
    keywords["min"] = lo + 1e-6 if field["lo_open"] else lo
    if hi < NO_UPPER_BOUND:
        keywords["max"] = hi
    else:
        keywords["soft_max"] = 10.0 * max(default if kind == "rgb"
                                          else [default]) or 1.0
    if field["help"].startswith("metres"):
        keywords.update(unit="LENGTH", precision=5)
    if kind == "float":
        if "unit" in keywords:
            keywords["subtype"] = "DISTANCE"
        return FloatProperty(default=default, **keywords)
    keywords["subtype"] = "COLOR" if hi <= 1.0 else "NONE"
    return FloatVectorProperty(size=3, default=tuple(default), **keywords)


def field_properties():
    """{property name: (member, bpy property)} of every field of the
    library's material schema that artists set (not DERIVED)."""
    return {property_name(m): (m, field_property(m, f))
            for m, f in native.material_fields().items()
            if m not in DERIVED}


class SSSSceneSettings(bpy.types.PropertyGroup):
    radius_scale: FloatProperty(
        name="Scene Radius Scale", min=0.0, soft_max=10.0, default=1.0,
        description="Multiplies every material's scattering distances "
        "(0: no scattering)")
    # Stored as the method's value in the library (0 = auto, the first
    # item and so the default).
    method: EnumProperty(name="Method", items=method_items)
    output_dir: StringProperty(
        name="Output Folder", subtype="DIR_PATH", default="",
        description="Where passes and results go (empty: a temporary "
        "folder)")
    enabled: BoolProperty(
        name="Screen-space SSS", default=False,
        description="Renders of this scene (blender -b -f/-a, scripts) "
        "scatter every frame: rendered with material SSS off, the frames, "
        "File Output nodes and Render Result show the result with SSS")
    transmission_layer: EnumProperty(
        name="Back-Light Layer", items=BACKLIGHT_LAYER, default="AUTO",
        description="The extra view layer that measures light arriving "
        "from behind and thickness, for transmission")
    transmission_samples: IntProperty(
        name="Back-Light Samples", min=0, max=65536, default=0,
        description="Samples of the back-light layer (its light is "
        "blurred, so few do); 0: a quarter of the scene's, at least 4")
    live: BoolProperty(
        name="Live Re-tune",
        description="After Render with SSS or Apply, keep the render's "
                    "passes in memory and scatter them again whenever an "
                    "SSS setting of the scene or a material changes",
        default=True)
    last_result: StringProperty(name="Last Result", subtype="FILE_PATH",
                                default="")


def scene_properties():
    """{property name: bpy property} of the scene settings that are one
    of the library's options (sss_option_field): Taps, with the option's
    range and default."""
    taps = native.option_fields()["taps"]
    return {"taps": IntProperty(
        name="Taps", min=int(taps["lo"]), max=int(taps["hi"]),
        default=int(taps["default"]),
        description="Samples per 1-D pass of the separable methods on "
        "blurs wider than 64 pixels (narrower ones read every pixel): "
        "more is smoother on wide blurs and slower")}


classes = (SSSMaterialSettings, SSSSceneSettings)

# Why the material settings lack the library's fields and the scene's
# its options (None: they have them); set by register().
library_error = None

# The scene settings a live re-tune follows (live.py); it follows every
# material one.
_SCENE_RETUNE = ("radius_scale", "method", "taps", "live")


def _changed(self, _context):
    live.changed(self.id_data)


def _follow(cls, names=None):
    """Every (or the named) property of cls tells live.py of a change."""
    for name, prop in cls.__annotations__.items():
        if names is None or name in names:
            prop.keywords.setdefault("update", _changed)


def register():
    # The library is loaded here (native.py finds it): without it the
    # material settings are the add-on's own only, and the panels say why.
    global library_error
    try:
        fields, scene_fields = field_properties(), scene_properties()
        library_error = None
    except native.LibraryError as e:
        fields, scene_fields, library_error = {}, {}, str(e)
    for name, (_member, prop) in fields.items():
        SSSMaterialSettings.__annotations__[name] = prop
    SSSSceneSettings.__annotations__.update(scene_fields)
    _follow(SSSMaterialSettings)
    _follow(SSSSceneSettings, _SCENE_RETUNE)
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Material.sss = PointerProperty(type=SSSMaterialSettings)
    bpy.types.Scene.sss = PointerProperty(type=SSSSceneSettings)


def unregister():
    del bpy.types.Scene.sss
    del bpy.types.Material.sss
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
