"""Spectral ratios → Blender scene-linear RGB (linear Rec.709 primaries, D65 white).

A baked table holds ratios (ρ in 1/sr, albedos), not light, so turning a
spectrum ρ(λ) into RGB needs a stated illuminant.  The convention here:

1. The spectrum, known at the simulation wavelengths, is taken as piecewise
   linear between them and constant beyond the first and last one, and
   integrated at 1 nm against the colour matching functions x̄ȳz̄ of the
   observer (default CIE 1931 2°) weighted by the illuminant's spectral power
   S(λ) (default CIE D65), normalised so that the illuminant itself has Y = 1::

       XYZ = ∫ ρ(λ) S(λ) x̄ȳz̄(λ) dλ / ∫ S(λ) ȳ(λ) dλ

2. XYZ → linear Rec.709 RGB ("ITU-R BT.709" in colour-science) with no
   chromatic adaptation: D65 is Rec.709's own white, and Blender's default
   scene-linear space is linear Rec.709.

3. Each channel is divided by the RGB the same steps give a spectrally flat
   ρ = 1, so a flat, non-absorbing yarn bakes to R = G = B exactly (white stays
   white; a white Blender sun on the table then shows the colour the yarn has
   in daylight).  For D65 these factors are within 3·10⁻⁴ of 1: they only absorb
   the difference between the tabulated D65 spectrum and Rec.709's nominal
   white point (x, y) = (0.3127, 0.3290), so the result is plain colorimetry.
   For another illuminant they are a white balance to that illuminant (a von
   Kries scaling in Rec.709 RGB): the illuminant changes how the spectrum's
   shape is weighted, never the colour of white.

The 10° and CIE 2015 observers are accepted, but Rec.709's matrix is defined
for the 1931 2° observer, so with them RGB is an approximation.

Spectra outside Rec.709's gamut (a saturated red dye reflects almost nothing
but long wavelengths) get a negative channel; :func:`clip_to_gamut` sets it
to 0 for the tables (a renderer cannot emit negative light) and reports how
much was clipped.  The paper's Table 1 compares B/R and G/R of the cloth at
normal incidence and view (:func:`channel_ratios`; real red cotton: 0.08 and
0.011).
"""

from __future__ import annotations

import functools

import colour
import numpy as np

from precompute.errors import ParameterError

DEFAULT_OBSERVER = "CIE 1931 2 Degree Standard Observer"
DEFAULT_ILLUMINANT = "D65"
RGB_SPACE = "ITU-R BT.709"
#: Observers whose colour matching functions are CIE XYZ ones (the others in colour-science are
#: cone fundamentals or RGB matching functions, which the XYZ → RGB matrix does not apply to).
OBSERVERS = (
    "CIE 1931 2 Degree Standard Observer",
    "CIE 1964 10 Degree Standard Observer",
    "CIE 2015 2 Degree Standard Observer",
    "CIE 2015 10 Degree Standard Observer",
)
#: Integration step of the colour matching functions, nm.
INTEGRATION_STEP_NM = 1.0
#: Wavelength range of the CIE 1931 colour matching functions, nm; spectra must lie inside it.
VISIBLE_RANGE_NM = (360.0, 830.0)


def illuminant_names() -> list[str]:
    """Names of the illuminants :func:`spectral_weights` accepts (colour-science's CIE and ISO set)."""
    return sorted(colour.SDS_ILLUMINANTS)


def _check_wavelengths(wavelengths_nm) -> np.ndarray:
    wavelengths = np.asarray(wavelengths_nm, float)
    if wavelengths.ndim != 1 or wavelengths.size < 2 or not np.all(np.isfinite(wavelengths)):
        raise ParameterError("wavelengths_nm", wavelengths_nm, "at least two finite wavelengths, nm")
    if np.any(np.diff(wavelengths) <= 0):
        raise ParameterError("wavelengths_nm", wavelengths_nm, "strictly increasing")
    low, high = VISIBLE_RANGE_NM
    if wavelengths[0] < low or wavelengths[-1] > high:
        raise ParameterError("wavelengths_nm", wavelengths_nm, f"inside [{low:g}, {high:g}] nm")
    return wavelengths


