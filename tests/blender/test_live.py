"""Re-tuning SSS after the render, live (live.py): after Render with SSS the
passes stay decoded in the library; a change of a material's radius
followed by Apply scatters them again in memory, pushes the pixels into the
compositor's image, writes no file, and equals the `sss` command on the
same passes and description."""
import os
import subprocess
import time

import bpy
import numpy as np
import pytest

from helpers import BUILD, build_blend, compat, load_addon, registered

separable_sss = load_addon()
from separable_sss import live, nodes, pipeline  # noqa: E402

from exr import read_channels  # noqa: E402

addon = registered(separable_sss)

# Frames free their kept working memory this long after a re-tune; short
# here, so that settle() does not wait the add-on's ten seconds.
live.TRIM_SECONDS = 0.2


@pytest.fixture(scope="module")
def blend(tmp_path_factory):
    d = tmp_path_factory.mktemp("blends")
    return build_blend("two", str(d / "two.blend"))


def open_rendered(blend, out_dir):
    """The scene rendered with SSS through the operator, as an artist does."""
    bpy.ops.wm.open_mainfile(filepath=blend)
    scene = bpy.context.scene
    scene.sss.output_dir = str(out_dir)
    assert bpy.ops.sss.render() == {'FINISHED'}
    return scene


def principled(scene):
    """The first scattering material's Principled BSDF."""
    found = pipeline.analyse(scene).materials
    assert found, "the test scene has no scattering material"
    return found[0].node


def scale_radius(scene, factor):
    sock = compat.radius_factor_input(principled(scene))
    sock.default_value = sock.default_value * factor


def shown_pixels(scene):
    """The pixels of the image the SSS Result node shows, rows top first."""
    image = nodes.find_result(scene).image
    w, h = image.size
    px = np.empty(w * h * 4, np.float32)
    image.pixels.foreach_get(px)
    return image, px.reshape(h, w, 4)[::-1]


def settle():
    """Runs the live loop's timer until it has nothing left to do, as
    Blender's event loop would (headless Blender runs no timers)."""
    for _ in range(2000):
        wait = live._settled()
        if wait is None:
            return
        time.sleep(wait)
    raise AssertionError("the live loop never settled")


def files(folder):
    return {name: os.stat(os.path.join(folder, name)).st_mtime_ns
            for name in os.listdir(folder)}


