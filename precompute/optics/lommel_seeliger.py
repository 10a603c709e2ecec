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

**A fuzz of finite depth.**  Fibres that reflect light also stand in its way: a layer of them of
optical depth τ along the normal (``fuzz_depth``) lets through to the cloth beneath, and back out,

    T(μi, μo) = exp(−τ (1/|μi| + 1/|μo|))                                  (fuzz_transmittance)

(Beer–Lambert along both slant paths, the same layer on either face of the cloth), and its own
single scattering is that of a finite layer (Hapke 1981, eq. 14 for a layer of optical depth τ;
Chandrasekhar, *Radiative Transfer*, 1960, §72):

    f_layer(l, v) = A (1 − T(μi, μo)) / (4π (μi + μo))                      (fuzz_brdf)

so the cloth is f = T f_yarn + f_layer + f_sheen: the sheen is the same top fibres' own
reflection, not shaded by them.  τ → ∞ is the semi-infinite law above with nothing seen beneath;
``fuzz_depth = 0`` keeps the fuzz as the presets before it had it, a Lommel–Seeliger veneer over an
unshaded cloth (f_LS added, T = 1).  The layer's directional albedo has no closed form; the
general mode takes :func:`fuzz_albedo_at_view`, a Gauss–Legendre sum over μi.

**Fibres that scatter forward, dyed.**  A fuzz of fibres does not scatter isotropically: light
grazing the cloth passes through its top fibres and leaves on the far side, forward, and through dyed
fibres it leaves coloured.  Measured red-fabric2 (``../shared/data/real_fabrics/neural``) rises
tenfold in red from θv 0° to 80° on the far side at θi 75°, with B/R there 0.32 against the 0.06 of its
diffuse light, and stays flat seen from the light (docs/fitting.md, "A fuzz that scatters forward").
The layer's single scattering with a Henyey–Greenstein phase function p_HG of asymmetry g
(``fuzz_asymmetry``; Henyey & Greenstein 1941; Hapke 1981, eq. 14 with its phase function P(g) = 4π p) is

    f_layer(l, v) = A 4π p_HG(−l·v; g) (1 − T(μi, μo)) / (4π (μi + μo))                     (fuzz_brdf)

