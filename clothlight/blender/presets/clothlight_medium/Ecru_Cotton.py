import bpy
medium = bpy.context.scene.clothlight.medium

# Loads precompute/presets/ecru_cotton.toml: its medium values and its bake settings.
medium.base = 'ecru_cotton'
