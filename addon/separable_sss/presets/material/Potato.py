# Separable SSS material preset: Potato.
# Jensen, Marschner, Levoy and Hanrahan 2001, table of measured coefficients
# (Potato): radius = 1/sigma_tr (mm, here in metres) as the diffuse mean
# free path, albedo = alpha'.
import bpy
material = getattr(bpy.context, "material", None) or \
    bpy.context.object.active_material

material.sss.profile = 'BURLEY'
material.sss.mapping = 'RANDOM_WALK'
material.sss.radius = (0.01430, 0.00723, 0.00204)
material.sss.albedo = (0.9965, 0.987, 0.821)
material.sss.radius_scale = 1.0
material.sss.strength = 1.0
material.sss.texturing = 'POST'
