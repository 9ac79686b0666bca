"""Back-lit transmission through the add-on, on a real Cycles render of a
thin slab lit only from behind (build_scene.py --kind slab), headless."""
import json
import os
import subprocess

import bpy
import numpy as np
import pytest

from helpers import BUILD, build_blend, diff, load_addon, snapshot

separable_sss = load_addon()
from separable_sss import blender_compat as compat  # noqa: E402
from separable_sss import description  # noqa: E402
from separable_sss import native, pipeline, transmission  # noqa: E402

import faults  # noqa: E402

from exr import read_channels  # noqa: E402


@pytest.fixture(scope="module", autouse=True)
def addon():
    separable_sss.register()
    yield
    separable_sss.unregister()


@pytest.fixture(scope="module")
def slab(tmp_path_factory):
    d = tmp_path_factory.mktemp("blends")
    return build_blend("slab", str(d / "slab.blend"), size=40, samples=16)


def open_scene(path, out_dir):
    bpy.ops.wm.open_mainfile(filepath=path)
    scene = bpy.context.scene
    scene.sss.output_dir = str(out_dir)
    scene.cycles.sample_clamp_indirect = 10.0
    bpy.data.materials["Skin"].sss.transmission = "BURLEY"  # off by default
    return scene


def state(scene):
    """What the back-light layer touches, beyond helpers.snapshot."""
    return {"layers": [(l.name, l.material_override and
                        l.material_override.name, l.samples,
                        [(a.name, a.type) for a in l.aovs])
                       for l in scene.view_layers],
            "materials": sorted(m.name for m in bpy.data.materials),
            "snapshot": snapshot(scene)}


def rgb(ch, prefix):
    return np.stack([ch[f"{prefix}.{c}"] for c in "RGB"], axis=-1)


def front(scene, tmp_path, model):
    """Mean SSS.Combined over the slab, and the pass file's layers."""
    bpy.data.materials["Skin"].sss.transmission = model
    job = pipeline.prepare_render(bpy.context)
    pipeline.scatter(job)
    out = read_channels(job.output_exr)[0]
    inp = read_channels(job.input_exr)[0]
    # The slab is the only material (its index 0 gets a free one for the
    # render and is restored after).
    mask = np.rint(inp["ViewLayer.IndexMA.X"]) > 0
    layers = {k.split(".")[0] for k in inp}
    return rgb(out, "SSS.Combined")[mask].mean(axis=0), mask, layers


def test_backlit_slab_brighter_and_closer_to_random_walk(slab, tmp_path):
    scene = open_scene(slab, tmp_path)
    need, why = transmission.wanted(scene, pipeline.analyse(scene))
    assert need, why
    off, mask, layers_off = front(scene, tmp_path, "OFF")
    on, _, layers_on = front(scene, tmp_path, "BURLEY")
    assert transmission.LAYER not in layers_off  # asked for only when on
    assert transmission.LAYER in layers_on
    # Cycles' random walk: the material's own SSS, more samples.
    scene.cycles.samples = 64
    scene.render.use_compositing = False
    assert bpy.ops.render.render() == {"FINISHED"}
    path = str(tmp_path / "rw.exr")
    pipeline.save_passes(scene, path)
    ref = rgb(read_channels(path)[0], "ViewLayer.Combined")[mask].mean(axis=0)
    lum = np.array([0.2126, 0.7152, 0.0722])
    print("front luminance: off", off @ lum, "on", on @ lum,
          "random walk", ref @ lum)
    assert on @ lum > 2.0 * (off @ lum) + 1e-3
    assert abs(on @ lum - ref @ lum) < abs(off @ lum - ref @ lum)
    # The diffusion slab lets out about what the random walk does (3-8 %
    # apart at 64x64 and 256 spp; this render is 40x40 at 16 spp).
    assert abs(on @ lum - ref @ lum) < 0.4 * (ref @ lum)


