"""Measuring a sweep (paper §4 steps 3–5) with physical calibration.

For each view the cloth pixels' RGB are summed.  With an orthographic view that sees only cloth
(yarns and the gaps between them) the mean pixel radiance is the cloth's macroscopic radiance
toward the camera, so the calibrated cloth BRDF is

    f(θi, θv) = mean(L_pixel) / (E⊥ cos θi)      [1/sr]

with E⊥ the sun's irradiance on a plane facing it.  The paper's own step 5 — pixel sums divided
by cos θv, then scaled so that normal incidence and view match the measurement — is reported
beside it as ``paper_normalised`` when a measurement is supplied.
"""

from __future__ import annotations

import math
import pathlib
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..materials import sync_sun
from ..measurement_render import render_to_array
from .rig import SUN_IRRADIANCE, RigSettings, set_incidence, set_view


@dataclass
class ViewMeasurement:
    theta_i_deg: float
    theta_v_deg: float
    rgb_sum: list[float]
    cloth_pixels: int
    brdf_rgb: list[float]
    paper_sum_over_cos_rgb: list[float] = field(default_factory=list)
    paper_normalised_rgb: list[float] = field(default_factory=list)


def measure_view(scene, pixels: np.ndarray, theta_i: float, theta_v: float) -> ViewMeasurement:
    cloth = pixels[..., 3] > 0.0
    rgb_sum = pixels[..., :3][cloth].sum(axis=0)
    mean_radiance = pixels[..., :3].sum(axis=(0, 1)) / (pixels.shape[0] * pixels.shape[1])
    brdf = mean_radiance / (SUN_IRRADIANCE * math.cos(math.radians(theta_i)))
    return ViewMeasurement(theta_i, theta_v, rgb_sum.tolist(), int(cloth.sum()), brdf.tolist(),
                           (rgb_sum / math.cos(math.radians(theta_v))).tolist())


def run_sweep(scene, sample, sun, camera, material, settings: RigSettings, incidences, views, out_dir,
              progress: Callable[[float], None] | None = None, cancel: Callable[[], bool] | None = None):
    """Render every (θi, θv) with ``material`` on the sample; returns the list of measurements."""
    sample.data.materials.clear()
    sample.data.materials.append(material)
    out_dir = pathlib.Path(out_dir)
    results = []
    total = len(incidences) * len(views)
    for a, theta_i in enumerate(incidences):
        set_incidence(sun, theta_i)
        scene.view_layers[0].update()
        sync_sun(material, sun)
        for b, theta_v in enumerate(views):
            if cancel is not None and cancel():
                raise InterruptedError("validation cancelled")
            set_view(camera, settings, theta_v)
            pixels = render_to_array(scene, out_dir / f"{material.name}_i{theta_i:+04.0f}_v{theta_v:+04.0f}.exr")
            results.append(measure_view(scene, pixels, theta_i, theta_v))
            if progress is not None:
                progress((a * len(views) + b + 1) / total)
    return results
