"""The baked table files a yarn material reads, checked before any render.

Cycles renders a missing table magenta and a wrong one silently wrong, so the
material builder takes a :class:`YarnTableFiles` that has been checked first.
"""

from __future__ import annotations

import pathlib
from dataclasses import dataclass

from .addon import import_precompute


@dataclass(frozen=True)
class YarnTableFiles:
    """Paths and grid sizes of one baked yarn: the BRDF atlas, the closure-lobe atlas and the
    unscattered light's attenuation.

    Attributes
    ----------
    brdf_path, lobe_path, unscattered_path
        Absolute paths of the OpenEXR tables (docs/table-spec.md).
    incidence_resolution, exit_resolution
        ``N_i`` (sphere grid) and ``N_o`` (hemisphere grid).
    lobe_shape
        Roughness of the general-lighting mode's shaped lobes, keyed as
        ``precompute.closure_fit.LobeShape`` (the bake's ``summary.json``).
    host_index
        Refractive index of the yarn host, for the specular Fresnel term and the refraction of
        the unscattered light.
    unscattered_samples
        Pixels of the attenuation table.
    """

    brdf_path: pathlib.Path
    lobe_path: pathlib.Path
    unscattered_path: pathlib.Path
    incidence_resolution: int
    exit_resolution: int
    lobe_shape: dict
    host_index: float
    unscattered_samples: int

    def __post_init__(self):
        for name in ("brdf_path", "lobe_path", "unscattered_path"):
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
    expected_schema = import_precompute("tables").SCHEMA
    schema = str(summary.get("schema", ""))
    if not schema.startswith("clothlight-table/"):
        raise ValueError(f"{summary_path}: not a ClothLight bake summary (schema {schema!r})")
    if schema != expected_schema:
        raise ValueError(f"{summary_path}: tables of schema {schema!r}, this ClothLight reads "
                         f"{expected_schema!r}: bake them again")
    return YarnTableFiles(
        brdf_path=folder / "brdf.exr",
        lobe_path=folder / "lobes.exr",
        unscattered_path=folder / "unscattered.exr",
        incidence_resolution=int(summary["incidence_resolution"]),
        exit_resolution=int(summary["exit_resolution"]),
        lobe_shape={key: float(value) for key, value in summary["lobe_shape"].items()},
        host_index=float(summary["host_index"]),
        unscattered_samples=int(summary["unscattered_samples"]),
    )
