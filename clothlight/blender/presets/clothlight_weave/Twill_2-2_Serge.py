import bpy
weave = bpy.context.scene.clothlight.weave

weave.pattern = 'twill_2_2'
weave.warp_count = 12
weave.weft_count = 12
weave.spacing_mm = 0.5
weave.cross_section = 'ROUND'
weave.yarn_radius_mm = 0.1
weave.section_relaxation = 0.0
weave.auto_crimp = True
weave.segments_per_crossing = 8
weave.segments_around = 12
weave.use_plies = False
weave.spacing_jitter = 0.0
weave.height_jitter = 0.0
weave.ply_radius_jitter = 0.0
