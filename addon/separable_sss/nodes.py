"""The compositor set-up that shows an SSS result: an Image node on the
result's SSS layer, an "SSS Composite" group (exposure, for grading) and the
Composite and Viewer outputs. Building it twice reuses the same nodes; user
nodes are never deleted."""
import bpy

from . import blender_compat as compat
from .errors import SSSError

RESULT_NAME = "SSS Result"
GROUP_NAME = "SSS Composite"       # both the group node and its node tree
VIEWER_NAME = "SSS Viewer"
ROLE_KEY = "sss_role"              # custom property that marks our nodes

RESULT_LAYER = "SSS"                # SSS_RESULT_LAYER in csrc/sss.h
RESULT_PASS = "Combined"


def _find(tree, role, name, idname):
    """Our node for `role`: marked by the custom property, else by name and
    type (a set-up made before the marker, or a renamed marker)."""
    for node in tree.nodes:
        if node.get(ROLE_KEY) == role and node.bl_idname == idname:
            return node
    node = tree.nodes.get(name)
    if node is not None and node.bl_idname == idname:
        node[ROLE_KEY] = role
        return node
    return None


def _new(tree, role, name, idname, location):
    node = tree.nodes.new(idname)
    node.name = name
    node.label = name
    node.location = location
    node[ROLE_KEY] = role
    return node


def _first(tree, idname):
    for node in tree.nodes:
        if node.bl_idname == idname:
            return node
    return None


def _link(tree, from_socket, to_socket):
    """Link unless the same link is already there (links.new replaces any
    other link into `to_socket`, which is what we want)."""
    for link in to_socket.links:
        if link.from_socket == from_socket:
            return link
    return tree.links.new(from_socket, to_socket)


def _ensure_group_tree():
    """The "SSS Composite" node tree: Image -> Exposure -> Image. An existing
    tree of that name is reused as is, so artists' edits survive."""
    tree = bpy.data.node_groups.get(GROUP_NAME)
    if tree is not None and tree.bl_idname == "CompositorNodeTree":
        return tree
    tree = bpy.data.node_groups.new(GROUP_NAME, "CompositorNodeTree")
    compat.new_group_socket(tree, 'INPUT', "NodeSocketColor", "Image")
    exposure = compat.new_group_socket(tree, 'INPUT', "NodeSocketFloat",
                                       "Exposure")
    exposure.default_value = 0.0
    exposure.min_value = -10.0
    exposure.max_value = 10.0
    compat.new_group_socket(tree, 'OUTPUT', "NodeSocketColor", "Image")

    group_in = tree.nodes.new("NodeGroupInput")
    group_in.location = (-300.0, 0.0)
    grade = tree.nodes.new("CompositorNodeExposure")
    grade.location = (0.0, 0.0)
    group_out = tree.nodes.new("NodeGroupOutput")
    group_out.location = (250.0, 0.0)
    tree.links.new(group_in.outputs["Image"], grade.inputs["Image"])
    tree.links.new(group_in.outputs["Exposure"], grade.inputs["Exposure"])
    tree.links.new(grade.outputs["Image"], group_out.inputs["Image"])
    return tree


def _show_layer(node, image):
    """Point `node` at `image` and, for a multilayer image, at the SSS layer.
    Returns the output socket carrying the SSS Combined pass.

    In Blender 3.4 the Image node of a multilayer EXR has a `layer` enum whose
    items are the file's layers (read when `node.image` is set), and one output
    socket per pass of the chosen layer, named after the pass ("Combined",
    "Alpha", "DiffLight")."""
    node.image = image
    if image.type == 'MULTILAYER' or getattr(node, "has_layers", False):
        try:
            node.layer = RESULT_LAYER
        except TypeError as ex:
            found = str(ex).partition(" not found in ")[2]
            raise ValueError(
                "%s has no %s layer (layers: %s)"
                % (bpy.path.basename(image.filepath) or image.name,
                   RESULT_LAYER, found or "none")) from None
        socket = node.outputs.get(RESULT_PASS)
        if socket is None or not socket.enabled:
            raise ValueError("%s has no %s.%s pass" % (
                image.name, RESULT_LAYER, RESULT_PASS))
        return socket
    socket = node.outputs.get("Image")
    return socket if socket is not None else node.outputs[0]