def test_thickness_and_facing_reach_the_pass_file(slab, tmp_path):
    """The back-light layer's AOVs reach the pass file on every Blender:
    the thickness every model but the baked slab reads, and the facing the
    fast model's view term reads. An AOV Output node names its AOV by its
    node name in 3.4 and by aov_name from 4.0 on (compat.set_aov_output):
    named the 3.4 way, 4.5 and 5.0 wrote both as 0 everywhere."""
    scene = open_scene(slab, tmp_path)
    mat = bpy.data.materials["Skin"]
    mat.sss.transmission = "FAST"
    mat.sss.transmission_distance = 0.05  # farther than the 1.5 cm slab
    job = pipeline.prepare_render(bpy.context)
    inp = read_channels(job.input_exr)[0]
    mask = np.rint(inp["ViewLayer.IndexMA.X"]) > 0
    layer = transmission.LAYER
    sq = inp[f"{layer}.{transmission.THICKNESS_AOV}.X"][mask]
    facing = inp[f"{layer}.{transmission.FACING_AOV}.X"][mask]
    thick = float(np.median(np.sqrt(np.maximum(sq, 0.0))))
    print("slab: median thickness", thick, "facing", np.median(facing))
    assert abs(thick - 0.015) < 0.005
    assert np.median(facing) > 0.9


def test_thin_parts_read_the_thickness(slab, tmp_path):
    """Where the library measured the walk's thin parts lit from the front
    (the slab's Random Walk (Skin) on 4.x: native.thin_measured), Match Energy
    asks for their loss (thin_reflectance 1) and the back-light layer
    writes the thickness for the baked slab too; elsewhere (3.4) neither,
    and the slab's AOV stays 0 (its layer costs less without)."""
    scene = open_scene(slab, tmp_path)
    job = pipeline.prepare_render(bpy.context)
    with open(job.scene_json) as f:
        entry = json.load(f)["materials"][0]
    inp = read_channels(job.input_exr)[0]
    mask = np.rint(inp["ViewLayer.IndexMA.X"]) > 0
    sq = inp[f"{transmission.LAYER}.{transmission.THICKNESS_AOV}.X"][mask]
    thick = float(np.median(np.sqrt(np.maximum(sq, 0.0))))
    print("slab:", entry.get("calibration"), "thin_reflectance",
          entry.get("thin_reflectance"), "median thickness", thick)
    assert entry["transmission_baked_scale"] > 0
    assert native.thin_measured(entry) == (bpy.app.version >= (4, 0, 0))
    if bpy.app.version >= (4, 0, 0):
        assert entry["calibration"] == "cycles4-random-walk-skin"
        assert entry["thin_reflectance"] == 1.0
        assert abs(thick - 0.015) < 0.005
    else:
        assert "thin_reflectance" not in entry
        assert thick == 0.0


def test_mean_chord(slab, tmp_path):
    """The AO distance's cap: 4 V / S of a closed mesh in world space (a
    sphere's 4 R / 3, scaled with its object), none for an open one."""
    open_scene(slab, tmp_path)
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.1, segments=64,
                                         ring_count=32)
    sphere = bpy.context.active_object
    sphere.scale = (2.0, 2.0, 2.0)
    bpy.context.view_layer.update()
    graph = bpy.context.evaluated_depsgraph_get()
    chord = transmission._mean_chord(sphere, graph)
    print("sphere of radius 0.2: mean chord", chord)
    assert chord == pytest.approx(4.0 * 0.2 / 3.0, rel=0.01)
    bpy.ops.mesh.primitive_plane_add(size=1.0)
    assert transmission._mean_chord(bpy.context.active_object, graph) is None


def test_restored_after_success(slab, tmp_path):
    scene = open_scene(slab, tmp_path)
    before = state(scene)
    job = pipeline.prepare_render(bpy.context)
    assert transmission.LAYER in {k.split(".")[0]
                                  for k in read_channels(job.input_exr)[0]}
    after = state(scene)
    assert after["layers"] == before["layers"]
    assert after["materials"] == before["materials"]
    assert diff(before["snapshot"], after["snapshot"]) == []


