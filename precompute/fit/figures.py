"""The figures by which issue 43 judges a cloth against a measured fabric, from the two BRDFs alone.

Given a cloth's BRDF and a measurement's at the same views (the project's CSV, 1/sr, RGB; the views
split by :func:`precompute.fit.objective.split_views`), :func:`fabric_figures` gives:

* **relative RMS** on the plane of incidence (the fitted views) and on the held-out views (every
  other azimuth: 45°, 90°, 135° on the raw-data curves), each two ways: *pooled* over the three
  channels, ``RMS(model − measured) / RMS(measured)`` over every view and channel (the validation
  report's figure, :func:`precompute.fit.measured_data.relative_rms_error`), and *per channel*,
  each channel normalised on its own and combined as the fit's objective combines them
  (:func:`precompute.fit.objective.combined`);
* **backscatter**: model / measured per channel at the views toward the light where woven round
  yarns show their lit faces only (:data:`BACKSCATTER_VIEWS`);
* **off-specular colour**: B/R and G/R of model and measurement at the diffuse views of
  :func:`off_specular_views`, and their ratio model / measured per view;
* **lit from behind / from the front**: a forward model's swatches (luminance at normal view), when given.

:func:`band_ratios` picks from these the ratios issue 43 holds within a band (0.85–1.15): the
backscatter in the fabric's main channel and the off-specular B/R and G/R medians; and
:func:`band_penalty` is how far a cloth lies outside a band, which a fit may add to its objective
(``python -m clothlight.fit --hold-bands``).

No rendering here: the caller brings both BRDFs (``scripts/fabric_figures.py`` with the fit's
forward model).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from precompute.bounds import parse_pair
from precompute.errors import ParameterError
from precompute.fit.measured_data import relative_rms_error
from precompute.fit.objective import CHANNELS, TOLERANCE_DEG, Views, channel_relative_rms, combined

#: The backscatter views of issue 43, (θi, signed θv) in degrees, θv < 0 on the light's side.
BACKSCATTER_VIEWS = ((60.0, -60.0), (60.0, -40.0), (45.0, -60.0))
#: Off-specular views: θi up to this, degrees ...
OFF_SPECULAR_MAX_INCIDENCE_DEG = 45.0
#: ... |θv| and the angle from the mirror direction at least this, degrees.
OFF_SPECULAR_MIN_ANGLE_DEG = 20.0
#: Rec. 709 luminance weights of linear R, G, B (the swatches' back/front ratio).
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def in_plane(views: Views) -> np.ndarray:
    """(M,) mask of the views in the plane of incidence (the fit views, the normal view included)."""
    return np.asarray(views.fit, bool)


def off_specular_views(views: Views) -> np.ndarray:
    """(M,) mask of the off-specular views: in the plane of incidence and :func:`off_specular`."""
    return in_plane(views) & off_specular(views.angles_deg[:, 0], views.signed_view_deg)


def off_specular(theta_i_deg, signed_view_deg) -> np.ndarray:
    """(…) whether in-plane views at θi ``theta_i_deg`` and signed θv ``signed_view_deg`` (degrees, negative
    on the light's side) are off-specular: θi ≤ 45°, |θv| ≥ 20° and at least 20° from the mirror
    direction (θv = θi beyond the normal), where a cloth's colour is its diffuse colour, not its sheen's."""
    theta_i, signed = np.asarray(theta_i_deg, float), np.asarray(signed_view_deg, float)
    return ((theta_i <= OFF_SPECULAR_MAX_INCIDENCE_DEG + TOLERANCE_DEG)
            & (np.abs(signed) >= OFF_SPECULAR_MIN_ANGLE_DEG - TOLERANCE_DEG)
            & (np.abs(signed - theta_i) >= OFF_SPECULAR_MIN_ANGLE_DEG - TOLERANCE_DEG))


def view_index(views: Views, theta_i_deg: float, signed_view_deg: float) -> int | None:
    """The index of the in-plane view (θi, signed θv), or None when the measurement lacks it."""
    match = np.flatnonzero(in_plane(views) & (np.abs(views.angles_deg[:, 0] - theta_i_deg) <= TOLERANCE_DEG)
                           & (np.abs(views.signed_view_deg - signed_view_deg) <= TOLERANCE_DEG))
    return int(match[0]) if match.size else None


def relative_rms(model: np.ndarray, measured: np.ndarray, mask: np.ndarray) -> dict:
    """Relative RMS of ``model`` against ``measured`` (M, 3) on the views of ``mask``: ``pooled``
    over channels, ``per_channel`` combined as the fit does, and each channel's."""
    if not mask.any():
        return {"views": 0, "pooled": None, "per_channel": None}
    errors = channel_relative_rms(model[mask], measured[mask])
    return {"views": int(mask.sum()), "pooled": relative_rms_error(model[mask], measured[mask]),
            "per_channel": combined(errors), **{c: float(e) for c, e in zip(CHANNELS, errors)}}


def channel_ratios(rgb: np.ndarray) -> dict[str, np.ndarray]:
    """B/R and G/R of each row of ``rgb`` (M, 3); NaN where red is 0."""
    rgb = np.asarray(rgb, float)
    red = np.where(rgb[:, 0] > 0, rgb[:, 0], np.nan)
    return {"B/R": rgb[:, 2] / red, "G/R": rgb[:, 1] / red}


def main_channel(measured_rgb: np.ndarray) -> int:
    """The index of the measurement's brightest channel over all its views (a red fabric's R)."""
    return int(np.argmax(np.asarray(measured_rgb, float).sum(axis=0)))


def band_ratios(model: np.ndarray, measured: np.ndarray, views: Views) -> dict[str, float]:
    """The ratios model / measured that issue 43 holds within 0.85–1.15: the backscatter at each of
    :data:`BACKSCATTER_VIEWS` the measurement has, in its main channel (:func:`main_channel`), keyed
    ``"backscatter θi/θv"``; and the medians over the off-specular views of B/R and G/R, model over
    measured, keyed ``"B/R"`` and ``"G/R"`` (left out where red is 0 at every such view)."""
    model, measured = np.asarray(model, float), np.asarray(measured, float)
    channel = main_channel(measured)
    ratios = {}
    for theta_i, theta_v in BACKSCATTER_VIEWS:
        index = view_index(views, theta_i, theta_v)
        if index is not None and measured[index, channel] > 0:
            ratios[f"backscatter {theta_i:g}/{theta_v:g}"] = float(model[index, channel] / measured[index, channel])
    off = off_specular_views(views)
    if off.any():
        ours, theirs = channel_ratios(model[off]), channel_ratios(measured[off])
        for key in ("B/R", "G/R"):
            ratio = ours[key] / theirs[key]
            if np.isfinite(ratio).any():
                ratios[key] = float(np.nanmedian(ratio))
    return ratios


def parse_band(text: str | Sequence[float]) -> tuple[float, float]:
    """``"0.9,1.1"`` (or a pair) → (low, high), with 0 < low < 1 < high: the band a ratio model /
    measured is held within (``--hold-bands``).  ParameterError otherwise."""
    allowed = "LOW,HIGH with 0 < LOW < 1 < HIGH, e.g. 0.85,1.15 (issue 43's band)"
    low, high = parse_pair(text, "--hold-bands", allowed)
    if not 0.0 < low < 1.0 < high:
        raise ParameterError("--hold-bands", text, allowed)
    return low, high


def band_penalty(model: np.ndarray, measured: np.ndarray, views: Views, band: tuple[float, float]) -> float:
    """How far ``model`` lies outside ``band`` = (low, high) on :func:`band_ratios`: the RMS over the
    ratios r of max(0, ln(r / high), ln(low / r)), 0 when every ratio is within the band; a ratio
    that is not positive counts as ln 10⁶ out.  Same scale as the fit's ratio penalty
    (:meth:`precompute.fit.objective.Objective.ratio_penalty`)."""
    low, high = band
    excess = []
    for ratio in band_ratios(model, measured, views).values():
        if not ratio > 0:
            excess.append(math.log(1e6))
            continue
        excess.append(max(0.0, math.log(ratio / high), math.log(low / ratio)))
    return float(math.sqrt(np.mean(np.square(excess)))) if excess else 0.0


def fabric_figures(model: np.ndarray, measured: np.ndarray, views: Views, *,
                   swatches: np.ndarray | None = None) -> dict:
    """The figures of the module docstring; ``model`` and ``measured`` (M, 3) at ``views``' views,
    ``swatches`` (2, 3) the model lit from the front and from straight behind at normal view."""
    model, measured = np.asarray(model, float), np.asarray(measured, float)
    plane = in_plane(views)
    figures = {"plane_of_incidence": relative_rms(model, measured, plane),
               "held_out": relative_rms(model, measured, np.asarray(views.held_out, bool))}
    backscatter = []
    for theta_i, theta_v in BACKSCATTER_VIEWS:
        index = view_index(views, theta_i, theta_v)
        if index is not None:
            backscatter.append({"theta_i_deg": theta_i, "theta_v_deg": theta_v,
                                "measured": measured[index].tolist(),
                                "model_over_measured": (model[index] / measured[index]).tolist()})
    figures["backscatter"] = backscatter
    off = off_specular_views(views)
    colour = {"views": int(off.sum())}
    if off.any():
        ours, theirs = channel_ratios(model[off]), channel_ratios(measured[off])
        for key in ("B/R", "G/R"):
            ratio = ours[key] / theirs[key]
            colour[key] = {"model": [float(np.nanmin(ours[key])), float(np.nanmax(ours[key]))],
                           "measured": [float(np.nanmin(theirs[key])), float(np.nanmax(theirs[key]))],
                           "model_over_measured": [float(np.nanmin(ratio)), float(np.nanmedian(ratio)),
                                                   float(np.nanmax(ratio))]}
    figures["off_specular"] = colour
    if swatches is not None:
        front, back = (float(LUMINANCE @ np.asarray(s, float)) for s in swatches)
        figures["back_over_front"] = back / front if front > 0 else math.inf
    return figures


def diffuse_shortfall(model: np.ndarray, measured: np.ndarray, views: Views) -> np.ndarray:
    """(3,) the constant BRDF per channel (1/sr, ≥ 0) that, added to ``model``, brings it closest to
    ``measured`` (both (M, 3)) on the plane of incidence: a Lambertian reflector of albedo π c that the
    cloth lacks.  Each channel's relative RMS is a sum of squares over a fixed norm, so its least-squares
    constant is the mean of measured − model over the plane's views, floored at 0 (a cloth cannot
    subtract light).  A diagnostic of the model's shape, not a fitted term: where adding it brings the
    held-out views closer too, the fabric reflects light the model's layers do not send back
    (``scripts/fabric_figures.py --diffuse-shortfall``, docs/fitting.md)."""
    model, measured = np.asarray(model, float), np.asarray(measured, float)
    plane = in_plane(views)
    if not plane.any():
        raise ParameterError("views", "none in the plane of incidence", "a measurement with in-plane views")
    return np.maximum(0.0, (measured[plane] - model[plane]).mean(axis=0))


def figures_text(figures: dict, label: str) -> list[str]:
    """``figures`` (:func:`fabric_figures`) as lines of text, headed by ``label``."""
    lines = [f"{label}:"]
    for key, name in (("plane_of_incidence", "plane of incidence"), ("held_out", "held out")):
        rms = figures[key]
        if not rms["views"]:
            lines.append(f"  relative RMS, {name}: no views")
            continue
        lines.append(f"  relative RMS, {name} ({rms['views']} views): pooled {rms['pooled']:.3f}, per channel "
                     f"{rms['per_channel']:.3f} (R {rms['R']:.3f}, G {rms['G']:.3f}, B {rms['B']:.3f})")
    for entry in figures["backscatter"]:
        ratio = " ".join(f"{v:.2f}" for v in entry["model_over_measured"])
        lines.append(f"  backscatter θi {entry['theta_i_deg']:g}° θv {entry['theta_v_deg']:g}°: model / measured "
                     f"R G B {ratio} (measured R {entry['measured'][0]:.4f})")
    colour = figures["off_specular"]
    for key in ("B/R", "G/R"):
        if key in colour:
            c = colour[key]
            lines.append(f"  off-specular {key} ({colour['views']} views): model "
                         f"{c['model'][0]:.3f}–{c['model'][1]:.3f}, "
                         f"measured {c['measured'][0]:.3f}–{c['measured'][1]:.3f}; model / measured min "
                         f"{c['model_over_measured'][0]:.2f}, median {c['model_over_measured'][1]:.2f}, "
                         f"max {c['model_over_measured'][2]:.2f}")
    if "back_over_front" in figures:
        lines.append(f"  lit from behind / from the front (luminance, normal view, the sun straight behind it: its "
                     f"unscattered beam included; in daylight: scripts/daylight_swatches.py): "
                     f"{figures['back_over_front']:.3f}")
    return lines


__all__ = ["BACKSCATTER_VIEWS", "band_penalty", "band_ratios", "diffuse_shortfall", "fabric_figures", "figures_text",
           "in_plane", "main_channel", "off_specular_views", "parse_band", "relative_rms", "view_index"]
