# Separable SSS material preset: Marble.
# Jensen, Marschner, Levoy and Hanrahan 2001, table of measured coefficients
# (Marble): radius = 1/sigma_tr (mm, here in metres) as the diffuse mean
# free path, albedo = alpha'.
import bpy
material = getattr(bpy.context, "material", None) or \
    bpy.context.object.active_material

material.sss.profile = 'BURLEY'
material.sss.mapping = 'RANDOM_WALK'
material.sss.radius = (0.00851, 0.00557, 0.00395)
material.sss.albedo = (0.999, 0.9984, 0.9976)
material.sss.radius_scale = 1.0
material.sss.strength = 1.0
material.sss.texturing = 'POST'