@pytest.mark.parametrize("where", ["render", "cancel"])
def test_restored_after_error(slab, tmp_path, monkeypatch, where):
    scene = open_scene(slab, tmp_path)
    before = state(scene)
    if where == "cancel":
        monkeypatch.setenv("SSS_TEST_FAIL", "cancel")
    else:
        faults.fail_after_render(monkeypatch, pipeline)
    with pytest.raises(pipeline.SSSError):
        pipeline.prepare_render(bpy.context)
    after = state(scene)
    assert after["layers"] == before["layers"]
    assert after["materials"] == before["materials"]
    assert diff(before["snapshot"], after["snapshot"]) == []


def test_no_layer_without_light_from_behind(slab, tmp_path):
    scene = open_scene(slab, tmp_path)
    back = scene.objects["Back"]
    back.location = (0.0, -0.6, 0.3)   # in front of the slab now
    bpy.context.view_layer.update()     # matrix_world follows
    need, why = transmission.wanted(scene, pipeline.analyse(scene))
    assert not need and "behind" in why
    scene.sss.transmission_layer = "ALWAYS"
    assert transmission.wanted(scene, pipeline.analyse(scene))[0]
    scene.sss.transmission_layer = "NEVER"
    assert not transmission.wanted(scene, pipeline.analyse(scene))[0]


def test_no_layer_where_the_light_crosses_under_half_a_pixel(slab, tmp_path):
    """Lit from behind, but at a radius scale where the light crosses less
    than half a pixel of the slab: no layer, and the report says why;
    back at scale 1 the layer returns."""
    scene = open_scene(slab, tmp_path)
    scene.sss.radius_scale = 1e-6
    need, why = transmission.wanted(scene, pipeline.analyse(scene))
    assert not need and "px of a transmitting part" in why, why
    job = pipeline.prepare_render(bpy.context)
    assert transmission.LAYER not in {k.split(".")[0] for k in
                                      read_channels(job.input_exr)[0]}
    assert "back-light layer off, the light crosses at most" in job.summary
    scene.sss.radius_scale = 1.0
    need, why = transmission.wanted(scene, pipeline.analyse(scene))
    assert need, why


def test_radius_scale_of_a_baked_back_light_is_refused(slab, tmp_path):
    """The slab's attenuation is baked into the back light at the scene's
    radius scale: `sss --radius-scale` cannot change it and says so
    (before, 1e-9 gave the same glow as 1); 0 is the plain composite."""
    scene = open_scene(slab, tmp_path)
    scene.sss.radius_scale = 2.0
    job = pipeline.prepare_render(bpy.context)
    with open(job.scene_json) as f:
        entry = json.load(f)["materials"][0]
    assert entry["transmission_baked_scale"] == pytest.approx(2.0)
    sss = os.path.join(BUILD, "sss")

    def run(scale):
        return subprocess.run([sss, job.input_exr, "-o",
                               str(tmp_path / f"out_{scale}.exr"), "--scene",
                               job.scene_json, "--radius-scale", scale],
                              capture_output=True, text=True)
    for scale in ("1e-9", "0.5"):
        proc = run(scale)
        assert proc.returncode != 0 and "transmission_baked_scale" in \
            proc.stderr and "render it again" in proc.stderr, proc.stderr
        assert not (tmp_path / f"out_{scale}.exr").exists()
    assert run("1").returncode == 0
    proc = run("0")
    assert proc.returncode == 0, proc.stderr
    out = read_channels(str(tmp_path / "out_0.exr"))[0]
    inp = read_channels(job.input_exr)[0]
    plain = rgb(inp, "ViewLayer.DiffDir") + rgb(inp, "ViewLayer.DiffInd")
    light = rgb(out, "SSS.DiffLight")
    assert np.abs(light - plain).max() <= 1e-6 * max(1.0, plain.max())


