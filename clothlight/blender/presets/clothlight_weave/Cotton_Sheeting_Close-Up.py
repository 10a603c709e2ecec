import bpy
# The close-up default (clothlight.weave.closeup.sheeting_weave): plain-woven cotton sheeting at Peirce's cover
# factor K = 14 (0.40 mm, 63.5 threads per inch of Ne 20), yarns flattened 1.6 : 1 where they cross and relaxed
# a quarter of the way to round between (1.42 : 1 midway), made of the Base Medium's plies at its twist angle, irregular
# as the cotton defaults of the [closeup] table say.
weave = bpy.context.scene.clothlight.weave

weave.pattern = 'plain'
weave.warp_count = 16
weave.weft_count = 16
weave.spacing_mm = 0.4
weave.cross_section = 'ELLIPTICAL'
weave.half_width_mm = 0.12
weave.half_thickness_mm = 0.075
weave.section_relaxation = 0.25
weave.auto_crimp = False
weave.crimp_warp_mm = 0.08475
weave.crimp_weft_mm = 0.08475
weave.segments_per_crossing = 16
weave.segments_around = 12
weave.use_plies = True
weave.spacing_jitter = 0.03
weave.height_jitter = 0.15
weave.ply_radius_jitter = 0.15
weave.irregularity_seed = 0
