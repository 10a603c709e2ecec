"""The cloth's specular term: Cook–Torrance about the cloth normal, in NumPy (no bpy).

Lobalzo & Voloboy 2008 compute the light reflected directly by the yarns' surface "in accordance
with [10] (Cook and Torrance 1982) per implementation proposed in [21] (Blinn)", against the normal
to the piece of cloth (§5.2), with the smoothness constant m = 0.8 (§6, the Lambert + Cook–Torrance
baseline); the paper numbers no equation for it.  The form used here is the shader's
``cl_cook_torrance`` (``osl/clothlight.h``):

    f_CT(l, v) = F(v·h) D(h) G(l, v) / (4 (n·l)(n·v))                               [1/sr]

with h the half vector, D the normalised Beckmann distribution of rms slope m,
D = exp(−tan²α / m²) / (π m² cos⁴α), α = ∠(n, h); G Smith's height-correlated shadowing of that
Beckmann surface, G = 1 / (1 + Λ(v) + Λ(l)), Λ = (erf(a) − 1)/2 + exp(−a²) / (2a√π),
a = cot θ / m (Cook and Torrance's V-cavity G is not the shadowing of a Beckmann surface; Cycles'
Beckmann closures use Smith's, so the shader does too); and F Cook and Torrance's unpolarised
dielectric Fresnel, with g² = n² − 1 + c², c = v·h.  Zero unless both directions are above the
plane.

:func:`cook_torrance_between` is the scalar twin the tests compare renders with (it lived in
``tests/helpers.py``); :func:`cook_torrance` the same, vectorised, for fits.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from scipy.special import erf

#: The shader's defaults (``osl/cloth_yarn.osl``): weight, rms slope m (the paper's 0.8), host index.
DEFAULT_WEIGHT = 1.0
DEFAULT_SLOPE = 0.8
DEFAULT_IOR = 1.557
#: The shader's default fuzz albedo (``FuzzAlbedo``, :mod:`precompute.optics.lommel_seeliger`): none.
DEFAULT_FUZZ_ALBEDO = 0.0
#: ... and fuzz depth (``FuzzDepth``): 0, the fuzz a veneer that shades nothing beneath it.
DEFAULT_FUZZ_DEPTH = 0.0
#: ... its asymmetry (``FuzzAsymmetry``, the Henyey–Greenstein g): 0, isotropic, the Lommel–Seeliger law.
DEFAULT_FUZZ_ASYMMETRY = 0.0
#: ... its red and blue albedo relative to its green (``FuzzTint``): 1, white.
DEFAULT_FUZZ_TINT = 1.0
#: ... and the share of its fibres that lie flat (``FuzzFlatness``): 0, fibres in every direction.
DEFAULT_FUZZ_FLATNESS = 0.0
#: The preset table holding the fitted cloth-scale terms (``[fit]``, keys ``specular_weight``,
#: ``specular_slope``, ``fuzz_albedo``, ``fuzz_depth``, ``fuzz_asymmetry``, ``fuzz_tint_red``,
#: ``fuzz_tint_blue`` and ``fuzz_flatness``, the shader's SpecularWeight, Slope, FuzzAlbedo, FuzzDepth,
#: FuzzAsymmetry, FuzzTint and FuzzFlatness; ``python -m clothlight.fit`` writes it); the medium's
#: loader ignores it.
FIT_TABLE = "fit"
#: The ``[fit]`` table's keys and the shader's defaults for them.
SPECULAR_DEFAULTS = {"specular_weight": DEFAULT_WEIGHT, "specular_slope": DEFAULT_SLOPE,
                     "fuzz_albedo": DEFAULT_FUZZ_ALBEDO, "fuzz_depth": DEFAULT_FUZZ_DEPTH,
                     "fuzz_asymmetry": DEFAULT_FUZZ_ASYMMETRY, "fuzz_tint_red": DEFAULT_FUZZ_TINT,
                     "fuzz_tint_blue": DEFAULT_FUZZ_TINT, "fuzz_flatness": DEFAULT_FUZZ_FLATNESS}
#: The keys of the fuzz's phase function, colour and fibre orientation: a record holds them only where
#: they are not the defaults, so that the tables of the presets before them keep their keys.
FUZZ_SHAPE_KEYS = ("fuzz_asymmetry", "fuzz_tint_red", "fuzz_tint_blue", "fuzz_flatness")


def cook_torrance_between(light, view, m=DEFAULT_SLOPE, n=DEFAULT_IOR) -> float:
    """Cook–Torrance (1/sr) about +z between unit directions toward the light and the viewer, from
    its definition (module docstring): F D G / (4 (n·l)(n·v)), Beckmann D = exp(−tan²α/m²) / (π m²
    cos⁴α), Smith's height-correlated G = 1 / (1 + Λ(v) + Λ(l)) of that surface with Λ = (erf(a) −
    1)/2 + exp(−a²)/(2a√π), a = cot θ / m, F Cook and Torrance's dielectric Fresnel with g² = n² −
    1 + c², c = v·h; 0 unless both are above the plane."""
    light, view = np.asarray(light, float), np.asarray(view, float)
    nl, nv = light[2], view[2]
    if nl <= 0.0 or nv <= 0.0:
        return 0.0
    half = (light + view) / np.linalg.norm(light + view)
    nh, vh = half[2], view @ half
    alpha = math.acos(min(nh, 1.0))
    d = math.exp(-((math.tan(alpha) / m) ** 2)) / (math.pi * m**2 * nh**4)

    def smith_lambda(cos_theta):
        a = cos_theta / (m * math.sqrt(1.0 - cos_theta**2)) if cos_theta < 1.0 else math.inf
        return 0.0 if math.isinf(a) else (math.erf(a) - 1) / 2 + math.exp(-a * a) / (2 * a * math.sqrt(math.pi))

    g_att = 1.0 / (1.0 + smith_lambda(nv) + smith_lambda(nl))
    return float(dielectric_fresnel(vh, n)) * d * g_att / (4 * nl * nv)


def _smith_lambda(cos_theta: np.ndarray, m: float) -> np.ndarray:
    c = np.clip(cos_theta, 1e-9, 1.0)
    sin = np.sqrt(np.maximum(1.0 - c * c, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.where(sin > 0.0, c / (m * np.where(sin > 0.0, sin, 1.0)), np.inf)
        value = (erf(a) - 1.0) / 2.0 + np.exp(-a * a) / (2.0 * a * math.sqrt(math.pi))
    return np.where(np.isfinite(a), value, 0.0)


def cook_torrance(light, view, m: float = DEFAULT_SLOPE, n: float = DEFAULT_IOR) -> np.ndarray:
    """:func:`cook_torrance_between`, vectorised: ``light`` and ``view`` are (..., 3) unit vectors
    (broadcast together) toward the light and the viewer; the BRDF (...), 1/sr, about +z."""
    light, view = np.broadcast_arrays(np.asarray(light, float), np.asarray(view, float))
    return dielectric_fresnel(_cosine_with_half(light, view), n) * beckmann_reflection(light, view, m)


def beckmann_reflection(light, view, m: float) -> np.ndarray:
    """The Beckmann microfacet reflection of rms slope ``m`` without a Fresnel factor, D G / (4 (n·l)(n·v))
    (…), 1/sr, about +z between unit directions ``light`` and ``view`` (…, 3) (broadcast together): the
    module docstring's f_CT with F = 1, what Cycles' ``microfacet("beckmann", …)`` closure and its
    Glossy BSDF (Beckmann, roughness √m) reflect; 0 unless both are above the plane."""
    light, view = np.broadcast_arrays(np.asarray(light, float), np.asarray(view, float))
    nl, nv = light[..., 2], view[..., 2]
    above = (nl > 0.0) & (nv > 0.0)
    half = _half_vector(light, view)
    nh = np.clip(half[..., 2], 1e-9, 1.0)
    tan2 = (1.0 - nh * nh) / (nh * nh)
    d = np.exp(-tan2 / (m * m)) / (math.pi * m * m * nh**4)
    g_att = 1.0 / (1.0 + _smith_lambda(nv, m) + _smith_lambda(nl, m))
    safe = np.where(above, 4.0 * nl * nv, 1.0)
    return np.where(above, d * g_att / safe, 0.0)


def _half_vector(light: np.ndarray, view: np.ndarray) -> np.ndarray:
    half = light + view
    norm = np.linalg.norm(half, axis=-1)
    return half / np.where(norm > 0.0, norm, 1.0)[..., None]


def _cosine_with_half(light: np.ndarray, view: np.ndarray) -> np.ndarray:
    return np.clip(np.sum(view * _half_vector(light, view), axis=-1), 0.0, 1.0)


def dielectric_fresnel(cos_theta, n: float = DEFAULT_IOR) -> np.ndarray:
    """Cook and Torrance's unpolarised dielectric Fresnel reflectance (…), dimensionless, at the
    cosine ``cos_theta`` (…) between a direction and the microfacet normal, for index ``n``:
    F = ½ (g − c)²/(g + c)² (1 + (c(g + c) − 1)²/(c(g − c) + 1)²), g² = n² − 1 + c²."""
    c = np.clip(np.asarray(cos_theta, float), 0.0, 1.0)
    g = np.sqrt(n * n - 1.0 + c * c)
    # n = 1 (a yarn of fibres in air) reflects nothing; the formula is 0/0 where c = 0 (light and view
    # opposite: the swatch lit from behind)
    g_plus_c = np.where(g + c > 0.0, g + c, 1.0)
    return 0.5 * (g - c) ** 2 / g_plus_c**2 * (1.0 + (c * (g + c) - 1.0) ** 2 / (c * (g - c) + 1.0) ** 2)


def direction(theta_deg, phi_deg) -> np.ndarray:
    """Unit vectors (..., 3) at zenith ``theta_deg`` from +z and azimuth ``phi_deg`` from +x."""
    theta, phi = np.radians(np.asarray(theta_deg, float)), np.radians(np.asarray(phi_deg, float))
    theta, phi = np.broadcast_arrays(theta, phi)
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)


def cloth_specular(angles_deg, weight: float = DEFAULT_WEIGHT, m: float = DEFAULT_SLOPE,
                   n: float = DEFAULT_IOR) -> np.ndarray:
    """The flat cloth's specular BRDF (M,), 1/sr, ``weight`` · f_CT about the cloth normal (0, 0, 1),
    at direction pairs ``angles_deg`` (M, 4): θi, φi, θo, φo in degrees (the measured-data CSV's
    columns)."""
    a = np.asarray(angles_deg, float)
    return weight * cook_torrance(direction(a[:, 0], a[:, 1]), direction(a[:, 2], a[:, 3]), m, n)


def sheen_index(medium) -> float:
    """The index n of the specular term's Fresnel factor for a yarn medium (a
    :class:`precompute.optics.medium.MediumParameters`), its real part averaged over the medium's
    wavelengths: that of the surfaces the sheen reflects from.  A yarn of fibres in air (host index
    1) has no refracting yarn surface and reflects its sheen from the fibres themselves, at the
    fibres' index (issue 43: with the boundary's index 1 its Fresnel factor, and so its sheen, is 0);
    any other yarn from its boundary, at the host's index (the paper's §5.2, the tables' host index)."""
    wavelengths = np.asarray(medium.wavelengths.values, float)
    host = float(np.mean(medium.host.refractive_index.at(wavelengths).real))
    if medium.fibres is not None and host == 1.0:
        return float(np.mean(medium.fibres.refractive_index.at(wavelengths).real))
    return host