def test_existing_layer_name_is_a_clear_error(slab, tmp_path):
    scene = open_scene(slab, tmp_path)
    scene.view_layers.new(transmission.LAYER)
    before = state(scene)
    with pytest.raises(Exception, match=transmission.LAYER):
        pipeline.prepare_render(bpy.context)
    assert state(scene)["layers"] == before["layers"]


def test_auto_is_profile_for_random_walk(slab, tmp_path):
    scene = open_scene(slab, tmp_path)
    mat = bpy.data.materials["Skin"]
    mat.sss.transmission = "AUTO"
    found = pipeline.analyse(scene).materials
    assert [transmission.model(f) for f in found] == ["BURLEY"]
    assert transmission.wanted(scene, pipeline.analyse(scene))[0]
    node = mat.node_tree.nodes["Principled BSDF"]
    node.subsurface_method = "BURLEY"
    found = pipeline.analyse(scene).materials
    assert [transmission.model(f) for f in found] == ["OFF"]
    assert not transmission.wanted(scene, pipeline.analyse(scene))[0]


def test_slab_objects_tagged_only_during_render(slab, tmp_path):
    scene = open_scene(slab, tmp_path)
    seen = {}

    def grab(scene_, *args):
        for obj in scene_.objects:
            if transmission.PROP_MODE in obj:
                # copied: an array property's view dies with it
                seen[obj.name] = [getattr(v, "to_list", lambda v=v: v)()
                                  for v in (obj.get(p) for p in
                                            transmission.PROPS)]
        seen["images"] = [i.name for i in bpy.data.images
                          if i.name.startswith(transmission.SLAB_IMAGE)]
    # A property of the same name the object had comes back as it was.
    bpy.data.objects["Cube"][transmission.PROP_ALBEDO] = [0.1, 0.2, 0.3]
    bpy.app.handlers.render_pre.append(grab)
    try:
        pipeline.prepare_render(bpy.context)
    finally:
        bpy.app.handlers.render_pre.remove(grab)
    own = bpy.data.objects["Cube"].get(transmission.PROP_ALBEDO).to_list()
    assert np.allclose(own, [0.1, 0.2, 0.3])
    del bpy.data.objects["Cube"][transmission.PROP_ALBEDO]
    # The slab carries its table's row, step and scale, and the table is
    # an image; nothing is left afterwards.
    mode, row, step, scale, albedo, reach = seen["Cube"]
    assert mode == 2.0 and row == 0.0 and step > 0.0 and scale > 0.0
    # and, where the layer measures the thickness (thin parts' reflectance
    # on 4.x), its AO distance: D, or the closed slab's mean chord 4 V / S
    # where that is less
    found = pipeline.analyse(scene).materials[0]
    if description.library_material(scene, found).get("thin_reflectance"):
        w, h, t = bpy.data.objects["Cube"].dimensions
        chord = 4.0 * w * h * t / (2.0 * (w * h + w * t + h * t))
        d = transmission.ao_distance(scene, pipeline.analyse(scene))
        assert reach == pytest.approx(min(d, chord), rel=1e-4)
    else:
        assert reach is None
    # and the albedo with which it reflects where an exit point sees it
    assert np.allclose(list(albedo), found.albedo or found.color)
    assert len(seen["images"]) == 1
    assert all(p not in o for o in scene.objects for p in transmission.PROPS)
    assert not [i for i in bpy.data.images
                if i.name.startswith(transmission.SLAB_IMAGE)]


