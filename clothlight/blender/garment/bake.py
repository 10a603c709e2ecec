"""Bake a cloth BSDF (measure → tables), or find it in the cache.

Two ways to measure, the same quantity (:mod:`clothlight.garment.response_measurement`):

* ``response`` (the default): the weave's cloth response (``cloth_response/<key>``: ``response.npz``,
  what every camera sample of every view sees in the yarn's frame), made once per weave and
  gonioreflectometer settings and keyed by them, how it was made and the code that makes it, whatever
  the yarn: traced without Blender in seconds (:mod:`clothlight.garment.traced_response`) where
  Embree (``embreex``) is installed, rendered by Cycles otherwise (:func:`.measure.measure_response`,
  about an hour); a yarn's measurement is then read off it in seconds, inside the tables' entry.
* ``render``: the measurement rendered with the yarn itself (``cloth_measurement/<key>``:
  ``measurement.npz``, ρ per side and coverage), keyed by the yarn's ρ, host index and specular term,
  the gonioreflectometer's settings (weave included) and the code that measures (the yarn shader
  included: the measurement renders it): the response's check.

The tables (``cloth_tables/<key>``) are keyed by what they were measured from (the measurement's
key, or the response's and the yarn's tables) and the code that fits and writes them (and renders
the weave detail texture, :mod:`.detail`).  Changing the fit re-renders nothing.
"""

from __future__ import annotations

import json
import pathlib
import tempfile
import time
from collections.abc import Callable

import numpy as np

from precompute.optics.cook_torrance import FUZZ_SHAPE_KEYS

from ...yarn_tables import yarn_tables_from_bake
from ...garment.goniometry import MEASUREMENT_METHODS, SIDES, ClothMeasurement
from ...garment.response import GarmentResponse
from ...garment.response_measurement import measurement_from_response, yarn_lookup
from ...garment.traced_response import trace_response, tracing_available
from ...garment.tables import DETAIL_FILE, SUMMARY_FILE, write_cloth_summary, write_cloth_tables
from .detail import render_weave_detail
from .measure import GoniometerSettings, _sample_weave, measure_cloth, measure_response

from precompute.cache import entries as cache
from precompute.cache import sources
from precompute.errors import ParameterError
from precompute.tables import exr as precompute_tables

MEASUREMENT_NAMESPACE = "cloth_measurement"
RESPONSE_NAMESPACE = "cloth_response"
TABLES_NAMESPACE = "cloth_tables"
MEASUREMENT_FILE = "measurement.npz"
RESPONSE_FILE = "response.npz"
#: Camera samples along a patch's side in the response (one per pixel, at a random place in it, each
#: pixel a square on the cloth): as close to many more samples as the render-based measurement's random
#: ones, for fewer (docs/garment.md, "Cloth tables in seconds").
RESPONSE_SAMPLES_PER_SIDE = 21
_ROOT = pathlib.Path(__file__).resolve().parents[3]
#: The code of each stage, digested into its key (``precompute.cache.sources``): the modules it runs and
#: every project module they import, transitively, with the OSL shaders they compile.  The
#: measurement runs :mod:`.measure` on the yarn tables :mod:`clothlight.yarn_tables` finds, and of
#: this file what stores it, without the fit this file imports (tests/test_sources.py checks that
#: what it calls here comes from those modules).  The response is traced by
#: :mod:`clothlight.garment.traced_response`, or rendered by :mod:`.measure`, and stored by them alone
#: (tests/test_garment_response_render.py checks it), not by what reads it.
MEASUREMENT_SOURCES = {"entries": ("clothlight.blender.garment.measure", "clothlight.yarn_tables"),
                       "files": ("clothlight/blender/garment/bake.py",)}
RESPONSE_SOURCES = {"traced": {"entries": ("clothlight.garment.traced_response",)},
                    "rendered": {"entries": ("clothlight.blender.garment.measure",)}}
TABLE_SOURCES = {"entries": ("clothlight.blender.garment.bake",)}


