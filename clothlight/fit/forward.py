"""The fit's forward model: a medium → the cloth BRDF at the measured views, in seconds.

A candidate runs the chain of a bake without what a sun-mode sweep does not read and without the
cache: optics → transport (a path budget set by the accuracy asked for) → eq. (5) on one fixed
incidence grid → RGB atlas and unscattered attenuation, clipped to the gamut as the tables are.
The sweep itself is the cloth response (:mod:`clothlight.validation.response`), rendered once per
weave, rig and view set and kept in the cache, then applied to each candidate's tables in
milliseconds.  The sample is measured at the azimuths its preset's ``[sample] azimuths_deg`` names
(0° and 90° by default) and averaged, as an instrument that measures cloth as an isotropic BRDF
averages the weave over its azimuth (``../shared/data/real_fabrics/README.md``: MERL's samples were
wrapped round a cylinder; :mod:`precompute.optics.measured_sample`).

Views are the measured-data CSV's ``(θi, φi, θo, φo)`` (``Measurement.angles_deg``): light at
φi = 180°, φo = 180° on the light's side, 0° beyond the normal, 90° the perpendicular plane, and any
azimuth between (the raw-data curves' 45° and 135°).  Each view is rendered with the camera square to
the sample's weave (the sample turned so that the camera's azimuth on it is 0° or 90°), so that every
view frames whole weave repeats: :func:`sample_azimuths`.
"""

from __future__ import annotations

import math
import pathlib
from collections.abc import Callable, Sequence

import numpy as np

from precompute.optics import ballistic
from precompute.bake import BAKE_DEFAULTS, transport_settings
from precompute.cache.entries import cache_key, canonical_json, default_cache_dir, lookup, store
from precompute.tables.color import clip_to_gamut, spectral_to_rgb
from precompute.errors import ParameterError
from precompute.fit.optimise import cloth_from_parts
from precompute.optics.medium import medium_from_dict
from precompute.optics.measured_sample import DEFAULT_SAMPLE_AZIMUTHS_DEG, sample_azimuths_deg, sample_weave_name
from precompute.optics.coefficients import medium_optics
from precompute.optics.cook_torrance import sheen_index
from precompute.cache.sources import stage_digest
from precompute.tables.layout import brdf_atlas

from ..weave import WeaveParameters
from ..weave.record import weave_record
from ..weave.sample_weaves import sample_weave

PROJECT_ROOT = pathlib.Path(__file__).resolve().parents[2]
#: Incidence grid of a candidate's eq. (5): the shipped tables' (an odd N_i puts the planes across
#: and along the yarn through cell centres), fixed so that one linear map serves every candidate.
FIT_INCIDENCE_RESOLUTION = 21
#: Paths per incidence cell at a relative error of 5 %; the budget grows as 1 / error².
PATHS_AT_FIVE_PERCENT = 1000
#: The §6.1 colour swatches the model also gives, after the measured views: normal view, lit from the
#: front and from straight behind, (θi, θv, φv) in degrees (clothlight.blender.validation.run's swatches).
SWATCH_VIEWS = ((0.0, 0.0, 0.0), (180.0, 0.0, 0.0))
#: The response's sweep resolution (pixels along the patch side) and camera samples per pixel
#: along each axis: 16 samples per pixel, as a default validation sweep.
RESPONSE_RESOLUTION = 64
RESPONSE_SUPERSAMPLING = 4
RESPONSE_FILE = "response.npz"
#: The validation weave (12 × 12 yarns, 6 mm) frames a patch with its edges out of view for views to
#: 70° and light to 60° (the ABC curves); beyond that (the raw-data curves: views to 80°, light to
#: 75°) the response renders this wider sample, 10 mm, which frames two repeats there.
WIDE_VIEW_WEAVE = WeaveParameters(warp_count=20, weft_count=20)
VALIDATION_WEAVE_MAX_VIEW_DEG = 70.0
VALIDATION_WEAVE_MAX_INCIDENCE_DEG = 60.0


def paths_per_cell(relative_error: float) -> int:
    """The transport's paths per incidence cell for a cloth-level relative error (e.g. 0.05)."""
    if not (isinstance(relative_error, (int, float)) and 0.0 < relative_error <= 0.5):
        raise ParameterError("relative_error", relative_error, "a number in (0, 0.5]")
    return max(64, int(round(PATHS_AT_FIVE_PERCENT * (0.05 / relative_error) ** 2)))


