"""The yarn BRDF from the BSSRDF by summation over the lit yarn surface (paper §5.3.2, eq. 5).

Definition used everywhere downstream: a parallel beam of irradiance E⊥
(measured on a plane facing the beam) arriving from direction ω_i (unit vector
toward the light, in the local frame of the receiving point: x = yarn axis,
y = n × t, z = outward normal; any direction of the sphere) gives the exit
radiance ``L_o = ρ(ω_i, ω_o) E⊥`` toward ω_o (z ≥ 0), volume light only (the
Fresnel surface reflection is the shader's Cook–Torrance term).  In 1/sr.

Every source cell dA of the yarn receives the flux ``E⊥ cos θ_in(dA) A_dA``
when it is lit (``f = 1`` iff cos θ_in > 0; light from behind the receiving
point reaches it through the yarn), so eq. (5) reads

    ρ(ω_i, ω_o) = Σ_dA S(ω_in(dA), dA → dB, ω_o) · cos θ_in(dA) · f · A_dA

with S the BSSRDF in 1/(mm² sr) (:class:`~.cylinder.YarnTransport`).  The
illumination is uniform along the axis, so the sum over the axial positions of
dA is S summed over all axial bins, overflow included — exact for an infinite
yarn.  Around the circumference each source cell is split into
``CIRCUMFERENTIAL_SUBSAMPLES`` positions (midpoint rule), at which the local
incidence direction is computed and S interpolated bilinearly between the
incidence cells' centres in the equal-area square (nearest cell optionally).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from precompute.errors import ParameterError
from precompute.tables.grids import AngularGrid
from precompute.tables.layout import incidence_corners
from precompute.transport._checks import integer_at_least
from precompute.transport.cylinder import ALBEDO_FLOOR, YarnTransport, mean_cos_per_cell

#: Positions per source cell around the circumference in the sum of eq. (5).
CIRCUMFERENTIAL_SUBSAMPLES = 16
INTERPOLATIONS = ("bilinear", "nearest")


@dataclass(frozen=True, eq=False)
class YarnBRDF:
    """ρ(ω_i, ω_o) = L_o / E⊥ (1/sr) at the centres of ``incidence_grid`` (sphere, ω_i in the
    receiving frame) and of ``exit_grid`` (hemisphere), shape (N_i², N_o², L), with its
    Monte-Carlo standard error ``rho_stderr``.  Volume (subsurface) light only."""

    wavelengths_nm: np.ndarray
    incidence_grid: AngularGrid
    exit_grid: AngularGrid
    rho: np.ndarray
    rho_stderr: np.ndarray

    def hemispherical_albedo(self) -> np.ndarray:
        """∫ ρ cos θ_o dω_o over the exit hemisphere, (N_i², L): exitance per unit E⊥."""
        cos_out = mean_cos_per_cell(self.exit_grid)
        return np.einsum("iol,o->il", self.rho, cos_out) * self.exit_grid.cell_solid_angle


def source_weights(transport: YarnTransport, directions: np.ndarray, *, interpolation: str = "bilinear",
                   subsamples: int = CIRCUMFERENTIAL_SUBSAMPLES) -> np.ndarray:
    """Weights W (n_dirs, n_in, n_around) of eq. (5): ρ = Σ_{c,δ} W[·, c, δ] S_axial[c, δ], in mm².

    For light from each of ``directions`` (n_dirs, 3; receiving frame), W[·, c, δ] sums
    cos θ_in · f · A_dA / subsamples over the sub-positions of the source cell δ cells
    before the receiving one whose local incidence direction falls in (or, bilinearly,
    near) incidence cell c.
    """
    if interpolation not in INTERPOLATIONS:
        raise ParameterError("interpolation", interpolation, f"one of {INTERPOLATIONS}")
    subsamples = integer_at_least("subsamples", subsamples, 1)
    directions = np.asarray(directions, float).reshape(-1, 3)
    norms = np.linalg.norm(directions, axis=1)
    if not np.all(np.isfinite(norms)) or np.any(np.abs(norms - 1.0) > 1e-6):
        raise ParameterError("directions", "not unit vectors", "unit vectors (n, 3)")
    grid = transport.incidence_grid
    n = grid.resolution
    n_around = transport.grids.n_around
    dpsi = 2.0 * math.pi / n_around
    weights = np.zeros((len(directions), grid.n_cells, n_around))
    rows = np.arange(len(directions))
    offsets = (np.arange(subsamples) + 0.5) / subsamples - 0.5
    for delta in range(n_around):
        for offset in offsets:
            # the source point sits at azimuth alpha from the receiving point
            alpha = (-delta + offset) * dpsi
            ca, sa = math.cos(alpha), math.sin(alpha)
            local = np.stack([directions[:, 0],
                              directions[:, 2] * sa + directions[:, 1] * ca,
                              directions[:, 2] * ca - directions[:, 1] * sa], axis=1)
            lit = local[:, 2] > 0.0
            if not np.any(lit):
                continue
            flux = local[lit, 2] * transport.cell_area_mm2 / subsamples
            target = weights[:, :, delta]
            if interpolation == "nearest":
                np.add.at(target, (rows[lit], grid.cell_of(local[lit])), flux)
                continue
            st = grid.direction_to_square(local[lit])
            fi = np.clip(st[:, 0] * n - 0.5, 0.0, n - 1.0)
            fj = np.clip(st[:, 1] * n - 0.5, 0.0, n - 1.0)
            i0 = np.minimum(fi.astype(int), n - 2)
            j0 = np.minimum(fj.astype(int), n - 2)
            ti = fi - i0
            tj = fj - j0
            for di, dj, w in ((0, 0, (1 - ti) * (1 - tj)), (1, 0, ti * (1 - tj)),
                              (0, 1, (1 - ti) * tj), (1, 1, ti * tj)):
                np.add.at(target, (rows[lit], (j0 + dj) * n + i0 + di), flux * w)
    return weights


def yarn_brdf_at(transport: YarnTransport, directions: np.ndarray, *, interpolation: str = "bilinear",
                 subsamples: int = CIRCUMFERENTIAL_SUBSAMPLES,
                 with_stderr: bool = True) -> tuple[np.ndarray, np.ndarray | None]:
    """ρ and its standard error (n_dirs, n_out, L), 1/sr, for light from ``directions`` (receiving frame);
    the error None when not ``with_stderr`` (its second moments are most of the work).

    The error is exact for the estimator: the traced incidence cells' paths are independent of each
    other's, and a path adds to one (offset, exit cell) bin of its cell's axial sum and, reflected, to
    one bin of each of its cell's mirror images (``transport.symmetry``), whose terms therefore add
    before they are squared.
    """
    weights = source_weights(transport, directions, interpolation=interpolation, subsamples=subsamples)
    axial = transport.axial_bssrdf()  # (n_in, n_around, n_out, L)
    n_in, n_around, n_out, n_wl = axial.shape
    rho = np.zeros((len(weights), n_out * n_wl))
    variance = np.zeros_like(rho)
    for traced in np.flatnonzero(transport.symmetry.traced):
        orbit = list(transport.symmetry.orbit(traced))
        # light from a direction reaches few incidence cells of the source frames: only those rows
        lit = np.flatnonzero(np.any([weights[:, cell, :].any(axis=1) for cell, _ in orbit], axis=0))
        if not len(lit):
            continue
        part = np.zeros((len(lit), n_out * n_wl))
        # image cell c = g(traced) reads the traced cell's bin (g δ, g o) for its (δ, o): its weights
        # on the traced cell's offsets, and the traced cell's exit cell that each of its own reads
        terms = []
        for cell, mirror in orbit:
            w = weights[lit, cell, :]
            part += w @ axial[cell].reshape(n_around, -1)
            terms.append((w[:, mirror.around], mirror.cells))
        rho[lit] += part
        if not with_stderr:
            continue
        moment = transport.bssrdf_axial_second_moment[traced].astype(np.float64)
        second = np.zeros_like(part)
        for w_a, cells_a in terms:
            for w_b, cells_b in terms:
                shared = cells_a == cells_b  # exit cells o for which both read the same bin
                if shared.any():
                    product = (w_a * w_b) @ moment[:, cells_a].reshape(n_around, -1)
                    if not shared.all():
                        product *= np.repeat(shared, n_wl)
                    second += product
        part *= part
        second -= part
        np.maximum(second, 0.0, out=second)
        second *= 1.0 / (transport.paths_per_cell[traced] - 1)
        variance[lit] += second
    shape = (len(weights), n_out, n_wl)
    return rho.reshape(shape), np.sqrt(variance).reshape(shape) if with_stderr else None


def yarn_brdf(transport: YarnTransport, incidence_resolution: int = 12, *, interpolation: str = "bilinear",
              subsamples: int = CIRCUMFERENTIAL_SUBSAMPLES) -> YarnBRDF:
    """Eq. (5) over the full sphere of incidence, at the cell centres of ``AngularGrid("sphere", N_i)``."""
    incidence_grid = AngularGrid("sphere", integer_at_least("incidence_resolution", incidence_resolution, 2))
    rho, stderr = yarn_brdf_at(transport, incidence_grid.cell_centers(), interpolation=interpolation,
                               subsamples=subsamples)
    return YarnBRDF(
        wavelengths_nm=transport.wavelengths_nm,
        incidence_grid=incidence_grid,
        exit_grid=transport.exit_grid,
        rho=rho,
        rho_stderr=stderr,
    )


#: Incidence resolutions an automatic choice tries, coarsest first.  Odd, so that the planes
#: x = 0 (light across the yarn) and y = 0 (the axis–normal plane), where the octahedral map
#: folds, run through cell centres and a bilinear lookup there blends cells on the plane.
INCIDENCE_RESOLUTIONS = (21, 25, 29, 33)
#: What an automatic choice holds, at every wavelength whose albedo counts: the table's
#: bilinear lookup of ρ within this share of eq. (5) evaluated exactly (signed, summed over
#: test directions and exit cells) ...
LOOKUP_BIAS_TOLERANCE = 0.01
#: ... and ∫ρ dω_i under uniform light within this share of what the transport's own tallies
#: give by reciprocity (``exit_fraction``, summed over the exit cells).
ENERGY_TOLERANCE = 0.02
#: Directions (a Fibonacci sphere) at which the lookup is checked against eq. (5).
LOOKUP_TEST_DIRECTIONS = 400


@dataclass(frozen=True)
class IncidenceGridCheck:
    """How well a table of incidence resolution ``resolution`` holds ρ, per wavelength (L,).

    ``lookup_bias``: Σ (bilinear lookup − eq. (5)) / Σ eq. (5) over the test directions and the
    exit cells; ``energy_error``: Σ_o ∫ρ dω_i / Σ_o exit_fraction − 1 (uniform light, the
    integral as the midpoint sum over the incidence cells); ``counted``: the wavelengths the
    tolerances apply to (albedo at least ALBEDO_FLOOR of the largest).
    """

    resolution: int
    lookup_bias: np.ndarray
    energy_error: np.ndarray
    counted: np.ndarray

    @property
    def within_tolerance(self) -> bool:
        return bool(np.all(np.abs(self.lookup_bias[self.counted]) <= LOOKUP_BIAS_TOLERANCE)
                    and np.all(np.abs(self.energy_error[self.counted]) <= ENERGY_TOLERANCE))

    def to_dict(self) -> dict:
        counted = self.counted
        return {
            "incidence_resolution": self.resolution,
            "lookup_bias_worst": float(np.abs(self.lookup_bias[counted]).max()),
            "energy_error_worst": float(np.abs(self.energy_error[counted]).max()),
            "lookup_bias": self.lookup_bias.tolist(),
            "energy_error": self.energy_error.tolist(),
        }


def fibonacci_sphere(count: int) -> np.ndarray:
    """``count`` unit directions spread evenly over the sphere (Fibonacci lattice), (count, 3)."""
    k = np.arange(count) + 0.5
    z = 1.0 - 2.0 * k / count
    phi = np.pi * (3.0 - math.sqrt(5.0)) * k
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def incidence_lookup(rho: np.ndarray, resolution: int, wi: np.ndarray) -> np.ndarray:
    """ρ (n_dirs, n_out, L) for light from ``wi`` (n_dirs, 3) by the tables' bilinear incidence
    lookup between the cell centres of ``rho`` (N_i², n_out, L)
    (:func:`precompute.tables.layout.interpolate_rho` without the exit interpolation)."""
    columns, rows, weights = incidence_corners(resolution, wi)
    return np.einsum("dk,dkol->dol", weights, rho[rows * resolution + columns])


def check_incidence_grid(transport: YarnTransport, brdf: YarnBRDF, test_directions: np.ndarray,
                         exact: np.ndarray) -> IncidenceGridCheck:
    """The checks of :class:`IncidenceGridCheck` for ``brdf``; ``exact`` is eq. (5) at ``test_directions``."""
    lookup = incidence_lookup(brdf.rho, brdf.incidence_grid.resolution, test_directions)
    total = exact.sum(axis=(0, 1))
    bias = np.divide((lookup - exact).sum(axis=(0, 1)), total, out=np.zeros_like(total), where=total > 0)
    integral = brdf.rho.sum(axis=0).sum(axis=0) * brdf.incidence_grid.cell_solid_angle
    reference = transport.exit_fraction.sum(axis=0)
    energy = np.divide(integral, reference, out=np.ones_like(reference), where=reference > 0) - 1.0
    albedo = transport.exit_fraction.mean(axis=0)
    return IncidenceGridCheck(brdf.incidence_grid.resolution, bias, energy, albedo >= ALBEDO_FLOOR * albedo.max())


def yarn_brdf_to_tolerance(transport: YarnTransport, resolutions=INCIDENCE_RESOLUTIONS, *,
                           subsamples: int = CIRCUMFERENTIAL_SUBSAMPLES) -> tuple[YarnBRDF, list[IncidenceGridCheck]]:
    """Eq. (5) on the coarsest incidence grid of ``resolutions`` that meets LOOKUP_BIAS_TOLERANCE and
    ENERGY_TOLERANCE (the finest if none does), with the checks of every grid tried."""
    if not resolutions:
        raise ParameterError("resolutions", resolutions, "at least one incidence resolution")
    test_directions = fibonacci_sphere(LOOKUP_TEST_DIRECTIONS)
    exact, _ = yarn_brdf_at(transport, test_directions, subsamples=subsamples, with_stderr=False)
    checks = []
    for resolution in resolutions:
        brdf = yarn_brdf(transport, resolution, subsamples=subsamples)
        checks.append(check_incidence_grid(transport, brdf, test_directions, exact))
        if checks[-1].within_tolerance:
            break
    return brdf, checks
