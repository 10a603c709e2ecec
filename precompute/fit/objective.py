"""What a medium fit minimises: the misfit to a measured cloth BRDF on the plane of incidence.

Views
-----
A measurement (``precompute/fit/measured_data.py``: the project's CSV, read with
``read_measurement``) is split by the view's azimuth relative to the light's, Δφ = φo − φi:

* **fit views**: the plane of incidence (Δφ = 0° or 180°, and the normal view), the paper's graphs;
* **held-out views**: every other azimuth (the perpendicular plane, Δφ = ±90°, and the raw-data
  curves' diagonals, ±45° and ±135°), never seen by the optimiser, reported as an honest check of
  the fitted medium.

The forward model is asked for every view at once, as (θi, φi, θo, φo) in the light-at-φi = 180°
frame of the shipped measurements (``shared/data/real_fabrics``) and of the validation rig: a file
with another φi is turned about the normal to it (:attr:`Views.forward_views`).

Misfit
------
For each RGB channel c, the relative RMS error over the fit views,

    e_c = sqrt(mean_v (model_vc − measured_vc)²) / sqrt(mean_v measured_vc²)

(``relative_rms_error`` of measured_data.py, per channel), and the objective is their RMS over the
channels, E = sqrt((e_R² + e_G² + e_B²) / 3).  Normalising per channel is what a saturated fabric
needs: on a red cotton green is 1–10 % of red, so a single normalisation over all channels would
make the fit blind to green and blue, which carry the colour (B/R, G/R) and the white sheen; per
channel, each counts as much as red, whatever its level.  Within a channel, views weigh by their
BRDF (an RMS, not a log-ratio): the bright views, where the measurement is most precise, count
more, and a near-zero value (a dark channel at a grazing view) cannot dominate as a ratio would.

Colour targets
--------------
Optional ``--target-ratios B/R=0.08,G/R=0.011``: the model's channel ratios at normal incidence and
near-normal view (θi = 0, θo ≤ 10°: the mean over those views of each channel) are pulled to the
targets with the penalty P = sqrt(mean_k ln²(r_k / t_k)), added to E with weight 1: a ratio 10 %
off costs about as much as a 10 % RMS misfit.
"""

from __future__ import annotations

import math
import pathlib
import re
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from precompute.errors import ParameterError
from precompute.fit.measured_data import read_measurement, relative_rms_error
from precompute.outputs import json_ready

CHANNELS = ("R", "G", "B")
#: Angles closer than this are the same, degrees (measured_data.ANGLE_TOLERANCE_DEG).
TOLERANCE_DEG = 0.5
#: The views that define the colour targets: θi = 0 and θo up to this, degrees.
NORMAL_VIEW_MAX_DEG = 10.0
#: The light's azimuth of the forward model's views (the shipped measurements'), degrees.
FORWARD_PHI_I_DEG = 180.0
_RATIO = re.compile(r"^\s*([RGB])\s*/\s*([RGB])\s*=\s*([^,]+?)\s*$")


def load_measurement(path: str | pathlib.Path, option: str = "--measured"):
    """``read_measurement(path)``; a missing or unreadable file as ParameterError naming ``option``
    (its format errors are MeasurementFormatError, also bad input)."""
    path = pathlib.Path(path)
    if not path.is_file():
        raise ParameterError(option, str(path), "an existing measured-data CSV file (docs/validation.md)")
    try:
        return read_measurement(path)
    except OSError as error:
        raise ParameterError(option, str(path), f"a measured-data CSV this user can read ({error.strerror})") from None


@dataclass(frozen=True)
class Views:
    """A measurement's direction pairs, sorted into fit and held-out views (module docstring).

    Attributes
    ----------
    angles_deg
        (M, 4) θi, φi, θo, φo of each measured view, degrees, in the file's order.
    fit, held_out
        (M,) masks of the fit views (plane of incidence) and the held-out views (every other azimuth).
    signed_view_deg
        (M,) the view angle for plots: in the plane of incidence −θo on the light's side, +θo beyond
        the normal (the paper's graphs); elsewhere θo.
    forward_views
        The views as the forward model takes them: (θi, φi, θo, φo), degrees, turned about the
        normal so that the light is at φi = 180° (the order of ``angles_deg``).
    """

    angles_deg: np.ndarray
    fit: np.ndarray
    held_out: np.ndarray
    signed_view_deg: np.ndarray
    forward_views: list[tuple[float, float, float, float]] = field(repr=False)

    @property
    def incidences(self) -> list[float]:
        """The distinct θi, ascending, degrees."""
        values: list[float] = []
        for theta in sorted(self.angles_deg[:, 0]):
            if not values or theta - values[-1] > TOLERANCE_DEG:
                values.append(float(theta))
        return values

    def at_incidence(self, theta_i_deg: float) -> np.ndarray:
        """(M,) mask of the views at incidence θi."""
        return np.abs(self.angles_deg[:, 0] - theta_i_deg) <= TOLERANCE_DEG

    def normal_views(self) -> np.ndarray:
        """(M,) mask of the views at θi = 0 and θo ≤ 10°: where the colour targets are read."""
        a = self.angles_deg
        return (a[:, 0] <= TOLERANCE_DEG) & (a[:, 2] <= NORMAL_VIEW_MAX_DEG + TOLERANCE_DEG)


