"""Everything that differs between the supported Blenders (3.4, 4.5 LTS,
5.0), in one place; the rest of the add-on, the scripts and the tests ask
this module instead of checking versions. It imports nothing of the
add-on's, so scripts and tests can import it on its own.

- The Principled BSDF. Up to 3.x its diffuse colour is
  mix(Base Color, Subsurface Color, Subsurface) and the radius is
  Subsurface Radius x Subsurface. From 4.0 ("v2") Subsurface Weight mixes
  diffuse and subsurface, the radius is Subsurface Radius x Subsurface
  Scale and the scattering colour is Base Color; Blender converts old files
  that way (Scale = old Subsurface, Weight 1, Base Color = the old mix).
- Subsurface methods. 3.x's Random Walk (radius adapted to the colour) is
  4.x's Random Walk (Skin); 3.x's Random Walk (Fixed Radius) is 4.x's
  Random Walk. The add-on speaks 4.x's names (METHODS). 4.0 also rewrote
  the walk itself: libsss's measured tables differ (WALK_CALIBRATION).
- The compositor. Up to 4.x it is scene.node_tree with a Composite node;
  in 5.0 it is a node group (scene.compositing_node_group) whose Group
  Output is the composite.
- Node group sockets: tree.inputs/outputs in 3.x, tree.interface from 4.0.
- EEVEE's engine name: BLENDER_EEVEE_NEXT in 4.2 to 4.5; its settings
  (plain_eevee) and AOV outputs (set_aov_output).
- Material.use_nodes and Scene.use_nodes are going away (5.0 warns).
- Image formats: 5.0 chooses a multilayer EXR by media type
  (MULTI_LAYER_IMAGE) before the file format.
- Node options that became input sockets in 5.0: the Denoise node's HDR
  (set_denoise_hdr).
- File Output nodes: base_path and file_slots up to 4.x; in 5.0 directory,
  file_name and file_output_items (set_file_output, file_output_inputs).
"""
import math
import os
from dataclasses import dataclass

import bpy

VERSION = tuple(bpy.app.version)
PRINCIPLED_V2 = VERSION >= (4, 0, 0)
COMPOSITOR_IS_GROUP = VERSION >= (5, 0, 0)
NODES_ALWAYS = VERSION >= (5, 0, 0)   # use_nodes is deprecated
CYCLES_WALK_V2 = VERSION >= (4, 0, 0)  # Cycles' random walk rewritten
EXTENSIONS = VERSION >= (4, 2, 0)     # blender_manifest.toml, wheels
EEVEE = "BLENDER_EEVEE_NEXT" if (4, 2, 0) <= VERSION < (5, 0, 0) \
    else "BLENDER_EEVEE"

if PRINCIPLED_V2:
    PRINCIPLED = {
        "base": "Base Color",
        "subsurface": "Subsurface Weight",   # the SSS switch
        "subsurface_radius": "Subsurface Radius",
        "subsurface_scale": "Subsurface Scale",
        "subsurface_ior": "Subsurface IOR",
        "subsurface_anisotropy": "Subsurface Anisotropy",
        "emission": "Emission Color",
        "emission_strength": "Emission Strength",
        "transmission": "Transmission Weight",
        "specular": "Specular IOR Level",
        "ior": "IOR",
        "roughness": "Roughness",
    }
else:
    PRINCIPLED = {
        "base": "Base Color",
        "subsurface": "Subsurface",          # factor; also scales the radius
        "subsurface_radius": "Subsurface Radius",
        "subsurface_color": "Subsurface Color",
        "emission": "Emission",
        "emission_strength": "Emission Strength",
        "transmission": "Transmission",
        "specular": "Specular",
        "ior": "IOR",
        "roughness": "Roughness",
    }
# The "specular" input's value that removes the specular layer: Specular 0,
# and from 4.0 Specular IOR Level 0 likewise.
SPECULAR_OFF = 0.0

# Blender's enum identifier for each method, by the names the add-on uses.
METHODS = ("BURLEY", "RANDOM_WALK", "RANDOM_WALK_SKIN")
_METHOD_FROM_BLENDER = {} if PRINCIPLED_V2 else {
    "RANDOM_WALK": "RANDOM_WALK_SKIN",
    "RANDOM_WALK_FIXED_RADIUS": "RANDOM_WALK"}
_METHOD_TO_BLENDER = {v: k for k, v in _METHOD_FROM_BLENDER.items()}

