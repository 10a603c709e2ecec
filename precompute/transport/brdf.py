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

from ..errors import ParameterError
from ..grids import AngularGrid
from ._checks import integer_at_least
from .cylinder import YarnTransport, mean_cos_per_cell

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
                 subsamples: int = CIRCUMFERENTIAL_SUBSAMPLES) -> tuple[np.ndarray, np.ndarray]:
    """ρ and its standard error (n_dirs, n_out, L), 1/sr, for light from ``directions`` (receiving frame).

    The error is exact for the estimator: each incidence cell's paths are independent of
    the others', and a path adds to one (offset, exit cell) bin of the axial sum only.
    """
    weights = source_weights(transport, directions, interpolation=interpolation, subsamples=subsamples)
    axial = transport.axial_bssrdf()  # (n_in, n_around, n_out, L)
    n_in, n_around, n_out, n_wl = axial.shape
    rho = np.zeros((len(weights), n_out * n_wl))
    variance = np.zeros_like(rho)
    for c in range(n_in):
        w = weights[:, c, :]
        if not np.any(w):
            continue
        part = w @ axial[c].reshape(n_around, -1)
        second = (w**2) @ transport.bssrdf_axial_second_moment[c].reshape(n_around, -1).astype(np.float64)
        rho += part
        variance += np.maximum(second - part**2, 0.0) / (transport.paths_per_cell[c] - 1)
    shape = (len(weights), n_out, n_wl)
    return rho.reshape(shape), np.sqrt(variance).reshape(shape)


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
