"""The light of the reference: an environment map black except a small bright cap.

A delta light seen through the yarn's delta (smooth dielectric) boundary gives a unidirectional
volumetric path tracer nothing from the medium: its shadow rays stop at the boundary and its
scattered paths never hit a delta light.  A cap of finite solid angle is hit by escaping paths, and
its irradiance is known exactly.

Mitsuba 3's ``envmap`` is a latitude–longitude map whose rows are *samples* at polar angles
θ_k = k·π/(H − 1) about its local +y pole, interpolated bilinearly (``eval_spectrum`` in
``src/emitters/envmap.cpp``; :func:`precompute.reference.check_cap_map` checks it on the installed
version).  The cap is centred on the pole (turned to the light direction by the map's transform)
and every column of a row holds the same value, so the radiance depends on θ alone:
``L(θ) = 1`` for θ ≤ θ_m, falling linearly to 0 at θ_{m+1}, 0 beyond (dimensionless: radiance
units cancel in L_o / E⊥).  Hence, exactly (Gauss–Legendre on each smooth piece),

* the irradiance on a plane facing the cap centre, ``E⊥ = 2π ∫ L(θ) cos θ sin θ dθ``, and
* for the table side, quadrature nodes ω_j and weights ``w_j = L(θ_j) dω_j / E⊥`` (1/sr·sr), so that
  the radiance a BRDF ρ predicts per E⊥ is ``Σ_j w_j ρ(ω_j, ω_o)`` — each direction element of the
  cap is a parallel beam of irradiance ``L dω`` on a plane facing it, which is how ρ is defined.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from precompute.errors import ParameterError


@dataclass(frozen=True)
class CapLight:
    """A cap of half-angle ``half_angle_deg`` (degrees) in a lat-long map of ``rows_per_degree`` rows per degree.

    The effective cap is slightly larger: the radiance ramps linearly from 1 to 0 over one row
    spacing past ``half_angle_deg`` (rounded to a whole number of rows).
    """

    half_angle_deg: float = 5.0
    rows_per_degree: int = 10

    def __post_init__(self):
        if not 0.0 < float(self.half_angle_deg) <= 30.0:
            raise ParameterError("cap.half_angle_deg", self.half_angle_deg, "(0, 30] degrees")
        if isinstance(self.rows_per_degree, bool) or not isinstance(self.rows_per_degree, (int, np.integer)) or \
                not 1 <= self.rows_per_degree <= 100:
            raise ParameterError("cap.rows_per_degree", self.rows_per_degree, "an integer in [1, 100]")
        if self.lit_rows < 1:
            raise ParameterError("cap.half_angle_deg", self.half_angle_deg, "at least one row spacing")

    @property
    def map_rows(self) -> int:
        """H, the rows of the lat-long map (row k at θ = k·π/(H − 1))."""
        return 180 * int(self.rows_per_degree) + 1

    @property
    def row_spacing(self) -> float:
        """π/(H − 1), radians."""
        return math.pi / (self.map_rows - 1)

    @property
    def lit_rows(self) -> int:
        """m: rows 0 … m hold 1, the others 0."""
        return int(round(math.radians(float(self.half_angle_deg)) / self.row_spacing))

    @property
    def flat_angle(self) -> float:
        """θ_m, radians: L = 1 up to here."""
        return self.lit_rows * self.row_spacing

    @property
    def outer_angle(self) -> float:
        """θ_{m+1}, radians: L = 0 from here."""
        return (self.lit_rows + 1) * self.row_spacing

    def map_image(self, columns: int = 4) -> np.ndarray:
        """The lat-long map (H, columns, 3), float32: row k is 1 for k ≤ m, else 0."""
        image = np.zeros((self.map_rows, columns, 3), np.float32)
        image[: self.lit_rows + 1] = 1.0
        return image

    def radiance(self, theta) -> np.ndarray:
        """L(θ) for angles θ (radians) from the cap centre, as the map interpolates it."""
        theta = np.asarray(theta, float)
        ramp = 1.0 - (theta - self.flat_angle) / self.row_spacing
        return np.clip(np.where(theta <= self.flat_angle, 1.0, ramp), 0.0, 1.0)

    def _pieces(self, nodes: int):
        """Gauss–Legendre nodes θ (radians) and weights dθ on [0, θ_m] and [θ_m, θ_{m+1}]."""
        x, w = np.polynomial.legendre.leggauss(nodes)
        thetas, weights = [], []
        for lo, hi in ((0.0, self.flat_angle), (self.flat_angle, self.outer_angle)):
            thetas.append(lo + (hi - lo) * (x + 1.0) / 2.0)
            weights.append(w * (hi - lo) / 2.0)
        return np.concatenate(thetas), np.concatenate(weights)

    @property
    def e_perp(self) -> float:
        """Irradiance on a plane facing the cap centre, per unit cap radiance (sr): 2π ∫ L cos θ sin θ dθ."""
        theta, weight = self._pieces(24)
        return float(2.0 * math.pi * np.sum(self.radiance(theta) * np.cos(theta) * np.sin(theta) * weight))

    @property
    def radiance_integral(self) -> float:
        """∫ L dω over the cap per unit cap radiance (sr)."""
        theta, weight = self._pieces(24)
        return float(2.0 * math.pi * np.sum(self.radiance(theta) * np.sin(theta) * weight))

    def quadrature(self, polar: int = 3, azimuths: int = 8) -> tuple[np.ndarray, np.ndarray]:
        """Nodes (n, 3) in the cap's own frame (centre +z) and weights (n,) = L dω / E⊥ (1/sr · sr).

        ``polar`` Gauss–Legendre nodes on each of the two pieces of L(θ), ``azimuths`` equally
        spaced azimuths (offset by half a step on alternate rings).  Σ w = ∫ L dω / E⊥ exactly.
        """
        if polar < 1 or azimuths < 1:
            raise ParameterError("cap quadrature", (polar, azimuths), "polar ≥ 1 and azimuths ≥ 1")
        theta, dtheta = self._pieces(polar)
        nodes, weights = [], []
        for ring, (t, dt) in enumerate(zip(theta, dtheta)):
            phi = 2.0 * math.pi * (np.arange(azimuths) + 0.5 * (ring % 2)) / azimuths
            nodes.append(np.stack([np.sin(t) * np.cos(phi), np.sin(t) * np.sin(phi),
                                   np.full(azimuths, np.cos(t))], axis=1))
            weights.append(np.full(azimuths, float(self.radiance(t)) * math.sin(t) * dt * 2.0 * math.pi / azimuths))
        weights = np.concatenate(weights)
        return np.concatenate(nodes), weights / self.e_perp


def cap_frame(centre: np.ndarray) -> np.ndarray:
    """A right-handed orthonormal frame (3, 3), rows e1, e2, centre, about the unit ``centre``."""
    c = np.asarray(centre, float)
    c = c / np.linalg.norm(c)
    helper = np.array([1.0, 0.0, 0.0]) if abs(c[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    e1 = np.cross(helper, c)
    e1 /= np.linalg.norm(e1)
    return np.stack([e1, np.cross(c, e1), c])