with −l·v the cosine of the scattering angle between the light's way in and the view's way out
(g = 0: the law above, 4π p = 1), and the albedo A may be a colour, the fibres' own: they are dyed
(``[fit] fuzz_albedo`` its green, ``fuzz_tint_red`` and ``fuzz_tint_blue`` its red and blue over it,
:func:`precompute.optics.cook_torrance.fuzz_colour`), applied by the caller per channel.  The
directional albedo of a phase function that is not isotropic depends on the azimuth:
:func:`fuzz_albedo_at_view` sums over it too.
"""

from __future__ import annotations

import math

import numpy as np

from precompute.optics.phase import henyey_greenstein_phase


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


#: Gauss–Legendre nodes over μi in (0, 1) of :func:`fuzz_albedo_at_view` (the shader's general mode sums the same).
FUZZ_ALBEDO_NODES = 8


def fuzz_quadrature(nodes: int = FUZZ_ALBEDO_NODES) -> tuple[np.ndarray, np.ndarray]:
    """The Gauss–Legendre cosines μ_k and weights w_k on (0, 1) (``nodes`` of each) of the general
    mode's sums over μ: NumPy's ``leggauss`` mapped by μ = (x + 1)/2, w/2 (``CL_FUZZ_NODE_COSINES``,
    ``CL_FUZZ_NODE_WEIGHTS`` in ``osl/clothlight.h``)."""
    x, w = np.polynomial.legendre.leggauss(nodes)
    return 0.5 * (x + 1.0), 0.5 * w


def fuzz_transmittance(mu_i, mu_o, depth: float) -> np.ndarray:
    """T(μi, μo) (…) of the module docstring: exp(−``depth`` (1/|μi| + 1/|μo|)), the share of the
    light that crosses a fuzz of optical depth ``depth`` to the cloth beneath and back; 1 where
    ``depth`` is 0, 0 at a grazing cosine."""
    mu_i, mu_o = np.abs(np.asarray(mu_i, float)), np.abs(np.asarray(mu_o, float))
    if depth <= 0.0:
        return np.ones(np.broadcast(mu_i, mu_o).shape)
    grazing = (mu_i <= 0.0) | (mu_o <= 0.0)
    with np.errstate(divide="ignore"):
        path = np.where(grazing, np.inf, 1.0 / np.where(grazing, 1.0, mu_i) + 1.0 / np.where(grazing, 1.0, mu_o))
    return np.exp(-depth * path)


def fuzz_phase(light, view, asymmetry: float = 0.0) -> np.ndarray:
    """4π p_HG(−l·v; g) (…): the fuzz's Henyey–Greenstein phase function relative to an isotropic
    one between unit directions ``light`` and ``view`` toward the light and the viewer, −l·v the
    cosine of the scattering angle; 1 everywhere for ``asymmetry`` g = 0."""
    light, view = np.broadcast_arrays(np.asarray(light, float), np.asarray(view, float))
    if asymmetry == 0.0:
        return np.ones(light.shape[:-1])
    return 4.0 * math.pi * henyey_greenstein_phase(-np.sum(light * view, axis=-1), asymmetry)


def fuzz_brdf(light, view, albedo: float = 1.0, depth: float = 0.0, asymmetry: float = 0.0) -> np.ndarray:
    """The fuzz's own BRDF (…), 1/sr, about +z (module docstring): :func:`lommel_seeliger` times
    (1 − :func:`fuzz_transmittance`) for a fuzz of optical depth ``depth`` > 0, the semi-infinite
    law itself for ``depth`` 0 (the veneer of the presets before it), times :func:`fuzz_phase` of
    asymmetry ``asymmetry``."""
    light, view = np.broadcast_arrays(np.asarray(light, float), np.asarray(view, float))
    law = lommel_seeliger(light, view, albedo) * fuzz_phase(light, view, asymmetry)
    if depth <= 0.0:
        return law
    return law * (1.0 - fuzz_transmittance(light[..., 2], view[..., 2], depth))


#: Azimuths of :func:`fuzz_albedo_at_view`'s sum where the fuzz scatters forward (midpoints on
#: (0, π), the phase function being even in the azimuth; ``CL_FUZZ_AZIMUTHS`` in ``osl/clothlight.h``).
FUZZ_ALBEDO_AZIMUTHS = 16


def fuzz_albedo_at_view(mu_o, albedo: float = 1.0, depth: float = 0.0, asymmetry: float = 0.0,
                        nodes: int = FUZZ_ALBEDO_NODES, azimuths: int = FUZZ_ALBEDO_AZIMUTHS) -> np.ndarray:
    """The directional albedo (…) of :func:`fuzz_brdf` at the view cosine ``mu_o`` (…): ∫ f_layer μi
    dω_i = (A/2) ∫₀¹ μi (1 − T) / (μi + μo) dμi, by ``nodes``-point Gauss–Legendre over μi;
    :func:`lommel_seeliger_albedo` for ``depth`` 0.  A fuzz of ``asymmetry`` g ≠ 0 weighs each μi by
    the mean of :func:`fuzz_phase` over the light's azimuth, ``azimuths`` midpoints on (0, π) (the
    semi-infinite law too, then: the closed form is the isotropic one's)."""
    if depth <= 0.0 and asymmetry == 0.0:
        return lommel_seeliger_albedo(mu_o, albedo)
    mu_o = np.clip(np.asarray(mu_o, float), 1e-6, 1.0)
    mu_i, weight = fuzz_quadrature(nodes)
    shade = 1.0 - fuzz_transmittance(mu_i, mu_o[..., None], depth) if depth > 0.0 else 1.0
    layer = shade * mu_i / (mu_i + mu_o[..., None])
    if asymmetry != 0.0:
        layer = layer * _azimuth_mean_phase(mu_i, mu_o, asymmetry, azimuths)
    return 0.5 * albedo * np.sum(weight * layer, axis=-1)


def _azimuth_mean_phase(mu_i: np.ndarray, mu_o: np.ndarray, asymmetry: float, azimuths: int) -> np.ndarray:
    """(…, nodes) the mean of :func:`fuzz_phase` over the azimuth between light and view, the light at
    the cosines ``mu_i`` (nodes,), the view at ``mu_o`` (…): −l·v = −(μi μo + sin θi sin θo cos φ)."""
    phi = (np.arange(azimuths) + 0.5) * math.pi / azimuths
    sin_i, sin_o = np.sqrt(1.0 - mu_i ** 2), np.sqrt(1.0 - mu_o[..., None] ** 2)
    cos_scattering = -(mu_i * mu_o[..., None])[..., None] - (sin_i * sin_o)[..., None] * np.cos(phi)
    return 4.0 * math.pi * henyey_greenstein_phase(cos_scattering, asymmetry).mean(axis=-1)


def hemispherical_transmittance(depth: float, nodes: int = FUZZ_ALBEDO_NODES) -> float:
    """The share of light from a uniform sky that crosses a fuzz of optical depth ``depth`` one way:
    ∫₀¹ 2 μ exp(−depth/μ) dμ = 2 E₃(depth) (the exponential integral), by ``nodes``-point
    Gauss–Legendre; 1 for ``depth`` 0.  The general mode shades the yarn's closures by it times
    exp(−depth/μo), the view's own path."""
    if depth <= 0.0:
        return 1.0
    mu, weight = fuzz_quadrature(nodes)
    return float(np.sum(2.0 * weight * mu * np.exp(-depth / mu)))


__all__ = ["FUZZ_ALBEDO_AZIMUTHS", "FUZZ_ALBEDO_NODES", "fuzz_albedo_at_view", "fuzz_brdf", "fuzz_phase",
           "fuzz_quadrature", "fuzz_transmittance",
           "hemispherical_transmittance", "lommel_seeliger", "lommel_seeliger_albedo"]