def measurement_inputs(yarn_tables, settings: GoniometerSettings) -> dict:
    """Everything a cloth measurement depends on (its cache key is their hash): of the yarn bake
    what the sun-mode yarn material reads (:func:`yarn_inputs`), the settings and the code."""
    return {**yarn_inputs(yarn_tables), "goniometer": settings.to_dict(),
            "code_digest": sources.stage_digest(_ROOT, **MEASUREMENT_SOURCES)}


def yarn_inputs(yarn_tables) -> dict:
    """What the sun-mode yarn material reads of a yarn bake: ρ and the unscattered light's
    attenuation (the pixels' hashes, not the bake's cache key, which also changes with the closure
    fit), the host index, the weight, slope and index of the specular term (a fitted preset's,
    ``YarnTableFiles.specular``; None: the shader's defaults) and the fuzz albedo, depth, asymmetry and
    tint where there are (the keys only then: the cloth bakes of yarns without them keep theirs)."""
    rho = precompute_tables.read_table(yarn_tables.brdf_path, "brdf").pixels
    attenuation = precompute_tables.read_table(yarn_tables.unscattered_path, "unscattered").pixels
    specular = yarn_tables.specular
    inputs = {"yarn_rho_sha256": precompute_tables.content_hash(rho),
              "yarn_unscattered_sha256": precompute_tables.content_hash(attenuation),
              "host_index": yarn_tables.host_index,
              "specular": None if specular is None else {key: float(specular[key]) for key in ("weight", "slope")},
              "specular_index": yarn_tables.specular_index}
    for key in ("fuzz_albedo", "fuzz_depth", *FUZZ_SHAPE_KEYS):
        if key in (specular or {}) and (key in FUZZ_SHAPE_KEYS or float(specular[key])):
            inputs[key] = float(specular[key])
    return inputs


def response_method() -> str:
    """How this Python makes a cloth response: ``traced`` where Embree (``embreex``) can be imported,
    else ``rendered`` (module docstring)."""
    return "traced" if tracing_available() else "rendered"


def response_inputs(settings: GoniometerSettings, samples_per_side: int = RESPONSE_SAMPLES_PER_SIDE,
                    method: str | None = None) -> dict:
    """Everything a cloth response depends on (its cache key is their hash): the gonioreflectometer's
    settings (weave included), the samples along a patch's side, how it is made (``method``, default
    :func:`response_method`) and the code that makes it — no yarn."""
    method = method or response_method()
    return {"goniometer": settings.to_dict(), "samples_per_side": int(samples_per_side), "method": method,
            "code_digest": sources.stage_digest(_ROOT, **RESPONSE_SOURCES[method])}


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


def cloth_response(settings: GoniometerSettings, tables, *, cache_dir,
                   samples_per_side: int = RESPONSE_SAMPLES_PER_SIDE,
                   progress: Callable[[int, int, str], None] | None = None, scheduler: str | None = None,
                   table_folder=None, method: str | None = None) -> tuple[pathlib.Path, str, bool]:
    """The cache folder of the cloth response of ``settings`` (``response.npz``), its key, and
    whether this call made it, by ``method`` (:func:`response_method`'s by default).  ``tables``
    (and ``table_folder``, their bake folder, for a ``scheduler``): any yarn's, to render the
    lookups with; tracing needs neither."""
    inputs = response_inputs(settings, samples_per_side, method)
    key = cache.cache_key(inputs)
    folder = cache.lookup(cache_dir, RESPONSE_NAMESPACE, key)
    if folder is not None:
        return folder, key, False

    def make(target: pathlib.Path) -> None:
        if inputs["method"] == "traced":
            response = trace_response(_sample_weave(settings), settings.incidence_resolution,
                                      settings.exit_resolution, samples_per_side=samples_per_side,
                                      pixels_per_patch=settings.pixels_per_patch,
                                      patch_repeats=settings.patch_repeats, seed=settings.seed, progress=progress)
            response.save(target / RESPONSE_FILE)
            return
        with tempfile.TemporaryDirectory(prefix="clothlight-gonio-") as renders:
            measure_response(tables, settings, samples_per_side=samples_per_side, render_dir=renders,
                             progress=progress, scheduler=scheduler, table_folder=table_folder
                             ).save(target / RESPONSE_FILE)

    folder, _ = cache.store(cache_dir, RESPONSE_NAMESPACE, key, inputs, make)
    return folder, key, True


