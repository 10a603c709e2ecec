"""The baked table files a yarn material reads, checked before any render.

Cycles renders a missing table magenta and a wrong one silently wrong, so the
material builder takes a :class:`YarnTableFiles` that has been checked first.
"""

from __future__ import annotations

import pathlib
from dataclasses import dataclass


@dataclass(frozen=True)
class YarnTableFiles:
    """Paths and grid sizes of one baked yarn: the BRDF atlas and the closure-lobe atlas.

    Attributes
    ----------
    brdf_path, lobe_path
        Absolute paths of the OpenEXR atlases (docs/table-spec.md).
    incidence_resolution, exit_resolution
        ``N_i`` (sphere grid) and ``N_o`` (hemisphere grid).
    lobe_count
        Number of closure lobes in the lobe atlas.
    host_index
        Refractive index of the yarn host, for the specular Fresnel term.
    """

    brdf_path: pathlib.Path
    lobe_path: pathlib.Path
    incidence_resolution: int
    exit_resolution: int
    lobe_count: int
    host_index: float

    def __post_init__(self):
        for name in ("brdf_path", "lobe_path"):
            path = pathlib.Path(getattr(self, name))
            if not path.is_absolute():
                raise ValueError(f"{name} must be absolute for OSL texture(): {path}")
            if not path.is_file():
                raise FileNotFoundError(f"ClothLight table {name} is missing: {path}")
            object.__setattr__(self, name, path)
