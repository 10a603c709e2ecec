import bpy
medium = bpy.context.scene.clothlight.medium

# Loads precompute/presets/dark_dyed_cotton.toml: its medium values and its bake settings.
medium.base = 'dark_dyed_cotton'
