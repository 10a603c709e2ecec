"""From a rendered view to the cloth's BRDF (paper §4 steps 4–5), physically calibrated.

Pure numpy, no Blender.  A view is an orthographic render of the patch (``framing``): N × N
pixels of linear scene-referred RGB with film alpha.  The rig's scene holds nothing but the sample
in front of a transparent, black background, so alpha > 0 marks exactly the pixels where cloth
is seen (the object mask) and RGB is premultiplied by that coverage: a pixel half on a yarn and
half on a gap between yarns holds half the yarn's radiance, as a detector would.

Calibration.  A pixel's value L_p is the mean radiance (W m⁻² sr⁻¹) of its beam, whose
cross-section perpendicular to the view is a_p = (P/N)² cos θv (``framing``).  The radiant
intensity of the patch toward the camera is I = Σ_p L_p a_p.  For a patch of area A = P² with
macroscopic BRDF f under a sun of irradiance E (on a plane facing it) at incidence θi,
I = f E cos θi · A cos θv, because the patch's projected area toward the camera is A cos θv.
The paper's step 5 divides the pixel sum by cos θv; with the pixel cross-section as weight it
gives S = Σ_p L_p a_p / cos θv = f E cos θi A, so

    f(θi, θv) = S / (E cos θi · A) = Σ_p L_p a_p / (E cos θi · A cos θv)      [1/sr].

Gaps between yarns are part of the cloth's area and contribute no light, as in a measurement of
real cloth.  With this framing every pixel covers (P/N)² of cloth at every view, so f is also the
mean of the N² pixel values over E cos θi.

The paper's normalisation (§4 step 5) scales a model's curves by one coefficient k that makes its
value at normal incidence and normal view equal the measurement's there; one coefficient for all
three channels (k = ΣRGB measured / ΣRGB model at θi = θv = 0), so that colour ratios survive.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .framing import ParameterError, pixel_cross_section_mm2


@dataclass
class ViewMeasurement:
    """One view of a sweep.

    Attributes
    ----------
    theta_i_deg, theta_v_deg
        Incidence and signed view zenith, degrees (negative θv: the light's side).
    rgb_sum
        Σ of linear RGB over cloth pixels (pixel values in W m⁻² sr⁻¹, summed).
    cloth_pixels
        Number of pixels where cloth is seen (alpha > 0), of ``resolution``².
    coverage
        Fraction of the patch's projection covered by yarn: Σ alpha / N².
    sum_over_cos_rgb
        The paper's step-5 quantity S = Σ_p L_p a_p / cos θv, W m⁻² sr⁻¹ · mm².
    brdf_rgb
        Calibrated cloth BRDF f = S / (E cos θi A), 1/sr.
    paper_normalised_rgb
        ``brdf_rgb`` times the paper's normalisation coefficient, 1/sr; empty without a measurement.
    """

    theta_i_deg: float
    theta_v_deg: float
    rgb_sum: list[float]
    cloth_pixels: int
    coverage: float
    sum_over_cos_rgb: list[float]
    brdf_rgb: list[float]
    paper_normalised_rgb: list[float] = field(default_factory=list)


def calibrated_brdf(sum_over_cos_rgb, theta_i_deg: float, sun_irradiance: float, patch_area_mm2: float) -> np.ndarray:
    """f = S / (E cos θi A): the cloth BRDF (1/sr) from the paper's step-5 sum S (W m⁻² sr⁻¹ · mm²),
    the sun's irradiance E (W/m² on a plane facing it) at incidence θi (degrees) and the patch area A (mm²)."""
    return np.asarray(sum_over_cos_rgb, float) / (sun_irradiance * math.cos(math.radians(theta_i_deg)) * patch_area_mm2)


def measure_view(pixels: np.ndarray, *, theta_i_deg: float, theta_v_deg: float, patch_mm: float,
                 sun_irradiance: float) -> ViewMeasurement:
    """Sum the cloth pixels of one view (N, N, 4) and calibrate them (module docstring).  A view in
    which no pixel shows cloth measures nothing: ParameterError naming the resolution."""
    pixels = np.asarray(pixels)
    if pixels.ndim != 3 or pixels.shape[2] != 4 or pixels.shape[0] != pixels.shape[1]:
        raise ParameterError("pixels", pixels.shape, "an (N, N, 4) RGBA image of the square patch")
    resolution = pixels.shape[0]
    alpha = pixels[..., 3].astype(np.float64)
    cloth = alpha > 0.0
    if not cloth.any():
        raise ParameterError("resolution", resolution, f"a resolution at which the cloth covers pixels in every "
                             f"view (at θi = {theta_i_deg:g}°, θv = {theta_v_deg:g}° none of the {resolution}² "
                             "pixels shows cloth: the view would measure nothing)")
    rgb_sum = pixels[..., :3][cloth].astype(np.float64).sum(axis=0)
    cross_section = pixel_cross_section_mm2(patch_mm, resolution, theta_v_deg)
    sum_over_cos = rgb_sum * cross_section / math.cos(math.radians(theta_v_deg))
    brdf = calibrated_brdf(sum_over_cos, theta_i_deg, sun_irradiance, patch_mm**2)
    return ViewMeasurement(
        theta_i_deg=float(theta_i_deg),
        theta_v_deg=float(theta_v_deg),
        rgb_sum=rgb_sum.tolist(),
        cloth_pixels=int(cloth.sum()),
        coverage=float(alpha.sum() / resolution**2),
        sum_over_cos_rgb=sum_over_cos.tolist(),
        brdf_rgb=brdf.tolist(),
    )


def mean_over_turns(turns) -> list[ViewMeasurement]:
    """Per view, the mean of its measurements at each turn of the sample about its normal
    (``turns``: one list of views per turn, the same views in the same order): the sample averaged
    over its azimuth, as an instrument that measures an isotropic BRDF reports it.  Every quantity
    is the mean of the turns' (``cloth_pixels`` rounded to a whole number); a single turn's views are
    returned as they are."""
    turns = [list(views) for views in turns]
    if not turns:
        raise ParameterError("turns", turns, "the views of at least one turn")
    if len(turns) == 1:
        return turns[0]
    angles = [(v.theta_i_deg, v.theta_v_deg) for v in turns[0]]
    if any([(v.theta_i_deg, v.theta_v_deg) for v in views] != angles for views in turns):
        raise ParameterError("turns", [len(views) for views in turns], "the same views at every turn")
    averaged = []
    for views in zip(*turns):
        def mean(name: str) -> list[float]:
            return np.mean([getattr(v, name) for v in views], axis=0).tolist()

        averaged.append(ViewMeasurement(
            theta_i_deg=views[0].theta_i_deg, theta_v_deg=views[0].theta_v_deg, rgb_sum=mean("rgb_sum"),
            cloth_pixels=int(round(float(np.mean([v.cloth_pixels for v in views])))),
            coverage=float(np.mean([v.coverage for v in views])), sum_over_cos_rgb=mean("sum_over_cos_rgb"),
            brdf_rgb=mean("brdf_rgb")))
    return averaged


def find_view(views, theta_i_deg: float, theta_v_deg: float):
    """The measurement at (θi, θv) in ``views``, or None."""
    return next((v for v in views if v.theta_i_deg == theta_i_deg and v.theta_v_deg == theta_v_deg), None)


def paper_normalisation_factor(model_rgb, measured_rgb) -> float:
    """The paper's coefficient k = ΣRGB measured / ΣRGB model at normal incidence and view."""
    model = float(np.sum(model_rgb))
    if not model > 0.0:
        raise ParameterError("model_rgb", list(model_rgb), "a positive sum at normal incidence and view")
    return float(np.sum(measured_rgb)) / model


def apply_paper_normalisation(views, factor: float) -> None:
    """Fill every view's ``paper_normalised_rgb`` with ``factor`` × its calibrated BRDF."""
    for view in views:
        view.paper_normalised_rgb = [factor * c for c in view.brdf_rgb]


def channel_ratios(rgb) -> dict[str, float]:
    """The paper's Table 1 colour check: B/R and G/R of an RGB triple (NaN when R is 0)."""
    r, g, b = (float(c) for c in rgb)
    return {"B/R": b / r if r > 0 else math.nan, "G/R": g / r if r > 0 else math.nan}
