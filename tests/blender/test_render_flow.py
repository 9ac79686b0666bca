"""SSS inside Blender's render flow (render_flow.py): with the scene's
switch on, an ordinary render writes the scattered image, every frame of
an animation its own, File Output nodes and every view layer included; a
frame that fails fails the job; with the switch off nothing changes."""
import glob
import os
import shutil
import subprocess

import bpy
import numpy as np
import OpenImageIO as oiio
import pytest

from helpers import BLENDER, BUILD, ROOT, build_blend, compat, diff, \
    load_addon, snapshot

separable_sss = load_addon()
from separable_sss import nodes, pipeline, render_flow  # noqa: E402

import faults  # noqa: E402

from exr import read_channels  # noqa: E402


@pytest.fixture(scope="module", autouse=True)
def addon():
    separable_sss.register()
    # In this process a failed frame must not end the test run (-b would):
    # the subprocess tests check that exit.
    render_flow.EXIT_ON_FAILURE = False
    yield
    separable_sss.unregister()


@pytest.fixture(scope="module")
def blend(tmp_path_factory):
    return build_blend("two", str(tmp_path_factory.mktemp("blends") /
                                  "two.blend"), size=48, samples=4)


def open_scene(path, out_dir):
    """The scene with a PNG output whose pixels are the linear image
    through the plain sRGB curve (no dither, Standard view)."""
    bpy.ops.wm.open_mainfile(filepath=path)
    scene = bpy.context.scene
    scene.sss.output_dir = str(out_dir)
    scene.render.image_settings.file_format = 'PNG'
    scene.render.image_settings.color_depth = '16'
    scene.render.image_settings.color_mode = 'RGB'
    scene.render.dither_intensity = 0.0
    scene.view_settings.view_transform = 'Standard'
    scene.view_settings.look = 'None'
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    return scene


def srgb(linear):
    x = np.clip(linear, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x,
                    1.055 * np.power(x, 1 / 2.4) - 0.055)


def png(path):
    """The file's own values in [0, 1] (Blender would linearise them)."""
    buf = oiio.ImageBuf(str(path))
    assert not buf.has_error, buf.geterror()
    return buf.get_pixels(oiio.FLOAT)[:, :, :3]


def expected(scene):
    """What the SSS pipeline gives for the current frame (the operator's
    own path: render with SSS off, then the library), as the PNG holds it."""
    job = pipeline.prepare_render(bpy.context)
    pipeline.scatter(job)
    ch, _ = read_channels(job.output_exr)
    rgb = np.stack([ch[f"SSS.Combined.{c}"] for c in "RGB"], axis=-1)
    return srgb(rgb)


def render_still(scene, path):
    scene.render.filepath = str(path)
    assert bpy.ops.render.render(write_still=True) == {'FINISHED'}
    render_flow.remove_leftovers()
    return png(str(path) + ".png")


def test_still_render_is_the_sss_result(blend, tmp_path):
    scene = open_scene(blend, tmp_path)
    want = expected(scene)
    scene.render.filepath = str(tmp_path / "still")
    before = snapshot(scene)
    scene.sss.enabled = True
    got = render_still(scene, tmp_path / "still")
    assert np.abs(got - want).max() <= 1.5 / 255
    scene.sss.enabled = False
    assert diff(before, snapshot(scene)) == []
    assert [s.name for s in bpy.data.scenes] == [scene.name]
    plain = render_still(scene, tmp_path / "plain")
    assert np.abs(plain - want).max() > 4 / 255  # SSS shows


