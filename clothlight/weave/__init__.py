"""Procedural woven cloth samples (paper §3.1; other weaves and yarn shapes, §7). No Blender needed.

    >>> from clothlight.weave import WeaveParameters, weave_pattern, build_woven_mesh
    >>> mesh = build_woven_mesh(WeaveParameters(interlacing=weave_pattern("twill_2_1")))
"""

from .errors import WeaveParameterError
from .geometry import WovenMesh, build_woven_mesh, minimum_clearance
from .params import WeaveParameters
from .patterns import BUILT_IN, basket, plain, satin, twill, validate_interlacing, weave_pattern

__all__ = [
    "BUILT_IN",
    "WeaveParameterError",
    "WeaveParameters",
    "WovenMesh",
    "basket",
    "build_woven_mesh",
    "minimum_clearance",
    "plain",
    "satin",
    "twill",
    "validate_interlacing",
    "weave_pattern",
]
