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

**A forward lobe in the general modes.**  A diffuse lobe of the directional albedo a(μo) keeps the
fuzz's light at each view but spreads it over every light: seen from a light low on the same side, a
forward fuzz is brighter than it is, and at grazing views facing a light low on the far side, its
rising forward peak is missing.  The general modes split a(μo) in two closures about the cloth
normal: a diffuse lobe of weight d and a Beckmann reflection of rms slope :data:`FUZZ_FORWARD_SLOPE`
without a Fresnel factor (:func:`precompute.optics.cook_torrance.beckmann_reflection`) of weight s,
chosen so that both the light the fuzz returns and how much more of it comes from lights on the far
side of the view than from lights on its own side are the fuzz's:

    d + s a_m(μo) = a(μo),        s b_m(μo) = b(μo),        b = (a_far − a_near) / 2

(:func:`fuzz_general_lobes`; a_m, b_m the lobe's, :func:`forward_lobe_albedos`, a diffuse lobe's
b being 0), s held to [0, a / a_m].  An isotropic fuzz has b = 0: a diffuse lobe alone, as before.

**Fibres that lie flat.**  The fibres of a fuzz (and all of a felt) lie mostly in the cloth's plane,
not in every direction: a fibre shows a light the area of its shadow, in proportion to |ω × t| for a
fibre along t, and fibres lying in the plane at every azimuth show a light at the cosine μ with the
normal the mean of that over t,

    s(μ) = (2/π) E(√(1 − μ²))                                                   (fuzz_projected_area)

(E the complete elliptic integral of the second kind, :func:`scipy.special.ellipe`): 1 along the
normal, 2/π at grazing, where a layer of fibres in every direction shows the same area in each.  A
fuzz whose fibres lie flat in the share F (``fuzz_flatness``, the rest in every direction) shows
s_F(μ) = 1 − F (1 − s(μ)) relative to its area along the normal, so its slant optical depth is
τ s_F(μ)/μ, and a fibre scatters in proportion to the area it shows both the light and the view
(reciprocal, and at most A of the light it meets for A ≤ 1):

    T(μi, μo) = exp(−τ (s_i/|μi| + s_o/|μo|)),
    f_layer(l, v) = A 4π p_HG (1 − T) s_i s_o / (4π (s_i μo + s_o μi))

with s_i = s_F(μi), s_o = s_F(μo); F = 0 is the layer above.  Lit and seen low the layer shows less
of itself than a layer of fibres in every direction: measured white-fabric and pink felt are darker
seen from a low light than the isotropic layer (docs/fitting.md, "Fibres that lie flat").
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy.special import ellipe

from precompute.optics.cook_torrance import beckmann_reflection
from precompute.optics.phase import henyey_greenstein_phase


def fuzz_projected_area(mu, flatness: float = 0.0) -> np.ndarray:
    """s_F(μ) (…) of the module docstring: the area a fuzz whose fibres lie flat in the share
    ``flatness`` F shows a direction at the cosine ``mu`` (…) with the normal (its sign ignored), over
    the area it shows along the normal: 1 − F (1 − (2/π) E(√(1 − μ²))); 1 everywhere for F = 0, from 1
    along the normal to 1 − F (1 − 2/π) at grazing."""
    mu = np.clip(np.abs(np.asarray(mu, float)), 0.0, 1.0)
    if flatness == 0.0:
        return np.ones_like(mu)
    return 1.0 - flatness * (1.0 - (2.0 / math.pi) * ellipe(1.0 - mu * mu))


def lommel_seeliger(light, view, albedo: float = 1.0, flatness: float = 0.0) -> np.ndarray:
    """The fuzz term f_LS (…), 1/sr, about +z between unit directions ``light`` and ``view`` (…, 3)
    (broadcast together) toward the light and the viewer: ``albedo`` / (4π (μi + μo)), 0 unless both
    are above the plane; ``albedo`` s_i s_o / (4π (s_i μo + s_o μi)) for fibres that lie flat in the
    share ``flatness`` (:func:`fuzz_projected_area`)."""
    mu_i, mu_o, above = _cosines_above(light, view)
    return np.where(above, albedo * _layer_share(mu_i, mu_o, 0.0, flatness) / (4.0 * math.pi), 0.0)


def _cosines_above(light, view) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """μi, μo of unit directions ``light`` and ``view`` (…, 3) (broadcast together), 1 where either is
    not above the plane, and where both are."""
    light, view = np.broadcast_arrays(np.asarray(light, float), np.asarray(view, float))
    mu_i, mu_o = light[..., 2], view[..., 2]
    above = (mu_i > 0.0) & (mu_o > 0.0)
    return np.where(above, mu_i, 1.0), np.where(above, mu_o, 1.0), above


