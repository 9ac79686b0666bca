# Separable SSS material preset: Wax.
# Not measured by Jensen et al.: chosen by eye. Warm (candle) wax: red
# travels furthest, blue is absorbed soonest.
import bpy
material = getattr(bpy.context, "material", None) or \
    bpy.context.object.active_material

material.sss.profile = 'BURLEY'
material.sss.mapping = 'RANDOM_WALK'
material.sss.radius = (0.01000, 0.00700, 0.00400)
material.sss.albedo = (0.98, 0.93, 0.8)
material.sss.radius_scale = 1.0
material.sss.strength = 1.0
material.sss.texturing = 'POST'
