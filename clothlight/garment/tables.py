"""The cloth BSDF as tables: what the gonioreflectometer measured, in the yarn tables' layout.

Per side (``front``, ``back``; frames: :mod:`.goniometry`), in that side's frame and in the
self-describing OpenEXR conventions of docs/table-spec.md:

``<side>_brdf.exr``
    A BRDF atlas (incidence over the sphere × exit over the side's hemisphere) of the cloth's
    ρ = f |cos θ_i|, 1/sr: incidence from the side's own hemisphere is reflection, from the other
    one transmission through the cloth.  Read exactly like a yarn's (``cl_yarn_rho``).
``<side>_lobes.exr``
    The general-lighting closure mixture fitted to it per exit cell
    (:func:`precompute.closure_fit.fit_closure_weights`).
``<side>_coverage.exr``
    Per exit cell, the fraction of the cloth hidden by yarn along that view: the rest is open
    weave that light crosses unscattered (a ``transparent()`` closure in the garment shader).

``summary.json`` (schema :data:`SUMMARY_SCHEMA`) says how they were made and holds the checks:
the energy balance per incidence cell and the fit errors.
"""

from __future__ import annotations

import json
import math
import pathlib
import time

import numpy as np

from ..addon import import_precompute
from .goniometry import SIDES, side_to_world

precompute_tables = import_precompute("tables")
table_layout = import_precompute("table_layout")
closure_fit = import_precompute("closure_fit")
AngularGrid = import_precompute("grids").AngularGrid

SUMMARY_SCHEMA = "clothlight-cloth/1"
SUMMARY_FILE = "summary.json"
TABLE_FILES = {kind: {side: f"{side}_{kind}.exr" for side in SIDES} for kind in ("brdf", "lobes", "coverage")}
UNITS = {"rho": "1/sr (ρ = f |cos θ_i|: radiance per irradiance on a plane facing the sun)",
         "coverage": "fraction of the cloth's area hidden by yarn along the view",
         "lengths": "mm", "angles": "unit vectors in the side's frame"}


def coverage_image(coverage: np.ndarray) -> np.ndarray:
    """Per-exit-cell coverage (N_o²,) as an (N_o, N_o, 3) image laid out like one lobe tile."""
    coverage = np.asarray(coverage, float)
    return table_layout.lobe_atlas(np.repeat(coverage[:, None, None], 3, axis=-1))


def energy_balance(rho: dict, coverage: dict, incidence_resolution: int) -> dict:
    """Where the light arriving from each of the front side's incidence cells goes, per unit of
    incident flux: ``reflected`` (integral of ρ cos θ_o over the lit side's exits / |cos θ_i|),
    ``transmitted`` (the same over the other side's exits, read from that side's table as the
    shader reads it), ``open`` (1 − coverage along the light: the open weave), and ``total``;
    each (N_i², 3) (open: (N_i²,)), indexed by the front side's incidence cells.  Light from
    behind is in the front table's lower incidence cells, so every direction is checked once."""
    n_i = incidence_resolution
    atlases = {side: table_layout.brdf_atlas(rho[side]) for side in SIDES}
    n_o = int(round(math.sqrt(rho["front"].shape[1])))
    exit_grid = AngularGrid("hemisphere", n_o)
    exits = exit_grid.cell_centers()
    weight = exits[:, 2] * exit_grid.cell_solid_angle
    incident = side_to_world(AngularGrid("sphere", n_i).cell_centers(), "front")
    result = {"reflected": [], "transmitted": [], "open": [], "total": []}
    for direction in incident:
        lit = "front" if direction[2] > 0 else "back"
        dark = "back" if lit == "front" else "front"
        cos_i = abs(direction[2])
        parts = {}
        for name, side in (("reflected", lit), ("transmitted", dark)):
            local = side_to_world(direction, side)
            values = table_layout.interpolate_rho(atlases[side], n_i, np.broadcast_to(local, exits.shape), exits)
            parts[name] = weight @ values / cos_i
        toward_light = side_to_world(direction, lit)
        cell = exit_grid.cell_of(toward_light)
        parts["open"] = 1.0 - float(coverage[lit][cell])
        for name, value in parts.items():
            result[name].append(value)
        result["total"].append(parts["reflected"] + parts["transmitted"] + parts["open"])
    return {name: np.asarray(value) for name, value in result.items()}


