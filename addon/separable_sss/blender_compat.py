"""Names that change between Blender versions, in one place, so a port to
4.x (where the Principled BSDF's inputs were renamed: "Subsurface Weight",
"Subsurface Scale", "Emission Color", "Transmission Weight", and the
diffuse colour is no longer mixed with a Subsurface Color) edits only this
file. These are Blender 3.4's."""
PRINCIPLED = {
    "base": "Base Color",
    "subsurface": "Subsurface",          # factor; also scales the radius
    "subsurface_radius": "Subsurface Radius",
    "subsurface_color": "Subsurface Color",
    "emission": "Emission",
    "emission_strength": "Emission Strength",
    "transmission": "Transmission",
}


def principled_input(node, key):
    """The Principled BSDF's input socket for a version-independent key."""
    return node.inputs[PRINCIPLED[key]]
