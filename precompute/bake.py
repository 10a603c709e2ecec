"""Bake a yarn: medium optics → Monte-Carlo transport → yarn BRDF → RGB tables, cached.

:func:`bake` turns a preset (a shipped name, a TOML path, its parsed content
or :class:`~precompute.optics.medium.MediumParameters`) plus ``key=value`` overrides
into the files the shaders read (docs/table-spec.md) and reports the paper's
Table 1 ratios B/R and G/R at normal incidence and view.

It runs in two cached stages (:mod:`precompute.cache.entries`):

``spectral``
    the simulation: optics (paper §3.3), transport and the yarn BRDF by eq. (5)
    (§5.3), kept spectrally in ``spectral.npz``.  Keyed by the medium, the
    ``[transport]`` settings and a digest of the physics code.
``tables``
    the colour conversion (:mod:`precompute.tables.color`, ``[bake]`` settings) and
    the OpenEXR tables.  Keyed by the spectral key, the ``[bake]`` settings,
    the table schema and a digest of this stage's code.

So a second bake of the same inputs is a cache hit that runs nothing, and a
bake for another illuminant or observer recomputes colour without simulating
again.

Preset TOML tables owned here (defaults merged when absent)::

    [transport]
    n_around = 32              # spatial cells around the yarn (the paper: 16 × 8 = 128 cells)
    n_along = 3                # spatial cells along the yarn; odd: a quarter of the incidence cells traced
    angular_resolution = 12    # N of the N × N hemisphere grids of the BSSRDF (the paper: 144 cells)
    incidence_resolution = "auto"  # N_i of the tables' sphere grid of incidence: odd, or "auto"
    target_rel_stderr = 0.01   # relative standard error of every cell's albedo to reach, or
    # paths_per_cell = 20000   # a fixed path budget per incidence cell instead
    seed = 0

    [bake]
    illuminant = "D65"         # colour-science illuminant name, see precompute/tables/color.py
    observer = "CIE 1931 2 Degree Standard Observer"

Read here too, written by ``python -m clothlight.fit`` (:data:`precompute.optics.cook_torrance.FIT_TABLE`)::

    [fit]
    specular_weight = 1.0      # the yarn shader's SpecularWeight (Cook–Torrance weight)
    specular_slope = 0.8       # its Slope: the Beckmann rms slope m (the paper's §6 value)

The bake does not simulate the specular term (the shader computes it); it records it — the
``[fit]`` values, or :data:`precompute.optics.cook_torrance.DEFAULT_WEIGHT` and ``DEFAULT_SLOPE`` stated as
defaults — in the tables' summary and headers as ``specular`` (docs/table-spec.md), with the
``index`` of its Fresnel factor, the medium's (the fibres' for a yarn of fibres in air, else the
host's: :func:`precompute.optics.cook_torrance.sheen_index`), and the materials set the shader from it.
It is part of the tables' key, not of the spectral one: a fitted preset reuses the simulation of
its medium.
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import json
import os
import pathlib
import shutil
import time
import tomllib
from collections.abc import Callable, Mapping, Sequence

import numba
import numpy as np

from precompute import __version__, bounds
from precompute.optics import ballistic
from precompute.bounds import Bound
from precompute.cache.entries import canonical_json, cache_key, default_cache_dir, lookup, store
from precompute.tables.closure_fit import LOBES, LobeShape, fit_closure_weights
from precompute.tables.color import (
    DEFAULT_ILLUMINANT,
    DEFAULT_OBSERVER,
    RGB_SPACE,
    channel_ratios,
    clip_to_gamut,
    spectral_stderr_to_rgb,
    spectral_to_rgb,
    spectral_weights,
    white_balance_factors,
)
from precompute.distributed import LOCAL, check_scheduler, open_executor
from precompute.errors import ParameterError
from precompute.optics.cook_torrance import FIT_TABLE, FUZZ_SHAPE_KEYS, fuzz_colour, sheen_index, specular_from_config
from precompute.optics.measured_sample import SAMPLE_AZIMUTHS_KEY, SAMPLE_TABLE, sample_azimuths_deg, sample_weave_name
from precompute.tables.grids import AngularGrid
from precompute.optics.medium import DEFAULT_PRESET, PRESET_DIR, MediumParameters, load_preset_config, medium_from_dict
from precompute.optics.coefficients import medium_optics, planned_phase_grid
from precompute.outputs import check_writable_folder
from precompute.cache.sources import stage_digest
from precompute.tables.layout import brdf_atlas, interpolate_attenuation, interpolate_rho, lobe_atlas
from precompute.tables.folder import (
    FILE_HASHES_KEY,
    SAMPLE_AZIMUTHS_RECORD_KEY,
    SAMPLE_WEAVE_KEY,
    SPECULAR_FROM_PRESET,
    SPECULAR_KEY,
    SUMMARY_FILE,
    YARN_FOLDER_FILES,
    YARN_TABLE_FILES,
    check_yarn_table_folder,
    default_specular,
    file_hashes,
    replace_folder,
)
from precompute.tables.exr import SCHEMA, write_table
from precompute.transport import TransportGrids, YarnGeometry, simulate_yarn
from precompute.transport.absorption import (
    absorption_steps,
    albedo_relative_stderr,
    interpolate_absorption,
    reweighted_absorption,
    reweighted_scattering,
    step_transport,
)
from precompute.transport.brdf import INCIDENCE_RESOLUTIONS, YarnBRDF, yarn_brdf, yarn_brdf_to_tolerance
from precompute.transport.cylinder import counted_wavelengths

TRANSPORT_DEFAULTS = bounds.TRANSPORT_DEFAULTS
BAKE_DEFAULTS = {"illuminant": DEFAULT_ILLUMINANT, "observer": DEFAULT_OBSERVER}
#: The ``[fit]`` keys and their defaults (the shader's: precompute.optics.cook_torrance), as the fit writes them.
FIT_DEFAULTS = specular_from_config({})
#: What the bake accepts of them (the shader's Cook–Torrance term is defined for any weight ≥ 0 and slope > 0;
#: its fuzz term for an albedo in [0, 1] and any depth ≥ 0).
SPECULAR_BOUNDS = {"specular_weight": Bound(f"{FIT_TABLE}.specular_weight", 0.0, float("inf"), high_open=True),
                   "specular_slope": Bound(f"{FIT_TABLE}.specular_slope", 0.0, float("inf"), low_open=True,
                                           high_open=True),
                   "fuzz_albedo": Bound(f"{FIT_TABLE}.fuzz_albedo", 0.0, 1.0),
                   "fuzz_depth": Bound(f"{FIT_TABLE}.fuzz_depth", 0.0, float("inf"), high_open=True),
                   "fuzz_asymmetry": Bound(f"{FIT_TABLE}.fuzz_asymmetry", -1.0, 1.0, low_open=True, high_open=True),
                   "fuzz_tint_red": Bound(f"{FIT_TABLE}.fuzz_tint_red", 0.0, float("inf"), high_open=True),
                   "fuzz_tint_blue": Bound(f"{FIT_TABLE}.fuzz_tint_blue", 0.0, float("inf"), high_open=True),
                   "fuzz_flatness": Bound(f"{FIT_TABLE}.fuzz_flatness", 0.0, 1.0)}
#: Version of the spectral stage's file (spectral.npz); bump when its content changes meaning.
SPECTRAL_FORMAT = "clothlight-spectral/2"
#: Incidence samples per side of the sphere square that the closure fit uses in all (cells ×
#: samples per cell), whatever N_i is.
CLOSURE_FIT_SAMPLES_PER_SIDE = 36
#: Code the result of each stage depends on, digested into its key (:mod:`precompute.cache.sources`): the
#: modules the stage runs and every project module they import, transitively.  The spectral stage
#: runs the optics, the transport (with its absorption reweighting, for dye series) and
#: :func:`_simulate`, :func:`_simulate_series` and :func:`_reweighted_spectral` of this file, without
#: the colour and fit this file imports (tests/test_sources.py checks that what those call comes
#: from the former).
PROJECT_ROOT = pathlib.Path(__file__).resolve().parents[1]
SPECTRAL_SOURCES = {"entries": ("precompute.optics.medium", "precompute.optics.coefficients", "precompute.transport",
                                "precompute.transport.absorption"),
                    "files": ("precompute/bake.py",)}
TABLE_SOURCES = {"entries": ("precompute.bake",)}
#: The table files of a bake folder, written in this order (summary.json last; precompute/tables/folder.py).
TABLE_FILES = YARN_TABLE_FILES
#: The spectral stage's file (named here, in the stage's code; precompute.tables.folder checks it by this name).
SPECTRAL_FILE = "spectral.npz"
#: A dye series' file and format (:func:`bake` with ``dye_series``): eq. (5)'s ρ at the absorption steps.
SERIES_FILE = "series.npz"
SERIES_FORMAT = "clothlight-dye-series/2"
#: The cache namespace of dye series: a folder per medium without its dye amount, an entry per range.
SERIES_NAMESPACE = "dye_series"
UNITS = {
    "rho": "1/sr: exit radiance L_o per irradiance E_perp of a parallel beam (plane facing the beam)",
    "brdf_stderr": "1/sr: upper bound of the standard error of rho",
    "albedo": "1: hemispherical albedo, integral of rho cos(theta_o) over the exit hemisphere",
    "closure_lobes": "1: weight of the clamped-cosine lobe max(0, m_k . w_i)/pi, see docs/table-spec.md",
    "unscattered": "1: transmittance of the unscattered light along a path of length l/R inside the yarn",
    "wavelengths": "nm (vacuum)",
    "lengths": "mm (suffix _mm), nm (suffix _nm)",
    "mu_s, mu_a": "1/mm",
    "dye": "weight_percent: % of fibre weight; mass_absorption_cm2_per_g: napierian, cm^2/g",
    "grids": "n_around, n_along: spatial cells; angular_resolution, incidence_resolution, exit_resolution: "
    "N of an N x N equal-solid-angle grid",
    "paths": "paths traced per incidence cell of the transport",
    "seconds": "s",
}


@dataclasses.dataclass(frozen=True)
class BakeConfiguration:
    """Everything a bake is made from: the medium, the ``[transport]`` and the ``[bake]`` settings,
    the specular term the tables record (:func:`specular_settings`) and the sample weave the preset
    was fitted on where its ``[sample]`` table names one (:mod:`precompute.optics.measured_sample`),
    else None, and the sample azimuths it was fitted at where the table names them, else None."""

    medium: MediumParameters
    transport: dict
    colour: dict
    specular: dict
    sample_weave: str | None = None
    sample_azimuths_deg: tuple[float, ...] | None = None


@dataclasses.dataclass(frozen=True)
class BakeResult:
    """Where a bake's files are and what it measured.

    ``cache_hit``: the tables came from the cache; ``simulated``: this call ran
    the Monte-Carlo transport.  ``summary`` is the bake's summary.json plus the
    file paths and these two flags.
    """

    folder: pathlib.Path
    cache_hit: bool
    simulated: bool
    summary: dict

    def table(self, kind: str) -> pathlib.Path:
        """Path of the table of ``kind`` (a key of :data:`TABLE_FILES`)."""
        return self.folder / TABLE_FILES[kind]

    @property
    def brdf_table(self) -> pathlib.Path:
        return self.table("brdf")

    @property
    def lobe_table(self) -> pathlib.Path:
        return self.table("closure_lobes")

    @property
    def spectral_file(self) -> pathlib.Path:
        return self.folder / SPECTRAL_FILE

    @property
    def blue_red(self) -> float | None:
        """B/R of the table at normal incidence and view (paper Table 1; real red cotton 0.08); None if R = 0."""
        return self.summary["table1_ratios_normal"]["B/R"]

    @property
    def green_red(self) -> float | None:
        """G/R of the table at normal incidence and view (paper Table 1; real red cotton 0.011); None if R = 0."""
        return self.summary["table1_ratios_normal"]["G/R"]


# ---- configuration ------------------------------------------------------------------------------


def parse_override(text: str) -> tuple[list[str], object]:
    """``"dye.weight_percent=2"`` → (["dye", "weight_percent"], 2); values are TOML literals, else strings."""
    key, separator, raw = text.partition("=")
    path = key.strip().split(".")
    if not separator or not all(part.strip() for part in path):
        raise ParameterError("--set", text, "key=value with a dotted key, e.g. dye.weight_percent=2")
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()
    return [part.strip() for part in path], value


def apply_overrides(config: dict, overrides: Sequence[str] | Mapping[str, object]) -> dict:
    """A copy of a preset's TOML content with overrides applied.

    ``overrides``: ``"key=value"`` strings or a mapping of dotted keys to values;
    a numeric part indexes an array of tables (``particles.0.diameter_nm``).
    """
    config = copy.deepcopy(config)
    items = (
        [(key.split("."), value) for key, value in overrides.items()]
        if isinstance(overrides, Mapping)
        else [parse_override(text) for text in overrides]
    )
    seen = {}
    for path, value in items:
        key = ".".join(path)
        if key in seen:  # the later value would hide the earlier one, which may be wrong
            raise ParameterError(key, value, f"one value per key (it is also set to {seen[key]!r})")
        seen[key] = value
        node = config
        for depth, part in enumerate(path[:-1]):
            name = ".".join(path[: depth + 1])
            if isinstance(node, list):
                if not part.isdigit() or int(part) >= len(node):
                    raise ParameterError(name, part, f"an index below {len(node)}")
                node = node[int(part)]
            else:
                node = node.setdefault(part, {})
                if not isinstance(node, (dict, list)):
                    raise ParameterError(name, node, "a TOML table to set keys in")
        if isinstance(node, list):
            raise ParameterError(".".join(path), value, "a key of one table of the array, e.g. particles.0.name")
        node[path[-1]] = value
    return config


def _settings(config: dict, table: str, defaults: dict) -> dict:
    given = config.get(table, {})
    if not isinstance(given, dict):
        raise ParameterError(table, given, "a TOML table")
    unknown = sorted(set(given) - set(defaults))
    if unknown:
        raise ParameterError(f"{table}.{unknown[0]}", given[unknown[0]], f"one of the keys {sorted(defaults)}")
    return {**defaults, **given}


def specular_settings(config: Mapping, medium: MediumParameters) -> dict:
    """The specular record of a preset's content (``specular`` of the summary, docs/table-spec.md):
    its ``[fit]`` table's ``specular_weight`` and ``specular_slope``, checked, a key it leaves out at
    the shader's default (:func:`precompute.tables.folder.default_specular` when it has no ``[fit]``),
    and the ``index`` of its Fresnel factor, the medium's
    (:func:`precompute.optics.cook_torrance.sheen_index`)."""
    given = _settings(dict(config), FIT_TABLE, FIT_DEFAULTS)
    default = {**default_specular(), "index": sheen_index(medium)}
    table = config.get(FIT_TABLE) or {}
    if not table:
        return default
    values = {key: SPECULAR_BOUNDS[key].check(value) for key, value in given.items()}
    # the fuzz: none, isotropic and white where the table leaves it out
    defaulted = [key for key, value in FIT_DEFAULTS.items()
                 if key not in table and value and key not in FUZZ_SHAPE_KEYS]
    source = SPECULAR_FROM_PRESET + (f"; {', '.join(defaulted)}: {default['source']}" if defaulted else "")
    # the fuzz's depth, phase function and colour only where it has them, so that the tables of every
    # other preset keep their keys
    depth = {"fuzz_depth": values["fuzz_depth"]} if values["fuzz_depth"] > 0.0 else {}
    shape = {key: values[key] for key in FUZZ_SHAPE_KEYS if values[key] != FIT_DEFAULTS[key]}
    if max(fuzz_colour(values)) > 1.0:
        raise ParameterError(f"{FIT_TABLE}.fuzz_albedo", values["fuzz_albedo"],
                             "an albedo whose every channel (fuzz_tint_red and fuzz_tint_blue times it) is at most 1")
    return {"weight": values["specular_weight"], "slope": values["specular_slope"], "index": default["index"],
            "fuzz_albedo": values["fuzz_albedo"], **depth, **shape, "source": source}


def _integer(name: str, value, low: int, high: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low or (high and value > high):
        raise ParameterError(name, value, f"an integer in [{low}, {high}]" if high else f"an integer ≥ {low}")
    return int(value)


def transport_settings(config: dict, *, seed=None, paths_per_cell=None, target_rel_stderr=None) -> dict:
    """The ``[transport]`` settings: defaults ← the preset's table ← explicit arguments, validated.

    An explicit ``paths_per_cell`` or ``target_rel_stderr`` replaces the preset's budget of either kind.
    A preset value an argument replaces is checked all the same: a wrong one is refused, not hidden.
    """
    settings = _settings(config, "transport", TRANSPORT_DEFAULTS)
    given = config.get("transport", {})
    for bound in (bounds.SEED, bounds.PATHS_PER_CELL, bounds.TARGET_REL_STDERR):
        key = bound.name.split(".")[-1]
        if given.get(key) is not None:
            bound.check(given[key])
    if seed is not None:
        settings["seed"] = seed
    if paths_per_cell is not None and target_rel_stderr is not None:
        raise ParameterError("paths_per_cell / target_rel_stderr", (paths_per_cell, target_rel_stderr), "one of them")
    if paths_per_cell is not None:
        settings.update(paths_per_cell=paths_per_cell, target_rel_stderr=None)
    elif target_rel_stderr is not None:
        settings.update(target_rel_stderr=target_rel_stderr, paths_per_cell=None)
    elif settings["paths_per_cell"] is not None and "target_rel_stderr" not in config.get("transport", {}):
        settings["target_rel_stderr"] = None  # the preset chose a fixed budget
    if (settings["paths_per_cell"] is None) == (settings["target_rel_stderr"] is None):
        raise ParameterError(
            "transport.paths_per_cell / transport.target_rel_stderr",
            (settings["paths_per_cell"], settings["target_rel_stderr"]),
            "exactly one of them",
        )
    if settings["paths_per_cell"] is not None:
        settings["paths_per_cell"] = bounds.PATHS_PER_CELL.check(settings["paths_per_cell"])
    else:
        settings["target_rel_stderr"] = bounds.TARGET_REL_STDERR.check(settings["target_rel_stderr"])
    settings["seed"] = bounds.SEED.check(settings["seed"])
    for bound in (bounds.N_AROUND, bounds.N_ALONG, bounds.ANGULAR_RESOLUTION):
        settings[bound.name.split(".")[-1]] = bound.check(settings[bound.name.split(".")[-1]])
    if settings["incidence_resolution"] != "auto":
        n_i = settings["incidence_resolution"]
        if isinstance(n_i, str) or not _is_allowed(bounds.INCIDENCE_RESOLUTION, n_i):
            raise ParameterError(
                "transport.incidence_resolution", n_i,
                f"\"auto\" or {bounds.INCIDENCE_RESOLUTION.allowed()} (with an even one the planes across and along "
                "the yarn fall on the octahedral map's crease, docs/table-spec.md)",
            )
    try:
        TransportGrids(settings["n_around"], settings["n_along"], settings["angular_resolution"])
    except ParameterError as exc:  # name the parameter as the preset spells it
        raise ParameterError(f"transport.{exc.name.split('.')[-1]}", exc.value, exc.allowed) from None
    return settings


def _is_allowed(bound: bounds.Bound, value) -> bool:
    try:
        bound.check(value)
    except ParameterError:
        return False
    return True


def check_transport_memory(settings: dict, wavelengths: int) -> int:
    """The estimated peak memory of the simulation of ``settings`` (bytes, :func:`precompute.bounds.
    transport_memory_bytes`); ParameterError naming the grid settings when it exceeds the limit."""
    n_i = settings["incidence_resolution"]
    n_i = max(INCIDENCE_RESOLUTIONS) if n_i == "auto" else n_i
    keys = bounds.GRID_SETTINGS
    estimate = bounds.transport_memory_bytes(settings["n_around"], settings["n_along"], settings["angular_resolution"],
                                             n_i, wavelengths)
    bounds.check_memory(estimate, "transport." + ", transport.".join(keys) + f" (with {wavelengths} wavelengths)",
                        tuple(settings[key] for key in keys))
    return estimate


def bake_configuration(
    preset_or_params: str | pathlib.Path | Mapping | MediumParameters = DEFAULT_PRESET,
    overrides: Sequence[str] | Mapping[str, object] = (),
    *,
    seed: int | None = None,
    paths_per_cell: int | None = None,
    target_rel_stderr: float | None = None,
) -> BakeConfiguration:
    """The validated inputs of a bake (see :func:`bake`)."""
    if isinstance(preset_or_params, MediumParameters):
        config = apply_overrides({}, overrides)
        foreign = sorted(set(config) - {"transport", "bake", FIT_TABLE})
        if foreign:
            raise ParameterError(
                f"--set {foreign[0]}", config[foreign[0]],
                f"transport.*, bake.* or {FIT_TABLE}.* keys when baking MediumParameters",
            )
        medium = preset_or_params
    else:
        if isinstance(preset_or_params, Mapping):
            config, base_dir = dict(preset_or_params), PRESET_DIR
        else:
            config, base_dir = load_preset_config(preset_or_params)
        config = apply_overrides(config, overrides)
        medium = medium_from_dict(config, base_dir)
    if medium.yarn.cross_section != "circle":
        raise ParameterError(
            "yarn.cross_section", medium.yarn.cross_section, "'circle' (the transport traces circular yarns)"
        )
    settings = transport_settings(config, seed=seed, paths_per_cell=paths_per_cell, target_rel_stderr=target_rel_stderr)
    check_transport_memory(settings, len(medium.wavelengths.values))
    colour = _settings(config, "bake", BAKE_DEFAULTS)
    # Checks the illuminant, the observer and that the wavelengths lie where colour is defined,
    # before any simulation.
    spectral_weights(medium.wavelengths.values, colour["illuminant"], colour["observer"])
    sample_weave = sample_weave_name(config) if SAMPLE_TABLE in config else None
    azimuths = sample_azimuths_deg(config) if SAMPLE_AZIMUTHS_KEY in config.get(SAMPLE_TABLE, {}) else None
    return BakeConfiguration(medium, settings, colour, specular_settings(config, medium), sample_weave, azimuths)


# ---- the two stages -----------------------------------------------------------------------------


def spectral_inputs(configuration: BakeConfiguration) -> dict:
    """What the spectral stage's result depends on: the key of its cache entry hashes this."""
    return {
        "format": SPECTRAL_FORMAT,
        "code_version": __version__,
        "code_digest": stage_digest(PROJECT_ROOT, **SPECTRAL_SOURCES),
        "medium": configuration.medium.to_dict(),
        # the cos θ grid the optics start from ("auto" in the medium record resolved, no Mie needed)
        "planned_phase_grid": dict(zip(("kind", "samples"), planned_phase_grid(configuration.medium))),
        "transport": configuration.transport,
    }


