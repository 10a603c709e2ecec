import bpy
medium = bpy.context.scene.clothlight.medium

# Loads precompute/presets/paper_2008.toml: its medium values and its bake settings.
medium.base = 'paper_2008'
