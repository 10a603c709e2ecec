"""What Cycles' hair BSDF needs to shade a medium's flyaway fibres: their absorption, index and radius.

A flyaway fibre is one fibre of the yarn, dyed as the yarn is: its material absorbs as the
medium's fibre material does, μₐ(λ) = the material's grey absorption (the fibres' own, or the
host's in the paper's yarn of one host, which is the fibre material) + the dye's
(:func:`precompute.optics.dye.dye_absorption_coefficient`: the dye's weight percent of the fibre
at the fibre's density).  Scattering inside one fibre is left out: the medium's scatterers (150 nm
particles, µm voids) give an optical depth of a few tenths across a 15 µm fibre at most.

Cycles' Principled Hair BSDF (Chiang et al. 2016), parametrised by absorption coefficient σ,
attenuates a path through the fibre by exp(−σ · 2 cos γₜ / cos θₜ) (Cycles'
``bsdf_principled_hair_chiang.h``, as pbrt-v3's hair): 2 cos γₜ is the chord of a circle of radius
1, so σ is per fibre radius, σ = μₐ · r.  Per RGB channel: σ = −ln(T_rgb) / 2, where T_rgb is the
linear Rec.709 colour (:mod:`precompute.tables.color`, D65) of the spectral transmittance
exp(−μₐ(λ) · 2r) straight through the fibre, so that a fibre seen against white light passes the
colour its spectrum has (averaging the spectrum, not σ, which the channels' wide bands would
bias towards the least absorbed wavelengths).
"""

from __future__ import annotations

import numpy as np

from precompute.optics.dye import dye_absorption_coefficient
from precompute.tables.color import spectral_to_rgb

#: Radius of a cotton fibre, mm, when the medium names no fibres: cotton fibres are 12–20 µm
#: across (the fibre_cotton preset's 15 µm).
COTTON_FIBRE_RADIUS_MM = 0.0075
#: The least transmittance a channel is given, so that σ stays finite for a channel the dye
#: absorbs completely (exp(−2σ) = 10⁻⁶: σ ≈ 6.9, black).
LEAST_TRANSMITTANCE = 1e-6


def fibre_radius_mm(medium) -> float:
    """Radius of the medium's fibres, mm: its ``[fibres]`` diameter, else a cotton fibre's."""
    return COTTON_FIBRE_RADIUS_MM if medium.fibres is None else medium.fibres.diameter_um / 2000.0


def fibre_absorption_per_mm(medium) -> np.ndarray:
    """Absorption coefficient of the medium's fibre material at its wavelengths, (L,) 1/mm."""
    wavelengths = medium.wavelengths.values
    grey = medium.host.absorption_per_mm if medium.fibres is None else medium.fibres.absorption_per_mm
    dye = 0.0 if medium.dye is None else dye_absorption_coefficient(medium.dye, wavelengths)
    return grey + dye * np.ones_like(wavelengths)


def fibre_refractive_index(medium) -> float:
    """The fibre material's refractive index, its mean over the medium's wavelengths."""
    index = medium.host.refractive_index if medium.fibres is None else medium.fibres.refractive_index
    return float(np.mean(index.n))


def hair_absorption_coefficient(medium, radius_mm: float | None = None) -> np.ndarray:
    """(3,) Cycles' hair absorption coefficient σ (per fibre radius) of the medium's fibres of
    radius ``radius_mm`` (default :func:`fibre_radius_mm`): module docstring."""
    radius = fibre_radius_mm(medium) if radius_mm is None else radius_mm
    transmittance = np.exp(-fibre_absorption_per_mm(medium) * 2.0 * radius)
    rgb = np.clip(spectral_to_rgb(transmittance, medium.wavelengths.values), LEAST_TRANSMITTANCE, 1.0)
    return np.maximum(-np.log(rgb) / 2.0, 0.0)
