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
# Transmission: the profile's own, warm tint (candles glow).
material.sss.transmission = 'BURLEY'
material.sss.transmission_strength = 1.0
material.sss.transmission_color = (1.0, 0.85, 0.6)
material.sss.transmission_distance = 0.01
material.sss.transmission_translucency = 0.83
material.sss.transmission_distortion = 0.2
material.sss.transmission_power = 4.0
material.sss.transmission_scale = 1.0
material.sss.transmission_ambient = 0.0
material.sss.thickness_scale = 1.0
