"""The extension (Blender 4.2 and later): installed with Blender's own
operator into an empty user folder, enabled, and used on a scene made here
with the Principled BSDF v2 (Subsurface Weight, Scale and Radius; a second
material whose Base Color is a texture)."""
import os
import sys

import bpy
import numpy as np
import pytest

from helpers import compat, diff, snapshot
from exr import pass_rgb, read_channels

ZIP = os.environ.get("SSS_EXTENSION_ZIP")
MODULE = "bl_ext.user_default.separable_sss"

pytestmark = pytest.mark.skipif(
    not compat.EXTENSIONS, reason="no extensions before Blender 4.2: "
    "test_install.py installs the legacy add-on there")


@pytest.fixture(scope="module", autouse=True)
def installed():
    if not ZIP or not os.path.exists(ZIP):
        pytest.fail("SSS_EXTENSION_ZIP is not set: run through make "
                    "blender-test")
    os.environ.pop("SSS_LIB", None)  # the wheel's library must be used
    user = bpy.utils.user_resource('EXTENSIONS')
    assert os.environ.get("BLENDER_USER_RESOURCES") and \
        user.startswith(os.environ["BLENDER_USER_RESOURCES"]), user
    assert not os.path.exists(os.path.join(user, "user_default",
                                           "separable_sss"))
    assert bpy.ops.extensions.package_install_files(
        filepath=ZIP, repo="user_default", enable_on_install=True) == \
        {'FINISHED'}
    assert MODULE in bpy.context.preferences.addons.keys()
    yield sys.modules[MODULE]
    bpy.ops.extensions.package_uninstall(repo_index=_repo_index(),
                                         pkg_id="separable_sss")


def _repo_index():
    repos = bpy.context.preferences.extensions.repos
    return [r.module for r in repos].index("user_default")


def test_library_comes_from_the_wheel(installed):
    lib = installed.native.library()
    site = os.path.join(bpy.utils.user_resource('EXTENSIONS'), ".local")
    assert lib._name.startswith(site) and \
        os.sep + "libsss_native" + os.sep in lib._name, lib._name


def build_v2_scene(path):
    """Two spheres on a floor under a sun: Skin (Weight 1, Scale 0.05,
    Radius (1, 0.2, 0.1)) and Textured (the same with a noise texture on
    Base Color)."""
    scene = bpy.context.scene      # emptied (factory settings would
    for obj in list(bpy.data.objects):  # disable the extension)
        bpy.data.objects.remove(obj, do_unlink=True)
    materials = []
    for name in ("Skin", "Textured"):
        mat = bpy.data.materials.new(name)
        tree = compat.ensure_nodes(mat)
        bsdf = tree.nodes["Principled BSDF"]
        compat.principled_input(bsdf, "base").default_value = \
            (0.8, 0.5, 0.4, 1.0)
        compat.principled_input(bsdf, "subsurface").default_value = 1.0
        compat.principled_input(bsdf, "subsurface_scale").default_value = \
            0.05
        compat.principled_input(bsdf, "subsurface_radius").default_value = \
            (1.0, 0.2, 0.1)
        if name == "Textured":
            noise = tree.nodes.new("ShaderNodeTexNoise")
            tree.links.new(noise.outputs["Color"],
                           compat.principled_input(bsdf, "base"))
        materials.append(mat)
    floor = bpy.data.materials.new("Floor")
    compat.ensure_nodes(floor)
    for mat, x in zip(materials, (-0.3, 0.3)):
        bpy.ops.mesh.primitive_uv_sphere_add(radius=0.25, location=(x, 0, 0))
        bpy.context.active_object.data.materials.append(mat)
    bpy.ops.mesh.primitive_plane_add(size=4, location=(0, 0, -0.25))
    bpy.context.active_object.data.materials.append(floor)
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy = 3.0
    sun.rotation_euler = (0.7, 0.2, 0.5)
    scene.collection.objects.link(sun)
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.location = (0.0, -2.0, 0.3)
    cam.rotation_euler = (1.45, 0.0, 0.0)
    scene.collection.objects.link(cam)
    scene.camera = cam
    scene.world = bpy.data.worlds.new("World")
    scene.render.engine = "CYCLES"
    scene.render.resolution_x, scene.render.resolution_y = 64, 48
    scene.render.resolution_percentage = 100
    scene.cycles.samples = 4
    scene.cycles.device = "CPU"
    scene.cycles.use_denoising = False
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.open_mainfile(filepath=path)
    return bpy.context.scene


def test_render_principled_v2(tmp_path):
    scene = build_v2_scene(str(tmp_path / "v2.blend"))
    scene.sss.output_dir = str(tmp_path / "out")
    before = snapshot(scene)
    assert bpy.ops.sss.render() == {'FINISHED'}
    after = snapshot(scene)
    after["node_tree"] = before["node_tree"]   # the result set-up was added
    assert diff(before, after) == []
    result = str(tmp_path / "saved.exr")
    assert bpy.ops.sss.save_result(filepath=result) == {'FINISHED'}
    assert scene.sss.last_result == result and os.path.exists(result)
    # The composite shows the SSS result.
    composite = compat.composite_input(compat.compositor_tree(scene),
                                       create=False)
    assert composite is not None and composite.is_linked
    ch, _ = read_channels(result)
    index = ch["ViewLayer.IndexMA.X"] if "ViewLayer.IndexMA.X" in ch \
        else ch["ViewLayer.Material Index.X"]
    changed = np.abs(pass_rgb(ch, "SSS.Combined") -
                     pass_rgb(ch, "ViewLayer.Combined")).max(-1) > 1e-5
    indices = {m.pass_index for m in bpy.data.materials
               if m.name in ("Skin", "Textured")}
    assert indices == {0}       # the indices the render used are gone again
    assert changed.mean() > 0.05
    assert np.all(index[changed] > 0), "a plain pixel changed"
    assert len(np.unique(index[changed])) == 2, "both materials scatter"