# Cycles' random walk as libsss measured it (csrc/sss_calibration.c): per
# method, the radius mapping and the energy calibration (scene.json
# names). 4.0 rewrote the walk: 3.x's Random Walk is 4.x's Random Walk
# (Skin), the same widths with less energy; 3.x's Fixed Radius has no
# measurement.
WALK_CALIBRATION = {
    "RANDOM_WALK_SKIN": ("cycles-random-walk", "cycles4-random-walk-skin"),
    "RANDOM_WALK": ("cycles4-random-walk", "cycles4-random-walk"),
} if CYCLES_WALK_V2 else {
    "RANDOM_WALK_SKIN": ("cycles-random-walk", "cycles-random-walk"),
}


def principled_input(node, key):
    """The Principled BSDF's input socket for a version-independent key.
    By iteration: from 4.0, inputs[name] does not find a socket that the
    current method leaves unused (Subsurface IOR outside Random Walk
    (Skin)), though it is there and restored like the others."""
    name = PRINCIPLED[key]
    for sock in node.inputs:
        if sock.name == name:
            return sock
    raise KeyError(f"{node.name} has no input {name!r}")


def method(node):
    """A Principled or Subsurface Scattering node's method, by 4.x's name."""
    raw = node.subsurface_method if node.type == "BSDF_PRINCIPLED" \
        else node.falloff
    return _METHOD_FROM_BLENDER.get(raw, raw)


def set_method(node, name):
    raw = _METHOD_TO_BLENDER.get(name, name)
    if node.type == "BSDF_PRINCIPLED":
        node.subsurface_method = raw
    else:
        node.falloff = raw


@dataclass
class PrincipledSSS:
    """What a Principled BSDF says about its subsurface scattering, read
    from the sockets (a linked socket contributes its unlinked value)."""
    weight: float          # how much of the diffuse lobe scatters (0..1)
    radius: tuple          # scene units per channel
    color: tuple           # the scattering colour
    albedo: tuple          # the diffuse colour Cycles' random walk uses
    linked: tuple          # names of the inputs driven by links
    ior: float = 1.4
    anisotropy: float = 0.0
    walk_ior: float = 1.5  # the surface plain Random Walk enters through
    walk_roughness: float = 0.5   # and its roughness


def walk_ior(ior, specular_level):
    """The index plain Random Walk (4.x) enters through, as Cycles makes
    it from the Principled BSDF's IOR and Specular IOR Level (the level
    scales the normal-incidence reflectance F0, 0.5 keeping the IOR's), in
    the range Cycles clamps it to."""
    eta = ior
    if specular_level != 0.5:
        f0 = ((ior - 1.0) / (ior + 1.0)) ** 2 * 2.0 * specular_level
        root = math.sqrt(min(max(f0, 0.0), 0.99))
        eta = (1.0 + root) / (1.0 - root)
        if ior < 1.0:
            eta = 1.0 / eta
    return min(max(eta, 1.01), 3.8)


def _rgb(sock):
    return tuple(float(v) for v in sock.default_value[:3])


def principled_sss(node):
    """The node's scattering as PrincipledSSS."""
    base = principled_input(node, "base")
    weight = principled_input(node, "subsurface")
    radius = principled_input(node, "subsurface_radius")
    if PRINCIPLED_V2:
        scale = principled_input(node, "subsurface_scale")
        socks = (weight, scale, radius, base)
        w = 1.0 if weight.is_linked else float(weight.default_value)
        r = tuple(float(v) * scale.default_value for v in
                  radius.default_value)
        return PrincipledSSS(
            min(max(w, 0.0), 1.0), r, _rgb(base), _rgb(base),
            tuple(s.name for s in socks if s.is_linked),
            float(principled_input(node, "subsurface_ior").default_value),
            float(principled_input(node, "subsurface_anisotropy")
                  .default_value),
            walk_ior(float(principled_input(node, "ior").default_value),
                     float(principled_input(node, "specular")
                           .default_value)),
            min(max(float(principled_input(node, "roughness")
                          .default_value), 0.0), 1.0))
    color = principled_input(node, "subsurface_color")
    socks = (weight, radius, color, base)
    f = 1.0 if weight.is_linked else float(weight.default_value)
    b, c = _rgb(base), _rgb(color)
    return PrincipledSSS(
        1.0 if f > 0.0 else 0.0,
        tuple(float(v) * f for v in radius.default_value), c,
        tuple(x + (y - x) * f for x, y in zip(b, c)),
        tuple(s.name for s in socks if s.is_linked))


