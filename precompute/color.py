"""Spectral → Blender scene-linear RGB (Rec.709 primaries, D65 white).

Convention: a spectral ratio ρ(λ) (a BRDF, an albedo) is seen under CIE
illuminant D65 by the CIE 1931 2° observer,

    XYZ = Σ ρ(λ) S_D65(λ) x̄ȳz̄(λ) / Σ S_D65(λ) ȳ(λ),

then taken to linear Rec.709 RGB and white-balanced per channel so that a
spectrally flat ρ = c gives exactly R = G = B = c (white stays white: the
per-channel factors are within 1 % of 1 and only absorb the difference
between the tabulated D65 spectrum on the simulation grid and Rec.709's
nominal D65 chromaticity).  Blender's scene-linear space is Rec.709 with D65
white, so a white sun on a baked table gives the colour the spectrum has in
daylight.  The spectral result is kept beside the RGB tables, so another
illuminant or observer is a recomputation, not a new simulation.
"""

from __future__ import annotations

import colour
import numpy as np

OBSERVER = "CIE 1931 2 Degree Standard Observer"
ILLUMINANT = "D65"
RGB_SPACE = "ITU-R BT.709"


def spectral_weights(wavelengths_nm) -> np.ndarray:
    """Matrix W (L, 3) such that ``rgb = ρ @ W`` under the convention of this module."""
    wavelengths_nm = np.asarray(wavelengths_nm, float)
    cmfs = colour.MSDS_CMFS[OBSERVER].copy()
    illuminant = colour.SDS_ILLUMINANTS[ILLUMINANT].copy()
    xyz_bar = np.stack([np.interp(wavelengths_nm, cmfs.wavelengths, cmfs.values[:, k]) for k in range(3)], axis=1)
    power = np.interp(wavelengths_nm, illuminant.wavelengths, illuminant.values)
    to_xyz = xyz_bar * power[:, None] / np.sum(power * xyz_bar[:, 1])
    to_rgb = to_xyz @ np.asarray(colour.RGB_COLOURSPACES[RGB_SPACE].matrix_XYZ_to_RGB).T
    white = to_rgb.sum(axis=0)
    return to_rgb / white[None, :]


def spectral_to_rgb(values, wavelengths_nm) -> np.ndarray:
    """Linear Rec.709 RGB (…, 3) of spectral ratios (…, L) on ``wavelengths_nm``.

    Saturated spectra (a dyed red reflects almost nothing but long wavelengths) lie outside
    the Rec.709 gamut and get a negative channel here; see :func:`clip_to_gamut`.
    """
    return np.asarray(values, float) @ spectral_weights(wavelengths_nm)


def clip_to_gamut(rgb) -> tuple[np.ndarray, float]:
    """Rec.709 RGB with negative channels set to 0 (a renderer cannot emit negative light), and
    the largest clipped amount relative to the largest channel, for reporting."""
    rgb = np.asarray(rgb, float)
    clipped = np.maximum(rgb, 0.0)
    scale = float(np.max(np.abs(rgb))) if rgb.size else 0.0
    return clipped, (float(np.max(clipped - rgb)) / scale if scale > 0 else 0.0)


def channel_ratios(rgb) -> dict[str, float]:
    """The paper's Table 1 quantities: B/R and G/R."""
    r, g, b = (float(c) for c in np.asarray(rgb, float)[:3])
    return {"B/R": b / r if r > 0 else float("nan"), "G/R": g / r if r > 0 else float("nan")}
