"""Settings stored in the .blend: per material (Material.sss) and per scene
(Scene.sss). Units follow the library: metres for radii and widths, mm for
Gaussian sigmas."""
import bpy
from bpy.props import (BoolProperty, EnumProperty, FloatProperty,
                       FloatVectorProperty, IntProperty, PointerProperty,
                       StringProperty)

from . import live, native

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

MAPPINGS = [
    ("AUTO", "Auto", "What this Blender's Cycles does with the radius for "
     "Random Walk materials (and the Burley profile), Cycles' Burley "
     "otherwise", 0),
    ("CYCLES", "Cycles Burley", "d = radius / 4 pi", 1),
    ("EEVEE", "EEVEE", "d = 0.0459 radius", 2),
    ("RANDOM_WALK", "Mean Free Path",
     "The radius is the diffuse mean free path (Christensen-Burley)", 3),
    ("CYCLES_RANDOM_WALK", "Cycles Random Walk",
     "What Cycles' random walk (3.x's Random Walk, 4.x's Random Walk "
     "(Skin)) does with the radius, as measured on slabs: its mean free "
     "path through Jensen's dipole, then Burley's fit", 4),
    ("CYCLES4_RANDOM_WALK", "Cycles 4 Random Walk",
     "What the Random Walk of Cycles 4.x and 5.x does with the radius, as "
     "measured on slabs (narrower for dark colours)", 5),
]

