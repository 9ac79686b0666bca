# Separable SSS material preset: Jade.
# Not measured by Jensen et al.: chosen by eye. Green-tinted, with a long
# mean free path in green so thin edges glow green.
import bpy
material = getattr(bpy.context, "material", None) or \
    bpy.context.object.active_material

material.sss.profile = 'BURLEY'
material.sss.mapping = 'RANDOM_WALK'
material.sss.radius = (0.00500, 0.01200, 0.00600)
material.sss.albedo = (0.8, 0.95, 0.85)
material.sss.radius_scale = 1.0
material.sss.strength = 1.0
material.sss.texturing = 'POST'
# Transmission: Beer-Lambert, green seen through 1 cm of jade.
material.sss.transmission = 'BEER_LAMBERT'
material.sss.transmission_strength = 1.0
material.sss.transmission_color = (0.35, 0.8, 0.5)
material.sss.transmission_distance = 0.01
material.sss.transmission_translucency = 0.83
material.sss.transmission_distortion = 0.2
material.sss.transmission_power = 4.0
material.sss.transmission_scale = 1.0
material.sss.transmission_ambient = 0.0
material.sss.thickness_scale = 1.0
