import bpy
medium = bpy.context.scene.clothlight.medium

# Loads precompute/presets/indigo_cotton.toml: its medium values and its bake settings.
medium.base = 'indigo_cotton'
