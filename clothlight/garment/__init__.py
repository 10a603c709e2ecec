"""Garment-scale material: the cloth BSDF measured on a woven sample (paper §7) and the shader
that renders any mesh with it.  Blender-free: ``goniometry`` (the measurement's directions),
``traced_response`` (the weave's cloth response traced with Embree), ``response_measurement`` (a
yarn's measurement read off it), ``between_yarns`` (the light between yarns), ``tables`` (the cloth
tables' format); the renders and the material are in
:mod:`clothlight.blender.garment`; ``python -m clothlight.garment`` is the command line."""
