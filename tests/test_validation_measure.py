"""From rendered pixels to a calibrated cloth BRDF, without Blender (clothlight/validation/measure.py):
the object mask and the calibration formula.  The rig that renders the pixels is tested in
tests/test_validation_rig.py."""

import math

import numpy as np
import pytest

from clothlight.validation.framing import pixel_cross_section_mm2
from clothlight.validation.measure import measure_view
from precompute.errors import ParameterError


def test_the_mask_sums_cloth_pixels_only_and_the_calibration_formula():
    n, radiance, alpha = 8, 0.4, np.ones((8, 8))
    pixels = np.zeros((n, n, 4))
    pixels[..., :3] = radiance
    pixels[..., 3] = alpha
    pixels[0, :, :3], pixels[0, :, 3] = 5.0, 0.0  # a bright row that is not cloth (alpha 0)
    pixels[1, :, :3], pixels[1, :, 3] = radiance / 2, 0.5  # half-covered pixels: premultiplied
    for theta_i, theta_v in ((0.0, 0.0), (60.0, -40.0), (30.0, 70.0)):
        view = measure_view(pixels, theta_i_deg=theta_i, theta_v_deg=theta_v, patch_mm=2.0, sun_irradiance=2.0)
        cloth_sum = radiance * (n * n - 2 * n) + radiance / 2 * n
        assert view.cloth_pixels == n * n - n
        np.testing.assert_allclose(view.rgb_sum, [cloth_sum] * 3)
        assert view.coverage == pytest.approx((n * n - 2 * n + 0.5 * n) / n**2)
        # f = Σ L_p a_p / (E cos θi A cos θv): the mean radiance over E cos θi, at every view
        a_p = pixel_cross_section_mm2(2.0, n, theta_v)
        assert a_p == pytest.approx((2.0 / n) ** 2 * math.cos(math.radians(theta_v)))
        np.testing.assert_allclose(view.brdf_rgb, cloth_sum / n**2 / (2.0 * math.cos(math.radians(theta_i))))


def test_a_view_without_a_cloth_pixel_is_refused_not_measured_as_zero():
    pixels = np.zeros((4, 4, 4))
    pixels[..., :3] = 0.3  # a background, alpha 0 everywhere
    with pytest.raises(ParameterError, match=r"resolution = 4 .*θi = 60°, θv = -40° none of the 4² pixels"):
        measure_view(pixels, theta_i_deg=60.0, theta_v_deg=-40.0, patch_mm=2.0, sun_irradiance=2.0)