def table_inputs(spectral_key: str, configuration: BakeConfiguration) -> dict:
    """What the tables depend on beyond the spectral result."""
    return {
        "schema": SCHEMA,
        "code_version": __version__,
        "code_digest": stage_digest(PROJECT_ROOT, **TABLE_SOURCES),
        "spectral_key": spectral_key,
        "colour": configuration.colour,
        # the shader's specular term, recorded in the tables (not simulated: no part of the spectral key)
        SPECULAR_KEY: configuration.specular,
        **_sample_weave_record(configuration),
    }


def _sample_weave_record(configuration: BakeConfiguration) -> dict:
    # Only where the preset names them, so that the tables of every other preset keep their keys.
    record = {} if configuration.sample_weave is None else {SAMPLE_WEAVE_KEY: configuration.sample_weave}
    if configuration.sample_azimuths_deg is not None:
        record[SAMPLE_AZIMUTHS_RECORD_KEY] = list(configuration.sample_azimuths_deg)
    return record


def _simulation_record(inputs: dict, key: str, optics, transport, brdf, checks, seconds: dict) -> dict:
    """The metadata of a simulated spectral entry or dye series: its inputs and key, what the optics,
    the transport and eq. (5) chose and measured, and the seconds each took."""
    return {
        **inputs,
        "key": key,
        "host_index": optics.boundary_index,
        "phase_grid": {"kind": optics.phase_grid, "samples": optics.phase_samples},
        "incidence_resolution": brdf.incidence_grid.resolution,
        "exit_resolution": brdf.exit_grid.resolution,
        "incidence_grid_checks": [check.to_dict() for check in checks],
        "radius_mm": transport.geometry.radius_mm,
        "paths": _paths_record(transport),
        "seconds": seconds,
    }