def test_light_reflected_onto_the_back_crosses(slab, tmp_path):
    """Light that reaches a part's back only after a bounce off what lies
    behind it crosses too, as in the random walk: the slab's light turned
    away, towards a wall behind it; the layer's light on the slab follows
    the wall's albedo (it was none at all before the surroundings
    reflected in the layer)."""
    scene = open_scene(slab, tmp_path)
    light = bpy.data.objects["Back"]
    light.location = (0.0, 0.3, 0.0)
    light.rotation_euler = (1.5708, 0.0, 0.0)   # emits along +y, away
    bpy.ops.mesh.primitive_plane_add(size=3.0, location=(0.0, 0.8, 0.0),
                                     rotation=(1.5708, 0.0, 0.0))
    wall = bpy.context.active_object
    mat = bpy.data.materials.new("Wall")
    compat.ensure_nodes(mat)
    wall.data.materials.append(mat)
    base = mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"]
    back = {}
    for albedo in (0.0, 0.9):
        base.default_value = (albedo, albedo, albedo, 1.0)
        job = pipeline.prepare_render(bpy.context)
        inp = read_channels(job.input_exr)[0]
        mask = np.rint(inp["ViewLayer.IndexMA.X"]) > 0
        layer = transmission.LAYER
        assert layer in {k.split(".")[0] for k in inp}
        back[albedo] = sum(float(inp[f"{layer}.{p}.{c}"][mask].mean())
                           for p in ("DiffDir", "DiffInd") for c in "RGB")
    print("back light on the slab, wall albedo 0 / 0.9:", back)
    assert back[0.9] > 20.0 * back[0.0] and back[0.9] > 1e-3


@pytest.fixture(scope="module")
def sphere(tmp_path_factory):
    d = tmp_path_factory.mktemp("sphere")
    return build_blend("sphere", str(d / "sphere.blend"), size=96,
                       samples=16)


def sphere_scene(path, out_dir):
    """The 8 cm skin sphere (front key light, dark world), transmitting,
    with the back-light layer rendered whatever it could add."""
    scene = open_scene(path, out_dir)
    scene.sss.transmission_layer = "ALWAYS"
    return scene


def sphere_pixels(ch):
    return (np.rint(ch["ViewLayer.IndexMA.X"]) > 0) & \
        (ch["ViewLayer.Depth.Z"] < 1e9)


def test_vanishing_radius_lit_by_the_world_from_behind(sphere, tmp_path):
    """A micrometre of radius under a bright world (the only light, all
    round the sphere) with the layer forced on: the result is the plain
    composite at every pixel up to float rounding, transmission included
    (before, rare rays grazing out of the visible surface next to the
    visible point brought its light back through the layer: 6.8e-5 here
    on 3.4, 4.5 % on a few pixels at 480x270)."""
    scene = sphere_scene(sphere, tmp_path)
    for obj in [o for o in scene.objects if o.type == "LIGHT"]:
        bpy.data.objects.remove(obj, do_unlink=True)
    bg = scene.world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    bg.inputs["Strength"].default_value = 1.0
    node = bpy.data.materials["Skin"].node_tree.nodes["Principled BSDF"]
    compat.radius_factor_input(node).default_value *= 1e-4  # red 1e-6 m
    job = pipeline.prepare_render(bpy.context)
    pipeline.scatter(job)
    inp = read_channels(job.input_exr)[0]
    assert transmission.LAYER in {k.split(".")[0] for k in inp}
    mask = sphere_pixels(inp)
    plain = rgb(inp, "ViewLayer.Combined")[mask]
    ours = rgb(read_channels(job.output_exr)[0], "SSS.Combined")[mask]
    rel = np.abs(ours - plain) / np.maximum(np.abs(plain), 1e-3)
    print("largest relative difference from the plain composite:",
          rel.max())
    assert rel.max() < 1e-5


class _Undo(list):
    def add(self, fn):
        self.append(fn)