def split_views(measurement) -> Views:
    """The fit and held-out views of ``measurement`` (a measured_data.Measurement); ParameterError
    when it has no fit view."""
    a = np.asarray(measurement.angles_deg, float)
    delta = (a[:, 3] - a[:, 1]) % 360.0
    folded = np.abs((delta + 180.0) % 360.0 - 180.0)  # |Δφ| in [0, 180]
    normal = a[:, 2] <= TOLERANCE_DEG
    light_side = folded <= TOLERANCE_DEG
    mirror_side = np.abs(folded - 180.0) <= TOLERANCE_DEG
    held_out = ~(normal | light_side | mirror_side)
    fit = ~held_out
    if not fit.any():
        raise ParameterError("--measured", f"{len(a)} views, none in the plane of incidence",
                             "views in the plane of incidence (φo = φi or φi + 180°) to fit")
    signed = np.where(light_side & ~normal & ~mirror_side, -a[:, 2], a[:, 2])
    phi_o = (delta + FORWARD_PHI_I_DEG) % 360.0
    forward = [(float(t_i), FORWARD_PHI_I_DEG, float(t_o), float(p_o))
               for t_i, t_o, p_o in zip(a[:, 0], a[:, 2], phi_o)]
    return Views(a, fit, held_out, signed, forward)


def parse_target_ratios(text: str | Mapping[str, float] | None) -> dict[str, float]:
    """``"B/R=0.08,G/R=0.011"`` (or a mapping) as ``{"B/R": 0.08, "G/R": 0.011}``; ParameterError
    naming ``--target-ratios`` for anything else (another form, a non-positive or repeated ratio)."""
    if text is None:
        return {}
    allowed = "comma-separated X/Y=value with X, Y two of R, G, B and value > 0, e.g. B/R=0.08,G/R=0.011"
    items = list(text.items()) if isinstance(text, Mapping) else [
        part for part in str(text).split(",") if part.strip()]
    ratios: dict[str, float] = {}
    for item in items:
        if isinstance(item, tuple):
            key, value = item
            match = _RATIO.match(f"{key}={value}")
        else:
            match = _RATIO.match(item)
        if not match or match.group(1) == match.group(2):
            raise ParameterError("--target-ratios", item if isinstance(item, str) else f"{item[0]}={item[1]}",
                                 allowed)
        key = f"{match.group(1)}/{match.group(2)}"
        try:
            value = float(match.group(3))
        except ValueError:
            raise ParameterError("--target-ratios", match.group(0).strip(), allowed) from None
        if not math.isfinite(value) or value <= 0.0:
            raise ParameterError("--target-ratios", match.group(0).strip(), allowed)
        if key in ratios:
            raise ParameterError("--target-ratios", key, "each ratio once")
        ratios[key] = value
    if not ratios and not isinstance(text, Mapping):
        raise ParameterError("--target-ratios", str(text), allowed)
    return ratios


def channel_relative_rms(model: np.ndarray, measured: np.ndarray) -> np.ndarray:
    """(3,) relative RMS error of each channel (measured_data.relative_rms_error per column); inf
    for a channel the measurement has all zero, NaN for no views."""
    model, measured = np.asarray(model, float), np.asarray(measured, float)
    if not len(measured):
        return np.full(3, math.nan)
    relative = relative_rms_error
    return np.array([relative(model[:, c], measured[:, c]) for c in range(3)])


