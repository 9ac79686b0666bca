# Separable SSS material preset: Skin.
# Jensen, Marschner, Levoy and Hanrahan 2001, table of measured coefficients
# (Skin1): radius = 1/sigma_tr (mm, here in metres) as the diffuse mean free
# path, albedo = alpha'.
import bpy
material = getattr(bpy.context, "material", None) or \
    bpy.context.object.active_material

material.sss.profile = 'BURLEY'
material.sss.mapping = 'RANDOM_WALK'
material.sss.radius = (0.00367, 0.00137, 0.00068)
material.sss.albedo = (0.9585, 0.838, 0.678)
material.sss.radius_scale = 1.0
material.sss.strength = 1.0
material.sss.texturing = 'POST'
# Transmission: the profile's own (ears and fingers glow red).
material.sss.transmission = 'BURLEY'
material.sss.transmission_strength = 1.0
material.sss.transmission_color = (1, 1, 1)
material.sss.transmission_distance = 0.01
material.sss.transmission_translucency = 0.83
material.sss.transmission_distortion = 0.2
material.sss.transmission_power = 4.0
material.sss.transmission_scale = 1.0
material.sss.transmission_ambient = 0.0
material.sss.thickness_scale = 1.0