def _layer_share(mu_i, mu_o, depth: float, flatness: float) -> np.ndarray:
    """(1 − T) s_i s_o / (s_i μo + s_o μi) at the cosines ``mu_i``, ``mu_o`` > 0 (…, broadcast together):
    the fuzz's single scattering over A p / (4π) (module docstring), 1 − T being 1 for ``depth`` 0."""
    s_i, s_o = fuzz_projected_area(mu_i, flatness), fuzz_projected_area(mu_o, flatness)
    share = s_i * s_o / (s_i * mu_o + s_o * mu_i)
    return share if depth <= 0.0 else share * (1.0 - fuzz_transmittance(mu_i, mu_o, depth, flatness))


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


def fuzz_transmittance(mu_i, mu_o, depth: float, flatness: float = 0.0) -> np.ndarray:
    """T(μi, μo) (…) of the module docstring: exp(−``depth`` (s_i/|μi| + s_o/|μo|)), the share of the
    light that crosses a fuzz of optical depth ``depth`` whose fibres lie flat in the share
    ``flatness`` (s: :func:`fuzz_projected_area`; 1 for none) to the cloth beneath and back; 1 where
    ``depth`` is 0, 0 at a grazing cosine."""
    mu_i, mu_o = np.abs(np.asarray(mu_i, float)), np.abs(np.asarray(mu_o, float))
    if depth <= 0.0:
        return np.ones(np.broadcast(mu_i, mu_o).shape)
    grazing = (mu_i <= 0.0) | (mu_o <= 0.0)
    s_i, s_o = fuzz_projected_area(mu_i, flatness), fuzz_projected_area(mu_o, flatness)
    with np.errstate(divide="ignore"):
        path = np.where(grazing, np.inf, s_i / np.where(grazing, 1.0, mu_i) + s_o / np.where(grazing, 1.0, mu_o))
    return np.exp(-depth * path)


def fuzz_phase(light, view, asymmetry: float = 0.0) -> np.ndarray:
    """4π p_HG(−l·v; g) (…): the fuzz's Henyey–Greenstein phase function relative to an isotropic
    one between unit directions ``light`` and ``view`` toward the light and the viewer, −l·v the
    cosine of the scattering angle; 1 everywhere for ``asymmetry`` g = 0."""
    light, view = np.broadcast_arrays(np.asarray(light, float), np.asarray(view, float))
    if asymmetry == 0.0:
        return np.ones(light.shape[:-1])
    return 4.0 * math.pi * henyey_greenstein_phase(-np.sum(light * view, axis=-1), asymmetry)


def fuzz_brdf(light, view, albedo: float = 1.0, depth: float = 0.0, asymmetry: float = 0.0,
              flatness: float = 0.0) -> np.ndarray:
    """The fuzz's own BRDF (…), 1/sr, about +z (module docstring): :func:`lommel_seeliger` times
    (1 − :func:`fuzz_transmittance`) for a fuzz of optical depth ``depth`` > 0, the semi-infinite
    law itself for ``depth`` 0 (the veneer of the presets before it), times :func:`fuzz_phase` of
    asymmetry ``asymmetry``, its fibres lying flat in the share ``flatness``."""
    mu_i, mu_o, above = _cosines_above(light, view)
    law = np.where(above, albedo * _layer_share(mu_i, mu_o, depth, flatness) / (4.0 * math.pi), 0.0)
    return law * fuzz_phase(light, view, asymmetry)


#: Azimuths of :func:`fuzz_albedo_at_view`'s sum where the fuzz scatters forward (midpoints on
#: (0, π), the phase function being even in the azimuth; ``CL_FUZZ_AZIMUTHS`` in ``osl/clothlight.h``).
FUZZ_ALBEDO_AZIMUTHS = 16


