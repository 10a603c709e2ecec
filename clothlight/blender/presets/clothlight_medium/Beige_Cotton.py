import bpy
medium = bpy.context.scene.clothlight.medium

# Loads precompute/presets/beige_cotton.toml: its medium values and its bake settings.
medium.base = 'beige_cotton'
