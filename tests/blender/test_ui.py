"""The add-on behaves as Blender's own tools do: Render with SSS is one undo
step, Apply SSS to Last Render is greyed out (with the reason) when there
is no render it can use, and every zero-means-automatic setting resolves
to a value the panels can show."""
import os

import bpy
import pytest

from helpers import build_blend, compat, load_addon, registered

separable_sss = load_addon()
from separable_sss import native, nodes, pipeline, transmission  # noqa: E402,E501
from separable_sss.properties import method_items  # noqa: E402


addon = registered(separable_sss)


@pytest.fixture(scope="module")
def blend(tmp_path_factory):
    return build_blend("two", str(tmp_path_factory.mktemp("b") / "two.blend"))


def open_scene(path, out_dir):
    bpy.ops.wm.open_mainfile(filepath=path)
    scene = bpy.context.scene
    scene.sss.output_dir = str(out_dir)
    return scene


def test_render_with_sss_is_one_undo_step(blend, tmp_path):
    scene = open_scene(blend, tmp_path)
    bpy.ops.ed.undo_push(message="before")
    assert nodes.find_result(scene) is None
    # As a button does it: an undo step if the operator asks for one.
    assert bpy.ops.sss.render('EXEC_DEFAULT', True) == {'FINISHED'}
    node = nodes.find_result(bpy.context.scene)
    assert node is not None and node.image.source == 'GENERATED'
    bpy.ops.ed.undo()
    scene = bpy.context.scene
    assert nodes.find_result(scene) is None, "undo left the SSS nodes"
    bpy.ops.ed.redo()
    assert nodes.find_result(bpy.context.scene) is not None


def test_apply_greyed_out_without_a_usable_render(blend, tmp_path):
    scene = open_scene(blend, tmp_path)
    for image in [i for i in bpy.data.images if i.type == 'RENDER_RESULT']:
        bpy.data.images.remove(image)
    assert not bpy.ops.sss.apply.poll()
    with pytest.raises(RuntimeError, match="no render yet"):
        bpy.ops.sss.apply()
    # A plain render without the passes the library reads.
    layer = scene.view_layers[0]
    layer.use_pass_material_index = False
    layer.use_pass_diffuse_direct = False
    scene.render.resolution_percentage = 25
    bpy.ops.render.render()
    assert not bpy.ops.sss.apply.poll()
    with pytest.raises(RuntimeError, match="Material Index"):
        bpy.ops.sss.apply()
    # Render with SSS renders them: Apply is available again.
    assert bpy.ops.sss.render() == {'FINISHED'}
    assert bpy.ops.sss.apply.poll()
    assert bpy.ops.sss.apply() == {'FINISHED'}


def test_automatic_values_resolve(blend, tmp_path):
    scene = open_scene(blend, tmp_path)
    scene.sss.transmission_samples = 0
    scene.cycles.samples = 40
    assert transmission.layer_samples(scene) == 10
    scene.sss.output_dir = ""
    assert pipeline.output_path(scene).endswith("separable_sss")
    # The method's summary the panel shows is the library's.
    assert all(len(item[2]) < 80 for item in method_items())


def test_compositor_nodes_left_unselected(blend, tmp_path):
    scene = open_scene(blend, tmp_path)
    assert bpy.ops.sss.render() == {'FINISHED'}
    tree = compat.compositor_tree(scene)
    ours = [n for n in tree.nodes if n.get(nodes.ROLE_KEY)]
    assert ours and not any(n.select for n in ours)


def test_preferences_name_the_library():
    native.set_preferred_path("/opt/sss/libsss.so")
    try:
        paths = list(native.candidates())
        # $SSS_LIB first (farms set it), then the preference.
        first = 1 if os.environ.get("SSS_LIB") else 0
        assert paths.index("/opt/sss/libsss.so") == first
    finally:
        native.set_preferred_path("")
    assert "/opt/sss/libsss.so" not in native.candidates()
    assert native.loaded_path() is None or native.loaded_path().endswith(
        "libsss.so")


def test_progress_is_the_librarys(blend, tmp_path):
    """The progress bar follows the library's stages, not the clock."""
    open_scene(blend, tmp_path)
    job = pipeline.prepare_render(bpy.context)
    seen = []
    pipeline.scatter(job, progress=lambda stage, done: seen.append(
        (stage, done)))
    assert [s for s, _ in seen][0] == "read" and seen[-1] == ("write", 1.0)
    stages = [s for s, _ in seen]
    assert stages.index("scatter") > stages.index("read")
    assert stages.index("write") > stages.index("scatter")
    writes = [d for s, d in seen if s == "write"]
    assert writes == sorted(writes) and writes[0] == 0.0
