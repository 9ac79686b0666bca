"""Back-lit transmission: the extra view layer that gives libsss the light
arriving through thin parts from behind, and the thickness there.

Facts this rests on (Blender 3.4, Cycles): light through a Translucent BSDF
lands in the diffuse passes, not the transmission ones, so it cannot be told
apart from front light inside one view layer. A second view layer whose
material override is a white Translucent BSDF has, in DiffDir + DiffInd,
exactly the light that reaches each visible point through the object from
behind, shadows included. Its override material also writes two AOVs:

- SSSThicknessSq: Ambient Occlusion (Inside, Only Local, Distance D) x D^2,
  D at most a closed mesh's mean chord 4 V / S (_mean_chord), or less on
  a small open one (OPEN_MESH_SHARE).
  Inside, AO is the share of cosine-distributed rays into the object that
  travel further than D; in a slab of thickness t a ray at angle theta
  travels t / cos(theta), so AO = (t / D)^2 and AO x D^2 = t^2. Averaged
  over the samples first, the library takes the square root (a root per
  sample would be biased low for thin parts, where AO is 0 most of the
  time). Parts thicker than D read as D: D is chosen where every model's
  transmittance is already negligible.
- SSSFacing: N . V (Geometry Normal . Incoming), the fast model's view term.

The layer renders at its own sample count (ViewLayer.samples, which Cycles
honours per layer): its light is blurred afterwards, so few samples do.
The add-on asks for it only when it can add something visible (wanted): a
scattering material transmits, a light reaches one of its objects from
behind (or the world is bright), and the light can cross more than half a
pixel of it. It removes the layer, its material and its AOVs afterwards."""
import contextlib
import math

import bpy
import numpy as np
from mathutils import Vector

from . import blender_compat as compat
from . import native
from .description import camera_pixels_per_metre, library_material, slab
from .lighting import (lights_behind, model,  # noqa: F401 (model: API)
                       objects_with, transmitting)

LAYER = "SSSBackLight"             # SSS_BACKLIGHT_LAYER in csrc/sss.h
THICKNESS_AOV = "SSSThicknessSq"   # SSS_THICKNESS_SQ_PASS
FACING_AOV = "SSSFacing"           # SSS_FACING_PASS
MATERIAL = "SSS Back Light Override"
TAG = "SSS back light"

# Render cost of the layer, measured on the head scene (make compare's
# first scene, 160x120, CPU): see docs/transmission.md.
COST_NOTE = ("measured on the head scene: the layer at a quarter of the "
             "samples adds 1 to 2 times the render time (every surface is "
             "a white translucent there, so its paths bounce long)")

# Surfaces more than this many bounces from the camera absorb in the
# back-light layer: camera -> visible point -> where the ray leaves the
# object (which gathers the light behind it) is depth 1. Deeper paths
# (light that left and re-entered, bounced off the surroundings) cost time
# and, on the head scene, made the back-lit error larger (0.136 vs 0.129
# RMSE at depth 1; docs/transmission.md).
LAYER_MAX_DEPTH = 1
# What the exit point sees (depth LAYER_MAX_DEPTH + 1: the skull behind a
# back-lit ear, a floor under a hand) reflects the light that reaches it,
# diffusely with its own albedo (PROP_ALBEDO), and absorbs what reaches it
# after that: the walk lets that light into the part's back too. The
# override is translucent everywhere else, so without this the light
# reaching a part's back after one bounce was lost: on the bundled head the
# glowing ears came out 0.83 of the walk in every channel, two thirds of
# its squared error (docs/transmission.md, "The surroundings' light").
# Ambient-occlusion rays per shading point for the thickness AOV (16 made
# the layer cost twice as much as 4 on the head scene, for the same
# averaged t^2).
AO_SAMPLES = 4
# Inside an object smaller than the AO distance D every ray ends within D,
# so the thickness reads 0 however thick the object is: marble beads at 3x
# their radius read 0 on 80 % of their pixels and, as thin parts, came out
# 0.65 of the walk (docs/transmission.md, "Thin parts lit from the
# front"). So a closed mesh's D is at most its mean chord 4 V / S (the
# mean length of the lines through a convex body, Cauchy): a slab of
# thickness t has 2 t and reads t; a sphere of radius R has 4 R / 3 and
# reads R (the AO reads 2 k R sqrt(1 - k^2) at D = 2 k R); a torus' tube of
# radius r has 2 r. An open mesh encloses no volume to measure (Suzanne's
# head, open at the eyes); its D is at most OPEN_MESH_SHARE of its smallest
# extent s, the D at which a ball of diameter s reads its radius (k =
# 1 / sqrt(2) above): on the bundled head at 3x and 10x its radius
# (make sweep) 0.169 / 0.159 of the error without SSS with D, 0.127 /
# 0.137 with this. A flat one (s = 0) keeps D.
OPEN_MESH_SHARE = 0.7
# The share of a mesh's edges that may border one face only for it to count
# as closed (Suzanne's 168 of 15828, 1 %, make it open).
CLOSED_HOLES = 0.001

