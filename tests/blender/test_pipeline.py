"""The add-on's pipeline on real Cycles renders, headless."""
import json
import os
import subprocess

import bpy
import numpy as np
import pytest

from helpers import (BLENDER, BUILD, ROOT, build_blend, compat, diff,
                     load_addon, snapshot)

separable_sss = load_addon()
from separable_sss import pipeline  # noqa: E402

import faults  # noqa: E402

from exr import pass_rgb, read_channels  # noqa: E402


@pytest.fixture(scope="module", autouse=True)
def addon():
    separable_sss.register()
    yield
    separable_sss.unregister()


@pytest.fixture(scope="module")
def blends(tmp_path_factory):
    d = tmp_path_factory.mktemp("blends")
    return {kind: build_blend(kind, str(d / f"{kind}.blend"))
            for kind in ("two", "none")}


def open_scene(path, out_dir):
    bpy.ops.wm.open_mainfile(filepath=path)
    scene = bpy.context.scene
    scene.sss.output_dir = str(out_dir)
    return scene


def render(scene):
    job = pipeline.prepare_render(bpy.context)
    pipeline.scatter(job)
    return job


def inject(where, monkeypatch):
    """A failure after the render, a cancelled render, or the library's
    refusal (tests/blender/faults.py)."""
    if where == "cancel":
        monkeypatch.setenv("SSS_TEST_FAIL", "cancel")
    elif where == "render":
        faults.fail_after_render(monkeypatch, pipeline)
    else:
        faults.library_refuses(monkeypatch, pipeline)


def test_scene_restored_exactly_after_render(blends, tmp_path):
    scene = open_scene(blends["two"], tmp_path)
    before = snapshot(scene)
    job = render(scene)
    assert os.path.exists(job.output_exr)
    assert diff(before, snapshot(scene)) == []


@pytest.mark.parametrize("where,needle", [
    ("render", "injected"), ("cancel", "cancelled"),
    ("library", "radius scale")])
def test_scene_restored_after_failure(blends, tmp_path, monkeypatch, where,
                                      needle):
    scene = open_scene(blends["two"], tmp_path)
    before = snapshot(scene)
    inject(where, monkeypatch)
    with pytest.raises(pipeline.SSSError) as err:
        render(scene)
    assert needle in str(err.value)
    assert diff(before, snapshot(scene)) == []


def test_unwritable_output_folder(blends, tmp_path):
    scene = open_scene(blends["two"], tmp_path)
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    scene.sss.output_dir = str(blocker / "sss")
    before = snapshot(scene)
    with pytest.raises(pipeline.SSSError) as err:
        render(scene)
    assert "not writable" in str(err.value) and "a_file" in str(err.value)
    assert diff(before, snapshot(scene)) == []


def test_missing_pass_is_one_clear_error(blends, tmp_path):
    """Apply to a render made without the passes: the library names the
    missing pass; nothing in the scene changes."""
    scene = open_scene(blends["two"], tmp_path)
    for layer in scene.view_layers:
        layer.use_pass_diffuse_direct = False
    bpy.ops.render.render()
    before = snapshot(scene)
    job = pipeline.prepare_last_render(bpy.context)
    with pytest.raises(pipeline.SSSError) as err:
        pipeline.scatter(job)
    assert "DiffDir" in str(err.value)
    assert diff(before, snapshot(scene)) == []


def test_radius_scale_zero_is_cycles_combined(blends, tmp_path):
    scene = open_scene(blends["two"], tmp_path)
    scene.sss.radius_scale = 0.0
    job = render(scene)
    ch, _ = read_channels(job.output_exr)
    want = np.stack([ch[f"ViewLayer.Combined.{c}"] for c in "RGBA"], -1)
    got = np.stack([ch[f"SSS.Combined.{c}"] for c in "RGBA"], -1)
    err = np.abs(got - want) / np.maximum(np.abs(want), 1e-2)
    assert err.max() < 1e-4, err.max()