def fuzz_albedo_at_view(mu_o, albedo: float = 1.0, depth: float = 0.0, asymmetry: float = 0.0,
                        flatness: float = 0.0, nodes: int = FUZZ_ALBEDO_NODES,
                        azimuths: int = FUZZ_ALBEDO_AZIMUTHS) -> np.ndarray:
    """The directional albedo (…) of :func:`fuzz_brdf` at the view cosine ``mu_o`` (…): ∫ f_layer μi
    dω_i = (A/2) ∫₀¹ μi (1 − T) s_i s_o / (s_i μo + s_o μi) dμi, by ``nodes``-point Gauss–Legendre
    over μi; :func:`lommel_seeliger_albedo` for ``depth`` 0 and no ``flatness``.  A fuzz of
    ``asymmetry`` g ≠ 0 weighs each μi by the mean of :func:`fuzz_phase` over the light's azimuth,
    ``azimuths`` midpoints on (0, π), the sum of :func:`fuzz_albedo_sides_at_view` (the semi-infinite
    law too, then: the closed form is the isotropic one's)."""
    if depth <= 0.0 and asymmetry == 0.0 and flatness == 0.0:
        return lommel_seeliger_albedo(mu_o, albedo)
    if asymmetry != 0.0:
        near, far = fuzz_albedo_sides_at_view(mu_o, albedo, depth, asymmetry, flatness, nodes, azimuths)
        return near + far
    mu_o = np.clip(np.asarray(mu_o, float), 1e-6, 1.0)
    mu_i, weight = fuzz_quadrature(nodes)
    layer = mu_i * _layer_share(mu_i, mu_o[..., None], depth, flatness)
    return 0.5 * albedo * np.sum(weight * layer, axis=-1)


def _azimuth_phase(mu_i: np.ndarray, mu_o: np.ndarray, asymmetry: float, azimuths: int) -> np.ndarray:
    """(…, nodes, azimuths) :func:`fuzz_phase` at ``azimuths`` midpoints φ on (0, π) between light and
    view (φ < π/2 the view's side), the light at the cosines ``mu_i`` (nodes,), the view at ``mu_o``
    (…): −l·v = −(μi μo + sin θi sin θo cos φ)."""
    phi = (np.arange(azimuths) + 0.5) * math.pi / azimuths
    sin_i, sin_o = np.sqrt(1.0 - mu_i ** 2), np.sqrt(1.0 - mu_o[..., None] ** 2)
    cos_scattering = -(mu_i * mu_o[..., None])[..., None] - (sin_i * sin_o)[..., None] * np.cos(phi)
    return 4.0 * math.pi * henyey_greenstein_phase(cos_scattering, asymmetry)


def fuzz_albedo_sides_at_view(mu_o, albedo: float = 1.0, depth: float = 0.0, asymmetry: float = 0.0,
                              flatness: float = 0.0, nodes: int = FUZZ_ALBEDO_NODES,
                              azimuths: int = FUZZ_ALBEDO_AZIMUTHS) -> tuple[np.ndarray, np.ndarray]:
    """:func:`fuzz_albedo_at_view` (…) in two parts, (a_near, a_far): the light from lights on the view's
    side of the cloth normal (azimuth from the view's within 90°) and from those on the far side, by the
    same sums (``azimuths`` even: half of its midpoints each side); a_near = a_far for an isotropic fuzz."""
    if azimuths % 2:
        raise ValueError(f"azimuths must be even to split at 90°, not {azimuths}")
    mu_o = np.clip(np.asarray(mu_o, float), 1e-6, 1.0)
    mu_i, weight = fuzz_quadrature(nodes)
    layer = (mu_i * _layer_share(mu_i, mu_o[..., None], depth, flatness))[..., None]
    phase = _azimuth_phase(mu_i, mu_o, asymmetry, azimuths)
    half = azimuths // 2
    sides = [np.sum(weight * np.mean(layer * part, axis=-1), axis=-1) * albedo / 4.0
             for part in (phase[..., :half], phase[..., half:])]
    return sides[0], sides[1]


#: The rms slope of the general modes' forward lobe of a fuzz (``CL_FUZZ_FORWARD_SLOPE``): the fuzz's
#: forward light rises toward grazing, most of it at the grazing mirror direction of the view.
FUZZ_FORWARD_SLOPE = 0.5
#: View angles, even in θo from 0 to 90°, at which ``osl/clothlight.h`` tabulates that lobe's albedos.
FUZZ_FORWARD_POINTS = 17