# The layer is skipped when the light could cross at most this many pixels
# of any transmitting part, however near it is: its glow would stay within
# half a pixel of the silhouettes.
MIN_REACH_PX = 0.5

# A ray from a visible point that leaves the object this close to the
# surface's tangent (|N . I| below it) through a face the camera sees
# carries nothing. On a surface of curvature radius R its chord is
# 2 R |N . I| long, so its exit lies within 0.3 R of the visible point,
# on the visible surface, and the slab reads a thickness of
# 2 R |N . I|^2 where the light travels the whole chord: it let through
# light that the walk does not carry (at |N . I| -> 0 at any radius) and
# that the blur already spreads near the point. Measured on the bundled
# back-lit scenes (make error-budget, Blender 4.5, ours + OIDN): 0.05 ->
# 0.15 takes the head from 0.1886 to 0.1853, marble from 0.0536 to
# 0.0508 and mixed from 0.0234 to 0.0226; 0.1 and 0.2 gain less on
# mixed, 0.3 makes it worse (0.0245), and dropping every exit through a
# seen face loses the light the walk carries from one visible part of the
# bangle to another (0.0268). docs/transmission.md.
GRAZING_COS = 0.15


def _distance_to_box(obj, point):
    """Scene units from point to obj's bounding box (0 inside it)."""
    corners = [obj.matrix_world @ Vector(c) for c in obj.bound_box]
    d2 = 0.0
    for i in range(3):
        lo = min(c[i] for c in corners)
        hi = max(c[i] for c in corners)
        gap = max(lo - point[i], 0.0, point[i] - hi)
        d2 += gap * gap
    return math.sqrt(d2)


def wanted(scene, analysis):
    """(bool, why): whether the render needs the back-light layer: some
    transmitting part is lit from behind and its light can cross enough of
    it to show (the library's reach, projected to pixels where the part is
    nearest the camera). Thickness alone cannot rule it out: near
    silhouettes and edges the light crosses short chords of any part
    (measured on make compare's mixed scene, docs/transmission.md)."""
    mode = scene.sss.transmission_layer
    mats = transmitting(analysis)
    if not mats:
        return False, "no scattering material has transmission on"
    if mode == "NEVER":
        return False, "the back-light layer is turned off"
    if mode == "ALWAYS":
        return True, "always on"
    if scene.camera is None:
        return False, "the scene has no camera"
    eye = scene.camera.matrix_world.translation
    reaching, widest = [], 0.0
    for found in mats:
        reach = _len_metres(found, scene)
        if not reach > 0.0:
            continue            # lets nothing through (radius scale 0)
        for obj in objects_with(scene, found.material):
            distance = _distance_to_box(obj, eye)
            px = math.inf if distance <= 0.0 else \
                reach * camera_pixels_per_metre(scene, distance)
            widest = max(widest, px)
            if px >= MIN_REACH_PX:
                reaching.append(obj)
    if not reaching:
        return False, (f"the light crosses at most {widest:.2g} px of a "
                       "transmitting part")
    behind = lights_behind(scene, reaching)
    if not behind:
        return False, "no light reaches a transmitting material from behind"
    return True, "lit from behind by " + ", ".join(behind)


def _len_metres(found, scene):
    """How thick a part can be before its transmittance is negligible
    (< 1 %), in metres: the AO distance must reach that far."""
    return native.transmission_reach(library_material(scene, found)) * \
        scene.sss.radius_scale