def test_sss_command_on_the_description_gives_the_same(blends, tmp_path):
    """The scene's radius scale travels in the description: the `sss`
    command on the add-on's own files gives the add-on's result."""
    scene = open_scene(blends["two"], tmp_path)
    scene.sss.radius_scale = 2.5
    job = render(scene)
    assert json.load(open(job.scene_json))["radius_scale"] == 2.5
    out = str(tmp_path / "cli.exr")
    proc = subprocess.run([os.path.join(BUILD, "sss"), job.input_exr, "-o",
                           out, "--scene", job.scene_json, "-q"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    a, _ = read_channels(job.output_exr)
    b, _ = read_channels(out)
    assert np.array_equal(pass_rgb(a, "SSS.Combined"),
                          pass_rgb(b, "SSS.Combined"))
    scene.sss.radius_scale = 1.0
    one = render(scene)
    c, _ = read_channels(one.output_exr)
    assert not np.array_equal(pass_rgb(a, "SSS.Combined"),
                              pass_rgb(c, "SSS.Combined"))


def test_two_materials_keep_their_profiles(blends, tmp_path):
    scene = open_scene(blends["two"], tmp_path)
    job = render(scene)
    desc = json.load(open(job.scene_json))
    mats = {m["name"]: m for m in desc["materials"]}
    assert set(mats) == {"Skin", "Jade"}
    assert mats["Skin"]["pass_index"] != mats["Jade"]["pass_index"]
    assert mats["Skin"]["radius"] != mats["Jade"]["radius"]
    # The render used these indices even though the materials had none.
    assert all(m.pass_index == 0 for m in bpy.data.materials)
    ch, _ = read_channels(job.output_exr)
    index = ch["ViewLayer.IndexMA.X"]
    before = pass_rgb(ch, "ViewLayer.Combined")
    after = pass_rgb(ch, "SSS.Combined")
    changed = np.abs(after - before).max(-1) > 1e-5
    scattering = np.isin(index, [m["pass_index"] for m in mats.values()])
    assert changed[scattering].mean() > 0.2
    assert not changed[~scattering].any(), "plain pixels changed"
    # Each material scattered with its own kernel: its pixels are exactly
    # what a table holding only that material gives.
    light = pass_rgb(ch, "SSS.DiffLight")
    for name in ("Skin", "Jade"):
        alone = dict(desc, materials=[mats[name]])
        path = tmp_path / f"{name}.json"
        path.write_text(json.dumps(alone))
        out = tmp_path / f"{name}.exr"
        subprocess.run([os.path.join(BUILD, "sss"), job.input_exr, "-o",
                        str(out), "--scene", str(path), "-q"], check=True)
        only, _ = read_channels(out)
        mask = index == mats[name]["pass_index"]
        assert np.array_equal(pass_rgb(only, "SSS.DiffLight")[mask],
                              light[mask]), name
        other = np.isin(index, [m["pass_index"] for m in mats.values()]) \
            & ~mask
        assert not np.array_equal(pass_rgb(only, "SSS.DiffLight")[other],
                                  light[other]), name


def test_switched_off_render_keeps_the_look(blends, tmp_path):
    """Rendering with SSS off changes only how light spreads, not the
    material's colour: the passes are those Cycles gives for the materials
    without SSS, made by hand the way Blender defines it (3.x: Base Color
    becomes mix(Base Color, Subsurface Color, Subsurface) and Subsurface 0;
    from 4.0: Subsurface Weight 0), on every scattering material (one
    left on would light the others differently)."""
    scene = open_scene(blends["two"], tmp_path)
    job = render(scene)
    ch, _ = read_channels(job.input_exr)
    desc = json.load(open(job.scene_json))
    skin = [m for m in desc["materials"] if m["name"] == "Skin"][0]
    mask = ch["ViewLayer.IndexMA.X"] == skin["pass_index"]
    assert mask.mean() > 0.02

    for entry in desc["materials"]:
        tree = bpy.data.materials[entry["name"]].node_tree
        node = tree.nodes["Principled BSDF"]
        weight = compat.principled_input(node, "subsurface")
        assert not weight.is_linked
        if not compat.PRINCIPLED_V2:
            base = compat.principled_input(node, "base")
            sub = compat.principled_input(node, "subsurface_color")
            t = weight.default_value
            if base.is_linked:      # a texture: mixed by a node
                mix = tree.nodes.new("ShaderNodeMixRGB")
                mix.inputs["Fac"].default_value = t
                mix.inputs["Color2"].default_value = sub.default_value
                tree.links.new(base.links[0].from_socket,
                               mix.inputs["Color1"])
                tree.links.new(mix.outputs["Color"], base)
            else:
                base.default_value = [
                    b + (c - b) * t for b, c in
                    zip(base.default_value, sub.default_value)]
        weight.default_value = 0.0
    for name in ("diffuse_direct", "diffuse_indirect", "diffuse_color"):
        setattr(scene.view_layers[0], "use_pass_" + name, True)
    bpy.ops.render.render()
    plain = str(tmp_path / "by_hand.exr")
    pipeline.save_passes(scene, plain)
    want, _ = read_channels(plain)
    for name in ("DiffCol", "DiffDir", "DiffInd", "Combined"):
        got = pass_rgb(ch, "ViewLayer." + name)
        ref = pass_rgb(want, "ViewLayer." + name)
        assert np.array_equal(got, ref), name   # the same shaders
    if not compat.PRINCIPLED_V2:   # and the formula itself, as in 3.x
        col = pass_rgb(ch, "ViewLayer.DiffCol")[mask]
        base, sub = np.array([0.8, 0.6, 0.5]), np.array([0.9, 0.5, 0.4])
        assert np.allclose(np.median(col, 0), base + (sub - base) * 0.5,
                           atol=2e-3)


# What the description asks for, per method: the radius mapping and the
# energy calibration measured for this Blender's random walk
# (csrc/sss_calibration.c); 4.0 rewrote the walk. Written out here, not
# read from blender_compat.WALK_CALIBRATION, so that the test checks it.
WALK = {"BURLEY": ("cycles", None),
        "RANDOM_WALK": ("cycles4-random-walk", "cycles4-random-walk"),
        "RANDOM_WALK_SKIN": ("cycles-random-walk",
                             "cycles4-random-walk-skin")} \
    if compat.CYCLES_WALK_V2 else {
        "BURLEY": ("cycles", None), "RANDOM_WALK": ("random-walk", None),
        "RANDOM_WALK_SKIN": ("cycles-random-walk", "cycles-random-walk")}


def skin_entry(scene, tmp_path):
    """The description the add-on writes for the scene: the Skin
    material's entry, once the library has taken the file without a
    warning."""
    path = str(tmp_path / "scene.json")
    found = pipeline.analyse(scene)
    with pipeline.switched_off(scene, found, backlight=False):
        pipeline.write_description(scene, found, path)
    from separable_sss import native
    with native.Scene(path) as loaded:
        assert loaded.warnings == []
    return [m for m in json.load(open(path))["materials"]
            if m["name"] == "Skin"][0]


@pytest.mark.parametrize("method", sorted(WALK))
def test_description_follows_the_method(blends, tmp_path, method):
    scene = open_scene(blends["two"], tmp_path)
    node = bpy.data.materials["Skin"].node_tree.nodes["Principled BSDF"]
    compat.set_method(node, method)
    skin = skin_entry(scene, tmp_path)
    assert (skin["mapping"], skin.get("calibration")) == WALK[method]


# 4.x's plain Random Walk enters through the material's own surface, whose
# index Cycles makes from IOR and Specular IOR Level (F0 scaled by twice
# the level, clamped to 1.01 .. 3.8), with the material's Roughness; the
# calibration follows both.
@pytest.mark.skipif(not compat.CYCLES_WALK_V2, reason="4.x's walk")
@pytest.mark.parametrize("ior, level, want", [
    (1.5, 0.5, 1.5), (1.5, 0.0, 1.01), (1.5, 1.0, 1.7887), (1.33, 0.5, 1.33),
    (1.5, 0.25, 1.3294)])
def test_description_takes_the_walks_surface(blends, tmp_path, ior, level,
                                             want):
    scene = open_scene(blends["two"], tmp_path)
    node = bpy.data.materials["Skin"].node_tree.nodes["Principled BSDF"]
    compat.set_method(node, "RANDOM_WALK")
    compat.principled_input(node, "ior").default_value = ior
    compat.principled_input(node, "specular").default_value = level
    compat.principled_input(node, "roughness").default_value = 0.3
    skin = skin_entry(scene, tmp_path)
    assert skin["walk_ior"] == pytest.approx(want, abs=1e-4)
    assert skin["walk_roughness"] == pytest.approx(0.3)


def test_no_scattering_material(blends, tmp_path):
    scene = open_scene(blends["none"], tmp_path)
    assert pipeline.analyse(scene).materials == []


def test_render_sss_script(blends, tmp_path):
    mtime = os.path.getmtime(blends["two"])
    out = tmp_path / "shot_####.exr"
    proc = subprocess.run(
        [BLENDER, "-b", blends["two"], "--python-exit-code", "1",
         "--python", os.path.join(ROOT, "blender_scripts", "render_sss.py"),
         "--", "--output", str(out), "--frames", "1-2", "--samples", "2",
         "--resolution", "48x40"], capture_output=True, text=True,
        timeout=600, env=dict(os.environ))
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    for f in (1, 2):
        exr = tmp_path / f"shot_{f:04d}.exr"
        ch, spec = read_channels(exr)
        assert (spec.width, spec.height) == (48, 40)
        assert "SSS.Combined.R" in ch and "ViewLayer.DiffDir.R" in ch
        assert (tmp_path / f"shot_{f:04d}_scene.json").exists()
        assert f"frame {f}:" in proc.stdout
    assert os.path.getmtime(blends["two"]) == mtime  # the .blend untouched


def test_non_scattering_material_index_is_off_limits(blends, tmp_path):
    """A render gives a scattering material another pass index when a
    material that does not scatter uses its index (their pixels would
    scatter with this profile), as Assign Pass Indices does; the material
    keeps its own index after the render."""
    scene = open_scene(blends["two"], tmp_path)
    found = pipeline.analyse(scene).materials
    mat = found[0].material
    mat.pass_index = 7
    plain = bpy.data.materials.new("Plain")
    plain.pass_index = 7
    job = render(scene)
    described = {m["name"]: m["pass_index"]
                 for m in json.load(open(job.scene_json))["materials"]}
    assert described[mat.name] != 7
    assert len(set(described.values())) == len(described)
    assert mat.pass_index == 7 and plain.pass_index == 7
    assert bpy.ops.sss.assign_pass_indices() == {'FINISHED'}
    assert mat.pass_index != 7 and plain.pass_index == 7