def _paths_record(transport) -> dict:
    return {
        "per_incidence_cell": transport.paths_per_cell.tolist(),
        # traced: a cell that mirrors another's tallies (precompute/transport/symmetry.py) shares its paths
        "total": transport.traced_paths,
        "incidence_cells_traced": int(transport.symmetry.traced.sum()),
        "min": int(transport.paths_per_cell.min()),
        "max": int(transport.paths_per_cell.max()),
        "scattering_events": int(transport.events),
        "albedo_rel_stderr_max": float(transport.counted_albedo_rel_stderr().max()),
        "lost_fraction_max": float(transport.lost_fraction.max()),
    }


def _simulate(configuration: BakeConfiguration, inputs: dict, key: str, threads, progress, executor) -> Callable:
    """The writer of a spectral cache entry: optics → transport → yarn BRDF → spectral.npz."""

    def write(folder: pathlib.Path) -> None:
        settings = configuration.transport
        start = time.perf_counter()
        optics = medium_optics(configuration.medium)
        geometry = YarnGeometry(configuration.medium.yarn.radius_mm, optics.boundary_index)
        grids = TransportGrids(settings["n_around"], settings["n_along"], settings["angular_resolution"])
        optics_seconds = time.perf_counter() - start

        def transport_progress(fraction: float) -> None:
            if progress is not None:
                progress(0.9 * fraction)  # the BRDF integration and the tables take the last tenth

        transport = simulate_yarn(
            optics, geometry, grids,
            paths_per_cell=settings["paths_per_cell"], target_rel_stderr=settings["target_rel_stderr"],
            seed=settings["seed"], threads=threads, progress=transport_progress, executor=executor,
        )
        brdf_start = time.perf_counter()
        n_i = settings["incidence_resolution"]
        brdf, checks = yarn_brdf_to_tolerance(transport, INCIDENCE_RESOLUTIONS if n_i == "auto" else (n_i,))
        record = _simulation_record(inputs, key, optics, transport, brdf, checks,
                                    {"optics": optics_seconds, "transport": transport.wall_seconds,
                                     "brdf": time.perf_counter() - brdf_start})
        # not compressed: ρ and its error are Monte-Carlo noise in float32, which zlib shrinks by ~12 %
        # (15.6 MB against 17.9 MB at the default) in ~0.5 s of every bake
        np.savez(
            folder / SPECTRAL_FILE,
            metadata=np.array(json.dumps(record, allow_nan=False)),
            wavelengths_nm=brdf.wavelengths_nm,
            rho=brdf.rho.astype(np.float32),
            rho_stderr=brdf.rho_stderr.astype(np.float32),
            hemispherical_albedo=brdf.hemispherical_albedo(),
            specular=transport.specular,
            exit_fraction=transport.exit_fraction,
            unscattered_fraction=transport.unscattered_fraction,
            absorbed_fraction=transport.absorbed_fraction,
            albedo_rel_stderr=transport.albedo_rel_stderr,
            paths_per_cell=transport.paths_per_cell,
            mu_s=optics.mu_s,
            mu_a=optics.mu_a,
            unscattered_mu_t=optics.unscattered_extinction_per_mm,
            g=optics.g,
        )

    return write


