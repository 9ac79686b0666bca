"""Which scattering objects Cycles' random walk will not follow the way
libsss does: a mesh with holes, or with loose parts in one object.

Cycles' random walk scatters inside the object's mesh and leaves it
through any of its surfaces. Its manual asks for closed meshes ("Overlapping
faces and holes in the mesh can cause problems"), and where eyes, teeth or
a mouth are loose parts of a head's mesh, the walk leaves the skin
through them and darkens it round them. libsss follows the surfaces the
camera sees, so on such meshes the two differ by design (docs/
comparison.md, "The head's eyes"). make compare and the error budget
print one note per such object, so that a difference is read for what it
is.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__))), "addon"))


def _parts(edges, vertex_count):
    """How many connected parts the edges (n x 2 vertex indices) make of
    the vertices they touch."""
    if not len(edges):
        return 0
    label = np.arange(vertex_count)
    while True:  # the smallest label of each part, by pointer jumping
        low = np.minimum(label[edges[:, 0]], label[edges[:, 1]])
        new = label.copy()
        np.minimum.at(new, edges[:, 0], low)
        np.minimum.at(new, edges[:, 1], low)
        new = new[new]
        if np.array_equal(new, label):
            break
        label = new
    used = np.unique(edges)
    return int(len(np.unique(label[used])))


def mesh_facts(obj, depsgraph):
    """(edges on one face only, edges on more than two, loose parts) of
    the object's evaluated mesh; None where it has no faces."""
    from separable_sss.transmission import edge_faces, evaluated_mesh
    with evaluated_mesh(obj, depsgraph) as mesh:
        if mesh is None:
            return None
        faces = edge_faces(mesh)
        verts = np.empty(len(mesh.edges) * 2, np.int64)
        mesh.edges.foreach_get("vertices", verts)
        used = faces > 0
        parts = _parts(verts.reshape(-1, 2)[used], len(mesh.vertices))
        return (int(np.count_nonzero(faces == 1)),
                int(np.count_nonzero(faces > 2)), parts)


def notes(scene, materials):
    """One sentence per rendered mesh object that has one of `materials`
    (bpy.types.Material) and holes, edges of more than two faces or more
    than one loose part; [] when every such mesh is closed and whole."""
    import bpy
    depsgraph = bpy.context.evaluated_depsgraph_get()
    wanted = set(m.name for m in materials)
    out = []
    for obj in sorted(scene.objects, key=lambda o: o.name):
        if obj.type != "MESH" or obj.hide_render:
            continue
        if not any(slot.material and slot.material.name in wanted
                   for slot in obj.material_slots):
            continue
        facts = mesh_facts(obj, depsgraph)
        if facts is None:
            continue
        open_edges, shared, parts = facts
        what = []
        if open_edges:
            what.append(f"{open_edges} edges on one face only (holes)")
        if shared:
            what.append(f"{shared} edges on more than two faces")
        if parts > 1:
            what.append(f"{parts} loose parts")
        if what:
            out.append(f"{obj.name}: " + ", ".join(what) + ": Cycles' "
                       "random walk leaves the object through them, which "
                       "libsss does not follow (give loose parts objects "
                       "of their own and close the mesh to compare)")
    return out
