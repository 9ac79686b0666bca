"""The packaged add-on: installed from the zip into an empty user scripts
folder, enabled, and used the way an artist or a farm would."""
import os
import subprocess

import addon_utils
import bpy
import numpy as np
import pytest

import faults
from helpers import BLENDER, build_blend, compat, diff, snapshot
from exr import pass_rgb, read_channels

ZIP = os.environ.get("SSS_ADDON_ZIP")


@pytest.fixture(scope="module", autouse=True)
def installed():
    if not ZIP or not os.path.exists(ZIP):
        pytest.fail("SSS_ADDON_ZIP is not set: run through make blender-test")
    os.environ.pop("SSS_LIB", None)  # the zip's own library must be used
    scripts = os.environ.get("BLENDER_USER_SCRIPTS", "")
    assert scripts and not os.listdir(scripts), "user scripts not empty"
    bpy.ops.preferences.addon_install(filepath=ZIP)
    addon_utils.enable("separable_sss", default_set=True)
    module = __import__("separable_sss")
    assert module.__file__.startswith(scripts), module.__file__
    yield
    addon_utils.disable("separable_sss")


@pytest.fixture(scope="module")
def blends(tmp_path_factory):
    d = tmp_path_factory.mktemp("blends")
    return {kind: build_blend(kind, str(d / f"{kind}.blend"))
            for kind in ("two", "none")}


def result_wiring(scene):
    """The Image node holding the result and the names of the nodes its
    output reaches."""
    from separable_sss import nodes
    node = nodes.find_result(scene)
    assert node is not None, "no SSS result node"
    reached, todo = set(), [node]
    while todo:
        n = todo.pop()
        for out in n.outputs:
            for link in out.links:
                if link.to_node.name not in reached:
                    reached.add(link.to_node.name)
                    todo.append(link.to_node)
    return node, reached


def test_render_operator(blends, tmp_path):
    bpy.ops.wm.open_mainfile(filepath=blends["two"])
    scene = bpy.context.scene
    scene.sss.output_dir = str(tmp_path)
    before = snapshot(scene)
    assert bpy.ops.sss.render() == {"FINISHED"}
    # The result is shown from memory: no file is written for it.
    assert scene.sss.last_result == ""
    assert not any(name.endswith("_sss.exr") for name in os.listdir(tmp_path))
    node, reached = result_wiring(scene)
    assert node.image.source == 'GENERATED' and node.image.is_float
    composite = compat.composite_input(compat.compositor_tree(scene),
                                       create=False)
    assert composite is not None and composite.node.name in reached
    after = snapshot(scene)
    after["node_tree"] = before["node_tree"]  # the set-up was added
    assert diff(before, after) == []
    # Save SSS Result writes it, as the sss command would.
    result = str(tmp_path / "saved.exr")
    assert bpy.ops.sss.save_result(filepath=result) == {"FINISHED"}
    assert scene.sss.last_result == result
    ch, _ = read_channels(result)
    shown = np.empty(node.image.size[0] * node.image.size[1] * 4, np.float32)
    node.image.pixels.foreach_get(shown)
    shown = shown.reshape(node.image.size[1], node.image.size[0], 4)[::-1]
    assert np.abs(shown[..., :3] - pass_rgb(ch, "SSS.Combined")).max() < 1e-5
    index = ch["ViewLayer.IndexMA.X"]
    changed = np.abs(pass_rgb(ch, "SSS.Combined") -
                     pass_rgb(ch, "ViewLayer.Combined")).max(-1) > 1e-5
    assert changed.any()
    assert np.all(index[changed] > 0), "a plain pixel changed"
    # Running it again reuses the set-up instead of adding nodes.
    count = len(compat.compositor_tree(scene).nodes)
    assert bpy.ops.sss.apply() == {"FINISHED"}
    assert len(compat.compositor_tree(scene).nodes) == count


def test_nothing_scatters(blends, tmp_path):
    bpy.ops.wm.open_mainfile(filepath=blends["none"])
    scene = bpy.context.scene
    scene.sss.output_dir = str(tmp_path)
    before = snapshot(scene)
    assert bpy.ops.sss.render() == {"CANCELLED"}
    assert diff(before, snapshot(scene)) == []
    assert os.listdir(tmp_path) == []


def test_library_error_is_one_line_and_restores(blends, tmp_path,
                                                monkeypatch):
    bpy.ops.wm.open_mainfile(filepath=blends["two"])
    scene = bpy.context.scene
    scene.sss.output_dir = str(tmp_path)
    before = snapshot(scene)
    import separable_sss.pipeline  # the installed add-on's
    faults.library_refuses(monkeypatch, separable_sss.pipeline)
    # Called from Python, an operator's ERROR report becomes a RuntimeError
    # carrying the report's text: one line, the library's own message.
    with pytest.raises(RuntimeError) as err:
        bpy.ops.sss.render()
    message = str(err.value).strip()
    assert "radius scale" in message and "\n" not in message
    assert "Traceback" not in message
    assert diff(before, snapshot(scene)) == []


def test_animation_render_with_the_switch(blends, tmp_path):
    """blender -b scene.blend -a with the installed add-on and the scene's
    Screen-space SSS on: every frame is written by Blender, scattered (a
    line per frame says so), and the .blend is untouched."""
    bpy.ops.wm.open_mainfile(filepath=blends["two"])
    scene = bpy.context.scene
    scene.sss.enabled = True
    scene.sss.output_dir = str(tmp_path)
    scene.frame_start, scene.frame_end = 1, 2
    scene.render.filepath = str(tmp_path / "frame_####")
    scene.render.image_settings.file_format = 'PNG'
    scene.cycles.samples = 2
    path = str(tmp_path / "anim.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    before = open(path, "rb").read()
    proc = subprocess.run(
        [BLENDER, "-b", path, "--python-expr",
         "import addon_utils; addon_utils.enable('separable_sss')", "-a"],
        capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    for f in (1, 2):
        assert (tmp_path / f"frame_{f:04d}.png").exists()
        assert f"frame {f}, view layer ViewLayer" in proc.stdout
    assert open(path, "rb").read() == before
