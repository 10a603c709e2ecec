"""Garment-scale material: the cloth BSDF measured on a woven sample (paper §7) and the shader
that renders any mesh with it.  Blender-free: ``goniometry`` (the measurement's directions),
``tables`` (the cloth tables' format); the renders and the material are in
:mod:`clothlight.blender.garment`; ``python -m clothlight.garment`` is the command line."""
