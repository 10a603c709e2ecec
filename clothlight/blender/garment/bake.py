"""Bake a cloth BSDF (measure → tables), or find it in the cache.

Two cache entries, as for a yarn (``precompute.bake``: spectral → tables): the measurement
(``measurement.npz``: ρ per side and coverage), keyed by the yarn's ρ, host index and specular term, the
gonioreflectometer's settings (weave included) and the code that measures (the yarn shader
included: the measurement renders it); and the tables written from it, keyed by that key and
the code that fits and writes them (and renders the weave detail texture, :mod:`.detail`).
Changing the fit re-renders nothing.
"""

from __future__ import annotations

import json
import pathlib
import tempfile
from collections.abc import Callable

import numpy as np

from ...yarn_tables import yarn_tables_from_bake
from ...garment.goniometry import SIDES
from .detail import render_weave_detail
from .measure import ClothMeasurement, GoniometerSettings, _sample_weave, measure_cloth
from ...garment.tables import DETAIL_FILE, SUMMARY_FILE, write_cloth_summary, write_cloth_tables

from precompute.cache import entries as cache
from precompute.cache import sources
from precompute.tables import exr as precompute_tables

MEASUREMENT_NAMESPACE = "cloth_measurement"
TABLES_NAMESPACE = "cloth_tables"
MEASUREMENT_FILE = "measurement.npz"
_ROOT = pathlib.Path(__file__).resolve().parents[3]
#: The code of each stage, digested into its key (``precompute.cache.sources``): the modules it runs and
#: every project module they import, transitively, with the OSL shaders they compile.  The
#: measurement runs :mod:`.measure` on the yarn tables :mod:`clothlight.yarn_tables` finds, and of
#: this file what stores it, without the fit this file imports (tests/test_sources.py checks that
#: what it calls here comes from those modules).
MEASUREMENT_SOURCES = {"entries": ("clothlight.blender.garment.measure", "clothlight.yarn_tables"),
                       "files": ("clothlight/blender/garment/bake.py",)}
TABLE_SOURCES = {"entries": ("clothlight.blender.garment.bake",)}


def measurement_inputs(yarn_tables, settings: GoniometerSettings) -> dict:
    """Everything a cloth measurement depends on (its cache key is their hash): of the yarn bake
    only what the sun-mode yarn material reads — ρ (the pixels' hash, not the bake's cache key,
    which also changes with the closure fit), the host index and the weight and slope of the
    specular term (a fitted preset's, ``YarnTableFiles.specular``; None: the shader's defaults)."""
    rho = precompute_tables.read_table(yarn_tables.brdf_path, "brdf").pixels
    specular = yarn_tables.specular
    return {"yarn_rho_sha256": precompute_tables.content_hash(rho), "host_index": yarn_tables.host_index,
            "specular": None if specular is None else {key: float(specular[key]) for key in ("weight", "slope")},
            "goniometer": settings.to_dict(), "code_digest": sources.stage_digest(_ROOT, **MEASUREMENT_SOURCES)}


#: The per-side arrays of a :class:`ClothMeasurement`, as the cache stores them.
PER_SIDE_ARRAYS = ("rho", "specular", "specular_visibility", "coverage")


def save_measurement(path, measurement: ClothMeasurement) -> None:
    arrays = {}
    for name in PER_SIDE_ARRAYS:
        arrays.update({f"{name}_{side}": getattr(measurement, name)[side] for side in SIDES})
    np.savez_compressed(path, **arrays, patch_mm=measurement.patch_mm,
                        specular_parameters=json.dumps(measurement.specular_parameters),
                        sample_size_mm=np.asarray(measurement.sample_size_mm),
                        half_thickness_mm=measurement.half_thickness_mm, render_seconds=measurement.render_seconds)


def load_measurement(path) -> ClothMeasurement:
    with np.load(path) as data:
        per_side = {name: {side: data[f"{name}_{side}"] for side in SIDES} for name in PER_SIDE_ARRAYS}
        return ClothMeasurement(**per_side, specular_parameters=json.loads(str(data["specular_parameters"])),
                                patch_mm=float(data["patch_mm"]),
                                sample_size_mm=tuple(float(v) for v in data["sample_size_mm"]),
                                half_thickness_mm=float(data["half_thickness_mm"]),
                                render_seconds=float(data["render_seconds"]))


def bake_cloth(yarn_bake_dir, settings: GoniometerSettings = GoniometerSettings(), *, cache_dir=None,
               progress: Callable[[int, int, str], None] | None = None,
               scheduler: str | None = None) -> tuple[pathlib.Path, bool]:
    """The folder of the cloth tables for the yarn bake ``yarn_bake_dir`` and ``settings``; and
    whether this call rendered the measurement (False: it was in the cache).  ``scheduler``: where
    the measurement's renders run (:func:`.measure.measure_cloth`); the tables do not depend on it."""
    tables = yarn_tables_from_bake(yarn_bake_dir)
    cache_dir = pathlib.Path(cache_dir) if cache_dir is not None else cache.default_cache_dir()
    measured_in = measurement_inputs(tables, settings)
    measured_key = cache.cache_key(measured_in)
    measured_folder = cache.lookup(cache_dir, MEASUREMENT_NAMESPACE, measured_key)
    rendered = measured_folder is None
    if rendered:
        def measure(target: pathlib.Path) -> None:
            with tempfile.TemporaryDirectory(prefix="clothlight-gonio-") as renders:
                save_measurement(target / MEASUREMENT_FILE,
                                 measure_cloth(tables, settings, render_dir=renders, progress=progress,
                                               scheduler=scheduler, table_folder=yarn_bake_dir))

        measured_folder, _ = cache.store(cache_dir, MEASUREMENT_NAMESPACE, measured_key, measured_in, measure)
    tables_in = {"measurement": measured_key, "code_digest": sources.stage_digest(_ROOT, **TABLE_SOURCES)}
    key = cache.cache_key(tables_in)
    folder = cache.lookup(cache_dir, TABLES_NAMESPACE, key)
    if folder is None:
        def write(target: pathlib.Path) -> None:
            summary = write_cloth_tables(target, load_measurement(measured_folder / MEASUREMENT_FILE), settings,
                                         tables, cache_key=key, code_digest=tables_in["code_digest"])
            summary["weave_detail"] = {"file": DETAIL_FILE,
                                       **render_weave_detail(_sample_weave(settings), target / DETAIL_FILE)}
            write_cloth_summary(target, summary)

        folder, _ = cache.store(cache_dir, TABLES_NAMESPACE, key, tables_in, write)
    return folder, rendered


def read_summary(folder) -> dict:
    return json.loads((pathlib.Path(folder) / SUMMARY_FILE).read_text())
