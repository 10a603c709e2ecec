import bpy
medium = bpy.context.scene.clothlight.medium

# Loads precompute/presets/paper_red_cotton.toml: its medium values and its bake settings.
medium.base = 'paper_red_cotton'
