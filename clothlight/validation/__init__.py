"""The virtual gonioreflectometer (paper §4, §6): the cloth's BRDF measured in Blender, against the
paper's baseline and measured data (docs/validation.md).

Blender-free: ``framing`` (where the sun and cameras go), ``measure`` (pixels → calibrated BRDF),
``measured_data`` (CSV format, importer, metrics), ``response`` (the cloth response: the sweep as a
linear map of the yarn tables), ``report`` (JSON, plots, swatches, Markdown).  The scene, the sweep
and the operator are in :mod:`clothlight.blender.validation`.
"""