def rig_views(measured_views: Sequence[tuple[float, float, float, float]]) -> list[tuple[float, float, float]]:
    """The rig's (θi, θv, φv) of measured-data views (θi, φi, θo, φo): θv signed in the plane of
    incidence (negative on the light's side, φv = 0), else θv = θo at the view's azimuth φv from the
    plane, folded into (0°, 180°) (an isotropic cloth reflects alike on both sides of the plane):
    90° for the perpendicular plane, 45° and 135° for the raw-data curves' diagonals."""
    views = []
    for theta_i, phi_i, theta_o, phi_o in measured_views:
        if theta_i != 0.0 and not math.isclose(float(phi_i) % 360.0, 180.0):
            raise ParameterError("view φi", phi_i, "180°: the rig's sun lies on the −x side")
        phi = float(phi_o) % 360.0
        folded = min(phi, 360.0 - phi)
        if theta_o == 0.0 or math.isclose(folded, 0.0, abs_tol=1e-9):
            views.append((float(theta_i), float(theta_o), 0.0))
        elif math.isclose(folded, 180.0):
            views.append((float(theta_i), -float(theta_o), 0.0))
        else:
            views.append((float(theta_i), float(theta_o), folded))
    return views


def sample_azimuths(phi_v_deg: float, azimuths_deg=DEFAULT_SAMPLE_AZIMUTHS_DEG) -> tuple[float, ...]:
    """The sample azimuths α (degrees) a view at azimuth ``phi_v_deg`` is rendered and averaged at:
    ``azimuths_deg`` (the preset's ``[sample] azimuths_deg``) less the view's azimuth modulo 90°, so
    that at the default 0° and 90° the camera lies at 0° or 90° on the sample (the response's renders
    turn sun and camera by α), where the framed patch holds whole weave repeats; the weave then lies
    at the same angles to the light in every view.  At a diagonal α the camera frames the weave
    turned by 45°, its patch holding part repeats at its edges."""
    turn = float(phi_v_deg) % 90.0
    return tuple(azimuth - turn for azimuth in azimuths_deg)


def lookup_tables_folder(root: pathlib.Path = PROJECT_ROOT) -> pathlib.Path:
    """Tables for the cloth response's renders, which record the shader's lookup directions and so
    take any medium's: the repository's example tables, or in the extension (which ships no
    ``example_blends/``) the first pre-baked preset's (``prebaked/<preset>/``)."""
    candidates = [root / "example_blends" / "tables" / "paper_2008", *sorted((root / "prebaked").glob("*"))]
    for folder in candidates:
        if (folder / "summary.json").is_file():
            return folder
    raise FileNotFoundError(f"no yarn tables to render the cloth response with: neither {candidates[0]} nor a "
                            f"pre-baked folder in {root / 'prebaked'}")


def cloth_response(measured_views, *, weave: WeaveParameters | None = None, seed: int = 0, cache_dir=None,
                   progress: Callable[[int, int], None] | None = None, azimuths_deg=DEFAULT_SAMPLE_AZIMUTHS_DEG):
    """The cloth response at ``measured_views``, each at the sample azimuths of ``azimuths_deg``
    (:func:`sample_azimuths`), from the cache or
    rendered (Blender as the ``bpy`` module; a minute or two) with Cycles' ``seed``, on ``weave``
    (None: the validation weave, or :data:`WIDE_VIEW_WEAVE` where the views need it)."""
    from ..validation.response import ClothResponse

    views = [(*view, azimuth) for view in (*rig_views(measured_views), *SWATCH_VIEWS)
             for azimuth in sample_azimuths(view[2], azimuths_deg)]
    inputs = {
        "schema": "clothlight-response-entry/1",
        "views": views,
        "resolution": RESPONSE_RESOLUTION,
        "supersampling": RESPONSE_SUPERSAMPLING,
        "seed": int(seed),
        "code_digest": stage_digest(PROJECT_ROOT, ["clothlight.blender.validation.response_render"]),
    }
    wide = (max(abs(v[1]) for v in views) > VALIDATION_WEAVE_MAX_VIEW_DEG
            or max(min(v[0], 180.0 - v[0]) for v in views) > VALIDATION_WEAVE_MAX_INCIDENCE_DEG)
    sample = weave or (WIDE_VIEW_WEAVE if wide else None)
    if weave is not None:
        inputs["sample_weave"] = weave_record(weave)
    elif wide:  # (responses of the validation weave keep the keys they had)
        inputs["sample_yarns"] = [WIDE_VIEW_WEAVE.warp_count, WIDE_VIEW_WEAVE.weft_count]
    cache_dir = pathlib.Path(cache_dir) if cache_dir is not None else default_cache_dir()
    key = cache_key(inputs)
    folder = lookup(cache_dir, "responses", key)
    if folder is None:

        def write(staging: pathlib.Path) -> None:
            from ..blender.validation.response_render import measure_response
            from ..yarn_tables import yarn_tables_from_bake

            # Any tables: the lookup directions do not depend on the medium.
            tables = yarn_tables_from_bake(lookup_tables_folder())
            measure_response(tables, views, sample, resolution=RESPONSE_RESOLUTION,
                             supersampling=RESPONSE_SUPERSAMPLING, seed=seed,
                             progress=progress).save(staging / RESPONSE_FILE)

        folder, _ = store(cache_dir, "responses", key, inputs, write)
    return ClothResponse.load(folder / RESPONSE_FILE)


