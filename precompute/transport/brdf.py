"""The yarn BRDF from the BSSRDF by integration over the lit yarn surface (paper §5.3.2, eq. 5).

For parallel light of irradiance E⊥ from direction ω_i (unit vector toward the
light, in the local frame of the receiving point: x = yarn axis, y = n × t,
z = outward normal; any direction of the sphere), every source cell dA of the
yarn receives the flux ``E⊥ cos θ_in(dA) A_dA`` when lit (``f = 1`` iff
``cos θ_in > 0``).  Summing the BSSRDF over them gives the exit radiance::

    ρ(ω_i, ω_o) = L_o / E⊥ = Σ_dA BSSRDF(ω_in(dA), dA, ω_o, dB) · cos θ_in(dA) · f · A_dA   [1/sr]

Illumination is uniform along the axis, so the sum over the axial offsets of
dA is the BSSRDF summed over all axial bins, overflow included — exact for an
infinite yarn.  Around the circumference each source cell is split into
sub-positions, so the cosine and the incidence cell follow the surface's
rotation within the cell.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..grids import AngularGrid
from .cylinder import YarnTransport, _mean_cos_per_cell

#: Sub-positions per source cell around the circumference.
CIRCUMFERENTIAL_SUBSAMPLES = 8


@dataclass(frozen=True)
class YarnBRDF:
    """ρ(ω_i, ω_o) = L_o / E⊥ (1/sr), shape (N_i², N_o², L), with its standard error.

    ``incidence_grid``: sphere grid of ω_i; ``exit_grid``: hemisphere grid of ω_o.
    Volume (subsurface) light only: the Fresnel surface reflection is the
    shader's Cook–Torrance term.
    """

    wavelengths_nm: np.ndarray
    incidence_grid: AngularGrid
    exit_grid: AngularGrid
    rho: np.ndarray
    rho_stderr: np.ndarray

    def hemispherical_albedo(self) -> np.ndarray:
        """∫ ρ cos θ_o dω_o over the exit hemisphere: (N_i², L), the exitance per E⊥."""
        cos_out = _mean_cos_per_cell(self.exit_grid)
        return np.einsum("iol,o->il", self.rho, cos_out) * self.exit_grid.cell_solid_angle


def yarn_brdf(transport: YarnTransport, incidence_resolution: int = 12) -> YarnBRDF:
    """Eq. (5) over the full sphere of incidence, evaluated at the centres of a sphere grid."""
    if int(incidence_resolution) < 2:
        raise ParameterError("incidence_resolution", incidence_resolution, "an integer ≥ 2")
    incidence_grid = AngularGrid("sphere", int(incidence_resolution))
    grids = transport.grids
    source_grid = transport.incidence_grid
    n_around = grids.n_around
    d_psi = 2.0 * math.pi / n_around
    area = transport.cell_area_mm2

    # Exit radiance per unit incident flux, summed along the axis: (G, n_src_dir, n_around, n_out, L)
    radiance = transport.exit_radiance_groups.astype(np.float64)
    omega = incidence_grid.cell_centers()  # receiving frame (t, b, n)
    n_dirs = len(omega)
    groups = radiance.shape[0]
    rho_groups = np.zeros((groups, n_dirs, radiance.shape[3], radiance.shape[4]))
    offsets = (np.arange(CIRCUMFERENTIAL_SUBSAMPLES) + 0.5) / CIRCUMFERENTIAL_SUBSAMPLES - 0.5
    for delta in range(n_around):
        for offset in offsets:
            alpha = (-delta + offset) * d_psi  # azimuth of the source point relative to the receiver
            ca, sa = math.cos(alpha), math.sin(alpha)
            local = np.stack(
                [omega[:, 0], omega[:, 2] * sa + omega[:, 1] * ca, omega[:, 2] * ca - omega[:, 1] * sa], axis=1
            )
            lit = local[:, 2] > 0.0
            if not np.any(lit):
                continue
            cells = source_grid.cell_of(local[lit])
            weight = local[lit, 2] * area / CIRCUMFERENTIAL_SUBSAMPLES
            rho_groups[:, lit] += radiance[:, cells, delta] * weight[None, :, None, None]
    rho = rho_groups.mean(axis=0)
    stderr = rho_groups.std(axis=0, ddof=1) / math.sqrt(groups)
    return YarnBRDF(
        wavelengths_nm=transport.wavelengths_nm,
        incidence_grid=incidence_grid,
        exit_grid=transport.exit_grid,
        rho=rho,
        rho_stderr=stderr,
    )
