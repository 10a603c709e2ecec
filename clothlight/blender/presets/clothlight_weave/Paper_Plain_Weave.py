import bpy
# The paper's sample (§3.1, Figure 1): plain-woven red cotton; round yarns of the red-cotton radius, 20 threads/cm.
weave = bpy.context.scene.clothlight.weave

weave.pattern = 'plain'
weave.warp_count = 8
weave.weft_count = 8
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