def forward_lobe_albedos(mu_o, slope: float = FUZZ_FORWARD_SLOPE, nodes: int = 48,
                         azimuths: int = 96) -> tuple[np.ndarray, np.ndarray]:
    """(a_m, b_m) (…) of the general modes' forward lobe at the view cosine ``mu_o`` (…): the directional
    albedo of :func:`precompute.optics.cook_torrance.beckmann_reflection` of rms slope ``slope`` and half
    its excess of light from lights on the far side of the normal over the view's side, by
    ``nodes``-point Gauss–Legendre over μi and ``azimuths`` midpoints over (0, π) (even in azimuth)."""
    mu_o = np.clip(np.asarray(mu_o, float), 1e-6, 1.0)
    mu_i, weight = fuzz_quadrature(nodes)
    phi = (np.arange(azimuths) + 0.5) * math.pi / azimuths
    sin_i = np.sqrt(1.0 - mu_i ** 2)
    light = np.stack([sin_i[:, None] * np.cos(phi), sin_i[:, None] * np.sin(phi),
                      np.broadcast_to(mu_i[:, None], (nodes, azimuths))], axis=-1)
    view = np.stack([-np.sqrt(1.0 - mu_o ** 2), np.zeros_like(mu_o), mu_o], axis=-1)
    lobe = beckmann_reflection(light, view[..., None, None, :], slope) * (weight * mu_i)[:, None]
    # azimuth 0 is the far side here: the view leans toward −x
    far, near = (2.0 * math.pi / azimuths * lobe[..., part].sum(axis=(-2, -1))
                 for part in (slice(0, azimuths // 2), slice(azimuths // 2, None)))
    return far + near, 0.5 * (far - near)


def forward_lobe_table(slope: float = FUZZ_FORWARD_SLOPE,
                       points: int = FUZZ_FORWARD_POINTS) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The view angles θo (radians), even from 0 to π/2, and (a_m, b_m) there (:func:`forward_lobe_albedos`):
    the table the shader interpolates linearly in θo (``CL_FUZZ_FORWARD_ALBEDO``, ``CL_FUZZ_FORWARD_EXCESS``;
    b_m falls as sin θo to 0 at normal view, which √μo or μo would miss)."""
    angles = np.linspace(0.0, 0.5 * math.pi, points)
    return (angles, *forward_lobe_albedos(np.cos(angles), slope))


@functools.cache
def _shader_forward_lobe_table() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return forward_lobe_table()  # on first use, not at import: a few tens of milliseconds


def _forward_lobe_at(mu_o: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    angles, albedo, excess = _shader_forward_lobe_table()
    angle = np.arccos(np.clip(mu_o, 0.0, 1.0))
    return np.interp(angle, angles, albedo), np.interp(angle, angles, excess)


def fuzz_general_lobes(mu_o, albedo: float = 1.0, depth: float = 0.0, asymmetry: float = 0.0,
                       flatness: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """The general modes' weights (d, s) (…) at the view cosine ``mu_o`` (…) of the fuzz's diffuse lobe
    and of its forward lobe (module docstring): s = b / b_m held to [0, a / a_m], d = a − s a_m (≥ 0), with
    (a_m, b_m) interpolated linearly in θo from :func:`forward_lobe_table`, as the shader does;
    (:func:`fuzz_albedo_at_view`, 0) for an isotropic fuzz."""
    if asymmetry == 0.0:
        total = fuzz_albedo_at_view(mu_o, albedo, depth, flatness=flatness)
        return total, np.zeros_like(total)
    near, far = fuzz_albedo_sides_at_view(mu_o, albedo, depth, asymmetry, flatness)
    lobe_albedo, lobe_excess = _forward_lobe_at(np.clip(np.asarray(mu_o, float), 1e-6, 1.0))
    total = near + far
    with np.errstate(divide="ignore", invalid="ignore"):
        forward = np.where(lobe_excess > 0.0, 0.5 * (far - near) / np.where(lobe_excess > 0.0, lobe_excess, 1.0), 0.0)
    forward = np.clip(forward, 0.0, total / lobe_albedo)
    return np.maximum(total - forward * lobe_albedo, 0.0), forward


def hemispherical_transmittance(depth: float, flatness: float = 0.0, nodes: int = FUZZ_ALBEDO_NODES) -> float:
    """The share of light from a uniform sky that crosses a fuzz of optical depth ``depth`` one way:
    ∫₀¹ 2 μ exp(−depth s(μ)/μ) dμ (= 2 E₃(depth), the exponential integral, for no ``flatness``;
    s: :func:`fuzz_projected_area`), by ``nodes``-point Gauss–Legendre; 1 for ``depth`` 0.  The
    general mode shades the yarn's closures by it times exp(−depth s(μo)/μo), the view's own path."""
    if depth <= 0.0:
        return 1.0
    mu, weight = fuzz_quadrature(nodes)
    return float(np.sum(2.0 * weight * mu * np.exp(-depth * fuzz_projected_area(mu, flatness) / mu)))


__all__ = ["FUZZ_ALBEDO_AZIMUTHS", "FUZZ_ALBEDO_NODES", "FUZZ_FORWARD_POINTS", "FUZZ_FORWARD_SLOPE",
           "forward_lobe_albedos", "forward_lobe_table", "fuzz_albedo_at_view", "fuzz_albedo_sides_at_view",
           "fuzz_brdf", "fuzz_general_lobes", "fuzz_phase", "fuzz_projected_area", "fuzz_quadrature",
           "fuzz_transmittance", "hemispherical_transmittance", "lommel_seeliger", "lommel_seeliger_albedo"]
