"""ClothLight add-on: woven cloth samples, yarn-BRDF materials and a virtual gonioreflectometer.

The core logic (weave geometry, table reading, background bake and fit jobs, the
gonioreflectometer's framing and calibration, the garment's goniometry) is importable and tested
without Blender; everything that imports Blender is in :mod:`clothlight.blender`, whose
:mod:`~clothlight.blender.registration` registers the add-on's classes from one list.  The layers
and the data flow: docs/architecture.md.
"""
