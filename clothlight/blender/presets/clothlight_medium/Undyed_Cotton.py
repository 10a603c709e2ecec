import bpy
medium = bpy.context.scene.clothlight.medium

# Loads precompute/presets/undyed_cotton.toml: its medium values and its bake settings.
medium.base = 'undyed_cotton'