# ---- dye series: any dye amount of a range from one simulation (precompute/transport/absorption.py) ----


def check_dye_series(configuration: BakeConfiguration, dye_series) -> tuple[float, float]:
    """The dye range (low, high) in % of fibre weight, checked: a dyed medium whose dye amount lies in it."""
    dye = configuration.medium.dye
    if dye is None:
        raise ParameterError("dye_series", dye_series, "a dyed medium (this preset has no [dye])")
    if not configuration.medium.dye_only_absorbs:
        raise ParameterError("dye_series", dye_series, "a medium whose dye only absorbs: in randomly oriented "
                                                       "fibres it changes how they scatter, so a dye change needs "
                                                       "a new simulation (fibres along the yarn axis take a series)")
    low, high = bounds.check_dye_range(dye_series)
    if not low <= dye.weight_percent <= high:
        raise ParameterError("dye.weight_percent", dye.weight_percent, f"within the dye series' {low:g}–{high:g} %")
    return low, high


def series_inputs(configuration: BakeConfiguration, dye_range: tuple[float, float]) -> tuple[str, dict]:
    """The folder (per medium without its dye amount) and the inputs of a dye series' cache entry."""
    inputs = spectral_inputs(configuration)
    inputs["medium"]["dye"]["weight_percent"] = None
    inputs["format"] = SERIES_FORMAT
    folder = f"{SERIES_NAMESPACE}/{cache_key(inputs)}"
    return folder, {**inputs, "dye_range_percent": list(dye_range)}


