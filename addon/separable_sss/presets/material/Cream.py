# Separable SSS material preset: Cream.
# Jensen, Marschner, Levoy and Hanrahan 2001, table of measured coefficients
# (Cream): radius = 1/sigma_tr (mm, here in metres) as the diffuse mean free
# path, albedo = alpha'.
import bpy
material = getattr(bpy.context, "material", None) or \
    bpy.context.object.active_material

material.sss.profile = 'BURLEY'
material.sss.mapping = 'RANDOM_WALK'
material.sss.radius = (0.01500, 0.00466, 0.00254)
material.sss.albedo = (1.0, 0.9995, 0.9949)
material.sss.radius_scale = 1.0
material.sss.strength = 1.0
material.sss.texturing = 'POST'