def test_render_keeps_the_passes(blend, tmp_path):
    scene = open_rendered(blend, tmp_path)
    entry = live.kept(scene)
    assert entry is not None
    assert (entry.frame.width, entry.frame.height) == \
        (scene.render.resolution_x * scene.render.resolution_percentage // 100,
         scene.render.resolution_y * scene.render.resolution_percentage // 100)
    assert entry.view_layer == bpy.context.view_layer.name
    # Nothing changed since the render: nothing to scatter.
    assert live.retune(scene) == {}


def test_retune_in_memory_equals_the_command(blend, tmp_path):
    scene = open_rendered(blend, tmp_path)
    first = live.kept(scene).combined.copy()
    before = files(tmp_path)
    scale_radius(scene, 4.0)
    assert bpy.ops.sss.apply() == {'FINISHED'}
    assert files(tmp_path) == before, "a re-tune wrote or changed a file"

    image, shown = shown_pixels(scene)
    assert image.name == live.image_name(scene)
    assert image.source == 'GENERATED' and image.is_float
    assert not np.allclose(shown, first, atol=1e-4), \
        "a 4x radius left the image as it was"

    # The `sss` command on the same passes and description.
    desc = tmp_path / "live.json"
    desc.write_text(live.kept(scene).description)
    passes = pipeline.paths_for(scene, scene.frame_current)[0]
    out = str(tmp_path / "cli.exr")
    proc = subprocess.run([os.path.join(BUILD, "sss"), passes, "-o", out,
                           "--scene", str(desc), "-q"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    ch, _ = read_channels(out)
    want = np.stack([ch[f"SSS.Combined.{c}"] for c in "RGBA"], -1)
    assert np.abs(shown - want).max() <= 1e-5


def test_idle_frame_frees_its_working_memory(blend, tmp_path):
    """A re-tune leaves the frame's working memory kept for the next one;
    once none comes for TRIM_SECONDS the live loop frees it, and a re-tune
    after that gives the same pixels."""
    scene = open_rendered(blend, tmp_path)
    assert not live.kept(scene).holds_memory    # the render's is freed
    live._pending.clear()
    scale_radius(scene, 3.0)
    assert bpy.ops.sss.apply() == {'FINISHED'}
    entry = live.kept(scene)
    assert entry.holds_memory
    assert bpy.app.timers.is_registered(live._settled)
    kept_then = entry.combined.copy()
    wait = live._settled()          # too soon: it waits to free it
    assert wait is not None and 0.0 < wait <= live.TRIM_SECONDS
    assert entry.holds_memory
    settle()
    assert not entry.holds_memory
    assert live.retune(scene, force=True)["scatter"] >= 0.0
    assert np.array_equal(entry.combined, kept_then)
    assert entry.holds_memory


def test_depsgraph_change_retunes_once_settled(blend, tmp_path):
    """A change seen by Blender's depsgraph is scattered once settings
    settle (the timer's work, run here by hand: headless Blender runs no
    timers); with Live Re-tune off nothing is scheduled."""
    scene = open_rendered(blend, tmp_path)
    live._pending.clear()
    scale_radius(scene, 3.0)
    bpy.context.view_layer.update()
    assert scene.name in live._pending
    first = live._settled()       # not settled yet: it waits
    assert first is not None and first > 0.0
    settle()
    assert live.kept(scene).timings.get("scatter", -1.0) >= 0.0
    assert live.retune(scene) == {}   # already done

    scene.sss.live = False
    live._pending.clear()
    scale_radius(scene, 2.0)
    bpy.context.view_layer.update()
    assert scene.name not in live._pending


def test_scene_settings_retune_too(blend, tmp_path):
    """The scene's method and radius scale are part of a re-tune."""
    scene = open_rendered(blend, tmp_path)
    scene.sss.method = 'SEPARABLE'
    timings = live.retune(scene)
    assert timings["scatter"] >= 0.0
    assert set(timings["methods"].values()) == {"separable"}
    scene.sss.radius_scale = 0.0
    live.retune(scene)
    _, shown = shown_pixels(scene)
    entry = live.kept(scene)
    assert np.array_equal(shown, entry.combined)


def test_passes_freed_with_the_file_and_another_render(blend, tmp_path):
    scene = open_rendered(blend, tmp_path)
    frame = live.kept(scene).frame
    bpy.ops.render.render()
    assert live.kept(scene) is None and not frame._ptr
    scene = open_rendered(blend, tmp_path)
    frame = live.kept(scene).frame
    bpy.ops.wm.open_mainfile(filepath=blend)
    assert live.kept(bpy.context.scene) is None and not frame._ptr


def test_apply_without_kept_passes_reads_the_render(blend, tmp_path):
    """Apply after a plain render (nothing kept) takes the file path and
    then keeps the passes too."""
    bpy.ops.wm.open_mainfile(filepath=blend)
    scene = bpy.context.scene
    scene.sss.output_dir = str(tmp_path)
    for layer in scene.view_layers:
        for name in ("diffuse_direct", "diffuse_indirect", "diffuse_color",
                     "z", "material_index"):
            setattr(layer, "use_pass_" + name, True)
    bpy.ops.render.render()
    assert live.kept(scene) is None
    assert bpy.ops.sss.apply() == {'FINISHED'}
    assert live.kept(scene) is not None


def test_render_with_the_switch_keeps_the_passes(blend, tmp_path):
    """A render with the scene's Screen-space SSS on (F12, -f) keeps its
    passes too; Apply then re-tunes them in memory."""
    bpy.ops.wm.open_mainfile(filepath=blend)
    scene = bpy.context.scene
    scene.sss.output_dir = str(tmp_path)
    scene.sss.enabled = True
    assert bpy.ops.render.render() == {'FINISHED'}
    entry = live.kept(scene)
    assert entry is not None and entry.view_layer == \
        bpy.context.view_layer.name
    scale_radius(scene, 3.0)
    assert bpy.ops.sss.apply() == {'FINISHED'}
    assert live.kept(scene).timings["scatter"] >= 0.0
    image, _ = shown_pixels(scene)
    assert image.name == live.image_name(scene)


def test_image_node_of_a_farm_render(blend, tmp_path):
    """A multilayer EXR of passes on a compositor Image node (a farm's
    render) scatters with the description beside it, live: the open
    scene's radius scale re-tunes it."""
    scene = open_rendered(blend, tmp_path)
    passes, _, desc = pipeline.paths_for(scene, scene.frame_current)
    assert live.description_beside(passes) == desc
    bpy.ops.wm.open_mainfile(filepath=blend)
    scene = bpy.context.scene
    tree = compat.compositor_tree(scene, create=True)
    node = tree.nodes.new("CompositorNodeImage")
    node.image = bpy.data.images.load(passes)
    tree.nodes.active = node
    assert nodes.image_node_file(node) == passes
    assert bpy.ops.sss.scatter_image() == {'FINISHED'}
    entry = live.kept(scene)
    assert entry is not None and entry.fixed is not None
    _, shown = shown_pixels(scene)
    out = str(tmp_path / "farm.exr")
    proc = subprocess.run([os.path.join(BUILD, "sss"), passes, "-o", out,
                           "--scene", desc, "-q"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    ch, _ = read_channels(out)
    want = np.stack([ch[f"SSS.Combined.{c}"] for c in "RGBA"], -1)
    assert np.abs(shown - want).max() <= 1e-5
    # 0: no scattering (the one other scale a baked back light allows).
    scene.sss.radius_scale = 0.0
    assert live.retune(scene)["scatter"] >= 0.0
    _, plain = shown_pixels(scene)
    assert not np.allclose(plain, want, atol=1e-4)


def test_image_node_without_passes_is_refused(blend, tmp_path):
    bpy.ops.wm.open_mainfile(filepath=blend)
    scene = bpy.context.scene
    tree = compat.compositor_tree(scene, create=True)
    node = tree.nodes.new("CompositorNodeImage")
    tree.nodes.active = node
    assert not bpy.ops.sss.scatter_image.poll()
    path = str(tmp_path / "plain.exr")
    image = bpy.data.images.new("plain", 4, 4, float_buffer=True)
    image.filepath_raw = path
    image.file_format = 'OPEN_EXR'
    image.save()
    with pytest.raises(pipeline.SSSError, match="DiffDir"):
        live.keep_file(scene, path)
    assert live.kept(scene) is None


def test_own_settings_schedule_a_retune(blend, tmp_path):
    """The add-on's own settings tell the live loop of a change (Blender's
    depsgraph does not report them); settings that do not change the
    scatter do not."""
    scene = open_rendered(blend, tmp_path)
    mat = principled(scene).id_data
    mat = next(m for m in bpy.data.materials if m.node_tree == mat) \
        if not isinstance(mat, bpy.types.Material) else mat
    for owner, name, value in ((mat.sss, "radius_scale", 2.0),
                               (scene.sss, "method", 'SEPARABLE'),
                               (scene.sss, "radius_scale", 0.0)):
        live._pending.clear()
        setattr(owner, name, value)
        assert scene.name in live._pending, name
    live._pending.clear()
    scene.sss.output_dir = str(tmp_path / "elsewhere")
    assert scene.name not in live._pending
    live._pending[scene.name] = 0.0
    settle()
    assert live.kept(scene).timings["scatter"] >= 0.0


def test_back_light_keeps_the_rendered_radius(blend, tmp_path):
    """A back light rendered at the scene's radius scale (the Burley
    transmission bakes it) cannot follow another scale: a re-tune at one
    says so and names what to do, and 0 (no scattering) still goes."""
    scene = open_rendered(blend, tmp_path)
    entry = live.kept(scene)
    if not entry.baked:
        pytest.skip("no material of this scene bakes its back light")
    assert set(entry.baked.values()) == {1.0}
    scene.sss.radius_scale = 2.0
    with pytest.raises(pipeline.SSSError, match="render it again"):
        live.retune(scene)
    live._pending[scene.name] = 0.0
    settle()
    assert "render it again" in live.last_error[scene.name]
    scene.sss.radius_scale = 0.0
    assert live.retune(scene)["scatter"] >= 0.0
    assert scene.name not in live.last_error


def test_background_retune_shows_when_done(blend, tmp_path):
    """The live loop scatters in a worker thread and shows the result on
    the main thread once done: the same pixels as Apply's scatter, and a
    change made meanwhile is scattered after it; freeing the passes waits
    for a running scatter."""
    scene = open_rendered(blend, tmp_path)
    live._pending.clear()
    scale_radius(scene, 3.0)
    live._pending[scene.name] = 0.0
    assert live._settled() == live.POLL_SECONDS     # started, running
    entry = live.kept(scene)
    assert entry.job is not None
    scale_radius(scene, 1.5)                        # changed meanwhile
    live._pending[scene.name] = 0.0
    settle()
    assert entry.job is None and scene.name not in live._pending
    _, shown = shown_pixels(scene)
    background = shown.copy()
    assert bpy.ops.sss.apply() == {'FINISHED'}      # the same, in front
    _, again = shown_pixels(scene)
    assert np.array_equal(background, again)
    # Freeing the passes while a scatter runs waits for it.
    scale_radius(scene, 2.0)
    live._pending[scene.name] = 0.0
    live._settled()
    frame = entry.frame
    bpy.ops.wm.open_mainfile(filepath=blend)
    assert not frame._ptr and live.kept(bpy.context.scene) is None
