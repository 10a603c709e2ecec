"""The virtual gonioreflectometer (paper §4, §6): the cloth's BRDF measured in Blender, against the
paper's baseline and measured data (docs/validation.md).

``framing`` (where the sun and cameras go; no Blender), ``rig`` (the Blender scene), ``measure``
(pixels → calibrated BRDF; no Blender), ``measured_data`` (CSV format, importer, metrics),
``report`` (JSON, plots, swatches, Markdown), ``run`` (the one code path: ``run_validation``),
``operator`` (the add-on's operator).  Modules without Blender import without it.
"""
