"""NumPy twins of the Cycles 5.0 closures the general-lighting modes (yarn, garment) mix.

Cycles' OSL accepts only its built-in closures, so the yarn BRDF is rendered
under arbitrary lighting as a weighted sum of them (:mod:`precompute.tables.closure_fit`).
The weights are fitted at bake time, which needs each closure's response outside
Blender: these functions return what Cycles' kernel returns as the closure's
``eval`` for a view direction ``V`` and a light direction ``L`` — the BSDF times the
cosine it carries, in 1/sr — so that a closure of weight ``w`` lit by a sun of
irradiance ``E`` (W/m² on a plane facing it) gives the radiance ``w · eval · E``.
That is also the yarn BRDF's convention ``ρ = L_o / E⊥`` (docs/transport.md).

They follow ``intern/cycles/kernel/closure/bsdf_diffuse.h``, ``bsdf_toon.h``, ``bsdf_hair.h`` and
``bsdf_microfacet.h`` of Blender 5.0 (the hair lobes are the Kajiya–Kay-like
"Hair BSDF" lobes, not the Chiang/Huang models); ``tests/test_cycles_closures.py``
renders each closure in Cycles and holds the twins to it.  All directions point
away from the surface and are unit vectors; arrays broadcast over leading axes.
"""

from __future__ import annotations

import numpy as np

from precompute.optics.cook_torrance import dielectric_fresnel

#: Cycles clamps the hair lobes' roughness to this range (``bsdf_hair_*_setup``).
HAIR_ROUGHNESS_RANGE = (0.001, 1.0)
#: Below this alpha² a microfacet closure is singular and has no ``eval`` in Cycles.
MICROFACET_SINGULAR_ALPHA2 = 1e-7


def _dot(a, b):
    return np.sum(np.asarray(a, float) * np.asarray(b, float), axis=-1)


def diffuse_eval(normal, light):
    """Cycles ``diffuse(N)``: ``max(0, N·L) / π``, 1/sr (exact only while N is the shading normal)."""
    return np.maximum(_dot(normal, light), 0.0) / np.pi


def translucent_eval(normal, light):
    """Cycles ``translucent(N)``: ``max(0, −N·L) / π``, 1/sr (exact only while N is the shading normal)."""
    return np.maximum(-_dot(normal, light), 0.0) / np.pi


def uniform_eval(normal, light):
    """Cycles ``diffuse_toon(N, 1, 0)`` (the Toon BSDF's diffuse component, size 1, no smoothing): the
    same ``1 / (2π)`` for every light above the plane, 1/sr — a lobe without the cosine a Lambertian
    one falls with (``bsdf_toon.h``: its eval is its uniform sampling pdf over the cone)."""
    return np.where(_dot(normal, light) > 0.0, 0.5 / np.pi, 0.0)


def _fibre_angles(tangent, view, light):
    """Longitudinal angles θ_r (view) and θ_i (light) from the fibre's normal plane, radians, and the
    cosine of the azimuth between the two directions projected onto that plane."""
    tangent = np.asarray(tangent, float)
    view_along = _dot(tangent, view)
    light_along = _dot(tangent, light)
    view_across = np.asarray(view, float) - tangent * view_along[..., None]
    light_across = np.asarray(light, float) - tangent * light_along[..., None]
    view_across = view_across / np.maximum(np.linalg.norm(view_across, axis=-1, keepdims=True), 1e-30)
    light_across = light_across / np.maximum(np.linalg.norm(light_across, axis=-1, keepdims=True), 1e-30)
    theta_r = np.arcsin(np.clip(view_along, -1.0, 1.0))
    theta_i = np.arcsin(np.clip(light_along, -1.0, 1.0))
    return theta_r, theta_i, np.clip(_dot(view_across, light_across), -1.0, 1.0)


def _longitudinal_pdf(theta_r, theta_i, roughness):
    """The hair lobes' Cauchy distribution of the half angle (θ_i + θ_r)/2 about 0, per solid angle."""
    bound_high = np.arctan((np.pi / 2 + theta_r) / 2 / roughness)
    bound_low = np.arctan((-np.pi / 2 + theta_r) / 2 / roughness)
    half = (theta_i + theta_r) / 2
    return roughness / (2 * (half * half + roughness * roughness) * (bound_high - bound_low)
                        * np.maximum(np.cos(theta_i), 1e-30))


def hair_reflection_eval(normal, tangent, view, light, roughness_longitudinal, roughness_azimuthal):
    """Cycles ``hair_reflection(N, r1, r2, T, 0)``, 1/sr.

    A lobe on the fibre's specular cone θ_i = −θ_r (light and view at opposite
    angles to the fibre's normal plane), Cauchy of width r1 in the half angle,
    ``cos(φ / 2 r2)`` in the azimuth φ between the two directions; lights behind N or
    more than 90° round the fibre from the view give nothing.
    """
    r1 = float(np.clip(roughness_longitudinal, *HAIR_ROUGHNESS_RANGE))
    r2 = float(np.clip(roughness_azimuthal, *HAIR_ROUGHNESS_RANGE))
    theta_r, theta_i, cos_phi = _fibre_angles(tangent, view, light)
    phi = np.minimum(np.arccos(cos_phi) / r2, np.pi)
    value = np.cos(phi / 2) / (4 * r2) * _longitudinal_pdf(theta_r, theta_i, r1)
    valid = (_dot(normal, light) >= 0.0) & (cos_phi >= 0.0) & (np.pi / 2 - np.abs(theta_i) >= 1e-3)
    return np.where(valid, value, 0.0)


