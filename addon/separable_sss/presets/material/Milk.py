# Separable SSS material preset: Milk.
# Jensen, Marschner, Levoy and Hanrahan 2001, table of measured coefficients
# (Skimmilk): radius = 1/sigma_tr (mm, here in metres) as the diffuse mean
# free path, albedo = alpha'.
import bpy
material = getattr(bpy.context, "material", None) or \
    bpy.context.object.active_material

material.sss.profile = 'BURLEY'
material.sss.mapping = 'RANDOM_WALK'
material.sss.radius = (0.01840, 0.01040, 0.00350)
material.sss.albedo = (0.998, 0.998, 0.9926)
material.sss.radius_scale = 1.0
material.sss.strength = 1.0
material.sss.texturing = 'POST'
