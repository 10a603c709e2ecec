"""The baked table files a yarn material reads, checked before any render.

Cycles renders a missing table magenta and a wrong one silently wrong, so the
material builder takes a :class:`YarnTableFiles` whose folder has been checked
first (:func:`yarn_tables_from_bake`).
"""

from __future__ import annotations

import math
import pathlib
from collections.abc import Mapping
from dataclasses import dataclass



#: The general mode of the yarn material leaves out an unscattered path whose weight, (1 − F)² F^k
#: times its attenuation, is below this in every channel (``CL_UNSCATTERED_MIN_FACTOR`` in
#: osl/clothlight.h): a path costs a closure, and one left out carries less than 0.3 % of the light
#: reaching the yarn.
GENERAL_MODE_MIN_WEIGHT = 0.003


def attenuation_reach(table, floor: float = GENERAL_MODE_MIN_WEIGHT) -> float:
    """The path length ℓ / R from which an attenuation table (``unscattered.exr``'s pixels, (1, M, C)
    or (M, C)), read as the shader reads it (linear between pixel centres, held at the ends:
    ``precompute.tables.layout.interpolate_attenuation``), is below ``floor`` in every channel;
    ``inf`` where its last pixel is not.  A general-mode path longer than this weighs less than
    ``floor`` (its Fresnel factor is at most 1), so the shader leaves it out before its lookup."""
    import numpy as np

    from precompute.optics.ballistic import MAX_LENGTH_OVER_RADIUS as max_length
    table = np.asarray(table, float).reshape(-1, np.shape(table)[-1])
    above = np.flatnonzero(np.any(table >= floor, axis=-1))
    first_below_for_good = 0 if above.size == 0 else int(above[-1]) + 1
    if first_below_for_good == table.shape[0]:
        return math.inf
    return first_below_for_good * max_length / (table.shape[0] - 1)


def shortest_unscattered_path(host_index: float) -> float:
    """The shortest path ℓ / R of light crossing a yarn of index ``host_index`` unscattered toward
    any view (``precompute.optics.ballistic.unscattered_paths``): the chord of the first refracted path,
    2 |u_z| / (1 − ω_x² / n²) for the view ω inside the yarn refracted to u, is least for a view at
    the horizon across the axis, 2 √(1 − 1/n²) (1.53 R at n = 1.557)."""
    return 2.0 * math.sqrt(max(0.0, 1.0 - 1.0 / host_index**2))


def has_unscattered_light(tables: YarnTableFiles) -> bool:
    """Whether the general mode of ``tables`` renders any unscattered light: a path as short as
    the shortest chord is still above the shader's floor (False for a medium that scatters within
    that chord, as the fitted round-yarn presets do; True for a nearly clear yarn, ``paper_2008``,
    and for a yarn of fibres in air, whose light passes between the fibres at its edges)."""
    return tables.unscattered_reach > 0.0 and tables.unscattered_reach >= shortest_unscattered_path(tables.host_index)


def unscattered_light_is_straight(tables: YarnTableFiles) -> bool:
    """Whether the unscattered light crosses the yarn in a straight line: a host of index 1 (fibres in
    air) neither refracts nor reflects it at the yarn's boundary, so its one path leaves along the
    light's own direction, and a plain Refraction BSDF about the view renders it (yarn_nodes)."""
    return abs(tables.host_index - 1.0) < 1e-9


def renders_in_nodes(tables: YarnTableFiles) -> bool:
    """Whether the general mode of ``tables`` can be plain Cycles nodes (clothlight.blender.yarn_nodes):
    it has no unscattered light to render, or only the straight path of a yarn of fibres in air.  The
    refracted and reflected paths of a denser host (one lobe each, about a direction computed per
    shading point) need the OSL shader."""
    return not has_unscattered_light(tables) or unscattered_light_is_straight(tables)


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
        ``precompute.tables.closure_fit.LobeShape`` (the bake's ``summary.json``).
    host_index
        Refractive index of the yarn host, for the refraction of the unscattered light (and the
        specular Fresnel factor where ``specular`` has no ``index``).
    unscattered_samples
        Pixels of the attenuation table.
    unscattered_reach
        ℓ / R from which the attenuation table is below the general mode's floor for an unscattered
        path (:func:`attenuation_reach`); ``inf`` when it never is.
    specular
        The yarn shader's specular term as the bake recorded it (``summary.json`` → ``specular``,
        docs/table-spec.md): ``weight`` (SpecularWeight), ``slope`` (Slope, the Beckmann rms slope m),
        ``index`` (SpecularIOR: :attr:`specular_index`) and ``source`` (a fitted preset's ``[fit]``
        table or the paper's defaults).  None: the shader's own defaults (tables made without a bake).
    """

    brdf_path: pathlib.Path
    lobe_path: pathlib.Path
    unscattered_path: pathlib.Path
    incidence_resolution: int
    exit_resolution: int
    lobe_shape: dict
    host_index: float
    unscattered_samples: int
    specular: Mapping | None = None
    unscattered_reach: float = math.inf

    def __post_init__(self):
        for name in ("brdf_path", "lobe_path", "unscattered_path"):
            path = pathlib.Path(getattr(self, name))
            if not path.is_absolute():
                raise ValueError(f"{name} must be absolute for OSL texture(): {path}")
            if not path.is_file():
                raise FileNotFoundError(f"ClothLight table {name} is missing: {path}")
            object.__setattr__(self, name, path)

    @property
    def specular_index(self) -> float:
        """The index of the specular term's Fresnel factor: the bake's record (the fibres' for a yarn
        of fibres in air, ``precompute.optics.cook_torrance.sheen_index``), else the host index."""
        return float((self.specular or {}).get("index", self.host_index))


def yarn_tables_from_bake(folder: str | pathlib.Path) -> YarnTableFiles:
    """The table files of a bake folder (``python -m precompute bake --out``, a cache entry, pre-baked
    tables), checked as a whole first.

    Every file of the folder is read and validated (``precompute.tables.folder.check_yarn_table_folder``:
    schema, kind, size against the summary's resolutions, content hash, finite values ≥ 0, one bake):
    ``precompute.tables.exr.TableError`` (a ValueError) names the file and the reason, so that a damaged,
    incomplete or mixed folder is refused rather than rendered.  ``precompute.tables.folder`` (and with
    it OpenEXR) is imported here, when tables are used, not when the add-on is enabled.  The specular
    term is the summary's, or the paper's defaults for a folder baked before bakes recorded it.
    """
    from precompute.tables import folder as table_folder
    checked = table_folder.check_yarn_table_folder(pathlib.Path(folder).resolve())
    files, summary = table_folder.YARN_TABLE_FILES, checked.summary
    return YarnTableFiles(
        brdf_path=checked.folder / files["brdf"],
        lobe_path=checked.folder / files["closure_lobes"],
        unscattered_path=checked.folder / files["unscattered"],
        incidence_resolution=summary["incidence_resolution"],
        exit_resolution=summary["exit_resolution"],
        lobe_shape={key: float(value) for key, value in summary["lobe_shape"].items()},
        host_index=float(summary["host_index"]),
        unscattered_samples=summary["unscattered_samples"],
        specular=table_folder.summary_specular(summary, checked.folder),
        unscattered_reach=attenuation_reach(checked.tables[files["unscattered"]].pixels),
    )