def hair_transmission_eval(normal, tangent, view, light, roughness_longitudinal, roughness_azimuthal):
    """Cycles ``hair_transmission(N, r1, r2, T, 0)``, 1/sr.

    The same longitudinal lobe as :func:`hair_reflection_eval` for lights behind N,
    with a Cauchy distribution of width r2 about the forward azimuth φ = π.
    """
    r1 = float(np.clip(roughness_longitudinal, *HAIR_ROUGHNESS_RANGE))
    r2 = float(np.clip(roughness_azimuthal, *HAIR_ROUGHNESS_RANGE))
    theta_r, theta_i, cos_phi = _fibre_angles(tangent, view, light)
    p = np.pi - np.arccos(cos_phi)
    azimuthal = r2 / (2 * np.arctan(np.pi / 2 / r2) * (p * p + r2 * r2))
    value = azimuthal * _longitudinal_pdf(theta_r, theta_i, r1)
    valid = (_dot(normal, light) < 0.0) & (np.pi / 2 - np.abs(theta_i) >= 1e-3)
    return np.where(valid, value, 0.0)


def _ggx_lambda(alpha2, cosine):
    cos2 = np.maximum(cosine * cosine, 1e-30)
    return (np.sqrt(1.0 + alpha2 * (1.0 - cos2) / cos2) - 1.0) / 2.0


def _beckmann_lambda(alpha2, cosine):
    # Cycles' rational approximation (Walter et al. 2007, eq. 27) of the Smith term's Λ.
    cos2 = np.clip(cosine * cosine, 1e-30, 1.0)
    a = np.sqrt(cos2 / np.maximum(alpha2 * (1.0 - cos2), 1e-30))
    return np.where(a < 1.6, (1.0 - 1.259 * a + 0.396 * a * a) / (3.535 * a + 2.181 * a * a), 0.0)


def _microfacet_reflection_eval(normal, view, light, alpha, distribution, smith_lambda):
    """``D(h) / (4 N·V) / (1 + Λ(V) + Λ(L))`` for ``distribution(α², cos θ_h)`` and
    ``smith_lambda(α², cos θ)``: Cycles' microfacet reflection without Fresnel (Walter et al. 2007
    with the height-correlated Smith term), zero for lights below N or views below N."""
    alpha = float(np.clip(alpha, 0.0, 1.0))
    alpha2 = alpha * alpha
    cos_view = _dot(normal, view)
    cos_light = _dot(normal, light)
    half = np.asarray(view, float) + np.asarray(light, float)
    half = half / np.maximum(np.linalg.norm(half, axis=-1, keepdims=True), 1e-30)
    value = distribution(alpha2, _dot(normal, half)) / np.maximum(cos_view, 1e-30) * 0.25 / (
        1.0 + smith_lambda(alpha2, cos_view) + smith_lambda(alpha2, cos_light))
    valid = (cos_view > 0.0) & (cos_light >= 0.0) & (alpha2 > MICROFACET_SINGULAR_ALPHA2)
    return np.where(valid, value, 0.0)


def _beckmann_distribution(alpha2, cos_half):
    cos2 = np.clip(cos_half, 1e-6, 1.0) ** 2
    alpha2 = max(alpha2, 1e-30)
    return np.exp(-(1.0 - cos2) / (cos2 * alpha2)) / (np.pi * alpha2 * cos2 * cos2)


def _ggx_distribution(alpha2, cos_half):
    return alpha2 / (np.pi * (1.0 + (alpha2 - 1.0) * cos_half * cos_half) ** 2)


def beckmann_reflection_eval(normal, view, light, alpha):
    """Cycles ``microfacet("beckmann", N, alpha, eta, 0)`` and the Glossy BSDF node's Beckmann
    distribution (roughness² = alpha): Beckmann reflection without Fresnel, 1/sr.

    D = exp(−tan²θ_h/α²) / (π α² cos⁴θ_h) (α the rms slope) with Cycles' approximation of Λ
    (:func:`_microfacet_reflection_eval`).
    """
    return _microfacet_reflection_eval(normal, view, light, alpha, _beckmann_distribution, _beckmann_lambda)


def beckmann_conductor_eval(normal, view, light, alpha, ior):
    """The Metallic BSDF node, Beckmann, a physical conductor of index ``ior`` and extinction 0:
    :func:`beckmann_reflection_eval` times the Fresnel reflectance at V·H, 1/sr.  Cycles' conductor
    Fresnel (Born and Wolf, ``bsdf_util.h``) with k = 0 is the unpolarised dielectric one, so this is
    the Cook–Torrance term times cos θ_L (:mod:`precompute.optics.cook_torrance`, Cycles' Λ)."""
    half = np.asarray(view, float) + np.asarray(light, float)
    half = half / np.maximum(np.linalg.norm(half, axis=-1, keepdims=True), 1e-30)
    return dielectric_fresnel(_dot(view, half), ior) * beckmann_reflection_eval(normal, view, light, alpha)


def ggx_reflection_eval(normal, view, light, alpha):
    """Cycles ``microfacet("ggx", N, alpha, eta, 0)``: GGX reflection without Fresnel, 1/sr
    (:func:`_microfacet_reflection_eval`)."""
    return _microfacet_reflection_eval(normal, view, light, alpha, _ggx_distribution, _ggx_lambda)