@pytest.mark.parametrize("radius", [3.67e-3, 1e-6])
def test_slab_lookup_renders_the_librarys_transmittance(tmp_path, radius):
    """The back-light override's slab lookup (the library's table in an
    image, transmission._slab_table), rendered by Cycles on an emission
    strip whose pixel j reads thickness t_j, gives the library's own
    T(t_j) / T(0) (sss_transmittance), from 0 to a thousand times the
    table's span; at a micrometre radius too, and nothing at all where the
    library lets nothing through."""
    material = {"profile": "burley", "mapping": "cycles-random-walk",
                "radius": [radius, 0.37 * radius, 0.18 * radius],
                "albedo": [0.8, 0.55, 0.45], "transmission": "burley"}
    step, span, table = native.transmission_table(material,
                                                  transmission.TABLE_SIZE)
    undo = _Undo()
    scene = bpy.data.scenes.new("lookup")
    try:
        image = transmission.slab_image(table, undo)
        width = 256
        # t_j = step (e^{j c} - 1): fine near 0, up to 1000 x span
        growth = np.log1p(1000.0 * span / step) / (width - 1)
        mat = bpy.data.materials.new("lookup")
        undo.add(lambda: bpy.data.materials.remove(mat))
        tree = compat.ensure_nodes(mat)
        for node in list(tree.nodes):
            tree.nodes.remove(node)
        coord = tree.nodes.new("ShaderNodeTexCoord")
        sep = tree.nodes.new("ShaderNodeSeparateXYZ")
        tree.links.new(coord.outputs["Object"], sep.inputs[0])
        m = transmission._math
        # the pixel's index from x in [-1, 1]: exact whatever the jitter
        j = m(tree, "FLOOR", m(tree, "MULTIPLY", m(tree, "ADD",
                                                     sep.outputs[0], 1.0),
                               width / 2.0))
        t = m(tree, "MULTIPLY", m(tree, "SUBTRACT", m(
            tree, "EXPONENT", m(tree, "MULTIPLY", j, growth)), 1.0), step)
        scale = (transmission.TABLE_SIZE - 1) / np.log1p(span / step)
        colour = transmission._slab_table(tree, t, 0.0, step, scale,
                                          [image])
        emit = tree.nodes.new("ShaderNodeEmission")
        tree.links.new(colour, emit.inputs["Color"])
        out = tree.nodes.new("ShaderNodeOutputMaterial")
        tree.links.new(emit.outputs[0], out.inputs["Surface"])
        mesh = bpy.data.meshes.new("strip")
        mesh.from_pydata([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)],
                         [], [(0, 1, 2, 3)])
        mesh.materials.append(mat)
        strip = bpy.data.objects.new("strip", mesh)
        cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
        cam.data.type = "ORTHO"
        cam.data.ortho_scale = 2.0
        cam.location = (0.0, 0.0, 5.0)
        for obj in (strip, cam):
            scene.collection.objects.link(obj)
            undo.add(lambda obj=obj: bpy.data.objects.remove(obj))
        scene.camera = cam
        scene.world = None
        scene.render.engine = "CYCLES"
        scene.cycles.samples = 1
        scene.cycles.use_denoising = False
        scene.cycles.device = "CPU"
        scene.render.filter_size = 0.01
        scene.render.resolution_x, scene.render.resolution_y = width, 1
        scene.render.resolution_percentage = 100
        scene.render.image_settings.file_format = "OPEN_EXR"
        scene.render.image_settings.color_depth = "32"
        scene.render.filepath = str(tmp_path / "lookup.exr")
        assert bpy.ops.render.render(write_still=True, scene=scene.name) \
            == {"FINISHED"}
        channels, _ = read_channels(tmp_path / "lookup.exr")
        got = np.stack([channels[k][0] for k in "RGB"], axis=1)
    finally:
        bpy.data.scenes.remove(scene)
        for fn in reversed(undo):
            fn()
    T0 = native.transmittance(material, 0.0)
    ts = step * np.expm1(np.arange(width) * growth)
    want = np.array([[v / v0 for v, v0 in zip(
        native.transmittance(material, float(t)), T0)] for t in ts])
    # The table's linear interpolation is within 3.4e-4 of the library at
    # worst (test_transmission.c); at these points 1e-6 was measured on
    # Blender 3.4, 4.5 and 5.0.
    assert np.abs(got - want).max() < 5e-4, np.abs(got - want).max()
    assert not got[want == 0.0].any()       # none where the library has none
    assert (want == 0.0).sum() > width / 4 and (want > 0.5).sum() > 5