def combined(errors: np.ndarray) -> float:
    """The RMS over channels of per-channel relative errors (channels with an infinite error, an
    all-zero measured channel, are left out)."""
    finite = np.asarray(errors, float)[np.isfinite(errors)]
    return float(np.sqrt(np.mean(finite**2))) if finite.size else math.nan


def ratios_at_normal(rgb: np.ndarray, views: Views) -> dict[str, float | None]:
    """B/R, G/R (and every other pair asked) of ``rgb`` (M, 3) averaged over the normal views, None
    where the denominator is 0 or there is no normal view."""
    select = views.normal_views()
    if not select.any():
        return {}
    mean = np.asarray(rgb, float)[select].mean(axis=0)
    out: dict[str, float | None] = {}
    for a in range(3):
        for b in range(3):
            if a != b:
                out[f"{CHANNELS[a]}/{CHANNELS[b]}"] = float(mean[a] / mean[b]) if mean[b] > 0 else None
    return out


class Objective:
    """The fit's objective (module docstring) for one measurement: ``objective(model_rgb)`` with the
    model's (M, 3) BRDF at every measured view (fit and held-out, the forward model's order)."""

    def __init__(self, measurement, views: Views | None = None, target_ratios: Mapping[str, float] | None = None,
                 ratio_weight: float = 1.0):
        self.measurement = measurement
        self.views = views or split_views(measurement)
        self.measured = np.asarray(measurement.rgb, float)
        self.target_ratios = dict(target_ratios or {})
        self.ratio_weight = float(ratio_weight)
        if self.target_ratios and not self.views.normal_views().any():
            raise ParameterError("--target-ratios", ",".join(f"{k}={v:g}" for k, v in self.target_ratios.items()),
                                 f"a measurement with views at θi = 0 and θo ≤ {NORMAL_VIEW_MAX_DEG:g}°, where "
                                 "the ratios are read")
        fit_rms = np.sqrt(np.mean(self.measured[self.views.fit] ** 2, axis=0))
        if not np.any(fit_rms > 0):
            raise ParameterError("--measured", "all zero", "a measurement with a non-zero BRDF on the fit views")

    def check(self, model_rgb) -> np.ndarray:
        model = np.asarray(model_rgb, float)
        if model.shape != self.measured.shape:
            raise RuntimeError(f"the forward model returned an array of shape {model.shape}; expected "
                               f"{self.measured.shape} (one RGB BRDF per measured view)")
        if not np.all(np.isfinite(model)):
            raise RuntimeError("the forward model returned non-finite BRDF values")
        return model

    def channel_errors(self, model_rgb, which: str = "fit") -> np.ndarray:
        """(3,) relative RMS error per channel on the ``"fit"`` or ``"held_out"`` views."""
        model = self.check(model_rgb)
        mask = self.views.fit if which == "fit" else self.views.held_out
        return channel_relative_rms(model[mask], self.measured[mask])

    def ratio_penalty(self, model_rgb) -> float:
        """P (module docstring); 0 without targets, a large finite value when a ratio is undefined."""
        if not self.target_ratios:
            return 0.0
        achieved = ratios_at_normal(self.check(model_rgb), self.views)
        logs = []
        for key, target in self.target_ratios.items():
            value = achieved.get(key)
            logs.append(math.log(value / target) if value and value > 0 else math.log(1e6))
        return float(math.sqrt(np.mean(np.square(logs))))

    def __call__(self, model_rgb) -> float:
        return combined(self.channel_errors(model_rgb)) + self.ratio_weight * self.ratio_penalty(model_rgb)

    def terms(self, model_rgb) -> dict:
        """Every part of the objective, for the report."""
        fit, held = self.channel_errors(model_rgb, "fit"), self.channel_errors(model_rgb, "held_out")
        out = {
            "objective": self(model_rgb),
            "fit_views": {"relative_rms": combined(fit), **{c: json_ready(e) for c, e in zip(CHANNELS, fit)}},
            "held_out_views": {"relative_rms": combined(held), **{c: json_ready(e) for c, e in zip(CHANNELS, held)}},
        }
        if self.target_ratios:
            achieved = ratios_at_normal(model_rgb, self.views)
            out["target_ratios"] = {key: {"target": target, "achieved": achieved.get(key)}
                                    for key, target in self.target_ratios.items()}
            out["ratio_penalty"] = self.ratio_penalty(model_rgb)
        return out


__all__ = ["CHANNELS", "Objective", "Views", "channel_relative_rms", "combined", "load_measurement",
           "parse_target_ratios", "ratios_at_normal", "split_views"]