def specular_from_config(config: Mapping) -> dict[str, float]:
    """The specular keywords a preset records in its ``[fit]`` table (a fitted preset), else the
    shader's defaults."""
    table = config.get(FIT_TABLE, {})
    table = table if isinstance(table, dict) else {}
    return {key: float(table.get(key, default)) for key, default in SPECULAR_DEFAULTS.items()}


def fuzz_tint(record: Mapping) -> np.ndarray:
    """The fuzz's albedo per channel over its green (3,), RGB, of a specular record or keywords
    (``fuzz_tint_red``, ``fuzz_tint_blue``, absent keys at their defaults): (t_R, 1, t_B), the
    shader's FuzzTint."""
    return np.array([float(record.get("fuzz_tint_red", DEFAULT_FUZZ_TINT)), 1.0,
                     float(record.get("fuzz_tint_blue", DEFAULT_FUZZ_TINT))])


def fuzz_colour(record: Mapping) -> np.ndarray:
    """The fuzz's albedo per channel (3,), RGB, of a specular record or keywords: ``fuzz_albedo``
    (absent: 0) times :func:`fuzz_tint`."""
    return float(record.get("fuzz_albedo", DEFAULT_FUZZ_ALBEDO)) * fuzz_tint(record)


__all__ = ["DEFAULT_FUZZ_ALBEDO", "DEFAULT_FUZZ_ASYMMETRY", "DEFAULT_FUZZ_DEPTH", "DEFAULT_FUZZ_TINT", "DEFAULT_IOR",
           "DEFAULT_SLOPE", "DEFAULT_WEIGHT", "FIT_TABLE", "FUZZ_SHAPE_KEYS", "SPECULAR_DEFAULTS", "cloth_specular",
           "beckmann_reflection", "cook_torrance", "cook_torrance_between",
           "dielectric_fresnel", "direction", "fuzz_colour", "fuzz_tint", "sheen_index", "specular_from_config"]