class ForwardModel:
    """``model(config, specular_weight=, specular_slope=, relative_error=, seed=, fuzz_albedo=0, fuzz_depth=0)`` →
    the cloth BRDF
    (n_views + 2, 3), 1/sr, linear Rec.709, at the measured views given to :func:`build_forward_model`
    and then at the :data:`SWATCH_VIEWS` (:attr:`swatch_count` rows: the BRDF lit from the front,
    and the BTDF lit from straight behind, both at normal view).  The specular term's Fresnel factor
    takes the candidate medium's index, as its bake records it for the shader
    (``precompute.optics.cook_torrance.sheen_index``: the fibres' for a yarn of fibres in air)."""

    swatch_count = len(SWATCH_VIEWS)

    def __init__(self, response, view_count: int, base_dir: pathlib.Path, threads: int | None = None,
                 azimuth_count: int = len(DEFAULT_SAMPLE_AZIMUTHS_DEG)):
        self.response = response
        self.view_count = view_count + self.swatch_count
        self.azimuth_count = azimuth_count
        self.base_dir = pathlib.Path(base_dir)
        self.threads = threads

    def tables(self, config: dict, *, relative_error: float, seed: int):
        """A candidate's BRDF atlas (N_i·N_o, N_i·N_o, 3), attenuation table (M, 3) and their layout."""
        from precompute.transport import simulate_yarn, yarn_brdf

        medium = medium_from_dict(config, self.base_dir)
        optics = medium_optics(medium)
        geometry, grids, settings = _yarn_and_grids(config, medium, optics, seed, paths_per_cell(relative_error))
        transport = simulate_yarn(optics, geometry, grids, paths_per_cell=settings["paths_per_cell"],
                                  seed=settings["seed"], threads=self.threads)
        return _candidate_tables(config, optics, geometry, yarn_brdf(transport, FIT_INCIDENCE_RESOLUTION).rho)

    def _mean_over_azimuths(self, per_view: np.ndarray) -> np.ndarray:
        return per_view.reshape(self.view_count, self.azimuth_count, *per_view.shape[1:]).mean(axis=1)

    def cloth_brdf(self, atlas, attenuation, layout, *, specular_weight: float, specular_slope: float,
                   specular_index: float | None = None, **fuzz) -> np.ndarray:
        """The cloth BRDF of given tables at the measured views, averaged over the sample azimuths;
        ``fuzz``: the fuzz's keywords of :meth:`clothlight.validation.response.ClothResponse.cloth_brdf`."""
        return self._mean_over_azimuths(self.response.cloth_brdf(
            atlas, attenuation, layout, specular_weight=specular_weight, specular_slope=specular_slope,
            specular_index=specular_index, **fuzz))

    def parts(self, config: dict, *, relative_error: float, seed: int):
        """The cloth BRDF split into what the medium gives and what the cloth-scale terms do: the
        first (n_views, 3), 1/sr, with neither, and :class:`ClothTerms`, ``terms(weight, slope,
        **fuzz)`` (n_views, 3), 1/sr: the sheen and the fuzz, and
        ``terms.transmittance(fuzz_depth)``, the fuzz's shade on the first.  A fit optimises their
        parameters for each medium in milliseconds."""
        atlas, attenuation, layout = self.tables(config, relative_error=relative_error, seed=seed)
        yarn = self.cloth_brdf(atlas, attenuation, layout, specular_weight=0.0, specular_slope=1.0)
        return yarn, ClothTerms(self, sheen_index(medium_from_dict(config, self.base_dir)))

    def __call__(self, config: dict, *, specular_weight: float, specular_slope: float, relative_error: float,
                 seed: int, **fuzz) -> np.ndarray:
        yarn, terms = self.parts(config, relative_error=relative_error, seed=seed)
        return cloth_from_parts(yarn, terms, {"specular_weight": specular_weight, "specular_slope": specular_slope,
                                              **fuzz})


