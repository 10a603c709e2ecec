"""Bake a cloth BSDF (measure → tables), or find it in the cache.

The key holds everything the tables depend on: the yarn tables' own cache key, the
gonioreflectometer's settings (weave included) and a digest of the code that measures and
writes them (the shaders included: the measurement renders the yarn material).
"""

from __future__ import annotations

import json
import pathlib
import tempfile
from collections.abc import Callable

from ..addon import import_precompute
from ..yarn_tables import yarn_tables_from_bake
from .measure import GoniometerSettings, measure_cloth
from .tables import SUMMARY_FILE, write_cloth_tables

cache = import_precompute("cache")

CACHE_NAMESPACE = "cloth"
_ROOT = pathlib.Path(__file__).resolve().parents[2]
CODE_SOURCES = (
    "clothlight/garment/goniometry.py", "clothlight/garment/measure.py", "clothlight/garment/tables.py",
    "clothlight/materials.py", "clothlight/measurement_render.py", "clothlight/weave/geometry.py",
    "osl/cloth_yarn.osl", "osl/clothlight.h", "precompute/closure_fit.py", "precompute/table_layout.py",
)


def cloth_inputs(yarn_bake_dir, settings: GoniometerSettings) -> dict:
    """Everything a cloth bake depends on (its cache key is their hash)."""
    summary = json.loads((pathlib.Path(yarn_bake_dir) / "summary.json").read_text())
    return {"yarn_tables": summary["cache_key"], "goniometer": settings.to_dict(),
            "code_digest": cache.source_digest(_ROOT, CODE_SOURCES)}


def bake_cloth(yarn_bake_dir, settings: GoniometerSettings = GoniometerSettings(), *, cache_dir=None,
               progress: Callable[[int, int, str], None] | None = None) -> tuple[pathlib.Path, bool]:
    """The folder of the cloth tables for the yarn bake ``yarn_bake_dir`` and ``settings``,
    measured unless the cache has them; and whether it did (False: a cache hit)."""
    tables = yarn_tables_from_bake(yarn_bake_dir)
    cache_dir = pathlib.Path(cache_dir) if cache_dir is not None else cache.default_cache_dir()
    inputs = cloth_inputs(yarn_bake_dir, settings)
    key = cache.cache_key(inputs)
    folder = cache.lookup(cache_dir, CACHE_NAMESPACE, key)
    if folder is not None:
        return folder, False

    def write(target: pathlib.Path) -> None:
        with tempfile.TemporaryDirectory(prefix="clothlight-gonio-") as renders:
            measurement = measure_cloth(tables, settings, render_dir=renders, progress=progress)
        write_cloth_tables(target, measurement, settings, tables, cache_key=key, code_digest=inputs["code_digest"])

    folder, _ = cache.store(cache_dir, CACHE_NAMESPACE, key, inputs, write)
    return folder, True


def read_summary(folder) -> dict:
    return json.loads((pathlib.Path(folder) / SUMMARY_FILE).read_text())