def ao_distance(scene, analysis):
    """D, in scene units: the thickest part any transmitting material
    still lets light through."""
    metres = max([_len_metres(f, scene) for f in transmitting(analysis)] +
                 [1e-6])
    unit = scene.unit_settings.scale_length or 1.0
    return metres / unit


def layer_samples(scene):
    s = scene.sss.transmission_samples
    return s if s > 0 else max(4, scene.cycles.samples // 4)


# Object custom properties the override material reads (Attribute node,
# type Object); set on the objects for the render and removed after.
PROP_MODE = "sss_tr_mode"      # 0 absorbs, 1 white translucent, 2 slab
PROP_ROW = "sss_tr_row"        # slab: which table (SLAB_IMAGE's order)
PROP_STEP = "sss_tr_step"      # slab: the table's step, scene units
PROP_SCALE = "sss_tr_scale"    # slab: (n - 1) / ln(1 + span / step)
PROP_ALBEDO = "sss_tr_albedo"  # diffuse albedo (RGB) where it reflects
PROP_AO = "sss_tr_ao"          # the thickness's AO distance, scene units
SLAB_PROPS = (PROP_ROW, PROP_STEP, PROP_SCALE)
PROPS = (PROP_MODE,) + SLAB_PROPS + (PROP_ALBEDO, PROP_AO)

# The library's slab table (sss_transmission_table) per slab material: an
# image TABLE_SIZE x 1 (RGB: T(t) / T(0) per channel), read with linear
# interpolation and its last sample (0) held beyond it. 4096 samples
# (64 KB) follow the library within 3.4e-4, at the kink where the slab
# starts to thin (1024: 1.3e-3; tests/test_transmission.c).
TABLE_SIZE = 4096
SLAB_IMAGE = "SSS Slab Transmittance"


def _math(tree, op, a, b=None, clamp=False):
    node = tree.nodes.new("ShaderNodeMath")
    node.operation = op
    node.use_clamp = clamp
    for i, v in enumerate((a, b)):
        if v is None:
            continue
        if isinstance(v, (int, float)):
            node.inputs[i].default_value = float(v)
        else:
            tree.links.new(v, node.inputs[i])
    return node.outputs[0]


def _slab_table(tree, t, row, step, scale, images):
    """Per channel T(t) / T(0) of the object's slab, looked up in the
    library's table: index ln(1 + t / step) x scale, the table's pixel
    centres at (index + 0.5) / TABLE_SIZE; row picks the object's image.
    Returns a colour socket."""
    index = _math(tree, "MULTIPLY", _math(
        tree, "LOGARITHM", _math(tree, "ADD", _math(tree, "DIVIDE", t, step),
                                 1.0), math.e), scale)
    uv = tree.nodes.new("ShaderNodeCombineXYZ")
    tree.links.new(_math(tree, "DIVIDE", _math(tree, "ADD", index, 0.5),
                         float(TABLE_SIZE)), uv.inputs[0])
    uv.inputs[1].default_value = 0.5
    out = None
    for i, image in enumerate(images):
        tex = tree.nodes.new("ShaderNodeTexImage")
        tex.image = image
        tex.interpolation = "Linear"
        tex.extension = "EXTEND"
        tree.links.new(uv.outputs[0], tex.inputs["Vector"])
        if out is None:
            out = tex.outputs["Color"]
            continue
        mix = compat.new_mix_rgb(tree)
        tree.links.new(out, mix.inputs["Color1"])
        tree.links.new(tex.outputs["Color"], mix.inputs["Color2"])
        this = _math(tree, "LESS_THAN", _math(tree, "ABSOLUTE", _math(
            tree, "SUBTRACT", row, float(i))), 0.5)
        tree.links.new(this, mix.inputs["Fac"])
        out = mix.outputs["Color"]
    return out


def slab_image(values, undo):
    """The image holding one slab table (TABLE_SIZE x 3 floats), as data
    (Non-Color), removed by undo."""
    image = bpy.data.images.new(SLAB_IMAGE, TABLE_SIZE, 1, alpha=False,
                                float_buffer=True, is_data=True)
    undo.add(lambda: bpy.data.images.remove(image))
    pixels = [1.0] * (4 * TABLE_SIZE)
    for i in range(TABLE_SIZE):
        pixels[4 * i:4 * i + 3] = values[3 * i:3 * i + 3]
    image.pixels[:] = pixels
    return image


def _camera_view(scene):
    """(k, c): the direction from the camera to a point p is k p + c, in
    scene units: (1, -eye) for a perspective or panoramic camera, (0, the
    viewing direction) for an orthographic one."""
    cam = scene.camera
    if cam is None:
        return None
    if cam.data.type == "ORTHO":
        forward = cam.matrix_world.to_3x3() @ Vector((0.0, 0.0, -1.0))
        return 0.0, tuple(forward.normalized())
    return 1.0, tuple(-cam.matrix_world.translation)


def _override_material(undo, need_ao=True, view=None, images=()):
    """White translucent everywhere a transmitting object is entered; where
    a ray inside an object with the slab model (PROP_MODE 2) reaches its
    surface again, the light that crosses is multiplied per channel by
    T(t) / T(0) with t = ray length x |N . I| (the slab's thickness along
    the normal there: exact for a slab, and averaged over the real chords
    of a curved part by the samples themselves), looked up in the
    library's table for the object's material (images, PROP_ROW's order;
    slab_image). The library then reads a
    thickness of 0 there and multiplies by T(0). Objects with no
    transmitting material absorb (PROP_MODE 0): they cast shadows and end
    the path instead of passing light on, and surfaces more than
    LAYER_MAX_DEPTH bounces from the camera absorb too, but for what the
    exit point sees, which reflects once with its albedo (PROP_ALBEDO;
    LAYER_MAX_DEPTH's note). A ray that leaves
    through a face the camera sees (view: _camera_view's (k, c)) at a
    grazing angle (GRAZING_COS) carries nothing: it crossed a sliver next
    to the visible point, whose light the blur already spreads, and the
    slab would let it through at any radius. need_ao: some transmitting
    material is not a slab, or reflects less where it is thin
    (thin_reflectance), and needs the thickness AOV (without, the AOV is 0
    and the layer costs less)."""
    mat = bpy.data.materials.new(MATERIAL)
    undo.add(lambda: bpy.data.materials.remove(mat))
    tree = compat.ensure_nodes(mat)
    for node in list(tree.nodes):
        tree.nodes.remove(node)
    out = tree.nodes.new("ShaderNodeOutputMaterial")
    out.target = "CYCLES"
    bsdf = tree.nodes.new("ShaderNodeBsdfTranslucent")
    tree.links.new(bsdf.outputs[0], out.inputs["Surface"])

    def attr(name):
        node = tree.nodes.new("ShaderNodeAttribute")
        node.attribute_type = "OBJECT"
        node.attribute_name = name
        return node

    mode = attr(PROP_MODE).outputs["Fac"]
    geo = tree.nodes.new("ShaderNodeNewGeometry")
    path = tree.nodes.new("ShaderNodeLightPath")
    dot = tree.nodes.new("ShaderNodeVectorMath")
    dot.operation = "DOT_PRODUCT"
    tree.links.new(geo.outputs["Normal"], dot.inputs[0])
    tree.links.new(geo.outputs["Incoming"], dot.inputs[1])
    cos = _math(tree, "ABSOLUTE", dot.outputs["Value"])
    if view is not None:
        # Leaving through a face the camera sees: at the exit the normal
        # faces the ray (into the object), so the face is seen when
        # N . (p - eye) > 0.
        k, c = view
        to_point = tree.nodes.new("ShaderNodeVectorMath")
        to_point.operation = "MULTIPLY_ADD"
        tree.links.new(geo.outputs["Position"], to_point.inputs[0])
        to_point.inputs[1].default_value = (k, k, k)
        to_point.inputs[2].default_value = c
        seen = tree.nodes.new("ShaderNodeVectorMath")
        seen.operation = "DOT_PRODUCT"
        tree.links.new(geo.outputs["Normal"], seen.inputs[0])
        tree.links.new(to_point.outputs[0], seen.inputs[1])
        front_exit = _math(tree, "MULTIPLY", geo.outputs["Backfacing"],
                           _math(tree, "GREATER_THAN", seen.outputs["Value"],
                                 0.0))
        grazing = _math(tree, "MULTIPLY", front_exit,
                        _math(tree, "LESS_THAN", cos, GRAZING_COS))
    t = _math(tree, "MULTIPLY", path.outputs["Ray Length"], cos)
    # slab = (mode > 1.5) x backfacing: leaving the object's medium
    slab = _math(tree, "MULTIPLY", _math(tree, "GREATER_THAN", mode, 1.5),
                 geo.outputs["Backfacing"])
    pick = compat.new_mix_rgb(tree)
    pick.inputs["Color1"].default_value = (1.0, 1.0, 1.0, 1.0)
    tree.links.new(slab, pick.inputs["Fac"])
    if images:
        tree.links.new(_slab_table(
            tree, t, *(attr(p).outputs["Fac"] for p in SLAB_PROPS), images),
            pick.inputs["Color2"])
    if view is not None:
        hide = compat.new_mix_rgb(tree)
        hide.inputs["Color2"].default_value = (0.0, 0.0, 0.0, 1.0)
        tree.links.new(grazing, hide.inputs["Fac"])
        tree.links.new(pick.outputs["Color"], hide.inputs["Color1"])
        pick = hide
    lit = compat.new_mix_rgb(tree)
    lit.inputs["Color1"].default_value = (0.0, 0.0, 0.0, 1.0)
    on = _math(tree, "GREATER_THAN", mode, 0.5)
    if LAYER_MAX_DEPTH >= 0:
        shallow = _math(tree, "LESS_THAN", path.outputs["Ray Depth"],
                        LAYER_MAX_DEPTH + 0.5)
        on = _math(tree, "MULTIPLY", on, shallow)
    tree.links.new(on, lit.inputs["Fac"])
    tree.links.new(pick.outputs["Color"], lit.inputs["Color2"])
    tree.links.new(lit.outputs["Color"], bsdf.inputs["Color"])
    # What the exit point sees reflects, with its albedo, once.
    reflect = tree.nodes.new("ShaderNodeBsdfDiffuse")
    albedo = attr(PROP_ALBEDO)
    seen = _math(tree, "LESS_THAN", path.outputs["Ray Depth"],
                 LAYER_MAX_DEPTH + 1.5)
    once = compat.new_mix_rgb(tree)
    once.inputs["Color1"].default_value = (0.0, 0.0, 0.0, 1.0)
    tree.links.new(seen, once.inputs["Fac"])
    tree.links.new(albedo.outputs["Color"], once.inputs["Color2"])
    tree.links.new(once.outputs["Color"], reflect.inputs["Color"])
    mix = tree.nodes.new("ShaderNodeMixShader")
    tree.links.new(_math(tree, "GREATER_THAN", path.outputs["Ray Depth"],
                         LAYER_MAX_DEPTH + 0.5), mix.inputs["Fac"])
    tree.links.new(bsdf.outputs[0], mix.inputs[1])
    tree.links.new(reflect.outputs[0], mix.inputs[2])
    tree.links.new(mix.outputs[0], out.inputs["Surface"])

    aov = tree.nodes.new("ShaderNodeOutputAOV")
    compat.set_aov_output(aov, THICKNESS_AOV)
    aov.inputs["Value"].default_value = 0.0
    if need_ao:
        # The AO node runs at every shading point of every path, so its
        # rays are most of the layer's cost; the AOV averages over the
        # pixel's samples anyway (t^2 stays unbiased with few rays).
        ao = tree.nodes.new("ShaderNodeAmbientOcclusion")
        ao.inside = True
        ao.only_local = True
        ao.samples = AO_SAMPLES
        reach = attr(PROP_AO).outputs["Fac"]   # _tag_objects: at most D
        tree.links.new(reach, ao.inputs["Distance"])
        sq = _math(tree, "MULTIPLY", ao.outputs["AO"],
                   _math(tree, "MULTIPLY", reach, reach))
        # The slab objects' attenuation is in the light already (the
        # library takes T(0) for a baked slab); their thickness is for the
        # thin parts' reflectance.
        tree.links.new(sq, aov.inputs["Value"])
    facing = tree.nodes.new("ShaderNodeOutputAOV")
    compat.set_aov_output(facing, FACING_AOV)
    tree.links.new(dot.outputs["Value"], facing.inputs["Value"])
    for node in tree.nodes:
        node.label = TAG
    return mat


def _slab_params(scene, found):
    """(step, scale, table) for a material whose transmission is the
    library's diffusion slab (the burley model on a Burley profile): its
    table (sss_transmission_table, TABLE_SIZE samples, its thickness scale
    applied), the table's step in scene units and the index scale (n - 1)
    / ln(1 + span / step); None otherwise (or when it lets nothing through
    or everything: thickness scale 0)."""
    if slab(scene, found) is None:
        return None             # not the slab, or a channel has no medium
    step, span, table = native.transmission_table(
        library_material(scene, found), TABLE_SIZE)
    unit = scene.unit_settings.scale_length or 1.0
    length = scene.sss.radius_scale / unit
    return (step * length, (TABLE_SIZE - 1) / math.log1p(span / step),
            table)


def _slab_tables(scene, analysis, undo):
    """{material: (row, step, scale)} of the transmitting materials with
    the slab model, and their tables' images in row order."""
    rows, images = {}, []
    for f in transmitting(analysis):
        params = _slab_params(scene, f)
        if params is None or f.material in rows:
            continue
        step, scale, table = params
        rows[f.material] = (len(images), step, scale)
        images.append(slab_image(table, undo))
    return rows, images


def _albedo(material, albedos):
    """A material's diffuse albedo where the back-light layer lets it
    reflect: a scattering material's (albedos, the analysis'), else the
    unlinked Base Color of its Principled BSDF or Color of its Diffuse
    BSDF; None (it absorbs) when a texture sets it or there is none."""
    if material is None:
        return None
    if material in albedos:
        return tuple(albedos[material][:3])
    if not compat.uses_nodes(material):
        return None
    for node in material.node_tree.nodes:
        if node.type in ("BSDF_PRINCIPLED", "BSDF_DIFFUSE"):
            sock = compat.principled_input(node, "base") \
                if node.type == "BSDF_PRINCIPLED" else node.inputs.get("Color")
            if sock is None or sock.is_linked:
                return None
            return tuple(sock.default_value[:3])
    return None


@contextlib.contextmanager
def evaluated_mesh(obj, depsgraph):
    """The object's evaluated mesh (None where it has none, or no faces),
    freed on leaving."""
    evaluated = obj.evaluated_get(depsgraph)
    try:
        mesh = evaluated.to_mesh()
    except RuntimeError:
        yield None
        return
    try:
        yield mesh if mesh is not None and mesh.polygons else None
    finally:
        evaluated.to_mesh_clear()


def edge_faces(mesh):
    """How many faces each edge of the mesh borders (numpy, per edge)."""
    edges = np.empty(len(mesh.loops), np.int64)
    mesh.loops.foreach_get("edge_index", edges)
    return np.bincount(edges, minlength=len(mesh.edges))


def _mean_chord(obj, depsgraph):
    """4 V / S of the object's evaluated mesh in world space, or None
    where it is not closed (an edge of more than two faces, or more than
    CLOSED_HOLES of its edges on one face only: a dense UV sphere's poles
    leave a few) or encloses nothing."""
    with evaluated_mesh(obj, depsgraph) as mesh:
        if mesh is None or not mesh.edges:
            return None
        faces = edge_faces(mesh)
        if np.any(faces > 2) or np.count_nonzero(faces < 2) > \
                CLOSED_HOLES * len(mesh.edges):
            return None
        if hasattr(mesh, "calc_loop_triangles"):
            mesh.calc_loop_triangles()
        tri = np.empty(len(mesh.loop_triangles) * 3, np.int64)
        mesh.loop_triangles.foreach_get("vertices", tri)
        co = np.empty(len(mesh.vertices) * 3, np.float64)
        mesh.vertices.foreach_get("co", co)
    world = np.array(obj.matrix_world, np.float64)
    co = co.reshape(-1, 3) @ world[:3, :3].T + world[:3, 3]
    a, b, c = (co[tri.reshape(-1, 3)[:, k]] for k in range(3))
    cross = np.cross(b - a, c - a)
    area = 0.5 * float(np.linalg.norm(cross, axis=1).sum())
    volume = abs(float(np.einsum("ij,ij->", a, cross))) / 6.0
    if not (area > 0.0 and volume > 0.0):
        return None
    return 4.0 * volume / area


def _tag_objects(scene, analysis, rows, undo, distance=None):
    """Sets PROP_* on every object the layer renders: 2 for objects with a
    slab-model material (rows: _slab_tables), with its table's row, step
    and scale, 1 for other transmitting ones, 0 for the rest; the albedo
    with which it reflects where the exit point sees it (_albedo; without
    it it absorbs there too); and, given distance (D, ao_distance: the
    layer measures the thickness), on transmitting ones the thickness's AO
    distance: D, or less on a small object (_mean_chord, OPEN_MESH_SHARE)."""
    transmits = {f.material for f in transmitting(analysis)}
    albedos = {f.material: f.albedo or f.color for f in analysis.materials}
    depsgraph = None if distance is None else \
        bpy.context.evaluated_depsgraph_get()
    for obj in scene.objects:
        if not hasattr(obj, "material_slots") or obj.type not in (
                "MESH", "CURVE", "SURFACE", "META", "FONT", "CURVES",
                "POINTCLOUD", "VOLUME"):
            continue
        mode, values = 0, None
        for slot in obj.material_slots:
            if slot.material in rows:
                mode, values = 2, rows[slot.material]
                break
            if slot.material in transmits:
                mode = 1
        albedo = next((a for a in (_albedo(slot.material, albedos)
                                   for slot in obj.material_slots)
                       if a is not None), None)
        # copied: an array property's value is a view that dies with it
        had = {k: getattr(obj[k], "to_list", lambda k=k: obj[k])()
               for k in PROPS if k in obj}

        def restore(obj=obj, had=had):
            for k in PROPS:
                if k in obj:
                    del obj[k]
            for k, v in had.items():
                obj[k] = v
        undo.add(restore)
        try:
            obj[PROP_MODE] = float(mode)
            if values is not None:
                for k, v in zip(SLAB_PROPS, values):
                    obj[k] = float(v)
            if albedo is not None:
                obj[PROP_ALBEDO] = [float(a) for a in albedo]
            if mode and distance is not None:
                chord = _mean_chord(obj, depsgraph)
                if chord is None:
                    chord = OPEN_MESH_SHARE * min(obj.dimensions) or distance
                obj[PROP_AO] = float(min(distance, chord))
        except (TypeError, AttributeError, RuntimeError):
            # A linked, non-editable object: it reads mode 0 (absorbs) in
            # the layer, so it casts shadows but lets no light through.
            pass


def _copy_collections(src, dst):
    """The new layer sees what the active one sees."""
    dst.exclude = src.exclude
    dst.holdout = src.holdout
    dst.indirect_only = src.indirect_only
    for a, b in zip(src.children, dst.children):
        _copy_collections(a, b)


def add_layer(scene, analysis, undo, source_layer=None):
    """Adds the back-light view layer (undone by undo); returns it, or None
    when the render does not need it."""
    need, _why = wanted(scene, analysis)
    if not need:
        return None
    if scene.render.engine != "CYCLES":
        return None
    if LAYER in scene.view_layers:
        raise RuntimeError(f"the scene already has a view layer named "
                           f"{LAYER}; rename it (the add-on uses that name "
                           "for back-lit transmission)")
    source = source_layer or bpy.context.view_layer
    distance = ao_distance(scene, analysis)
    rows, images = _slab_tables(scene, analysis, undo)
    need_ao = any(f.material not in rows or
                  library_material(scene, f).get("thin_reflectance", 0.0) > 0
                  for f in transmitting(analysis))
    mat = _override_material(undo, need_ao, _camera_view(scene),
                             images)
    layer = scene.view_layers.new(LAYER)
    undo.add(lambda: scene.view_layers.remove(layer))
    if source is not None and source.name in scene.view_layers:
        _copy_collections(source.layer_collection, layer.layer_collection)
    _tag_objects(scene, analysis, rows, undo, distance if need_ao else None)
    layer.material_override = mat
    undo.add(lambda: setattr(layer, "material_override", None))
    layer.samples = layer_samples(scene)
    layer.use_pass_diffuse_direct = True
    layer.use_pass_diffuse_indirect = True
    for name in (THICKNESS_AOV, FACING_AOV):
        aov = layer.aovs.add()
        aov.name = name
        aov.type = "VALUE"
    # Other view layers are left as they are: one render gives both.
    return layer
