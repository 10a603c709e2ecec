"""The unscattered (ballistic) light through a yarn, exactly, instead of binned.

Light that crosses the yarn without scattering is deterministic: it refracts in,
is attenuated along straight chords by Beer–Lambert (extinction μt = μs + μa:
whatever scatters leaves the beam and is in the scattered table), is partly
reflected inside at every hit of the boundary, and refracts out.  Binned into the
tables' direction cells it is a caustic that no grid resolves (the red yarn's
retro-reflection when lit from the front and its straight-through beam when lit
from behind), so the transport keeps it out of ρ (it tallies it separately,
``YarnTransport.unscattered_fraction``) and this module gives it in closed form.

Geometry (yarn frame of the exit point: x = axis, y = n × t, z = outward normal;
the circular cross-section is the y–z plane, its centre at −R z).  Follow the
light backwards from the exit direction ω_o: it refracts in at the exit point,
crosses a chord, and at each later hit of the boundary either leaves (the point
where the light came in) or is reflected on.  On a circle every chord meets the
boundary at the same angle, so with θ the refraction angle of ω_o:

* every hit has the same Fresnel reflectance F = F(cos θ_o) (the same from both
  sides), so the path with k internal reflections carries
  ``(1 − F)² F^k`` of the radiance;
* every chord has the same length, ``2 R cos θ_t / (1 − u_x²)`` with u the
  refracted direction (cos θ_t = |u_z|), so that path runs ``(k + 1)`` chords;
* the axial direction cosine is kept: ω_i · x = −ω_o · x (the fibre's specular
  cone).

As a BRDF of the exit point, in the tables' convention (L_o = ρ E⊥, 1/sr)::

    ρ_u(ω_i, ω_o) = Σ_k (1 − F)² F^k A((k + 1) ℓ_c) δ(ω_i − ω_i^(k)(ω_o))

with A(ℓ) = e^{−μt ℓ} the attenuation along a path of length ℓ (radiance divided
by n² is invariant along a refracted ray, and the light leaves into the medium
it came from).  A renderer needs a finite width: :func:`unscattered_rho` spreads
each delta over a normalised von Mises–Fisher cone (the cap of a real light),
which keeps its energy.

The radiance factor is linear in the spectrum and F does not depend on the
wavelength (one boundary index, as in the transport), so its colour is
``(1 − F)² F^k · A_rgb(ℓ)``: the tables store A_rgb as a function of ℓ / R
(:func:`attenuation_lengths`, the ``unscattered.exr`` table of
docs/table-spec.md) and the shader forms the rest, exactly as here.
"""

from __future__ import annotations

import numpy as np

from precompute.errors import ParameterError

#: Unscattered paths followed per exit direction: k = 0 … ORDERS − 1 internal reflections.
#: F ≤ 0.1 up to θ_o ≈ 70° for cotton's index, so the fifth path carries < 10⁻⁴ of the first there.
ORDERS = 4
#: Samples of the attenuation table over ℓ / R ∈ [0, 2 · ORDERS] (a chord is at most 2 R).
ATTENUATION_SAMPLES = 257
MAX_LENGTH_OVER_RADIUS = 2.0 * ORDERS
#: σ of :func:`cone_kernel` in the sun mode of the yarn material, radians: the cap of a real sun
#: (0.27° radius) blurred to what a measurement's pixels resolve.  The material sets the shader's
#: ``UnscatteredSpread`` to it.
SUN_MODE_SPREAD_RAD = 0.05
#: The cone of :func:`cone_kernel` is zero where κ (1 − cos γ) exceeds this: e^{−14} ≈ 8·10⁻⁷ of its
#: peak.  The shader then skips the path's attenuation lookup, most of the sun mode's cost for it.
CONE_CUTOFF = 14.0