def bake_cloth(yarn_bake_dir, settings: GoniometerSettings = GoniometerSettings(), *, cache_dir=None,
               progress: Callable[[int, int, str], None] | None = None,
               scheduler: str | None = None, method: str = MEASUREMENT_METHODS[0]) -> tuple[pathlib.Path, bool]:
    """The folder of the cloth tables for the yarn bake ``yarn_bake_dir`` and ``settings``; and
    whether this call rendered the measurement or the response (False: it was in the cache).
    ``method``: one of :data:`~clothlight.garment.goniometry.MEASUREMENT_METHODS` (module docstring).
    ``scheduler``: where the renders run (:func:`.measure.measure_cloth`); the tables do not depend
    on it."""
    if method not in MEASUREMENT_METHODS:
        raise ParameterError("method", method, f"one of {MEASUREMENT_METHODS}")
    tables = yarn_tables_from_bake(yarn_bake_dir)
    cache_dir = pathlib.Path(cache_dir) if cache_dir is not None else cache.default_cache_dir()
    code_digest = sources.stage_digest(_ROOT, **TABLE_SOURCES)
    if method == "render":
        measured_folder, measured_key, rendered = _rendered_measurement(tables, settings, cache_dir, progress,
                                                                        scheduler, yarn_bake_dir)
        tables_in = {"measurement": measured_key, "code_digest": code_digest}
    else:
        response_folder, response_key, rendered = cloth_response(settings, tables, cache_dir=cache_dir,
                                                                 progress=progress, scheduler=scheduler,
                                                                 table_folder=yarn_bake_dir)
        tables_in = {"response": response_key, "yarn": yarn_inputs(tables), "code_digest": code_digest}
    key = cache.cache_key(tables_in)
    folder = cache.lookup(cache_dir, TABLES_NAMESPACE, key)
    if folder is None:
        def write(target: pathlib.Path) -> None:
            if method == "render":
                measurement = load_measurement(measured_folder / MEASUREMENT_FILE)
                how = {"method": method, "measurement_key": measured_key}
            else:
                start = time.perf_counter()
                response = GarmentResponse.load(response_folder / RESPONSE_FILE)
                measurement = measurement_from_response(response, yarn_lookup(tables))
                how = {"method": method, "response_key": response_key, **response.metadata,
                       "seconds": time.perf_counter() - start}
            summary = write_cloth_tables(target, measurement, settings, tables, cache_key=key,
                                         code_digest=tables_in["code_digest"])
            summary["measurement"] = how
            summary["weave_detail"] = {"file": DETAIL_FILE,
                                       **render_weave_detail(_sample_weave(settings), target / DETAIL_FILE)}
            write_cloth_summary(target, summary)

        folder, _ = cache.store(cache_dir, TABLES_NAMESPACE, key, tables_in, write)
    return folder, rendered


def _rendered_measurement(tables, settings, cache_dir, progress, scheduler, yarn_bake_dir):
    """The cache folder of the render-based measurement of ``tables`` (measured now, or found), its
    key, and whether this call rendered it."""
    measured_in = measurement_inputs(tables, settings)
    measured_key = cache.cache_key(measured_in)
    measured_folder = cache.lookup(cache_dir, MEASUREMENT_NAMESPACE, measured_key)
    if measured_folder is not None:
        return measured_folder, measured_key, False

    def measure(target: pathlib.Path) -> None:
        with tempfile.TemporaryDirectory(prefix="clothlight-gonio-") as renders:
            save_measurement(target / MEASUREMENT_FILE,
                             measure_cloth(tables, settings, render_dir=renders, progress=progress,
                                           scheduler=scheduler, table_folder=yarn_bake_dir))

    measured_folder, _ = cache.store(cache_dir, MEASUREMENT_NAMESPACE, measured_key, measured_in, measure)
    return measured_folder, measured_key, True


def read_summary(folder) -> dict:
    return json.loads((pathlib.Path(folder) / SUMMARY_FILE).read_text())
