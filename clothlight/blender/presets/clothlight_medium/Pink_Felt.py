import bpy
medium = bpy.context.scene.clothlight.medium

# Loads precompute/presets/pink_felt.toml: its medium values and its bake settings.
medium.base = 'pink_felt'
