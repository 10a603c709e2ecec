"""The paper's baseline, fitted to the same views as the medium: Lambert + Cook–Torrance.

Lobalzo & Voloboy 2008 (§6) compare their cloth with "a classical approach": a Lambert diffuse
term (their kd = (0.6/π, 0, 0)) plus Cook–Torrance against the cloth's normal (m = 0.8).  To make
the comparison fair, the fit gives the baseline the same freedom a fit gives the medium: its five
parameters, the Lambert albedo (R, G, B) and the Cook–Torrance weight and rms slope m, are fitted
to the same fit views with the same misfit (per-channel relative RMS, :mod:`precompute.fit.objective`).

The baseline's cloth BRDF at a view is the flat-cloth form

    f(l, v) = a_c / π + w · f_CT(l, v; n = (0, 0, 1), m, n_host = 1.557)           [1/sr]

with f_CT the shader's Cook–Torrance (:mod:`precompute.optics.cook_torrance`, ``cl_cook_torrance``): the
cloth a flat sheet, no weave, no shadowing by yarns.  Fitted with scipy's bounded least squares
(trust-region reflective) from three starting slopes, the best kept.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from precompute.optics.cook_torrance import DEFAULT_IOR, cloth_specular
from precompute.fit.objective import CHANNELS, Objective

#: Bounds of the baseline's parameters: albedo (each channel), weight, rms slope m.
ALBEDO_BOUNDS = (0.0, 1.0)
WEIGHT_BOUNDS = (0.0, 10.0)
SLOPE_BOUNDS = (0.02, 2.0)
#: Starting rms slopes of the least-squares fits (the best result is kept).
STARTING_SLOPES = (0.15, 0.4, 0.8)


@dataclass(frozen=True)
class BaselineFit:
    """The fitted baseline: Lambert ``albedo`` (R, G, B), Cook–Torrance ``weight`` and ``slope`` (m)."""

    albedo: tuple[float, float, float]
    weight: float
    slope: float
    ior: float = DEFAULT_IOR

    def brdf(self, angles_deg) -> np.ndarray:
        """(M, 3) BRDF, 1/sr, at direction pairs (M, 4): θi, φi, θo, φo in degrees."""
        specular = cloth_specular(angles_deg, self.weight, self.slope, self.ior)
        return np.asarray(self.albedo)[None, :] / math.pi + specular[:, None]

    def to_dict(self) -> dict:
        return {"form": "albedo/pi + weight * f_CT(l, v; n=(0,0,1), m=slope, ior)",
                "albedo": dict(zip(CHANNELS, map(float, self.albedo))), "weight": float(self.weight),
                "slope": float(self.slope), "ior": float(self.ior)}


def baseline_brdf(angles_deg, albedo, weight: float, slope: float, ior: float = DEFAULT_IOR) -> np.ndarray:
    """(M, 3) the baseline's BRDF (module docstring) at direction pairs (M, 4), degrees."""
    return BaselineFit(tuple(albedo), weight, slope, ior).brdf(angles_deg)


def fit_baseline(objective: Objective, ior: float = DEFAULT_IOR) -> BaselineFit:
    """The baseline fitted to ``objective``'s fit views (module docstring): minimises the sum over
    channels of the squared per-channel relative RMS errors, i.e. the objective without colour
    targets."""
    views = objective.views
    angles = views.angles_deg[views.fit]
    measured = objective.measured[views.fit]
    scale = np.sqrt(np.mean(measured**2, axis=0))
    weights = np.where(scale > 0, 1.0 / np.where(scale > 0, scale, 1.0), 0.0) / math.sqrt(len(measured))

    def residuals(x):
        albedo, weight, slope = x[:3], x[3], x[4]
        model = albedo[None, :] / math.pi + weight * cloth_specular(angles, 1.0, slope, ior)[:, None]
        return ((model - measured) * weights[None, :]).ravel()

    albedo0 = np.clip(math.pi * np.median(measured, axis=0), ALBEDO_BOUNDS[0] + 1e-6, ALBEDO_BOUNDS[1] - 1e-6)
    low = [ALBEDO_BOUNDS[0]] * 3 + [WEIGHT_BOUNDS[0], SLOPE_BOUNDS[0]]
    high = [ALBEDO_BOUNDS[1]] * 3 + [WEIGHT_BOUNDS[1], SLOPE_BOUNDS[1]]
    best = None
    for slope0 in STARTING_SLOPES:
        x0 = np.array([*albedo0, 0.5, slope0])
        result = least_squares(residuals, x0, bounds=(low, high), method="trf", x_scale=[0.1, 0.1, 0.1, 0.5, 0.2],
                               max_nfev=2000)
        if best is None or result.cost < best.cost:
            best = result
    x = best.x
    return BaselineFit((float(x[0]), float(x[1]), float(x[2])), float(x[3]), float(x[4]), ior)


__all__ = ["ALBEDO_BOUNDS", "SLOPE_BOUNDS", "STARTING_SLOPES", "WEIGHT_BOUNDS", "BaselineFit", "baseline_brdf",
           "fit_baseline"]
