"""Bake a yarn: medium optics → Monte-Carlo transport → yarn BRDF → RGB tables, cached.

One call turns a preset (plus overrides) into the files the shaders read
(docs/table-spec.md): ``brdf.exr`` (ρ atlas, 1/sr), ``lobes.exr`` (closure
weights for general lighting), ``spectral.npz`` (the spectral ρ and albedo, so
another illuminant or observer is a recomputation) and ``summary.json``.
"""

from __future__ import annotations

import copy
import dataclasses
import json
import pathlib
import time
import tomllib
from collections.abc import Callable

import numpy as np

from . import __version__
from .cache import cache_key, default_cache_dir, lookup, store
from .closure_fit import closure_lobe_directions, fit_closure_weights
from .color import channel_ratios, clip_to_gamut, spectral_to_rgb
from .errors import ParameterError
from .medium import DEFAULT_PRESET, load_preset_config, medium_from_dict
from .optics import medium_optics
from .table_layout import brdf_atlas, interpolate_rho, lobe_atlas
from .tables import SCHEMA, write_table
from .transport import TransportGrids, YarnGeometry, simulate_yarn, yarn_brdf

#: Transport and table settings of a bake, overridable in a preset's [transport] table.
TRANSPORT_DEFAULTS = {
    "n_around": 16,
    "n_along": 8,
    "angular_resolution": 12,
    "incidence_resolution": 12,
    "target_rel_stderr": 0.01,
    "paths_per_cell": None,
    "seed": 0,
}


@dataclasses.dataclass(frozen=True)
class BakeResult:
    """Where a bake's files are and what it measured."""

    folder: pathlib.Path
    cache_hit: bool
    summary: dict

    @property
    def brdf_table(self) -> pathlib.Path:
        return self.folder / "brdf.exr"

    @property
    def lobe_table(self) -> pathlib.Path:
        return self.folder / "lobes.exr"


def parse_override(text: str) -> tuple[list[str], object]:
    """``"dye.weight_percent=2"`` → (["dye", "weight_percent"], 2.0); values are TOML literals."""
    if "=" not in text:
        raise ParameterError("--set", text, "key=value, e.g. dye.weight_percent=2")
    key, raw = text.split("=", 1)
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw
    return key.strip().split("."), value


def apply_overrides(config: dict, overrides: list[str]) -> dict:
    """A copy of a preset's TOML content with ``key=value`` overrides applied (lists by index)."""
    config = copy.deepcopy(config)
    for text in overrides:
        path, value = parse_override(text)
        node = config
        for part in path[:-1]:
            if isinstance(node, list):
                if not part.isdigit() or int(part) >= len(node):
                    raise ParameterError(f"--set {'.'.join(path)}", part, f"an index below {len(node)}")
                node = node[int(part)]
            else:
                node = node.setdefault(part, {})
        node[path[-1]] = value
    return config


def bake_settings(config: dict, *, seed=None, paths_per_cell=None, target_rel_stderr=None) -> dict:
    """Transport settings of a bake: defaults ← preset [transport] ← explicit arguments."""
    settings = dict(TRANSPORT_DEFAULTS)
    unknown = set(config.get("transport", {})) - set(settings)
    if unknown:
        name = sorted(unknown)[0]
        raise ParameterError(f"transport.{name}", config["transport"][name], f"one of {sorted(settings)}")
    settings.update(config.get("transport", {}))
    if seed is not None:
        settings["seed"] = int(seed)
    if paths_per_cell is not None:
        settings.update(paths_per_cell=int(paths_per_cell), target_rel_stderr=None)
    elif target_rel_stderr is not None:
        settings.update(target_rel_stderr=float(target_rel_stderr), paths_per_cell=None)
    return settings


