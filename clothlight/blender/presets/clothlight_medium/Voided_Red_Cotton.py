import bpy
medium = bpy.context.scene.clothlight.medium

# Loads precompute/presets/voided_red_cotton.toml: its medium values and its bake settings.
medium.base = 'voided_red_cotton'
