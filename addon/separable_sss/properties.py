"""Settings stored in the .blend: per material (Material.sss) and per scene
(Scene.sss). Units follow the library: metres for radii and widths, mm for
Gaussian sigmas."""
import bpy
from bpy.props import (BoolProperty, EnumProperty, FloatProperty,
                       FloatVectorProperty, IntProperty, PointerProperty,
                       StringProperty)

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
    ("AUTO", "Auto", "Random walk for Random Walk materials, Cycles' "
     "Burley otherwise", 0),
    ("CYCLES", "Cycles Burley", "d = radius / 4 pi", 1),
    ("EEVEE", "EEVEE", "d = 0.0459 radius", 2),
    ("RANDOM_WALK", "Mean Free Path",
     "The radius is the diffuse mean free path (random walk)", 3),
]

TEXTURING = [
    ("POST", "Post-Scatter",
     "Blur the light, multiply by the colour after: crisp texture", 0),
    ("PRE_AND_POST", "Pre- and Post-Scatter",
     "Square root of the colour before and after: texture bleeds a little",
     1),
]

METHODS = [
    ("SEPARABLE", "Separable", "Two 1-D passes: fast", 0),
    ("SEPARABLE_EXACT", "Separable Exact", "Two 1-D passes per Gaussian "
     "lobe: exact for Gaussian sums, Burley fitted; slower than Separable", 1),
    ("DISK", "Disk", "Stochastic disk samples (64 per pixel): grainy on "
     "fine detail", 2),
    ("REFERENCE", "Reference", "Brute-force 2-D: slow, exact in screen "
     "space", 3),
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
        description="Multiplies this material's scattering distances")
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
    taps: IntProperty(name="Taps", min=0, max=4097, default=0,
                      description="Taps per 1-D pass, 0 = the scene's")


class SSSSceneSettings(bpy.types.PropertyGroup):
    radius_scale: FloatProperty(
        name="Radius Scale", min=0.0, soft_max=10.0, default=1.0,
        description="Multiplies every scattering distance (0: no "
        "scattering)")
    method: EnumProperty(name="Method", items=METHODS, default="SEPARABLE")
    taps: IntProperty(
        name="Quality (taps)", min=1, max=4097, default=33,
        description="Taps per 1-D pass; wider kernels are sampled with "
        "this many taps")
    output_dir: StringProperty(
        name="Output Folder", subtype="DIR_PATH", default="",
        description="Where passes and results go (empty: a temporary "
        "folder)")
    use_animation: BoolProperty(
        name="Apply to Animation Renders", default=False,
        description="Render Animation (and blender -b -a) renders with "
        "material SSS off and writes each frame's SSS result beside it")
    last_result: StringProperty(name="Last Result", subtype="FILE_PATH",
                                default="")


classes = (SSSMaterialSettings, SSSSceneSettings)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Material.sss = PointerProperty(type=SSSMaterialSettings)
    bpy.types.Scene.sss = PointerProperty(type=SSSSceneSettings)


def unregister():
    del bpy.types.Scene.sss
    del bpy.types.Material.sss
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
