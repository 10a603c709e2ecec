"""The table side of the comparison: what a yarn BRDF predicts for each width bin of the reference image.

For each bin, positions b/R are taken across the bin (uniform in b, as the image is); at each the
yarn frame (:func:`~.geometry.yarn_frames`), ω_o (the view, +z of the scene) and, over the cap,
ω_i are expressed in that frame and

    scattered = mean over positions of Σ_j w_j ρ(ω_i,j, ω_o)                          [1/sr]

with the cap quadrature (:meth:`~.cap.CapLight.quadrature`, w_j = L dω_j / E⊥).  The unscattered
(ballistic) light, when a function for it is given (the contract of
``precompute.optics.ballistic.unscattered_paths``: ``(wo, index, orders) -> (wi (…, K, 3), fresnel_factor
(…, K), length_over_radius (…, K))``), adds

    ballistic = mean over positions of Σ_k fresnel_factor_k · exp(−μt R chord_k) · L(ω_i,k) / E⊥

at many more positions (it is a delta in ω_i, so its bin average is an integral over b of the cap
profile).  ρ must then be the scattered part only, or the ballistic light is counted twice.
"""

from __future__ import annotations

import json
import math
import pathlib
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from precompute.errors import ParameterError
from precompute.reference.cap import CapLight, cap_frame
from precompute.reference.geometry import VIEW, bin_edges, bin_positions, glint_paths, to_local, to_world, yarn_frames
from precompute.reference.render import DEFAULT_EDGE, ReferenceMedium