@functools.lru_cache(maxsize=16)
def _weighted_cmfs(illuminant: str, observer: str) -> tuple[np.ndarray, np.ndarray]:
    """1 nm wavelengths and x̄ȳz̄·S / ∫S ȳ dλ on them (Y of the illuminant = 1)."""
    if illuminant not in colour.SDS_ILLUMINANTS:
        raise ParameterError("bake.illuminant", illuminant, f"one of {illuminant_names()}")
    if observer not in OBSERVERS:
        raise ParameterError("bake.observer", observer, f"one of {list(OBSERVERS)}")
    shape = colour.SpectralShape(*VISIBLE_RANGE_NM, INTEGRATION_STEP_NM)
    cmfs = colour.MSDS_CMFS[observer].copy().align(shape)
    power = colour.SDS_ILLUMINANTS[illuminant].copy().align(shape)
    weighted = cmfs.values * power.values[:, None]
    weighted /= np.sum(weighted[:, 1]) * INTEGRATION_STEP_NM
    return np.asarray(shape.wavelengths, float), weighted * INTEGRATION_STEP_NM


def spectral_to_xyz_weights(
    wavelengths_nm, illuminant: str = DEFAULT_ILLUMINANT, observer: str = DEFAULT_OBSERVER
) -> np.ndarray:
    """Matrix (L, 3) such that ``XYZ = ρ @ W`` (step 1 of the module's convention), Y(flat 1) = 1."""
    wavelengths = _check_wavelengths(wavelengths_nm)
    fine, weighted = _weighted_cmfs(illuminant, observer)
    # Hat functions of piecewise-linear interpolation (constant past the ends): column l is the
    # spectrum that is 1 at wavelength l and 0 at the others.
    hats = np.stack([np.interp(fine, wavelengths, unit) for unit in np.eye(wavelengths.size)], axis=1)
    return hats.T @ weighted


def white_balance_factors(
    wavelengths_nm, illuminant: str = DEFAULT_ILLUMINANT, observer: str = DEFAULT_OBSERVER
) -> np.ndarray:
    """(3,) factors of step 3: 1 / (linear Rec.709 RGB of a flat ρ = 1) before balancing."""
    to_rgb = np.asarray(colour.RGB_COLOURSPACES[RGB_SPACE].matrix_XYZ_to_RGB)
    flat_rgb = to_rgb @ spectral_to_xyz_weights(wavelengths_nm, illuminant, observer).sum(axis=0)
    return 1.0 / flat_rgb


def spectral_weights(
    wavelengths_nm, illuminant: str = DEFAULT_ILLUMINANT, observer: str = DEFAULT_OBSERVER
) -> np.ndarray:
    """Matrix W (L, 3) such that ``rgb = ρ @ W`` under the convention of this module."""
    to_rgb = np.asarray(colour.RGB_COLOURSPACES[RGB_SPACE].matrix_XYZ_to_RGB)
    rgb_weights = spectral_to_xyz_weights(wavelengths_nm, illuminant, observer) @ to_rgb.T
    return rgb_weights * white_balance_factors(wavelengths_nm, illuminant, observer)[None, :]


def spectral_to_rgb(
    values, wavelengths_nm, illuminant: str = DEFAULT_ILLUMINANT, observer: str = DEFAULT_OBSERVER
) -> np.ndarray:
    """Linear Rec.709 RGB (…, 3) of spectral ratios (…, L) sampled at ``wavelengths_nm`` (nm).

    The unit is the spectrum's (1/sr for ρ, none for an albedo).  Out-of-gamut
    spectra give negative channels; see :func:`clip_to_gamut`.
    """
    values = np.asarray(values, float)
    weights = spectral_weights(wavelengths_nm, illuminant, observer)
    if values.shape[-1] != weights.shape[0]:
        raise ParameterError("values", values.shape, f"last axis of {weights.shape[0]} wavelengths")
    return values @ weights