def set_principled(node, base=None, subsurface=0.0, radius=None,
                   subsurface_color=None, **inputs):
    """Sets a Principled BSDF from 3.x's terms (Base Color, Subsurface
    factor, Subsurface Radius, Subsurface Color), converted for 4.x the way
    Blender converts an old file, so that a scene built by script looks the
    same on every version. Other inputs by key (roughness, specular)."""
    if PRINCIPLED_V2:
        if base is not None and subsurface_color is not None:
            base = tuple(b + (c - b) * subsurface
                         for b, c in zip(base, subsurface_color))
        if base is not None:
            principled_input(node, "base").default_value = base
    else:
        if base is not None:
            principled_input(node, "base").default_value = base
        if subsurface_color is not None:
            principled_input(node, "subsurface_color").default_value = \
                subsurface_color
    set_subsurface_factor(node, subsurface)
    if radius is not None:
        principled_input(node, "subsurface_radius").default_value = radius
    for key, value in inputs.items():
        principled_input(node, key).default_value = value


def radius_factor_input(node):
    """The input that scales the radius: Subsurface in 3.x (also the
    switch), Subsurface Scale from 4.0."""
    return principled_input(node, "subsurface_scale" if PRINCIPLED_V2
                            else "subsurface")


def scale_radius(node, scale):
    """Multiply the Principled BSDF's scattering radius by scale, leaving
    what it mixes alone: Subsurface Scale from 4.0; in 3.x Subsurface Radius,
    since Subsurface there is also the mix between diffuse and subsurface
    (Cycles extrapolates the colours past 1: mix(Base Color, Subsurface
    Color, Subsurface)). Raises ValueError when that input is linked."""
    sock = principled_input(node, "subsurface_scale" if PRINCIPLED_V2
                            else "subsurface_radius")
    if sock.is_linked:
        raise ValueError(f"{sock.name} is driven by a link")
    if PRINCIPLED_V2:
        sock.default_value *= scale
    else:
        sock.default_value = [v * scale for v in sock.default_value]


def set_subsurface_factor(node, factor):
    """3.x's Subsurface factor on any version: from 4.0 Scale = factor and
    Weight = 1 (0 for factor 0), as Blender converts old files."""
    radius_factor_input(node).default_value = factor
    if PRINCIPLED_V2:
        principled_input(node, "subsurface").default_value = \
            1.0 if factor > 0.0 else 0.0


# ------------------------------------------------------------ node trees

def uses_nodes(idblock):
    """Whether a material or world shades with its node tree."""
    if NODES_ALWAYS:
        return idblock.node_tree is not None
    return bool(idblock.use_nodes) and idblock.node_tree is not None


def ensure_nodes(idblock):
    """Gives a material or world its node tree (the default one)."""
    if not NODES_ALWAYS or idblock.node_tree is None:
        idblock.use_nodes = True
    return idblock.node_tree


def new_group_socket(tree, in_out, socket_type, name):
    """Adds a node group input ('INPUT') or output ('OUTPUT')."""
    if hasattr(tree, "interface"):
        return tree.interface.new_socket(name, in_out=in_out,
                                         socket_type=socket_type)
    sockets = tree.inputs if in_out == 'INPUT' else tree.outputs
    return sockets.new(socket_type, name)


def new_mix_rgb(tree):
    """A colour Mix node with inputs Fac, Color1, Color2 and output Color
    (the legacy MixRGB node, which every supported version still runs)."""
    return tree.nodes.new("ShaderNodeMixRGB")


# ---------------------------------------------------------- image output

_IMAGE_SETTINGS = ("media_type", "file_format", "color_depth", "exr_codec")


def image_settings_state(settings):
    """The output format settings, for restore_image_settings()."""
    return tuple((name, getattr(settings, name)) for name in
                 _IMAGE_SETTINGS if hasattr(settings, name))


def restore_image_settings(settings, state):
    for name, value in state:      # media type first: it limits the rest
        setattr(settings, name, value)


def set_multilayer_exr(settings, depth="32", codec="ZIP"):
    """Multilayer OpenEXR, every view layer and pass in one file."""
    if hasattr(settings, "media_type"):
        settings.media_type = "MULTI_LAYER_IMAGE"
    settings.file_format = "OPEN_EXR_MULTILAYER"
    settings.color_depth = depth
    settings.exr_codec = codec


def is_multilayer_exr(settings):
    return settings.file_format == "OPEN_EXR_MULTILAYER"