def test_render_with_sss_setup_never_shows_an_old_result(blend, tmp_path):
    """Render with SSS leaves its result node in the compositor; a later
    render with the switch on shows the new frame, not that old result."""
    scene = open_scene(blend, tmp_path)
    assert bpy.ops.sss.render() == {'FINISHED'}
    scene.camera.data.lens *= 1.5
    scene.sss.output_dir = str(tmp_path / "new")  # the old file stays
    want = expected(scene)
    scene.sss.enabled = True
    got = render_still(scene, tmp_path / "still")
    assert np.abs(got - want).max() <= 1.5 / 255
    # Afterwards the set-up shows Render with SSS's in-memory result again.
    node = nodes.find_result(scene)
    assert node.image.source == 'GENERATED'
    assert [link.to_node.bl_idname for link in node.outputs["Image"].links] \
        == ["CompositorNodeGroup"]


def test_transmission_as_for_stills(tmp_path):
    """A back-lit slab: the render's copy gets the back-light layer as the
    still pipeline does, and the frame is that pipeline's result."""
    slab = build_blend("slab", str(tmp_path / "slab.blend"), size=40,
                       samples=16)
    scene = open_scene(slab, tmp_path)
    want = expected(scene)
    scene.sss.transmission_layer = 'NEVER'
    without = expected(scene)
    scene.sss.transmission_layer = 'AUTO'
    assert np.abs(want - without).max() > 4 / 255  # transmission shows
    scene.sss.enabled = True
    got = render_still(scene, tmp_path / "still")
    assert np.abs(got - want).max() <= 1.5 / 255


def test_denoiser_applies_to_the_scattered_image(blend, tmp_path):
    """With the scene's denoiser on, the frame is the SSS result through
    OIDN (with the render's albedo and normal): the same image, less
    noise. Without OIDN in this Blender, the Denoise node passes it."""
    import _cycles
    scene = open_scene(blend, tmp_path)
    want = expected(scene)  # not denoised
    scene.cycles.use_denoising = True
    scene.sss.enabled = True
    got = render_still(scene, tmp_path / "still")
    if not getattr(_cycles, "with_openimagedenoise", False):
        assert np.abs(got - want).max() <= 1.5 / 255
        return

    def roughness(img):  # high-frequency energy: what a denoiser removes
        return np.abs(np.diff(img, axis=0)).mean() + \
            np.abs(np.diff(img, axis=1)).mean()
    assert roughness(got) < 0.8 * roughness(want)
    assert abs(got.mean() - want.mean()) < 0.02
    assert scene.cycles.use_denoising  # the scene's setting is kept


def test_switch_off_never_shows_an_old_result(blend, tmp_path):
    """Render with SSS leaves its result on the Composite; an ordinary
    render with the switch off (a script, -f, F12's operator) writes what
    Blender renders, and the set-up is back afterwards."""
    scene = open_scene(blend, tmp_path)
    plain = render_still(scene, tmp_path / "plain")
    assert bpy.ops.sss.render() == {'FINISHED'}
    scene.render.filepath = str(tmp_path / "after")
    before = snapshot(scene)
    after = render_still(scene, tmp_path / "after")
    assert np.array_equal(after, plain)
    assert diff(before, snapshot(scene)) == []
    assert bpy.ops.sss.render_frame() == {'FINISHED'}
    path = str(tmp_path / "result.png")
    bpy.data.images["Render Result"].save_render(path, scene=scene)
    assert np.array_equal(png(path), plain)


def test_multilayer_exr_output_keeps_every_pass(blend, tmp_path):
    """A compositing-only render writes only the composite into a
    multilayer EXR: the frame's passes and SSS layer join it."""
    scene = open_scene(blend, tmp_path)
    compat.set_multilayer_exr(scene.render.image_settings)
    scene.sss.enabled = True
    scene.frame_start = scene.frame_end = 1
    scene.render.filepath = str(tmp_path / "frame_####")
    assert bpy.ops.render.render(animation=True) == {'FINISHED'}
    render_flow.remove_leftovers()
    ch, _ = read_channels(tmp_path / "frame_0001.exr")
    for name in ("Composite.Combined.R", "SSS.Combined.R",
                 "ViewLayer.DiffDir.R", "ViewLayer.Depth.Z"):
        assert name in ch, sorted(ch)
    composite = np.stack([ch[f"Composite.Combined.{c}"] for c in "RGB"], -1)
    sss = np.stack([ch[f"SSS.Combined.{c}"] for c in "RGB"], -1)
    assert np.abs(composite - sss).max() < 1e-3


