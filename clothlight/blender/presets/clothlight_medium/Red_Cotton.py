import bpy
medium = bpy.context.scene.clothlight.medium

# Loads precompute/presets/red_cotton.toml: its medium values and its bake settings.
medium.base = 'red_cotton'