def _simulate_series(configuration: BakeConfiguration, inputs: dict, key: str, dye_range, threads,
                     progress, executor) -> Callable:
    """The writer of a dye series: one transport at the least dye with its exits tallied at the
    absorption steps up to the most (:func:`precompute.transport.absorption.absorption_steps`), and
    eq. (5) at every step on the incidence grid the least-dyed yarn needs."""

    def write(folder: pathlib.Path) -> None:
        settings = configuration.transport
        start = time.perf_counter()
        reference = medium_optics(configuration.medium.with_dye(dye_range[0]))
        largest = medium_optics(configuration.medium.with_dye(dye_range[1]))
        steps = absorption_steps(reweighted_absorption(reference), reweighted_absorption(largest))
        geometry = YarnGeometry(configuration.medium.yarn.radius_mm, reference.boundary_index)
        grids = TransportGrids(settings["n_around"], settings["n_along"], settings["angular_resolution"])
        optics_seconds = time.perf_counter() - start
        transport = simulate_yarn(
            reference, geometry, grids,
            paths_per_cell=settings["paths_per_cell"], target_rel_stderr=settings["target_rel_stderr"],
            seed=settings["seed"], threads=threads, extra_absorption_per_mm=steps,
            progress=None if progress is None else (lambda fraction: progress(0.8 * fraction)), executor=executor,
        )
        brdf_start = time.perf_counter()
        n_i = settings["incidence_resolution"]
        brdf, checks = yarn_brdf_to_tolerance(transport, INCIDENCE_RESOLUTIONS if n_i == "auto" else (n_i,))
        rho_steps = np.empty((*brdf.rho.shape, len(steps)), np.float32)
        for step in range(len(steps)):
            rho_steps[..., step] = yarn_brdf(step_transport(transport, step), brdf.incidence_grid.resolution).rho
            if progress is not None:
                progress(0.8 + 0.1 * (step + 1) / len(steps))
        decayed = transport.decayed
        record = _simulation_record(inputs, key, reference, transport, brdf, checks,
                                    {"optics": optics_seconds, "transport": transport.wall_seconds,
                                     "brdf": time.perf_counter() - brdf_start})
        np.savez_compressed(
            folder / SERIES_FILE,
            metadata=np.array(json.dumps(record, allow_nan=False)),
            wavelengths_nm=brdf.wavelengths_nm,
            absorption_steps=steps,
            rho_steps=rho_steps,
            rho_stderr=brdf.rho_stderr.astype(np.float32),
            specular=transport.specular,
            exit_fraction_steps=decayed.exit_fraction,
            exit_second_moment_steps=decayed.exit_second_moment,
            unscattered_fraction_steps=decayed.unscattered_fraction,
            lost_fraction=transport.lost_fraction,
            albedo_rel_stderr=transport.albedo_rel_stderr,
            paths_per_cell=transport.paths_per_cell,
            mu_s=reference.mu_s,
            mu_a=reference.mu_a,
            reweighted_mu_a=reweighted_absorption(reference),
            reweighted_scattering=reweighted_scattering(reference),
            g=reference.g,
        )

    return write