def test_layer_named_as_another_layers_result_is_refused(blend, tmp_path):
    """A multilayer EXR output gets SSS-NAME for view layer NAME's result:
    a view layer already called that would be replaced, so the frame
    fails with the reason (as the library refuses one named SSS)."""
    scene = open_scene(blend, tmp_path)
    compat.set_multilayer_exr(scene.render.image_settings)
    scene.view_layers.new("Second")
    scene.view_layers.new("SSS-Second")
    tree = compat.compositor_tree(scene, create=True)
    out = tree.nodes.new("CompositorNodeOutputFile")
    compat.set_file_output(out, str(tmp_path / "fo"), "PNG", '16')
    names = ["Second", "SSS-Second"]  # both shown, so both rendered
    sockets = compat.file_output_inputs(out, ["a", "b"])
    for name, socket in zip(names, sockets):
        node = tree.nodes.new("CompositorNodeRLayers")
        node.layer = name
        tree.links.new(node.outputs["Image"], socket)
    scene.sss.enabled = True
    scene.frame_start = scene.frame_end = 1
    scene.render.filepath = str(tmp_path / "frame_####")
    render_flow.last_error = None
    bpy.ops.render.render(animation=True)
    render_flow.remove_leftovers()
    assert "view layer 'SSS-Second' has the name of view layer 'Second''s " \
        "SSS result" in str(render_flow.last_error)


def test_switch_off_is_plain_cycles(blend, tmp_path):
    scene = open_scene(blend, tmp_path)
    with_addon = render_still(scene, tmp_path / "a")
    render_flow.unregister()
    try:
        without = render_still(scene, tmp_path / "b")
    finally:
        render_flow.register()
    assert np.array_equal(with_addon, without)


