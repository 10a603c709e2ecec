import bpy
medium = bpy.context.scene.clothlight.medium

# Loads precompute/presets/blue_cotton.toml: its medium values and its bake settings.
medium.base = 'blue_cotton'