def _reweighted_spectral(configuration: BakeConfiguration, inputs: dict, key: str,
                         series_folder: pathlib.Path) -> Callable:
    """The writer of a spectral entry read from a dye series at the configuration's dye amount: the
    same file as a simulation's (:func:`_simulate`), in seconds."""

    def write(folder: pathlib.Path) -> None:
        start = time.perf_counter()
        arrays, series = load_spectral(series_folder / SERIES_FILE)
        optics = medium_optics(configuration.medium)
        wavelengths = arrays["wavelengths_nm"]
        if not np.allclose(reweighted_scattering(optics), arrays["reweighted_scattering"], rtol=1e-12, atol=0.0):
            raise ParameterError("dye_series", series["key"], "a series of this medium's scattering (it differs)")

        def at_dye(values):
            return interpolate_absorption(values, arrays["reweighted_mu_a"], arrays["absorption_steps"],
                                          reweighted_absorption(optics), wavelengths)

        exit_fraction = at_dye(arrays["exit_fraction_steps"])
        albedo_rel_stderr = albedo_relative_stderr(exit_fraction, at_dye(arrays["exit_second_moment_steps"]),
                                                   arrays["paths_per_cell"])
        unscattered = at_dye(arrays["unscattered_fraction_steps"])
        rho = at_dye(arrays["rho_steps"])
        # ρ's error: the least dye's, scaled with ρ and with how much the albedo's relative error grew
        growth = np.divide(albedo_rel_stderr, arrays["albedo_rel_stderr"], out=np.ones_like(albedo_rel_stderr),
                           where=arrays["albedo_rel_stderr"] > 0).mean(axis=0)
        reference_rho = arrays["rho_steps"][..., 0]
        rho_stderr = arrays["rho_stderr"] * growth * np.divide(rho, reference_rho, out=np.zeros_like(rho),
                                                               where=reference_rho > 0)
        incidence_grid = AngularGrid("sphere", series["incidence_resolution"])
        exit_grid = AngularGrid("hemisphere", series["exit_resolution"])
        brdf = YarnBRDF(wavelengths, incidence_grid, exit_grid, rho, rho_stderr)
        counted = counted_wavelengths(exit_fraction)
        record = {
            **inputs,
            "key": key,
            **{name: series[name] for name in ("host_index", "phase_grid", "incidence_resolution", "exit_resolution",
                                               "incidence_grid_checks", "radius_mm")},
            # the series' paths, with the error they give at this dye amount (larger than at the least dye)
            "paths": {**series["paths"], "albedo_rel_stderr_max": float(albedo_rel_stderr[counted].max())},
            "seconds": {"optics": 0.0, "transport": 0.0, "brdf": 0.0, "reweighting": time.perf_counter() - start},
        }
        np.savez_compressed(
            folder / SPECTRAL_FILE,
            metadata=np.array(json.dumps(record, allow_nan=False)),
            wavelengths_nm=wavelengths,
            rho=rho.astype(np.float32),
            rho_stderr=rho_stderr.astype(np.float32),
            hemispherical_albedo=brdf.hemispherical_albedo(),
            specular=arrays["specular"],
            exit_fraction=exit_fraction,
            unscattered_fraction=unscattered,
            absorbed_fraction=1.0 - arrays["specular"] - exit_fraction - unscattered - arrays["lost_fraction"],
            albedo_rel_stderr=albedo_rel_stderr,
            paths_per_cell=arrays["paths_per_cell"],
            mu_s=optics.mu_s,
            mu_a=optics.mu_a,
            unscattered_mu_t=optics.unscattered_extinction_per_mm,
            g=optics.g,
        )

    return write


def load_spectral(path: str | pathlib.Path) -> tuple[dict, dict]:
    """The arrays and the metadata of a ``spectral.npz`` (see :func:`_simulate`)."""
    with np.load(path, allow_pickle=False) as data:
        arrays = {name: data[name] for name in data.files if name != "metadata"}
        metadata = json.loads(str(data["metadata"]))
    return arrays, metadata


def _normal_rgb(atlas: np.ndarray, incidence_resolution: int) -> np.ndarray:
    """ρ at normal incidence and normal view, interpolated as the shader does."""
    normal = np.array([0.0, 0.0, 1.0])
    return interpolate_rho(atlas, incidence_resolution, normal, normal)


