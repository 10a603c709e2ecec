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


def yarn_tables_from_bake(folder: str | pathlib.Path) -> YarnTableFiles:
    """The table files of a bake folder (``python -m precompute bake --out`` or a cache entry).

    Reads the bake's ``summary.json`` (plain JSON, so it works inside Blender without
    OpenEXR bindings) and refuses a folder that is not a complete bake.
    """
    import json

    folder = pathlib.Path(folder).resolve()
    summary_path = folder / "summary.json"
    if not summary_path.is_file():
        raise FileNotFoundError(f"{folder} is not a ClothLight bake: no summary.json")
    summary = json.loads(summary_path.read_text())
    if not str(summary.get("schema", "")).startswith("clothlight-table/"):
        raise ValueError(f"{summary_path}: not a ClothLight bake summary (schema {summary.get('schema')!r})")
    return YarnTableFiles(
        brdf_path=folder / "brdf.exr",
        lobe_path=folder / "lobes.exr",
        incidence_resolution=int(summary["incidence_resolution"]),
        exit_resolution=int(summary["exit_resolution"]),
        lobe_count=int(summary["lobe_count"]),
        host_index=float(summary["host_index"]),
    )