TEXTURING = [
    ("POST", "Post-Scatter",
     "Blur the light, multiply by the colour after: crisp texture", 0),
    ("PRE_AND_POST", "Pre- and Post-Scatter",
     "Square root of the colour before and after: texture bleeds a little",
     1),
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


TRANSMISSION = [
    ("AUTO", "Auto", "Profile for Random Walk materials (measured "
     "against Cycles' random walk), off for the others", 5),
    ("OFF", "Off", "No light through thin parts from behind", 0),
    ("BURLEY", "Profile", "Burley profiles: the share of the light "
     "entering the back that leaves by the front, from diffusion in the "
     "random walk's own medium (per sample, along the real paths); "
     "Gaussian sums: their mass beyond the thickness", 1),
    ("JIMENEZ", "Jimenez", "Jimenez et al. 2010: d'Eon's skin Gaussians "
     "through s = t 8.25 (1 - translucency) / width", 2),
    ("BEER_LAMBERT", "Beer-Lambert", "The colour seen through the given "
     "distance: colour ^ (thickness / distance)", 3),
    ("FAST", "Fast (GDC 2011)", "pow(N.V (1 - distortion), power) x scale "
     "+ ambient, fading out at the distance: an artist model", 4),
]

BACKLIGHT_LAYER = [
    ("AUTO", "Auto", "Render the back-light layer when a transmitting "
     "material is lit from behind (a light past 75 degrees from the "
     "camera, or a bright world)", 0),
    ("ALWAYS", "Always", "Whenever a scattering material transmits", 1),
    ("NEVER", "Never", "No transmission", 2),
]


class SSSMaterialSettings(bpy.types.PropertyGroup):
    profile: EnumProperty(name="Profile", items=PROFILES, default="BLENDER")
    strength: FloatProperty(
        name="Strength", min=0.0, max=1.0, default=1.0,
        description="Share of the diffuse light that scatters")
    texturing: EnumProperty(name="Texturing", items=TEXTURING,
                            default="POST")
    mapping: EnumProperty(
        name="Radius Meaning", items=MAPPINGS, default="AUTO",
        description="How a Burley radius becomes the profile's shape")
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
    radius: FloatVectorProperty(
        name="Radius", size=3, min=0.0, soft_max=0.1, precision=5,
        subtype="NONE", unit="LENGTH",
        default=(0.00367, 0.00137, 0.00068),
        description="Scattering distance per channel (Burley profile)")
    albedo: FloatVectorProperty(
        name="Albedo", size=3, min=0.0, max=1.0, subtype="COLOR",
        default=(0.8, 0.8, 0.8),
        description="Surface albedo, for the mean-free-path meaning")
    gaussian_scale: FloatProperty(
        name="Scale", min=0.0, soft_max=20.0, default=1.0,
        description="Multiplies the skin Gaussians' widths")
    jimenez_width: FloatProperty(
        name="Width", min=0.0, soft_max=0.1, default=0.012, precision=4,
        subtype="DISTANCE", unit="LENGTH",
        description="World span of the kernel (three kernel units)")
    jimenez_strength: FloatVectorProperty(
        name="Strength", size=3, min=0.0, max=1.0, subtype="COLOR",
        default=(0.48, 0.41, 0.28))
    jimenez_falloff: FloatVectorProperty(
        name="Falloff", size=3, min=0.001, max=10.0, subtype="COLOR",
        default=(1.0, 0.37, 0.3))
    scatter_scale: FloatProperty(name="Scatter Scale", min=0.0,
                                 soft_max=10.0, default=1.0)
    near_far_balance: FloatProperty(
        name="Near/Far Balance", min=0.0, max=1.0, default=0.5,
        description="1: all near (tight), 0: all far (wide)")
    near_sigma: FloatVectorProperty(name="Near Sigma (mm)", size=3,
                                    min=0.001, soft_max=10.0,
                                    default=(0.35, 0.07, 0.035))
    far_sigma: FloatVectorProperty(name="Far Sigma (mm)", size=3,
                                   min=0.001, soft_max=20.0,
                                   default=(1.0, 0.12, 0.10))
    taps: IntProperty(
        name="Taps", min=0, max=4097, default=0,
        description="Samples per 1-D pass for this material; 0: the "
        "scene's Taps")
    transmission: EnumProperty(
        name="Transmission", items=TRANSMISSION, default="AUTO",
        description="Light through thin parts lit from behind (ears, "
        "fingers, jade, wax, leaves)")
    transmission_strength: FloatProperty(
        name="Strength", min=0.0, max=1.0, default=1.0,
        description="Share of the back light that crosses")
    transmission_color: FloatVectorProperty(
        name="Tint", size=3, min=0.0, max=1.0, subtype="COLOR",
        default=(1.0, 1.0, 1.0),
        description="Tint; Beer-Lambert: the colour seen through Distance")
    transmission_distance: FloatProperty(
        name="Distance", min=1e-6, soft_max=0.1, default=0.01, precision=4,
        subtype="DISTANCE", unit="LENGTH",
        description="Beer-Lambert: where the colour is measured; Fast: "
        "the thickness where it fades out")
    transmission_translucency: FloatProperty(
        name="Translucency", min=0.0, max=1.0, default=0.83,
        description="Jimenez: 1 lets everything through")
    transmission_distortion: FloatProperty(
        name="Distortion", min=0.0, max=1.0, default=0.2,
        description="Fast: normal shift of the light vector")
    transmission_power: FloatProperty(name="Power", min=0.01,
                                      soft_max=32.0, default=4.0)
    transmission_scale: FloatProperty(name="Scale", min=0.0, soft_max=10.0,
                                      default=1.0)
    transmission_ambient: FloatProperty(name="Ambient", min=0.0,
                                        soft_max=1.0, default=0.0)
    thickness_scale: FloatProperty(
        name="Thickness", min=0.0, soft_max=10.0, default=1.0,
        description="Multiplies the measured thickness (below 1: thinner)")


class SSSSceneSettings(bpy.types.PropertyGroup):
    radius_scale: FloatProperty(
        name="Scene Radius Scale", min=0.0, soft_max=10.0, default=1.0,
        description="Multiplies every material's scattering distances "
        "(0: no scattering)")
    # Stored as the method's value in the library (0 = auto, the first
    # item and so the default).
    method: EnumProperty(name="Method", items=method_items)
    taps: IntProperty(
        name="Taps", min=1, max=4097, default=33,
        description="Samples per 1-D pass of the separable methods on "
        "blurs wider than 64 pixels (narrower ones read every pixel): "
        "more is smoother on wide blurs and slower")
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


classes = (SSSMaterialSettings, SSSSceneSettings)

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
