"""Shared helpers for the tests that run inside Blender."""
import os
import subprocess
import sys

import bpy

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
BUILD = os.environ.get("SSS_BUILD", os.path.join(ROOT, "build"))
sys.path.insert(0, os.path.join(ROOT, "tests", "python"))  # exr helpers
# The version differences, without importing (registering) the add-on.
sys.path.insert(0, os.path.join(ROOT, "addon", "separable_sss"))
import blender_compat as compat  # noqa: E402

# The Blender running these tests, for the ones that start another: a
# `blender` binary, or the bpy module's command line.
BLENDER = compat.blender_command()


def load_addon():
    """The add-on from the source tree, on the library just built (not an
    installed copy: test_install.py covers that)."""
    os.environ.setdefault("SSS_LIB", os.path.join(BUILD, "libsss.so"))
    if os.path.join(ROOT, "addon") not in sys.path:
        sys.path.insert(0, os.path.join(ROOT, "addon"))
    import separable_sss
    return separable_sss


def registered(addon):
    """A module-scoped autouse fixture (assign it to a name in the test
    module): the add-on registered for the module's tests, unregistered
    after them."""
    import pytest

    @pytest.fixture(scope="module", autouse=True)
    def fixture():
        addon.register()
        yield
        addon.unregister()
    return fixture


def build_blend(kind, path, size=96, samples=8):
    """A scene from blender_scripts/build_scene.py, in its own process so
    this one's data is untouched."""
    proc = subprocess.run(
        [BLENDER, "-b", "--factory-startup",
         "--python-exit-code", "1", "--python",
         os.path.join(ROOT, "blender_scripts", "build_scene.py"), "--",
         "--kind", kind, "--out", path, "--size", str(size), "--samples",
         str(samples)], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    return path


def _value(sock):
    v = getattr(sock, "default_value", None)
    if v is None or isinstance(v, (bool, int, float, str)):
        return v
    try:
        return tuple(v)
    except TypeError:
        return repr(v)


def snapshot(scene):
    """Everything the add-on may touch, as plain comparable data."""
    data = {}
    for mat in bpy.data.materials:
        entry = {"pass_index": mat.pass_index,
                 "use_nodes": compat.uses_nodes(mat)}
        if mat.node_tree:
            tree = mat.node_tree
            entry["nodes"] = {
                n.name: (n.bl_idname, n.label, tuple(n.location),
                         tuple((s.identifier, _value(s)) for s in n.inputs),
                         getattr(n, "subsurface_method", None),
                         getattr(n, "blend_type", None))
                for n in tree.nodes}
            entry["links"] = sorted(
                (l.from_node.name, l.from_socket.identifier,
                 l.to_node.name, l.to_socket.identifier)
                for l in tree.links)
        data["material:" + mat.name] = entry
    for layer in scene.view_layers:
        data["layer:" + layer.name] = {
            a: getattr(layer, a) for a in dir(layer)
            if a.startswith("use_pass_")}
    s = scene.render.image_settings
    data["image_settings"] = compat.image_settings_state(s)
    r = scene.render
    data["render"] = (r.engine, r.resolution_x, r.resolution_y,
                      r.resolution_percentage, r.filepath,
                      r.film_transparent, scene.cycles.samples)
    tree = compat.compositor_tree(scene)
    data["node_tree"] = None if tree is None else sorted(
        (n.name, n.bl_idname) for n in tree.nodes)
    return data


def diff(a, b):
    """Human-readable differences between two snapshots."""
    out = []
    for key in sorted(set(a) | set(b)):
        if a.get(key) != b.get(key):
            out.append(f"{key}: {a.get(key)!r} != {b.get(key)!r}"[:600])
    return out
