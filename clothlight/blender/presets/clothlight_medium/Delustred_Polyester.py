import bpy
medium = bpy.context.scene.clothlight.medium

# Loads precompute/presets/delustred_polyester.toml: its medium values and its bake settings.
medium.base = 'delustred_polyester'