def spectral_stderr_to_rgb(
    stderr, wavelengths_nm, illuminant: str = DEFAULT_ILLUMINANT, observer: str = DEFAULT_OBSERVER
) -> np.ndarray:
    """An upper bound (…, 3) on the standard error of :func:`spectral_to_rgb` from per-wavelength ones.

    Every wavelength is estimated from the same paths, so their errors are
    correlated; Σ |W| σ (the errors adding in phase) bounds the RGB error for
    any correlation.
    """
    return np.asarray(stderr, float) @ np.abs(spectral_weights(wavelengths_nm, illuminant, observer))


def clip_to_gamut(rgb) -> tuple[np.ndarray, float]:
    """RGB with negative channels set to 0, and the largest clipped amount relative to the largest channel."""
    rgb = np.asarray(rgb, float)
    clipped = np.maximum(rgb, 0.0)
    scale = float(np.max(np.abs(rgb))) if rgb.size else 0.0
    return clipped, (float(np.max(clipped - rgb)) / scale if scale > 0 else 0.0)


def blue_red_ratio(rgb) -> float:
    """B/R of one RGB triple (the paper's Table 1; NaN when R = 0)."""
    r, _, b = (float(c) for c in np.asarray(rgb, float).reshape(3))
    return b / r if r != 0 else float("nan")


def green_red_ratio(rgb) -> float:
    """G/R of one RGB triple (the paper's Table 1; NaN when R = 0)."""
    r, g, _ = (float(c) for c in np.asarray(rgb, float).reshape(3))
    return g / r if r != 0 else float("nan")


def channel_ratios(rgb) -> dict[str, float]:
    """``{"B/R": …, "G/R": …}`` of one RGB triple: the paper's Table 1 quantities."""
    return {"B/R": blue_red_ratio(rgb), "G/R": green_red_ratio(rgb)}


def srgb_to_linear_rgb(srgb) -> np.ndarray:
    """sRGB-encoded values in [0, 1] (…, 3) → linear Rec.709 RGB: the colour a picker or a ``#rrggbb``
    names, as Blender's scene-linear space holds it (IEC 61966-2-1: the same primaries and white)."""
    srgb = np.asarray(srgb, float)
    if srgb.shape[-1:] != (3,) or not np.all(np.isfinite(srgb)) or np.any(srgb < 0) or np.any(srgb > 1):
        raise ParameterError("sRGB colour", srgb.tolist(), "three values in [0, 1]")
    return colour.cctf_decoding(srgb, function="sRGB")


def linear_rgb_to_lab(rgb) -> np.ndarray:
    """Linear Rec.709 RGB (…, 3), white (1, 1, 1) → CIELAB (…, 3) under D65, CIE 1931 2° (L* of white 100)."""
    space = colour.RGB_COLOURSPACES[RGB_SPACE]
    xyz = np.asarray(rgb, float) @ np.asarray(space.matrix_RGB_to_XYZ).T
    return colour.XYZ_to_Lab(xyz, space.whitepoint)


def delta_e_2000(lab_a, lab_b) -> np.ndarray:
    """CIEDE2000 colour difference (Sharma, Wu & Dalal 2005) of two CIELAB colours (…, 3): about 1 is
    the smallest difference seen side by side, 2 a close match."""
    return colour.delta_E(np.asarray(lab_a, float), np.asarray(lab_b, float), method="CIE 2000")


def linear_to_srgb(rgb) -> np.ndarray:
    """Linear Rec.709 RGB (…, 3) → sRGB-encoded values, clipped to [0, 1] (the inverse of
    :func:`srgb_to_linear_rgb` inside the gamut)."""
    return colour.cctf_encoding(np.clip(np.asarray(rgb, float), 0.0, 1.0), function="sRGB")
