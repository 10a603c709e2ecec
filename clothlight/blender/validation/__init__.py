"""The virtual gonioreflectometer in Blender: ``rig`` (the scene: sample, sun, cameras), ``run``
(the sweep's one code path, ``run_validation``), ``response_render`` (the cloth response's lookup
renders), ``operator`` (the add-on's operator).  Framing, calibration, measured data and reports
are Blender-free, in :mod:`clothlight.validation`."""