class ClothTerms:
    """The cloth-scale terms of one candidate at a forward model's views (:meth:`ForwardModel.parts`):
    ``terms(weight, slope, fuzz_albedo=0, fuzz_depth=0, fuzz_asymmetry=0, fuzz_tint=(1, 1, 1),
    fuzz_flatness=0)`` what the sheen and the fuzz add (n_views, 3), 1/sr, RGB, and
    ``terms.transmittance(fuzz_depth, fuzz_flatness)`` (n_views,) the share of the yarn's light that
    crosses the fuzz (:mod:`precompute.optics.lommel_seeliger`)."""

    def __init__(self, model: ForwardModel, index: float):
        self.model, self.index = model, index

    def __call__(self, weight: float, slope: float, fuzz_albedo: float = 0.0, fuzz_depth: float = 0.0,
                 fuzz_asymmetry: float = 0.0, fuzz_tint=(1.0, 1.0, 1.0), fuzz_flatness: float = 0.0) -> np.ndarray:
        return self.model._mean_over_azimuths(self.model.response.specular_brdf(
            weight, slope, self.index, fuzz_albedo, fuzz_depth, fuzz_asymmetry, fuzz_tint, fuzz_flatness))

    def transmittance(self, fuzz_depth: float, fuzz_flatness: float = 0.0) -> np.ndarray:
        return self.model._mean_over_azimuths(self.model.response.fuzz_transmittance(fuzz_depth, fuzz_flatness))


def _yarn_and_grids(config: dict, medium, optics, seed: int, paths: int):
    """The yarn, the transport grids and the ``[transport]`` settings of a candidate at ``paths`` per cell."""
    from precompute.transport import TransportGrids, YarnGeometry

    settings = transport_settings(config, seed=seed, paths_per_cell=paths)
    geometry = YarnGeometry(medium.yarn.radius_mm, optics.boundary_index)
    grids = TransportGrids(settings["n_around"], settings["n_along"], settings["angular_resolution"])
    return geometry, grids, settings


def absorption_series(config: dict, medium, reference, largest_mu_a: np.ndarray, *, relative_error: float,
                      seed: int, threads: int | None = None):
    """One transport of ``medium`` at the ``reference`` optics (the least absorbing), its exits tallied at
    the absorption steps up to ``largest_mu_a`` (L,), 1/mm (:mod:`precompute.transport.absorption`; the
    absorption it reweights, :func:`~precompute.transport.absorption.reweighted_absorption`), and eq. (5)
    at every step on the fit's incidence grid: (reference μa, steps (K, L), ρ (N_i², N_o², L, K) float32,
    yarn geometry), from which any absorption in between is read in about a second."""
    from precompute.transport import simulate_yarn, yarn_brdf
    from precompute.transport.absorption import absorption_steps, reweighted_absorption, step_transport

    geometry, grids, settings = _yarn_and_grids(config, medium, reference, seed, paths_per_cell(relative_error))
    reference_mu_a = reweighted_absorption(reference)
    steps = absorption_steps(reference_mu_a, largest_mu_a)
    transport = simulate_yarn(reference, geometry, grids, paths_per_cell=settings["paths_per_cell"],
                              seed=settings["seed"], threads=threads, extra_absorption_per_mm=steps)
    rho_steps = np.stack([yarn_brdf(step_transport(transport, k), FIT_INCIDENCE_RESOLUTION).rho
                          for k in range(len(steps))], axis=-1).astype(np.float32)
    return reference_mu_a, steps, rho_steps, geometry


def _candidate_tables(config: dict, optics, geometry, rho: np.ndarray):
    """Eq. (5)'s spectral ρ (N_i², N_o², L) on the fit's incidence grid → the BRDF atlas, the
    attenuation table (RGB, clipped to the gamut as the bake's tables) and their layout."""
    from ..validation.response import TableLayout

    colour = {**BAKE_DEFAULTS, **config.get("bake", {})}

    def to_rgb(values):
        return clip_to_gamut(spectral_to_rgb(values, optics.wavelengths_nm, colour["illuminant"],
                                             colour["observer"]))[0]

    atlas = brdf_atlas(to_rgb(rho))
    attenuation = to_rgb(ballistic.attenuation(optics.unscattered_extinction_per_mm, geometry.radius_mm,
                                               ballistic.attenuation_lengths()))
    exit_resolution = round(math.sqrt(rho.shape[1]))
    layout = TableLayout(FIT_INCIDENCE_RESOLUTION, exit_resolution, ballistic.ATTENUATION_SAMPLES,
                         optics.boundary_index, ballistic.SUN_MODE_SPREAD_RAD)
    return atlas, attenuation, layout