def _tables(configuration: BakeConfiguration, inputs: dict, key: str, spectral_folder: pathlib.Path) -> Callable:
    """The writer of a tables cache entry: spectral.npz → RGB → OpenEXR tables and summary.json."""

    def write(folder: pathlib.Path) -> None:
        start = time.perf_counter()
        arrays, spectral = load_spectral(spectral_folder / SPECTRAL_FILE)
        colour = configuration.colour
        wavelengths = arrays["wavelengths_nm"]
        n_i, n_o = spectral["incidence_resolution"], spectral["exit_resolution"]

        def to_rgb(values):
            return spectral_to_rgb(values, wavelengths, colour["illuminant"], colour["observer"])

        rho_unclipped = to_rgb(arrays["rho"])
        rho, clipped_share = clip_to_gamut(rho_unclipped)
        stderr = spectral_stderr_to_rgb(arrays["rho_stderr"], wavelengths, colour["illuminant"], colour["observer"])
        albedo, _ = clip_to_gamut(to_rgb(arrays["hemispherical_albedo"]))
        atlas = brdf_atlas(rho)
        attenuation_spectra = ballistic.attenuation(
            arrays["unscattered_mu_t"], spectral["radius_mm"], ballistic.attenuation_lengths()
        )
        attenuation, _ = clip_to_gamut(to_rgb(attenuation_spectra))
        unscattered_table = attenuation[None]
        host_index = spectral["host_index"]
        lobe_shape = LobeShape()
        weights, fit_error = fit_closure_weights(
            atlas, n_i, lobe_shape, subsamples=max(1, round(CLOSURE_FIT_SAMPLES_PER_SIDE / n_i))
        )
        rho_normal = _normal_rgb(atlas, n_i)
        rho_normal_unclipped = _normal_rgb(brdf_atlas(rho_unclipped), n_i)
        header = {
            "code_version": __version__,
            "code_digest": {"spectral": spectral["code_digest"], "tables": inputs["code_digest"]},
            "cache_key": key,
            "spectral_key": spectral["key"],
            "medium": spectral["medium"],
            "phase_grid": spectral.get("phase_grid"),
            "transport": spectral["transport"],
            **({"dye_series": spectral["dye_series"]} if "dye_series" in spectral else {}),
            "paths": spectral["paths"],
            "colour": {
                **colour,
                "rgb_space": f"linear {RGB_SPACE} (Blender scene linear)",
                "white_balance_factors": white_balance_factors(
                    wavelengths, colour["illuminant"], colour["observer"]
                ).tolist(),
                "gamut_clipping_max_relative": clipped_share,
            },
            "units": UNITS,
            "host_index": spectral["host_index"],
            SPECULAR_KEY: configuration.specular,
            **_sample_weave_record(configuration),
            "wavelengths_nm": wavelengths.tolist(),
        }
        layout = {"incidence_resolution": n_i, "exit_resolution": n_o}
        images = {
            "brdf": atlas,
            "brdf_stderr": brdf_atlas(stderr),
            "albedo": albedo.reshape(n_i, n_i, 3),
            "closure_lobes": lobe_atlas(weights),
            "unscattered": unscattered_table,
        }
        extra_layout = {
            "closure_lobes": {"lobe_count": len(LOBES)},
            "unscattered": {
                "attenuation_samples": ballistic.ATTENUATION_SAMPLES,
                "max_length_over_radius": ballistic.MAX_LENGTH_OVER_RADIUS,
                "orders": ballistic.ORDERS,
            },
        }
        for kind, image in images.items():
            metadata = {**header, "table": kind, "layout": {**layout, **extra_layout.get(kind, {})}}
            if kind == "closure_lobes":
                metadata["lobes"] = list(LOBES)
                metadata["lobe_shape"] = lobe_shape.to_dict()
            write_table(folder / TABLE_FILES[kind], image, metadata)
        _link_or_copy(spectral_folder / SPECTRAL_FILE, folder / SPECTRAL_FILE)
        summary = {
            **header,
            "schema": SCHEMA,
            "spectral_format": SPECTRAL_FORMAT,
            "files": {**TABLE_FILES, "spectral": SPECTRAL_FILE},
            "incidence_resolution": n_i,
            "exit_resolution": n_o,
            "lobe_count": len(LOBES),
            "lobe_shape": lobe_shape.to_dict(),
            "unscattered_samples": ballistic.ATTENUATION_SAMPLES,
            "rho_normal_rgb": rho_normal.tolist(),
            "unscattered_normal_view_rgb": ballistic.unscattered_radiance_factor(
                np.array([0.0, 0.0, 1.0]), host_index,
                lambda length: interpolate_attenuation(unscattered_table, length),
            ).tolist(),
            "incidence_grid_checks": spectral["incidence_grid_checks"],
            "table1_ratios_normal": _json_ratios(rho_normal),
            "table1_ratios_normal_unclipped": _json_ratios(rho_normal_unclipped),
            "table1_ratios_paper_real_red_cotton": {"B/R": 0.08, "G/R": 0.011},
            "closure_fit_relative_error_median_rgb": np.median(fit_error, axis=0).tolist(),
            "seconds": {**spectral["seconds"], "tables": time.perf_counter() - start},
            # every file's bytes, so that a reader finds a file changed or mixed in from another bake
            FILE_HASHES_KEY: file_hashes(folder, [*TABLE_FILES.values(), SPECTRAL_FILE]),
        }
        (folder / SUMMARY_FILE).write_text(json.dumps(json.loads(canonical_json(summary)), indent=1))

    return write


def _json_ratios(rgb) -> dict:
    """B/R and G/R, None where undefined (R = 0: a yarn black at normal incidence and view)."""
    return {name: value if np.isfinite(value) else None for name, value in channel_ratios(rgb).items()}


def _link_or_copy(source: pathlib.Path, target: pathlib.Path) -> None:
    try:
        os.link(source, target)
    except OSError:
        shutil.copy2(source, target)


