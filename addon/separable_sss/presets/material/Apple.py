# Separable SSS material preset: Apple.
# Jensen, Marschner, Levoy and Hanrahan 2001, table of measured coefficients
# (Apple): radius = 1/sigma_tr (mm, here in metres) as the diffuse mean free
# path, albedo = alpha'.
import bpy
material = getattr(bpy.context, "material", None) or \
    bpy.context.object.active_material

material.sss.profile = 'BURLEY'
material.sss.mapping = 'RANDOM_WALK'
material.sss.radius = (0.00696, 0.00640, 0.00190)
material.sss.albedo = (0.9987, 0.9986, 0.9772)
material.sss.radius_scale = 1.0
material.sss.strength = 1.0
material.sss.texturing = 'POST'