class DyeSeriesForwardModel(ForwardModel):
    """The forward model of a fit that frees only the dye amount (and the sheen): one transport for
    the whole ``dye_range`` (% of fibre weight), at the least dye with its exits tallied at the
    absorption steps up to the most, at ``relative_error``; every candidate's ρ is then read from it
    in about a second (:mod:`precompute.transport.absorption`), all from the same paths, so the
    candidates differ by no Monte-Carlo noise.  Every candidate has the series' accuracy, whatever
    ``relative_error`` it asks for.  A candidate that changes anything but the dye amount starts a
    new series."""

    def __init__(self, response, view_count: int, base_dir: pathlib.Path, dye_range: tuple[float, float],
                 threads: int | None = None, relative_error: float = 0.02, seed: int = 0,
                 azimuth_count: int = len(DEFAULT_SAMPLE_AZIMUTHS_DEG)):
        super().__init__(response, view_count, base_dir, threads, azimuth_count)
        self.dye_range = (float(dye_range[0]), float(dye_range[1]))
        self.relative_error = relative_error
        self.seed = seed
        self._series = None

    def _series_for(self, config: dict, medium):
        undyed = {**config, "dye": {**config["dye"], "weight_percent": None}}
        identity = canonical_json(undyed)
        if self._series is not None and self._series[0] == identity:
            return self._series[1]
        from precompute.transport.absorption import reweighted_absorption

        low, high = (medium_optics(medium.with_dye(w)) for w in self.dye_range)
        series = absorption_series(config, medium, low, reweighted_absorption(high), relative_error=self.relative_error,
                                   seed=self.seed, threads=self.threads)
        self._series = (identity, series)
        return series

    def tables(self, config: dict, *, relative_error: float, seed: int):
        from precompute.transport.absorption import interpolate_absorption, reweighted_absorption

        if "dye" not in config:
            raise ParameterError("dye", None, "a dyed medium (a dye series reads dye amounts)")
        medium = medium_from_dict(config, self.base_dir)
        if not self.dye_range[0] <= medium.dye.weight_percent <= self.dye_range[1]:
            raise ParameterError("dye.weight_percent", medium.dye.weight_percent,
                                 f"within the series' {self.dye_range[0]:g}–{self.dye_range[1]:g} %")
        reference_mu_a, steps, rho_steps, geometry = self._series_for(config, medium)
        optics = medium_optics(medium)
        rho = interpolate_absorption(rho_steps, reference_mu_a, steps, reweighted_absorption(optics),
                                     optics.wavelengths_nm)
        return _candidate_tables(config, optics, geometry, rho)


def build_forward_model(measured_views, preset_config: dict, base_dir, *, seed: int = 0, cache_dir=None,
                        threads: int | None = None, progress: Callable[[int, int], None] | None = None,
                        dye_range: tuple[float, float] | None = None) -> ForwardModel:
    """The forward model at ``measured_views`` ((θi, φi, θo, φo) in degrees, the CSV's convention)
    for media written like ``preset_config`` (checked here, before any render; relative files
    resolve against ``base_dir``), on the sample weave its ``[sample]`` table names, averaged over
    the azimuths it names (:mod:`precompute.optics.measured_sample`).  ``progress(done, total)``
    follows the response's renders when it is not cached yet; ``seed`` is Cycles' for those renders
    (candidates take theirs per call).  With
    ``dye_range`` (% of fibre weight), a :class:`DyeSeriesForwardModel` for fits of the dye alone."""
    medium = medium_from_dict(preset_config, pathlib.Path(base_dir))
    if dye_range is not None and not medium.dye_only_absorbs:
        # the dye of randomly oriented fibres changes their scattering (their index), not only the absorption
        raise ParameterError("--dye-series", "a medium of randomly oriented fibres",
                             "a medium whose dye only absorbs (no [fibres], or fibres along the yarn axis)")
    weave = sample_weave(sample_weave_name(preset_config), medium.yarn.radius_mm)
    azimuths = sample_azimuths_deg(preset_config)
    measured_views = [tuple(float(a) for a in view) for view in measured_views]
    response = cloth_response(measured_views, weave=weave, seed=seed, cache_dir=cache_dir, progress=progress,
                              azimuths_deg=azimuths)
    if dye_range is not None:
        return DyeSeriesForwardModel(response, len(measured_views), base_dir, dye_range, threads, seed=seed,
                                     azimuth_count=len(azimuths))
    return ForwardModel(response, len(measured_views), base_dir, threads, len(azimuths))
