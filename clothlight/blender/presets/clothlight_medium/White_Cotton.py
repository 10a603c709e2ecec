import bpy
medium = bpy.context.scene.clothlight.medium

# Loads precompute/presets/white_cotton.toml: its medium values and its bake settings.
medium.base = 'white_cotton'
