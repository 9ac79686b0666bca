# Separable SSS material preset: Leaf/Paper.
# Thin sheets (leaves, paper lanterns, lamp shades): barely any blur in
# front, and most of the light behind crosses, yellow-green for a leaf
# (chosen by eye). Beer-Lambert: the colour seen through 0.5 mm.
import bpy
material = getattr(bpy.context, "material", None) or \
    bpy.context.object.active_material

material.sss.profile = 'BURLEY'
material.sss.mapping = 'RANDOM_WALK'
material.sss.radius = (0.00100, 0.00100, 0.00060)
material.sss.albedo = (0.8, 0.85, 0.6)
material.sss.radius_scale = 1.0
material.sss.strength = 1.0
material.sss.texturing = 'POST'
material.sss.transmission = 'BEER_LAMBERT'
material.sss.transmission_strength = 0.8
material.sss.transmission_color = (0.7, 0.85, 0.35)
material.sss.transmission_distance = 0.0005
material.sss.transmission_translucency = 0.83
material.sss.transmission_distortion = 0.2
material.sss.transmission_power = 4.0
material.sss.transmission_scale = 1.0
material.sss.transmission_ambient = 0.0
material.sss.thickness_scale = 1.0