@pytest.mark.parametrize("layer_name", ["Second", "ViewLayer.001"])
def test_file_output_and_second_view_layer(blend, tmp_path, monkeypatch,
                                           layer_name):
    """Every shown view layer is scattered, also one named as Blender
    names a copy (ViewLayer.001: names split from the end); the `sss`
    command on the same passes gives that layer the same result."""
    scene = open_scene(blend, tmp_path)
    scene.view_layers.new(layer_name)
    want = expected(scene)
    tree = compat.compositor_tree(scene, create=True)
    first = next(n for n in tree.nodes
                 if n.bl_idname == "CompositorNodeRLayers")
    second = tree.nodes.new("CompositorNodeRLayers")
    second.layer = layer_name
    out = tree.nodes.new("CompositorNodeOutputFile")
    compat.set_file_output(out, str(tmp_path / "fo"), "PNG", '16')
    sockets = compat.file_output_inputs(out, ["first", "second"])
    tree.links.new(first.outputs["Image"], sockets[0])
    tree.links.new(second.outputs["Image"], sockets[1])
    kept = {}
    scatter = pipeline.scatter

    def keeping(job):  # the render flow's files for that layer, kept
        scatter(job)
        if job.layer == layer_name:
            for key in ("input_exr", "scene_json", "output_exr"):
                kept[key] = str(tmp_path / ("kept_" + key))
                shutil.copy(getattr(job, key), kept[key])
    monkeypatch.setattr(pipeline, "scatter", keeping)
    scene.sss.enabled = True
    render_still(scene, tmp_path / "still")
    for name in ("first", "second"):
        files = glob.glob(str(tmp_path / "fo" / f"{name}*.png"))
        assert len(files) == 1, os.listdir(tmp_path / "fo")
        got = png(files[0])
        assert np.abs(got - want).max() <= 1.5 / 255, name
    cli = str(tmp_path / "cli.exr")
    proc = subprocess.run([os.path.join(BUILD, "sss"), kept["input_exr"],
                           "-l", layer_name, "-o", cli, "--scene",
                           kept["scene_json"], "-q"], capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    a, _ = read_channels(kept["output_exr"])
    b, _ = read_channels(cli)
    assert f"{layer_name}.DiffDir.R" in b
    assert np.array_equal(np.stack([a[f"SSS.Combined.{c}"] for c in "RGB"]),
                          np.stack([b[f"SSS.Combined.{c}"] for c in "RGB"]))


def test_failed_frame_restores_and_reports(blend, tmp_path, monkeypatch):
    """In a session (no exit) the failed render composites nothing, the
    error names the pass, and the scene is as before at the end."""
    scene = open_scene(blend, tmp_path)
    before = snapshot(scene)
    scene.sss.enabled = True
    faults.drop_a_pass(monkeypatch, render_flow)
    with pytest.raises(RuntimeError) as err:  # the operator's ERROR report
        bpy.ops.sss.render_frame()
    message = str(err.value).strip()
    assert "DiffCol" in message and "\n" not in message
    scene.sss.enabled = False
    assert diff(before, snapshot(scene)) == []
    assert [s.name for s in bpy.data.scenes] == [scene.name]


def test_render_key_operator(blend, tmp_path):
    """F12's operator: with the switch on, the Render Result is the
    scattered frame; off, it is Blender's own render."""
    scene = open_scene(blend, tmp_path)
    want = expected(scene)
    scene.sss.enabled = True
    assert bpy.ops.sss.render_frame() == {'FINISHED'}
    path = str(tmp_path / "result.png")
    bpy.data.images["Render Result"].save_render(path, scene=scene)
    assert np.abs(png(path) - want).max() <= 1.5 / 255


def run_blender(path, *args, env=None):
    enable = ("import sys; sys.path.insert(0, %r); import separable_sss; "
              "separable_sss.register(); import bpy; "
              "bpy.context.scene.sss.enabled = True"
              % os.path.join(ROOT, "addon"))
    return subprocess.run([BLENDER, "-b", path, "--python-expr", enable,
                           *args], capture_output=True, text=True,
                          timeout=900, env={**os.environ, **(env or {})})


def test_animation_follows_the_camera_per_frame(blend, tmp_path):
    scene = open_scene(blend, tmp_path)
    cam = scene.camera.data
    scene.frame_start, scene.frame_end = 1, 3
    for f, lens in ((1, 40.0), (3, 70.0)):
        cam.lens = lens
        cam.keyframe_insert("lens", frame=f)
    scene.render.filepath = str(tmp_path / "frame_####")
    scene.frame_current = 2  # set up on frame 2: its result waits for it
    path = str(tmp_path / "anim.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    proc = run_blender(path, "-a")
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-2000:]
    assert proc.stdout.count(", view layer ViewLayer:") == 3, proc.stdout
    frames = []
    for f in (1, 2, 3):
        scene.frame_set(f)
        want = expected(scene)
        got = png(tmp_path / f"frame_{f:04d}.png")
        assert np.abs(got - want).max() <= 1.5 / 255, f
        frames.append(got)
    assert np.abs(frames[0] - frames[2]).max() > 0.05  # the lens moved


def test_failed_frame_fails_blender_b(blend, tmp_path):
    scene = open_scene(blend, tmp_path)
    scene.render.filepath = str(tmp_path / "frame_####")
    path = str(tmp_path / "fail.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    drop = ("import sys; sys.path.insert(0, %r); import faults; "
            "from separable_sss import render_flow; "
            "faults.patch(render_flow)" % os.path.dirname(__file__))
    proc = run_blender(path, "--python-expr", drop, "-f", "1")
    assert proc.returncode != 0
    assert "DiffCol" in proc.stdout and "frame 1" in proc.stdout, \
        proc.stdout[-2000:]
    assert not (tmp_path / "frame_0001.png").exists()
