"""Procedural woven cloth samples (paper §3.1, Figure 1; other weaves and elliptical yarns, §7).

Yarns are smooth tubes, or plies twisted at the medium's twist angle (:mod:`.plies`); a sample
can be regular or seeded-irregular (:mod:`.irregularity`).  Pure Python and numpy: no Blender
needed (trimesh only for export and checks).  Lengths are in millimetres throughout; the cloth
lies in the x-y plane with its normal +z, warps along x.

    >>> from clothlight.weave import WeaveParameters, build_woven_mesh
    >>> mesh = build_woven_mesh(WeaveParameters(interlacing="twill_2_1", warp_count=6, weft_count=6))
    >>> mesh.vertices.shape[1], mesh.faces.shape[1]
    (3, 3)
"""

from .clearance import crossing_gaps, minimum_gap, sample_gaps
from .errors import WeaveParameterError
from .export import export_mesh, to_trimesh
from .geometry import WovenMesh, build_woven_mesh
from .params import WeaveParameters
from .patterns import BUILT_IN, basket, plain, satin, satin_moves, twill, validate_interlacing, weave_pattern
from .wif import WeavingDraft, format_wif, parse_wif, read_wif, write_wif

__all__ = [
    "BUILT_IN",
    "WeaveParameterError",
    "WeaveParameters",
    "WeavingDraft",
    "WovenMesh",
    "basket",
    "build_woven_mesh",
    "crossing_gaps",
    "export_mesh",
    "format_wif",
    "minimum_gap",
    "parse_wif",
    "plain",
    "read_wif",
    "sample_gaps",
    "satin",
    "satin_moves",
    "to_trimesh",
    "twill",
    "validate_interlacing",
    "weave_pattern",
    "write_wif",
]