def ensure_setup(scene, image):
    """Build or update the SSS result set-up in `scene`'s compositor and
    return its Image node. Calling it again reuses the same nodes."""
    tree = compat.compositor_tree(scene, create=True)
    if tree is None:
        raise SSSError("The scene has no compositor node tree")

    render_layers = _first(tree, "CompositorNodeRLayers")
    base_x, base_y = ((render_layers.location.x, render_layers.location.y)
                      if render_layers is not None else (0.0, 0.0))
    # Below the Render Layers node, whose height grows with its passes
    # (node.dimensions is only known once drawn).
    sockets = len([o for o in render_layers.outputs if o.enabled]) \
        if render_layers is not None else 0
    y = base_y - max(450.0, 60.0 + 22.0 * sockets)

    result = _find(tree, "result", RESULT_NAME, "CompositorNodeImage")
    created = result is None
    if created:
        result = _new(tree, "result", RESULT_NAME, "CompositorNodeImage",
                      (base_x, y))
    previous = result.image
    try:
        source = _show_layer(result, image)
    except ValueError as ex:
        if created:
            tree.nodes.remove(result)
        else:
            result.image = previous
        raise SSSError(str(ex)) from None

    if image.source == 'SEQUENCE':
        result.frame_start = scene.frame_start
        result.frame_duration = scene.frame_end - scene.frame_start + 1
        result.use_auto_refresh = True

    group = _find(tree, "group", GROUP_NAME, "CompositorNodeGroup")
    if group is None:
        group = _new(tree, "group", GROUP_NAME, "CompositorNodeGroup",
                     (base_x + 300.0, y))
    if group.node_tree is None:
        group.node_tree = _ensure_group_tree()
    group.width = max(group.width, 160.0)

    composite = compat.composite_input(tree, location=(base_x + 600.0, y))
    viewer = _find(tree, "viewer", VIEWER_NAME, "CompositorNodeViewer")
    if viewer is None:
        viewer = _new(tree, "viewer", VIEWER_NAME, "CompositorNodeViewer",
                      (base_x + 600.0, y - 200.0))
        tree.nodes.active = viewer          # the backdrop shows this one

    _link(tree, source, group.inputs[0])
    _link(tree, group.outputs[0], composite)
    _link(tree, group.outputs[0], viewer.inputs["Image"])
    # A run leaves the artist's selection as it was, not ours selected.
    for node in (result, group, viewer):
        node.select = False
    return result


def find_result(scene):
    """The SSS Image node of `scene`, or None."""
    tree = compat.compositor_tree(scene)
    if tree is None:
        return None
    for node in tree.nodes:
        if node.get(ROLE_KEY) == "result":
            return node
    return None


def remove_setup(scene):
    """Remove the SSS nodes (not the group's node tree, which may hold an
    artist's grading, nor the image). Where the Composite is left without an
    input, the Render Layers image goes back into it. Returns the number of
    nodes removed."""
    tree = compat.compositor_tree(scene)
    if tree is None:
        return 0
    ours = [node for node in tree.nodes
            if node.get(ROLE_KEY) in {"result", "group", "viewer"}]
    for node in ours:
        tree.nodes.remove(node)

    composite = compat.composite_input(tree, create=False)
    render_layers = _first(tree, "CompositorNodeRLayers")
    if (ours and composite is not None and render_layers is not None
            and not composite.is_linked):
        tree.links.new(render_layers.outputs["Image"], composite)
    return len(ours)


def image_node_file(node):
    """The multilayer EXR file a compositor Image node shows (this frame's
    for a sequence), or None."""
    if node is None or node.bl_idname != "CompositorNodeImage" or \
            node.image is None or node.image.type != 'MULTILAYER':
        return None
    image = node.image
    try:
        path = image.filepath_from_user(image_user=node.image_user)
    except (AttributeError, TypeError):
        path = image.filepath
    return bpy.path.abspath(path, library=image.library) or None
