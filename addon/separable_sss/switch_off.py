"""Render with material SSS switched off, without changing the look, and
put everything back exactly afterwards, also after an error or a cancelled
render.

In Blender 3.x the Principled BSDF's diffuse colour is
mix(Base Color, Subsurface Color, Subsurface): for the render, Base Color
becomes that mix (a Mix node when any of the three is linked to a texture;
nothing is baked) and Subsurface becomes 0. From 4.0 the diffuse colour is
Base Color: Subsurface Weight becomes 0 (unlinked if a texture drives it),
which is the render Cycles gives with Weight 0. A Subsurface Scattering node is
replaced by a Diffuse BSDF of the same colour and normal. The passes the
library reads are enabled on every view layer, and scattering materials
without a pass index get a free one."""
from contextlib import contextmanager

import bpy

from . import blender_compat as compat
from . import native, transmission
from .blender_compat import principled_input


def required_passes():
    """Blender's names (use_pass_<name>) of the passes the library needs
    of a Cycles render, from its own table (sss_render_pass): Apply SSS to
    Last Render checks that a render had them."""
    return tuple(p["blender"] for p in native.render_passes()
                 if p["need"] != "optional")


# What every render with SSS also asks for: with the required ones,
# whatever the scene holds; then the optional ones, as the scene needs.
GLOSSY_PASSES = ("glossy_direct", "glossy_indirect", "glossy_color")
OPTIONAL_PASSES = {"emit": "emits", "environment": None,
                   "transmission_direct": "transmits",
                   "transmission_indirect": "transmits",
                   "transmission_color": "transmits", "position": None}

TAG = "SSS switch-off"  # label of every node we add


class Undo:
    """A list of closures that put things back, run in reverse order."""

    def __init__(self):
        self.steps = []

    def set(self, obj, attr, value):
        old = getattr(obj, attr)
        if not isinstance(old, (bool, int, float, str)):
            old = tuple(old)  # a copy, not a view of the property
        self.steps.append(lambda: setattr(obj, attr, old))
        setattr(obj, attr, value)

    def add(self, fn):
        self.steps.append(fn)

    def run(self):
        errors = []
        while self.steps:
            step = self.steps.pop()
            try:
                step()
            except Exception as e:  # keep restoring the rest
                errors.append(str(e))
        return errors


def _link_source(sock):
    return sock.links[0].from_socket if sock.is_linked else None


def _relink(tree, undo, from_socket, to_socket):
    link = tree.links.new(from_socket, to_socket)
    undo.add(lambda: tree.links.remove(link))
    return link


def _unlink(tree, undo, sock):
    """Removes the link into sock; the undo step recreates it."""
    if not sock.is_linked:
        return
    source = sock.links[0].from_socket
    tree.links.remove(sock.links[0])
    undo.add(lambda: tree.links.new(source, sock))


def _new_node(tree, undo, kind, location):
    """A node of type kind (an idname, or a function of the tree that
    makes one) that the undo step removes."""
    node = kind(tree) if callable(kind) else tree.nodes.new(kind)
    node.label = TAG
    node.location = location
    undo.add(lambda: tree.nodes.remove(node))
    return node


def _switch_principled(tree, node, undo):
    factor = principled_input(node, "subsurface")
    if compat.PRINCIPLED_V2:
        _unlink(tree, undo, factor)
        undo.set(factor, "default_value", 0.0)
        return
    base = principled_input(node, "base")
    sscol = principled_input(node, "subsurface_color")
    if not (base.is_linked or sscol.is_linked or factor.is_linked):
        t = factor.default_value
        mixed = tuple(b + (s - b) * t for b, s in
                      zip(base.default_value, sscol.default_value))
        undo.set(base, "default_value", mixed)
        undo.set(factor, "default_value", 0.0)
        return
    mix = _new_node(tree, undo, compat.new_mix_rgb,
                    (node.location.x - 220, node.location.y))
    mix.blend_type = "MIX"
    for src, dst in ((factor, mix.inputs["Fac"]),
                     (base, mix.inputs["Color1"]),
                     (sscol, mix.inputs["Color2"])):
        if src.is_linked:
            _relink(tree, undo, _link_source(src), dst)
        else:
            dst.default_value = src.default_value
    _unlink(tree, undo, base)
    _relink(tree, undo, mix.outputs["Color"], base)
    _unlink(tree, undo, factor)
    undo.set(factor, "default_value", 0.0)


def _switch_sss_node(tree, node, undo):
    diffuse = _new_node(tree, undo, "ShaderNodeBsdfDiffuse",
                        (node.location.x, node.location.y - 200))
    for name in ("Color", "Normal"):
        src = node.inputs[name]
        if src.is_linked:
            _relink(tree, undo, _link_source(src), diffuse.inputs[name])
        elif name == "Color":
            diffuse.inputs[name].default_value = src.default_value
    for link in list(node.outputs[0].links):
        target = link.to_socket
        _unlink(tree, undo, target)
        _relink(tree, undo, diffuse.outputs[0], target)


def pass_indices(analysis):
    """The pass index each scattering material renders with, {material:
    index}: its own when it has one that no other material uses, else a
    free one. The one rule for the render, the description of its
    result (also a live re-tune's, which changes nothing) and the Assign
    Pass Indices operator. Another material's index is off limits, a
    non-scattering one's too: its pixels would scatter with this
    profile."""
    scattering = {f.material for f in analysis.materials}
    taken = {m.pass_index for m in bpy.data.materials
             if m not in scattering and m.pass_index}
    next_index = max(taken | {m.pass_index for m in scattering} | {0}) + 1
    used, out = set(), {}
    for found in analysis.materials:
        mat = found.material
        if mat in out:
            continue
        index = mat.pass_index
        if not index or index in taken or index in used:
            index = next_index
            next_index += 1
        used.add(index)
        out[mat] = index
    return out


def assign_pass_indices(analysis):
    """Sets every found material's pass index in the analysis (not on the
    material) by pass_indices(); returns the mapping."""
    indices = pass_indices(analysis)
    for found in analysis.materials:
        found.pass_index = indices[found.material]
    return indices


def _free_pass_indices(scene, analysis, undo):
    for mat, index in assign_pass_indices(analysis).items():
        if mat.pass_index != index:
            undo.set(mat, "pass_index", index)


def _enable_passes(scene, analysis, undo):
    for layer in scene.view_layers:
        for name in required_passes() + GLOSSY_PASSES:
            undo.set(layer, "use_pass_" + name, True)
        for name, needs in OPTIONAL_PASSES.items():
            if hasattr(layer, "use_pass_" + name) and (
                    needs is None or getattr(analysis, needs)):
                undo.set(layer, "use_pass_" + name, True)


@contextmanager
def switched_off(scene, analysis, backlight=True):
    """Within the block the scene renders without material SSS and with
    the passes libsss needs (and, with backlight, the back-light view layer
    when a transmitting material is lit from behind: transmission.py); on
    leaving (normally or by an exception) every changed value, link, node,
    layer and material is restored or removed."""
    undo = Undo()
    try:
        _free_pass_indices(scene, analysis, undo)
        _enable_passes(scene, analysis, undo)
        if backlight:
            transmission.add_layer(scene, analysis, undo)
        for found in analysis.materials:
            tree = found.material.node_tree
            if found.node.type == "BSDF_PRINCIPLED":
                _switch_principled(tree, found.node, undo)
            else:
                _switch_sss_node(tree, found.node, undo)
        yield undo
    finally:
        errors = undo.run()
        if errors:
            raise RuntimeError("could not restore the scene exactly: " +
                               "; ".join(errors))