def write_cloth_tables(folder, measurement, settings, yarn_tables, *, cache_key: str, code_digest: str) -> dict:
    """Write the tables of a :class:`.measure.ClothMeasurement` into ``folder`` (created) and its
    summary; returns the summary."""
    start = time.perf_counter()
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    yarn = precompute_tables.read_table(yarn_tables.brdf_path, "brdf").metadata
    n_i, n_o = settings.incidence_resolution, settings.exit_resolution
    shape = closure_fit.LobeShape()
    header = {key: yarn[key] for key in precompute_tables.REQUIRED_METADATA if key not in ("cache_key",)}
    header.update(
        cache_key=cache_key,
        code_digest={"yarn": yarn.get("code_digest"), "cloth": code_digest},
        yarn_cache_key=yarn["cache_key"],
        goniometer=settings.to_dict(),
        sample={"patch_mm": measurement.patch_mm, "size_mm": list(measurement.sample_size_mm),
                "half_thickness_mm": measurement.half_thickness_mm},
        units={**yarn["units"], **UNITS},
    )
    layout = {"incidence_resolution": n_i, "exit_resolution": n_o}
    fit_error = {}
    for side in SIDES:
        atlas = table_layout.brdf_atlas(measurement.rho[side])
        weights, error = closure_fit.fit_closure_weights(atlas, n_i, shape)
        fit_error[side] = np.median(error, axis=0).tolist()
        side_header = {**header, "side": side, "layout": layout}
        precompute_tables.write_table(folder / TABLE_FILES["brdf"][side], atlas, {**side_header, "table": "brdf"})
        precompute_tables.write_table(
            folder / TABLE_FILES["lobes"][side], table_layout.lobe_atlas(weights),
            {**side_header, "table": "closure_lobes", "layout": {**layout, "lobe_count": len(closure_fit.LOBES)},
             "lobes": list(closure_fit.LOBES), "lobe_shape": shape.to_dict()})
        precompute_tables.write_table(folder / TABLE_FILES["coverage"][side], coverage_image(measurement.coverage[side]),
                                      {**side_header, "table": "coverage"})
    energy = energy_balance(measurement.rho, measurement.coverage, n_i)
    total = energy["total"]
    worst = np.unravel_index(int(np.argmax(total)), total.shape)
    summary = {
        **header,
        "schema": SUMMARY_SCHEMA,
        "table_schema": precompute_tables.SCHEMA,
        "files": TABLE_FILES,
        "incidence_resolution": n_i,
        "exit_resolution": n_o,
        "lobe_count": len(closure_fit.LOBES),
        "lobe_shape": shape.to_dict(),
        "closure_fit_relative_error_median_rgb": fit_error,
        "coverage_normal": {side: float(measurement.coverage[side][AngularGrid("hemisphere", n_o).cell_of(
            np.array([0.0, 0.0, 1.0]))]) for side in SIDES},
        "energy": {
            "max_total": float(total.max()),
            "worst_incidence_front_frame": side_to_world(AngularGrid("sphere", n_i).cell_centers(), "front")[worst[0]].tolist(),
            "per_incidence_total_rgb": total.tolist(),
            "per_incidence_open": energy["open"].tolist(),
        },
        "seconds": {"renders": measurement.render_seconds, "tables": time.perf_counter() - start},
    }
    (folder / SUMMARY_FILE).write_text(json.dumps(summary, indent=1))
    return summary