def bake(
    preset_or_params: str | pathlib.Path | Mapping | MediumParameters = DEFAULT_PRESET,
    overrides: Sequence[str] | Mapping[str, object] = (),
    *,
    seed: int | None = None,
    paths_per_cell: int | None = None,
    target_rel_stderr: float | None = None,
    threads: int | None = None,
    cache_dir: str | pathlib.Path | None = None,
    progress: Callable[[float], None] | None = None,
    dye_series: tuple[float, float] | None = None,
    scheduler: str | None = None,
) -> BakeResult:
    """Bake (or find in the cache) the tables of a yarn.

    Parameters
    ----------
    preset_or_params
        A shipped preset's name, a preset TOML path, a preset's parsed TOML
        content, or :class:`~precompute.optics.medium.MediumParameters` (then only
        ``transport.*`` and ``bake.*`` overrides apply).
    overrides
        ``"key=value"`` strings (values are TOML literals) or a mapping of
        dotted keys, e.g. ``dye.weight_percent=2``, ``transport.seed=3``.
    seed, paths_per_cell, target_rel_stderr
        Override the ``[transport]`` seed and path budget (paths per incidence
        cell, or the relative standard error of every cell's albedo).
    threads
        CPU threads of the transport (default: all); with ``scheduler="local"`` its worker processes.
        The result does not depend on it.
    cache_dir
        Cache folder (default :func:`precompute.cache.entries.default_cache_dir`).
    progress
        Called with the completed fraction in [0, 1].
    dye_series
        A dye range (low, high), % of fibre weight, holding the preset's dye amount: the simulation
        is made once for the range (at the least dye, its exits tallied at the absorption steps up to
        the most; cached) and the tables at any dye amount in it are read from it in seconds
        (:mod:`precompute.transport.absorption`), instead of a simulation per amount.
    scheduler
        Where the transport runs (:mod:`precompute.distributed`): None (default) in this process,
        ``"local"`` on a LocalCluster of this machine's cores, ``"tcp://HOST:PORT"`` on that cluster.
        The tables and every cache key are the same wherever it ran; the cluster is reached (and its
        workers' code checked) only when there is something to simulate, before anything is written.
    """
    started = time.perf_counter()
    scheduler = check_scheduler(scheduler, "scheduler")
    if threads is not None:
        if scheduler not in (None, LOCAL):
            raise ParameterError("threads", threads, f"unset with the cluster {scheduler} (its workers' threads count)")
        _integer("threads", threads, 1, numba.config.NUMBA_NUM_THREADS)
    configuration = bake_configuration(
        preset_or_params, overrides, seed=seed, paths_per_cell=paths_per_cell, target_rel_stderr=target_rel_stderr
    )
    cache_dir = check_writable_folder(cache_dir if cache_dir is not None else default_cache_dir(), "cache_dir",
                                      what="a cache folder")
    spectral_in = spectral_inputs(configuration)
    if dye_series is not None:
        dye_range = check_dye_series(configuration, dye_series)
        series_folder_name, series_in = series_inputs(configuration, dye_range)
        series_key = cache_key(series_in)
        spectral_in["dye_series"] = {"key": series_key, "dye_range_percent": list(dye_range)}
    spectral_key = cache_key(spectral_in)
    tables_in = table_inputs(spectral_key, configuration)
    tables_key = cache_key(tables_in)

    folder = lookup(cache_dir, "tables", tables_key)
    cache_hit = folder is not None
    simulated = False
    if not cache_hit:
        spectral_folder = lookup(cache_dir, "spectral", spectral_key)
        if spectral_folder is None and dye_series is not None:
            series_folder = lookup(cache_dir, series_folder_name, series_key)
            if series_folder is None:
                with _transport_executor(scheduler, threads) as executor:
                    simulate = _simulate_series(configuration, series_in, series_key, dye_range, threads, progress,
                                                executor)
                    series_folder, _ = store(cache_dir, series_folder_name, series_key, series_in, simulate)
                simulated = True
            reweight = _reweighted_spectral(configuration, spectral_in, spectral_key, series_folder)
            spectral_folder, _ = store(cache_dir, "spectral", spectral_key, spectral_in, reweight)
        elif spectral_folder is None:
            with _transport_executor(scheduler, threads) as executor:
                simulate = _simulate(configuration, spectral_in, spectral_key, threads, progress, executor)
                spectral_folder, _ = store(cache_dir, "spectral", spectral_key, spectral_in, simulate)
            simulated = True
        write_tables = _tables(configuration, tables_in, tables_key, spectral_folder)
        folder, _ = store(cache_dir, "tables", tables_key, tables_in, write_tables)
    if progress is not None:
        progress(1.0)
    summary = json.loads((folder / SUMMARY_FILE).read_text())
    summary.update(
        folder=str(folder),
        brdf_table=str(folder / TABLE_FILES["brdf"]),
        lobe_table=str(folder / TABLE_FILES["closure_lobes"]),
        cache_hit=cache_hit,
        simulated=simulated,
        call_seconds=time.perf_counter() - started,
    )
    return BakeResult(folder, cache_hit, simulated, summary)


def _transport_executor(scheduler: str | None, threads: int | None):
    """A ``with`` context giving the transport's executor on ``scheduler``, checked (None: this process)."""
    if scheduler is None:
        return contextlib.nullcontext()
    return open_executor(scheduler, code=SPECTRAL_SOURCES, workers=threads if scheduler == LOCAL else None)


def export_bake(result: BakeResult, out_dir: str | pathlib.Path) -> dict:
    """Copy a bake's files into the folder ``out_dir`` as a whole; the summary with the new paths.

    ``out_dir`` must be new, empty or an earlier bake's folder (:func:`precompute.tables.folder.
    check_output_folder`, ParameterError otherwise).  The copy is checked
    (:func:`~precompute.tables.folder.check_yarn_table_folder`) and then swapped in for the previous
    folder in one step (:func:`~precompute.tables.folder.replace_folder`): a reader, or a bake killed at
    any moment, finds the complete previous folder or the complete new one, never a mixture.
    """

    def write(staging: pathlib.Path) -> None:
        for name in YARN_FOLDER_FILES:
            if (result.folder / name).is_file():
                shutil.copy2(result.folder / name, staging / name)
        check_yarn_table_folder(staging)

    out_dir = replace_folder(out_dir, write, YARN_FOLDER_FILES)
    return {
        **result.summary,
        "folder": str(out_dir),
        "cache_folder": str(result.folder),
        "brdf_table": str(out_dir / TABLE_FILES["brdf"]),
        "lobe_table": str(out_dir / TABLE_FILES["closure_lobes"]),
    }


__all__ = [
    "BAKE_DEFAULTS",
    "TRANSPORT_DEFAULTS",
    "BakeConfiguration",
    "BakeResult",
    "apply_overrides",
    "bake",
    "bake_configuration",
    "export_bake",
    "load_spectral",
    "parse_override",
    "specular_settings",
    "transport_settings",
]