def bake(
    preset: str | pathlib.Path = DEFAULT_PRESET,
    overrides: list[str] = (),
    *,
    seed: int | None = None,
    paths_per_cell: int | None = None,
    target_rel_stderr: float | None = None,
    threads: int | None = None,
    cache_dir: str | pathlib.Path | None = None,
    progress: Callable[[float], None] | None = None,
) -> BakeResult:
    """Bake the tables of a preset (name or TOML path) with ``key=value`` overrides, or reuse the cache."""
    config, base_dir = load_preset_config(preset)
    config = apply_overrides(config, list(overrides))
    params = medium_from_dict(config, base_dir)
    settings = bake_settings(config, seed=seed, paths_per_cell=paths_per_cell, target_rel_stderr=target_rel_stderr)
    grids = TransportGrids(settings["n_around"], settings["n_along"], settings["angular_resolution"])
    inputs = {
        "schema": SCHEMA,
        "code_version": __version__,
        "medium": params.to_dict(),
        "transport": settings,
    }
    key = cache_key(inputs)
    cache_dir = pathlib.Path(cache_dir) if cache_dir else default_cache_dir()
    found = lookup(cache_dir, key)
    if found is not None:
        if progress is not None:
            progress(1.0)
        return _result(found, cache_hit=True)

    def write(folder: pathlib.Path) -> None:
        start = time.perf_counter()
        optics = medium_optics(params)
        geometry = YarnGeometry(params.yarn.radius_mm, optics.boundary_index)
        transport = simulate_yarn(
            optics, geometry, grids,
            paths_per_cell=settings["paths_per_cell"], target_rel_stderr=settings["target_rel_stderr"],
            seed=settings["seed"], threads=threads, progress=progress,
        )
        brdf = yarn_brdf(transport, settings["incidence_resolution"])
        rho_rgb_unclipped = spectral_to_rgb(brdf.rho, brdf.wavelengths_nm)
        rho_rgb, gamut_clipping = clip_to_gamut(rho_rgb_unclipped)
        weights, fit_error = fit_closure_weights(rho_rgb, brdf.incidence_grid)
        normal = np.array([0.0, 0.0, 1.0])
        atlas = brdf_atlas(rho_rgb)
        rho_normal = interpolate_rho(atlas, brdf.incidence_grid.resolution, normal, normal)
        summary = {
            **inputs,
            "key": key,
            "incidence_resolution": brdf.incidence_grid.resolution,
            "exit_resolution": brdf.exit_grid.resolution,
            "lobe_count": int(weights.shape[1]),
            "host_index": optics.boundary_index,
            "units": {"rho": "1/sr (L_o / E_perp)", "radius": "mm", "wavelength": "nm", "mu": "1/mm"},
            "paths_total": int(transport.paths_per_cell.sum()),
            "paths_per_cell_min": int(transport.paths_per_cell.min()),
            "scattering_events": transport.events,
            "albedo_rel_stderr_max": float(transport.counted_albedo_rel_stderr().max()),
            "lost_fraction_max": float(transport.lost_fraction.max()),
            "rho_normal_rgb": rho_normal.tolist(),
            "table1_ratios_normal": channel_ratios(rho_normal),
            "table1_ratios_normal_before_gamut_clipping": channel_ratios(
                interpolate_rho(brdf_atlas(rho_rgb_unclipped), brdf.incidence_grid.resolution, normal, normal)),
            "gamut_clipping_max_relative": gamut_clipping,
            "closure_fit_relative_rms_median": float(np.median(fit_error)),
            "wall_seconds": time.perf_counter() - start,
        }
        header = {key_: summary[key_] for key_ in ("schema", "code_version", "medium", "transport", "key", "units")}
        write_table(folder / "brdf.exr", atlas, {**header, "table": "yarn_brdf",
                                                  "incidence_resolution": summary["incidence_resolution"],
                                                  "exit_resolution": summary["exit_resolution"]})
        write_table(folder / "lobes.exr", lobe_atlas(weights), {**header, "table": "closure_lobes",
                                                                 "lobe_directions": closure_lobe_directions().tolist(),
                                                                 "exit_resolution": summary["exit_resolution"]})
        np.savez_compressed(
            folder / "spectral.npz", wavelengths_nm=brdf.wavelengths_nm, rho=brdf.rho.astype(np.float32),
            rho_stderr=brdf.rho_stderr.astype(np.float32), hemispherical_albedo=brdf.hemispherical_albedo(),
            specular=transport.specular, exit_fraction=transport.exit_fraction,
            absorbed_fraction=transport.absorbed_fraction,
        )
        (folder / "summary.json").write_text(json.dumps(summary, indent=2, default=float))

    return _result(store(cache_dir, key, write), cache_hit=False)


def _result(folder: pathlib.Path, cache_hit: bool) -> BakeResult:
    summary = json.loads((folder / "summary.json").read_text())
    summary.update(folder=str(folder), brdf_table=str(folder / "brdf.exr"), lobe_table=str(folder / "lobes.exr"),
                   cache_hit=cache_hit)
    return BakeResult(folder, cache_hit, summary)