# ----------------------------------------------------------------- EEVEE

def plain_eevee(scene, samples):
    """EEVEE at `samples` without the screen effects Cycles has no
    counterpart for: bloom (gone in 4.2) and ambient occlusion (gone in
    5.0)."""
    e = scene.eevee
    for name in ("use_bloom", "use_gtao"):
        if hasattr(e, name):
            setattr(e, name, False)
    e.taa_render_samples = samples


def set_aov_output(node, name):
    """Points an AOV Output shader node at the view layer AOV `name`
    (3.4: the node's name; later: its aov_name)."""
    if hasattr(node, "aov_name"):
        node.aov_name = name
    else:
        node.name = name


# ------------------------------------------------------------ compositor

def compositor_tree(scene, create=False):
    """The scene's compositor node tree, or None; with create, one is made
    (in 5.0 the group Blender's own "New" makes: Render Layers into the
    Group Output) and compositing is switched on."""
    if COMPOSITOR_IS_GROUP:
        tree = scene.compositing_node_group
        if tree is None and create:
            tree = bpy.data.node_groups.new("Compositing",
                                            "CompositorNodeTree")
            new_group_socket(tree, 'OUTPUT', "NodeSocketColor", "Image")
            layers = tree.nodes.new("CompositorNodeRLayers")
            layers.location = (-300.0, 0.0)
            out = tree.nodes.new("NodeGroupOutput")
            out.location = (200.0, 0.0)
            tree.links.new(layers.outputs["Image"], out.inputs[0])
            scene.compositing_node_group = tree
        if tree is not None and create:
            scene.render.use_compositing = True
        return tree
    if create:
        scene.use_nodes = True
    return scene.node_tree if scene.use_nodes or create else None


def remove_compositor(scene, tree):
    """Undoes compositor_tree(scene, create=True)."""
    if COMPOSITOR_IS_GROUP:
        scene.compositing_node_group = None
        bpy.data.node_groups.remove(tree)
    else:
        scene.use_nodes = False


def composite_input(tree, create=True, location=(0.0, 0.0)):
    """The socket whose image is the composite: the Composite node's Image
    input (made if missing and create), or in 5.0 the group output's
    first input."""
    kind = "NodeGroupOutput" if COMPOSITOR_IS_GROUP else \
        "CompositorNodeComposite"
    node = next((n for n in tree.nodes if n.bl_idname == kind), None)
    if node is None:
        if not create:
            return None
        node = tree.nodes.new(kind)
        node.location = location
        if COMPOSITOR_IS_GROUP and not tree.interface.items_tree:
            new_group_socket(tree, 'OUTPUT', "NodeSocketColor", "Image")
    return node.inputs[0]


def set_bilateral(node, size, threshold):
    """A Bilateral Blur node's one pass of spatial size (pixels) and colour
    threshold: properties up to 4.x, the Size and Threshold inputs in
    5.0."""
    if COMPOSITOR_IS_GROUP:
        node.inputs["Size"].default_value = int(round(size))
        node.inputs["Threshold"].default_value = threshold
    else:
        node.iterations = 1
        node.sigma_space = size
        node.sigma_color = threshold


def set_file_output(node, directory, file_format="PNG", depth="8"):
    """A File Output node writing file_format images into directory."""
    if VERSION >= (5, 0, 0):
        node.directory = directory
        node.file_name = ""
        node.format.media_type = 'IMAGE'
    else:
        node.base_path = directory
    node.format.file_format = file_format
    node.format.color_depth = depth


def file_output_inputs(node, names):
    """Replaces the node's inputs by one image input per name (each
    written to a file named after it); returns them."""
    if VERSION >= (5, 0, 0):
        node.file_output_items.clear()
        for name in names:
            node.file_output_items.new('RGBA', name)
    else:
        node.file_slots.clear()
        for name in names:
            node.file_slots.new(name)
    return [node.inputs[name] for name in names]


def set_denoise_hdr(node, hdr=True):
    """The Denoise node's HDR switch: a property up to 4.x, an input
    socket in 5.0."""
    if hasattr(node, "use_hdr"):
        node.use_hdr = hdr
    else:
        node.inputs["HDR"].default_value = hdr


def blender_command():
    """The program that runs this Blender again with Blender's command
    line: its binary, or for the bpy module the `blender` command line
    beside its interpreter that started this process (SSS_BLENDER)."""
    return bpy.app.binary_path or os.environ.get("SSS_BLENDER") or None
