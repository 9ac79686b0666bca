# Separable SSS material preset: Ketchup.
# Jensen, Marschner, Levoy and Hanrahan 2001, table of measured coefficients
# (Ketchup): radius = 1/sigma_tr (mm, here in metres) as the diffuse mean
# free path, albedo = alpha'.
import bpy
material = getattr(bpy.context, "material", None) or \
    bpy.context.object.active_material

material.sss.profile = 'BURLEY'
material.sss.mapping = 'RANDOM_WALK'
material.sss.radius = (0.00476, 0.00057, 0.00039)
material.sss.albedo = (0.747, 0.067, 0.02)
material.sss.radius_scale = 1.0
material.sss.strength = 1.0
material.sss.texturing = 'POST'