Rho = Callable[[np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True, eq=False)
class BinPrediction:
    """The table side per width bin, each in 1/sr (L_o / E⊥).

    ``scattered``: from ρ; ``ballistic``: the unscattered paths (0 without a ballistic function);
    ``glint``: the first-surface reflection (0 unless asked for; the tables exclude it).
    """

    bin_edges: np.ndarray
    scattered: np.ndarray
    ballistic: np.ndarray
    glint: np.ndarray

    @property
    def total(self) -> np.ndarray:
        return self.scattered + self.ballistic + self.glint

    @property
    def width_mean(self) -> float:
        return float(self.total.mean())


def _view_frames(edges: np.ndarray, per_bin: int):
    """Yarn frames (B, S, 3, 3) at ``per_bin`` positions in each bin and the view in them (B, S, 3)."""
    b = bin_positions(edges, per_bin)  # (B, S)
    frames = yarn_frames(b)  # (B, S, 3, 3)
    return frames, to_local(frames, VIEW)


def scattered_prediction(rho: Rho, light, edges: np.ndarray, cap: CapLight, *, sub_positions: int = 16,
                         cap_polar: int = 2, cap_azimuths: int = 8) -> np.ndarray:
    """(B,) cap- and bin-averaged ρ (1/sr) for the bins of ``edges`` (b/R), light toward ``light``."""
    light = np.asarray(light, float) / np.linalg.norm(light)
    frames, wo = _view_frames(edges, sub_positions)
    nodes, weights = cap.quadrature(cap_polar, cap_azimuths)
    directions = nodes @ cap_frame(light)  # (C, 3) scene frame
    wi = np.einsum("bsij,cj->bsci", frames, directions)  # (B, S, C, 3)
    wo = np.broadcast_to(wo[:, :, None, :], wi.shape)
    values = np.asarray(rho(wi, wo), float).reshape(wi.shape[:-1])
    return np.einsum("bsc,c->b", values, weights) / sub_positions


def ballistic_prediction(ballistic, light, edges: np.ndarray, cap: CapLight, *, index: float, mu_t: float,
                         radius_mm: float, orders: int = 4, sub_positions: int = 2048) -> np.ndarray:
    """(B,) the unscattered paths' L_o / E⊥ (1/sr) per bin; ``ballistic`` as in the module docstring."""
    light = np.asarray(light, float) / np.linalg.norm(light)
    frames, wo = _view_frames(edges, sub_positions)
    wi, factor, chord = (np.asarray(a, float) for a in ballistic(wo, index, orders))
    world = to_world(frames[:, :, None, :, :], wi)  # (B, S, K, 3)
    theta = np.arccos(np.clip(world @ light, -1.0, 1.0))
    radiance = factor * np.exp(-mu_t * radius_mm * chord) * cap.radiance(theta)
    return radiance.sum(axis=-1).mean(axis=-1) / cap.e_perp


def glint_prediction(light, edges: np.ndarray, cap: CapLight, *, index: float,
                     sub_positions: int = 2048) -> np.ndarray:
    """(B,) the first-surface reflection's L_o / E⊥ (1/sr) per bin (what the glint-free BSDF removes)."""
    light = np.asarray(light, float) / np.linalg.norm(light)
    frames, wo = _view_frames(edges, sub_positions)
    wi, reflectance = glint_paths(wo, index)
    theta = np.arccos(np.clip(to_world(frames, wi) @ light, -1.0, 1.0))
    return (reflectance * cap.radiance(theta)).mean(axis=-1) / cap.e_perp


def predict_bins(rho: Rho | None, light, *, bins: int = 16, edge: float = DEFAULT_EDGE, cap: CapLight = CapLight(),
                 sub_positions: int = 16, cap_polar: int = 2, cap_azimuths: int = 8, ballistic=None,
                 medium: ReferenceMedium | None = None, ballistic_orders: int = 4,
                 ballistic_sub_positions: int = 2048, glint: bool = False) -> BinPrediction:
    """The table-side prediction for the bins of :func:`~.render.render_reference` (same ``bins``, ``edge``, ``cap``).

    ``rho(wi, wo) -> (…,)`` in 1/sr, both (…, 3) in the yarn frame (None: no scattered term);
    ``ballistic``: a function with the contract of ``precompute.optics.ballistic.unscattered_paths`` or None;
    ``medium`` (its index, μt and R) is needed for the ballistic term and the glint.
    """
    edges = bin_edges(bins, edge)
    zeros = np.zeros(bins)
    scattered = zeros if rho is None else scattered_prediction(
        rho, light, edges, cap, sub_positions=sub_positions, cap_polar=cap_polar, cap_azimuths=cap_azimuths)
    if (ballistic is not None or glint) and medium is None:
        raise ParameterError("medium", None, "a ReferenceMedium (index, μt, R) for the ballistic term or the glint")
    unscattered = zeros if ballistic is None else ballistic_prediction(
        ballistic, light, edges, cap, index=medium.index, mu_t=medium.mu_t, radius_mm=medium.radius_mm,
        orders=ballistic_orders, sub_positions=ballistic_sub_positions)
    reflected = zeros if not glint else glint_prediction(light, edges, cap, index=medium.index,
                                                         sub_positions=ballistic_sub_positions)
    return BinPrediction(edges, scattered, unscattered, reflected)


# ---- ρ from the project's data ------------------------------------------------------------------


def transport_rho(transport, wavelength_index: int = 0, *, chunk: int = 1024) -> tuple[Rho, Rho]:
    """ρ and its standard error straight from a :class:`~precompute.transport.YarnTransport`: eq. (5) at
    the exact ω_i (``yarn_brdf_at``), read between exit-cell centres at ω_o as a table tile is read.
    No incidence grid is involved.  Returns two functions ``(wi, wo) -> (…,)`` in 1/sr."""
    from precompute.transport import yarn_brdf_at

    grid = transport.exit_grid

    def evaluate(wi, wo, which):
        wi, wo = np.broadcast_arrays(np.asarray(wi, float), np.asarray(wo, float))
        flat_i, flat_o = wi.reshape(-1, 3), wo.reshape(-1, 3)
        out = np.empty(len(flat_i))
        for start in range(0, len(flat_i), chunk):
            part = slice(start, start + chunk)
            result = yarn_brdf_at(transport, flat_i[part])[which][:, :, wavelength_index]
            out[part] = np.einsum("ko,ko->k", _exit_weights(grid, flat_o[part]), result)
        return out.reshape(wi.shape[:-1])

    return (lambda wi, wo: evaluate(wi, wo, 0)), (lambda wi, wo: evaluate(wi, wo, 1))


def _exit_weights(grid, wo: np.ndarray) -> np.ndarray:
    """Bilinear weights (n, N²) of the exit cells for directions ``wo`` (n, 3): between pixel centres,
    clamped, as :func:`precompute.tables.layout.interpolate_exit_tile` reads one tile."""
    n = grid.resolution
    st = grid.direction_to_square(wo)
    half = 0.5 / n
    x = np.clip(st[:, 0], half, 1.0 - half) * n - 0.5
    y = np.clip(st[:, 1], half, 1.0 - half) * n - 0.5
    x0 = np.clip(np.floor(x).astype(int), 0, n - 1)
    y0 = np.clip(np.floor(y).astype(int), 0, n - 1)
    x1, y1 = np.minimum(x0 + 1, n - 1), np.minimum(y0 + 1, n - 1)
    ax, ay = x - x0, y - y0
    weights = np.zeros((len(wo), n * n))
    rows = np.arange(len(wo))
    for xi, yi, w in ((x0, y0, (1 - ax) * (1 - ay)), (x1, y0, ax * (1 - ay)), (x0, y1, (1 - ax) * ay),
                      (x1, y1, ax * ay)):
        np.add.at(weights, (rows, yi * n + xi), w)
    return weights


@dataclass(frozen=True, eq=False)
class TransportPrediction:
    """The bins predicted by eq. (5) at the exact ω_i (no incidence grid), with exact Monte-Carlo errors.

    ``rho``, ``rho_stderr`` (B,), 1/sr; ``width_mean``, ``width_mean_stderr``: their mean over the bins.
    """

    bin_edges: np.ndarray
    rho: np.ndarray
    rho_stderr: np.ndarray
    width_mean: float
    width_mean_stderr: float


def transport_prediction(transport, light, *, bins: int = 16, edge: float = DEFAULT_EDGE,
                         cap: CapLight = CapLight(), wavelength_index: int = 0, sub_positions: int = 16,
                         cap_polar: int = 2, cap_azimuths: int = 8) -> TransportPrediction:
    """What a :class:`~precompute.transport.YarnTransport` predicts for the reference's bins, from its
    BSSRDF tallies directly: eq. (5) (``source_weights``) at every exact ω_i of the cap quadrature and
    sub-position, exit cells read bilinearly at ω_o as a table tile is read.

    Every bin is a linear functional Σ A[c, δ, o] S[c, δ, o] of the axis-summed BSSRDF; folded onto the
    traced cells (``transport.symmetry.fold_exits``: an image cell's S is its source's, reflected) a path
    adds to one (δ, o) bin of its incidence cell c only, so the standard error is exact:
    Var = Σ_c (Σ_{δ,o} A² M2[c, δ, o] − (Σ_{δ,o} A S)²) / (N_c − 1), c over the traced cells.
    """
    from precompute.transport import source_weights

    light = np.asarray(light, float) / np.linalg.norm(light)
    edges = bin_edges(bins, edge)
    frames, wo = _view_frames(edges, sub_positions)
    nodes, weights = cap.quadrature(cap_polar, cap_azimuths)
    directions = nodes @ cap_frame(light)
    wi = np.einsum("bsij,cj->bsci", frames, directions)  # (B, S, C, 3)
    n_cap = len(directions)
    exit_w = _exit_weights(transport.exit_grid, wo.reshape(-1, 3)).reshape(bins, sub_positions, -1)
    axial = transport.axial_bssrdf()[..., wavelength_index]  # (n_in, n_around, n_out)
    second = transport.bssrdf_axial_second_moment[..., wavelength_index].astype(float)
    functionals = np.zeros((bins + 1,) + axial.shape)  # per bin, and the width mean last
    for b in range(bins):
        w = source_weights(transport, wi[b].reshape(-1, 3)).reshape(sub_positions, n_cap, *axial.shape[:2])
        a = np.einsum("scid,c,so->ido", w, weights, exit_w[b]) / sub_positions
        functionals[b] = a
    functionals[bins] = functionals[:bins].mean(axis=0)
    values = np.einsum("kido,ido->k", functionals, axial)
    # on the traced cells only: a cell's tallies and its mirror images' are one set of paths
    functionals = np.moveaxis(transport.symmetry.fold_exits(np.moveaxis(functionals, 0, -1)), -1, 0)
    per_cell = np.einsum("kido,ido->ki", functionals, axial)
    second_sum = np.einsum("kido,ido->ki", functionals**2, second)
    paths = transport.paths_per_cell.astype(float)
    variance = np.sum(np.maximum(second_sum - per_cell**2, 0.0) / (paths - 1.0), axis=1)
    errors = np.sqrt(variance)
    return TransportPrediction(edges, values[:bins], errors[:bins], float(values[bins]), float(errors[bins]))


def table_rho(rho_table: np.ndarray, incidence_resolution: int) -> Rho:
    """ρ read from a spectral table at one wavelength (N_i², N_o²) exactly as the shader reads it
    (:func:`precompute.tables.layout.interpolate_rho` on the atlas)."""
    from precompute.tables.layout import brdf_atlas, interpolate_rho

    atlas = brdf_atlas(np.asarray(rho_table, float)[:, :, None])

    def rho(wi, wo):
        return interpolate_rho(atlas, incidence_resolution, wi, wo)[..., 0]

    return rho


@dataclass(frozen=True, eq=False)
class BakeWavelength:
    """One wavelength of a bake: the medium to render and the table to predict with.

    ``rho``/``rho_stderr``: functions ``(wi, wo) -> (…,)`` (1/sr) reading the spectral table at
    this wavelength as the shader does; ``spectral_path``: the ``spectral.npz`` read.
    """

    wavelength_nm: float
    wavelength_index: int
    medium: ReferenceMedium
    rho: Rho
    rho_stderr: Rho
    spectral_path: pathlib.Path
    metadata: dict


def medium_from_record(record: dict):
    """:class:`precompute.optics.medium.MediumParameters` from its ``to_dict()`` record (a bake's ``medium``)."""
    from precompute.optics.medium import (
        Dye,
        Host,
        MediumParameters,
        ParticleSpecies,
        RefractiveIndex,
        WavelengthGrid,
        Yarn,
    )

    def tuples(value):
        return tuple(value) if isinstance(value, list) else value

    def index(spec):
        return RefractiveIndex(**{k: tuples(v) for k, v in spec.items()})

    host = Host(index(record["host"]["refractive_index"]), record["host"]["absorption_per_mm"])
    particles = tuple(
        ParticleSpecies(**{**p, "refractive_index": index(p["refractive_index"])}) for p in record["particles"])
    dye = None if record.get("dye") is None else Dye(**{k: tuples(v) for k, v in record["dye"].items()})
    yarn = Yarn(**{k: tuples(v) for k, v in record["yarn"].items()})
    wavelengths = WavelengthGrid(**{k: tuples(v) for k, v in record["wavelengths"].items()})
    medium = MediumParameters(record["name"], host, particles, dye, yarn, wavelengths,
                              record["dependent_scattering"], record["phase_samples"], record["description"])
    if json.dumps(medium.to_dict(), sort_keys=True) != json.dumps(record, sort_keys=True):
        raise ParameterError("medium record", record.get("name"), "a MediumParameters.to_dict() record")
    return medium


def find_spectral(folder, cache_dir=None) -> pathlib.Path | None:
    """The ``spectral.npz`` of a bake folder: in the folder, else the spectral cache entry its
    ``summary.json`` names (``spectral_key``) in ``cache_dir`` (default: the user cache); None if neither."""
    folder = pathlib.Path(folder)
    if (folder / "spectral.npz").is_file():
        return folder / "spectral.npz"
    summary = folder / "summary.json"
    if not summary.is_file():
        return None
    from precompute.cache.entries import default_cache_dir, lookup

    key = json.loads(summary.read_text()).get("spectral_key")
    entry = lookup(pathlib.Path(cache_dir) if cache_dir else default_cache_dir(), "spectral", key) if key else None
    return None if entry is None or not (entry / "spectral.npz").is_file() else entry / "spectral.npz"


def bake_wavelength(spectral_path, wavelength_nm: float) -> BakeWavelength:
    """The bake's data at its simulated wavelength nearest ``wavelength_nm``.

    μs and μa come from ``spectral.npz``; the phase table is not stored there, so it is recomputed
    from the medium record (:func:`precompute.optics.coefficients.medium_optics`, deterministic, its cos θ grid
    chosen again when ``phase_samples`` is ``"auto"``) and the μs, μa it gives are checked against the
    stored ones, the grid against the bake's ``phase_grid`` where recorded.  The phase table is the
    transport's (:func:`precompute.transport.media.medium_from_optics`), on the uniform cos θ grid.
    R and the boundary index are the bake's.
    """
    from precompute.bake import load_spectral
    from precompute.optics.coefficients import medium_optics
    from precompute.transport.media import medium_from_optics

    spectral_path = pathlib.Path(spectral_path)
    arrays, metadata = load_spectral(spectral_path)
    wavelengths = np.asarray(arrays["wavelengths_nm"], float)
    k = int(np.argmin(np.abs(wavelengths - float(wavelength_nm))))
    params = medium_from_record(metadata["medium"])
    optics = medium_optics(params)
    if optics.oriented_fibres is not None:
        # the brute-force renderer's medium is one phase function of cos Θ: it has no oriented fibres
        raise ParameterError("fibres.orientation", params.fibres.orientation,
                             "'random' for the reference renderer (a phase function of cos Θ)")
    recorded = metadata.get("phase_grid")
    if recorded is not None and recorded != {"kind": optics.phase_grid, "samples": optics.phase_samples}:
        raise RuntimeError(f"{spectral_path}: the bake's phase grid {recorded} is not the one the medium record "
                           f"gives now ({optics.phase_grid}, {optics.phase_samples}): the optics code changed")
    for name in ("mu_s", "mu_a"):
        stored, again = float(arrays[name][k]), float(getattr(optics, name)[k])
        if not math.isclose(stored, again, rel_tol=1e-9, abs_tol=1e-12):
            raise RuntimeError(f"{spectral_path}: {name} at {wavelengths[k]:g} nm is {stored}, the medium record "
                               f"gives {again}: the optics code changed since this bake")
    # The transport's own table (uniform in cos θ, as tabphase wants): resampled from a grid uniform in θ.
    phase = medium_from_optics(optics).phase_table[k]
    medium = ReferenceMedium(float(params.yarn.radius_mm), float(metadata["host_index"]), float(arrays["mu_s"][k]),
                             float(arrays["mu_a"][k]), phase)
    n_i = int(metadata["incidence_resolution"])
    return BakeWavelength(float(wavelengths[k]), k, medium, table_rho(arrays["rho"][:, :, k], n_i),
                          table_rho(arrays["rho_stderr"][:, :, k], n_i), spectral_path, metadata)


def default_ballistic():
    """The project's unscattered-path function if ``precompute/optics/ballistic.py`` exists, else None:
    ``ballistic_paths``, or ``unscattered_paths`` (the same contract), whichever it defines."""
    import importlib
    import importlib.util

    if importlib.util.find_spec("precompute.optics.ballistic") is None:
        return None
    module = importlib.import_module("precompute.optics.ballistic")
    for name in ("ballistic_paths", "unscattered_paths"):
        if callable(getattr(module, name, None)):
            return getattr(module, name)
    raise ImportError("precompute.optics.ballistic defines neither ballistic_paths nor unscattered_paths")


__all__ = [
    "BakeWavelength",
    "BinPrediction",
    "bake_wavelength",
    "ballistic_prediction",
    "default_ballistic",
    "find_spectral",
    "glint_prediction",
    "medium_from_record",
    "predict_bins",
    "scattered_prediction",
    "table_rho",
    "transport_prediction",
    "transport_rho",
    "TransportPrediction",
]