def _fresnel(cos_i: np.ndarray, eta: float) -> np.ndarray:
    """Unpolarised Fresnel reflectance from outside (index 1) into index ``eta`` at cosine ``cos_i``
    (0 for ``eta`` = 1, where the formula is 0/0 at grazing)."""
    c = np.clip(cos_i, 0.0, 1.0)
    if eta == 1.0:
        return np.zeros_like(c)
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - (1.0 - c * c) / (eta * eta)))
    rs = (c - eta * cos_t) / (c + eta * cos_t)
    rp = (eta * c - cos_t) / (eta * c + cos_t)
    return 0.5 * (rs * rs + rp * rp)


def unscattered_paths(wo, index: float, orders: int = ORDERS):
    """The unscattered paths that leave a yarn surface point toward ``wo``.

    Parameters
    ----------
    wo
        Exit directions (…, 3), unit, yarn frame, z ≥ 0.
    index
        Boundary index of the yarn (host), outside index 1; 1 for a yarn of fibres in air, whose
        unscattered light crosses it straight, with no reflection inside (one path of weight 1).
    orders
        Paths per direction: k = 0 … orders − 1 internal reflections.

    Returns
    -------
    wi : (…, orders, 3)
        Unit direction toward the light whose unscattered path k exits toward ``wo``.
    fresnel_factor : (…, orders)
        ``(1 − F)² F^k``, dimensionless.
    length_over_radius : (…, orders)
        The path's length inside the yarn divided by the yarn radius.
    """
    if not np.isfinite(index) or index < 1.0:
        raise ParameterError("index", index, "a boundary index ≥ 1")
    if int(orders) < 1:
        raise ParameterError("orders", orders, "an integer ≥ 1")
    wo = np.asarray(wo, float)
    cos_o = np.clip(wo[..., 2], 0.0, 1.0)
    reflectance = _fresnel(cos_o, index)
    # Follow the light backwards (lengths in units of R; section centre at −z): refracted in at
    # the exit point, then from hit to hit of the circle.
    u = np.empty(wo.shape)
    u[..., :2] = -wo[..., :2] / index
    u[..., 2] = -np.sqrt(np.maximum(0.0, 1.0 - np.sum(u[..., :2] ** 2, axis=-1)))
    position = np.zeros(wo.shape)  # relative to the section's centre: y, z; x along the axis
    position[..., 2] = 1.0
    wi = np.empty(wo.shape[:-1] + (orders, 3))
    length = np.empty(wo.shape[:-1] + (orders,))
    travelled = np.zeros(wo.shape[:-1])
    for k in range(orders):
        # far intersection of the line p + s u with the circle y² + z² = 1
        a = np.maximum(u[..., 1] ** 2 + u[..., 2] ** 2, 1e-300)
        b = position[..., 1] * u[..., 1] + position[..., 2] * u[..., 2]
        c = position[..., 1] ** 2 + position[..., 2] ** 2 - 1.0
        step = (-b + np.sqrt(np.maximum(b * b - a * c, 0.0))) / a
        position = position + step[..., None] * u
        travelled = travelled + step
        normal = position.copy()
        normal[..., 0] = 0.0
        normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
        cos_hit = np.sum(u * normal, axis=-1)
        # leaving here: the direction toward the light
        tangential = (u - cos_hit[..., None] * normal) * index
        out_normal = np.sqrt(np.maximum(0.0, 1.0 - np.sum(tangential**2, axis=-1)))
        wi[..., k, :] = tangential + out_normal[..., None] * normal
        length[..., k] = travelled
        u = u - 2.0 * cos_hit[..., None] * normal
    k = np.arange(orders)
    fresnel_factor = (1.0 - reflectance[..., None]) ** 2 * reflectance[..., None] ** k
    return wi, fresnel_factor, length


def attenuation_lengths(samples: int = ATTENUATION_SAMPLES) -> np.ndarray:
    """Path lengths ℓ / R (dimensionless) at which the attenuation table is stored: uniform over
    [0, MAX_LENGTH_OVER_RADIUS], the first and last at the table's first and last pixel centres."""
    return np.linspace(0.0, MAX_LENGTH_OVER_RADIUS, samples)


