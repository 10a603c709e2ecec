"""The cloth's fuzz term: the white first reflections of its surface fibres, a Lommel–Seeliger law
about the cloth normal, in NumPy (no bpy).

A cloth's surface fibres (its fuzz: fibre ends and loops above the yarns) reflect a few percent of
the light undyed before any of it meets a dye.  The single scattering of a semi-infinite layer of
isotropic scatterers is the Lommel–Seeliger law (Hapke, "Bidirectional reflectance spectroscopy 1.
Theory", J. Geophys. Res. 86 (B4), 1981, eq. 14 without the opposition and multiple-scattering
terms):

    f_LS(l, v) = A / (4π (μi + μo))                                                   [1/sr]

with μi = n·l, μo = n·v the cosines with the cloth normal n and A the fuzz albedo (white: the same
in every channel).  It rises toward grazing light and view in every azimuth.  Its directional
albedo, the light it returns from a view (or, by reciprocity, from a light) at cosine μ, is

    a(μ) = ∫ f_LS μi dω_i = (A / 2) (1 − μ ln(1 + 1/μ)).

The yarn shader renders it exactly in sun mode (``cl_cloth_fuzz``, ``osl/clothlight.h``) and, in
the general mode, as a diffuse closure of weight a(μo) about the cloth normal, which returns the
same light at each view and spreads it over the lights as a Lambertian would.
"""

from __future__ import annotations

import math

import numpy as np


def lommel_seeliger(light, view, albedo: float = 1.0) -> np.ndarray:
    """The fuzz term f_LS (…), 1/sr, about +z between unit directions ``light`` and ``view`` (…, 3)
    (broadcast together) toward the light and the viewer: ``albedo`` / (4π (μi + μo)), 0 unless both
    are above the plane."""
    light, view = np.broadcast_arrays(np.asarray(light, float), np.asarray(view, float))
    mu_i, mu_o = light[..., 2], view[..., 2]
    above = (mu_i > 0.0) & (mu_o > 0.0)
    return np.where(above, albedo / (4.0 * math.pi * np.where(above, mu_i + mu_o, 1.0)), 0.0)


def lommel_seeliger_albedo(mu, albedo: float = 1.0) -> np.ndarray:
    """The directional albedo a(μ) (…) of the fuzz term at the cosine ``mu`` (…) with the normal:
    (``albedo`` / 2)(1 − μ ln(1 + 1/μ)); ``albedo``/2 at grazing (μ → 0)."""
    mu = np.clip(np.asarray(mu, float), 0.0, 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        log_term = np.where(mu > 0.0, mu * np.log1p(1.0 / np.where(mu > 0.0, mu, 1.0)), 0.0)
    return 0.5 * albedo * (1.0 - log_term)


__all__ = ["lommel_seeliger", "lommel_seeliger_albedo"]