def attenuation(mu_t_per_mm, radius_mm: float, length_over_radius) -> np.ndarray:
    """Beer–Lambert transmittance ``exp(−μt R ℓ/R)`` of the unscattered light, (…, L).

    ``mu_t_per_mm`` (L,) extinction μs + μa in 1/mm, ``radius_mm`` the yarn radius in mm,
    ``length_over_radius`` (…) path lengths in units of the radius.
    """
    mu_t = np.asarray(mu_t_per_mm, float)
    length = np.asarray(length_over_radius, float)[..., None] * float(radius_mm)
    return np.exp(-mu_t * length)


def cone_kernel(cos_angle, spread_rad: float) -> np.ndarray:
    """The normalised cone that a delta direction is spread over, in 1/sr: a von Mises–Fisher
    density of concentration κ = 1/σ² (σ = ``spread_rad``, its angular standard deviation per axis
    for small σ), ``κ e^{κ(cos γ − 1)} / (2π (1 − e^{−2κ}))``, integrating to 1 over the sphere
    (to 1 − e^{−CONE_CUTOFF} with its tail cut off at ``CONE_CUTOFF``)."""
    if not spread_rad > 0.0:
        raise ParameterError("spread_rad", spread_rad, "an angle > 0 rad")
    kappa = 1.0 / (spread_rad * spread_rad)
    exponent = kappa * (np.clip(np.asarray(cos_angle, float), -1.0, 1.0) - 1.0)
    cone = kappa * np.exp(exponent) / (2.0 * np.pi * -np.expm1(-2.0 * kappa))
    return np.where(exponent < -CONE_CUTOFF, 0.0, cone)


def unscattered_cone_weights(wi, wo, index: float, spread_rad: float, orders: int = ORDERS):
    """Each unscattered path's weight toward (``wi``, ``wo``) and its length: ``(1 − F)² F^k`` times
    :func:`cone_kernel` about its exact direction (…, K), 1/sr, and ℓ / R (…, K).  ρ_u is the sum
    of weight × attenuation at that length (:func:`unscattered_rho`): linear in the attenuation."""
    wi, wo = np.broadcast_arrays(np.asarray(wi, float), np.asarray(wo, float))
    directions, fresnel_factor, length = unscattered_paths(wo, index, orders)
    cos_angle = np.sum(directions * wi[..., None, :], axis=-1)
    return fresnel_factor * cone_kernel(cos_angle, spread_rad), length


def unscattered_rho(wi, wo, index: float, attenuation_of_length, spread_rad: float,
                    orders: int = ORDERS) -> np.ndarray:
    """ρ_u(ω_i, ω_o) (…, C) in 1/sr, each unscattered path's delta spread by :func:`cone_kernel`.

    ``wi`` (…, 3) toward the light and ``wo`` (…, 3) toward the viewer, unit, yarn frame;
    ``attenuation_of_length`` maps ℓ / R (…, K) to the transmittance (…, K, C) — :func:`attenuation`
    of a medium, or the RGB table as the shader reads it
    (:func:`precompute.tables.layout.interpolate_attenuation`).
    """
    weight, length = unscattered_cone_weights(wi, wo, index, spread_rad, orders)
    return np.einsum("...k,...kc->...c", weight, attenuation_of_length(length))


def unscattered_radiance_factor(wo, index: float, attenuation_of_length, orders: int = ORDERS) -> np.ndarray:
    """∫ ρ_u dω_i (…, C): the exit radiance toward ``wo`` under unit radiance from every direction,
    dimensionless.  By reciprocity also the share of the flux entering at a point from ``wo``
    (toward the light) that crosses the yarn unscattered (``YarnTransport.unscattered_fraction``)."""
    _, fresnel_factor, length = unscattered_paths(np.asarray(wo, float), index, orders)
    return np.einsum("...k,...kc->...c", fresnel_factor, attenuation_of_length(length))
