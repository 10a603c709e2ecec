"""Spectral → linear Rec.709: the stated convention, checked against colour-science's own pipeline."""

import dataclasses

import colour
import numpy as np
import pytest

from precompute.bake import bake
from precompute.tables.color import (
    DEFAULT_OBSERVER,
    RGB_SPACE,
    blue_red_ratio,
    channel_ratios,
    clip_to_gamut,
    green_red_ratio,
    spectral_stderr_to_rgb,
    spectral_to_rgb,
    white_balance_factors,
)
from precompute.errors import ParameterError
from precompute.optics.medium import load_preset
from precompute.tables.exr import read_table

PAPER_GRID = np.arange(390.0, 731.0, 10.0)
UNEVEN_GRID = np.array([380.0, 400, 430, 470, 520, 560, 600, 640, 690, 780])


@pytest.mark.parametrize("wavelengths", [PAPER_GRID, UNEVEN_GRID])
@pytest.mark.parametrize("illuminant", ["D65", "A", "FL2"])
def test_flat_spectrum_is_neutral(wavelengths, illuminant):
    for level in (1.0, 0.37, 1e-4):
        rgb = spectral_to_rgb(np.full(wavelengths.size, level), wavelengths, illuminant)
        np.testing.assert_allclose(rgb, level, rtol=1e-12)


def test_d65_white_balance_is_only_the_white_point_rounding():
    # Rec.709's white is D65: balancing must be a tiny correction, i.e. the convention is colorimetric.
    np.testing.assert_allclose(white_balance_factors(PAPER_GRID), 1.0, atol=3e-4)
    # ... while illuminant A's orange light needs a real white balance.
    factors_a = white_balance_factors(PAPER_GRID, "A")
    assert factors_a[2] > 2.0 * factors_a[0]


def _colour_science_rgb(values, wavelengths, illuminant="D65"):
    """The same convention through colour-science's own integration and XYZ → RGB, without balancing."""
    shape = colour.SpectralShape(360, 830, 1)
    sd = colour.SpectralDistribution(dict(zip(wavelengths, values)))
    sd = sd.copy().align(shape, interpolator=colour.LinearInterpolator)
    cmfs = colour.MSDS_CMFS[DEFAULT_OBSERVER].copy().align(shape)
    power = colour.SDS_ILLUMINANTS[illuminant].copy().align(shape)
    xyz = colour.sd_to_XYZ(sd, cmfs, power, method="Integration") / 100.0
    return colour.XYZ_to_RGB(xyz, RGB_SPACE, chromatic_adaptation_transform=None, apply_cctf_encoding=False)


@pytest.mark.parametrize("patch", ["red", "moderate red", "blue", "green", "yellow", "neutral 8 (.23 D)"])
def test_colour_checker_patches_match_colour_science(patch):
    reflectance = colour.SDS_COLOURCHECKERS["BabelColor Average"][patch]
    values = np.interp(PAPER_GRID, reflectance.wavelengths, reflectance.values)
    expected = _colour_science_rgb(values, PAPER_GRID)
    np.testing.assert_allclose(spectral_to_rgb(values, PAPER_GRID), expected, rtol=1e-3, atol=1e-5)


def test_long_wavelengths_are_red_beyond_the_gamut():
    # Light above 620 nm lies outside Rec.709's red primary: green goes negative, clipping reports it.
    rgb = spectral_to_rgb((PAPER_GRID >= 630).astype(float), PAPER_GRID)
    assert rgb[0] > 0 and rgb[1] < 0 and abs(rgb[2]) < 0.05 * rgb[0]
    clipped, share = clip_to_gamut(rgb)
    assert clipped[1] == 0 and share == pytest.approx(-rgb[1] / rgb[0])


def test_table1_ratio_helpers():
    assert channel_ratios([2.0, 0.5, 0.25]) == {"B/R": 0.125, "G/R": 0.25}
    assert blue_red_ratio([0.5, 0.1, 0.04]) == pytest.approx(0.08)
    assert green_red_ratio([1.0, 0.011, 0.08]) == pytest.approx(0.011)
    assert np.isnan(blue_red_ratio([0.0, 1.0, 1.0]))


def test_rgb_stderr_bounds_correlated_and_independent_noise():
    rng = np.random.default_rng(4)
    mean = 0.2 + 0.1 * np.sin(PAPER_GRID / 40.0)
    sigma = 0.01 * (1.0 + rng.random(PAPER_GRID.size))
    bound = spectral_stderr_to_rgb(sigma, PAPER_GRID)
    for correlated in (True, False):
        z = rng.standard_normal((20000, 1 if correlated else PAPER_GRID.size))
        spread = spectral_to_rgb(mean + sigma * z, PAPER_GRID).std(axis=0)
        assert np.all(spread <= bound * 1.03)
    # Fully correlated noise propagates linearly: its RGB spread is |Σ W σ|, below the bound Σ |W| σ.
    z = rng.standard_normal((20000, 1))
    spread = spectral_to_rgb(mean + sigma * z, PAPER_GRID).std(axis=0)
    np.testing.assert_allclose(spread, np.abs(spectral_to_rgb(sigma, PAPER_GRID)), rtol=0.03)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"illuminant": "D66"}, "bake.illuminant"),
        ({"observer": "Stockman & Sharpe 2 Degree Cone Fundamentals"}, "bake.observer"),
        ({"wavelengths_nm": np.array([300.0, 400, 500])}, "wavelengths_nm"),
        ({"wavelengths_nm": np.array([500.0, 400, 600])}, "wavelengths_nm"),
    ],
)
def test_bad_colour_inputs_name_the_parameter(kwargs, name):
    arguments = {"values": np.ones(3), "wavelengths_nm": np.array([400.0, 500, 600]), **kwargs}
    with pytest.raises(ParameterError) as error:
        spectral_to_rgb(**arguments)
    assert error.value.name == name


def test_spectrally_flat_yarn_bakes_to_grey(tmp_path):
    # No particles, no dye, a host absorbing alike at every wavelength and refracting without
    # dispersion: every wavelength takes the same paths, so the whole pipeline
    # (optics → transport → BRDF → colour → table) must give R = G = B.
    cotton = load_preset("undyed_cotton")
    host = dataclasses.replace(cotton.host, absorption_per_mm=2.0)
    clear = dataclasses.replace(cotton, host=host, particles=(), dye=None)
    small = ["transport.angular_resolution=4", "transport.incidence_resolution=5",
             "transport.n_around=8", "transport.n_along=4"]
    result = bake(clear, small, paths_per_cell=200, cache_dir=tmp_path)
    # nothing scatters: all the light through the yarn is the unscattered light, none is in ρ
    assert read_table(result.brdf_table, kind="brdf").pixels.max() == 0.0
    attenuation = read_table(result.folder / "unscattered.exr", kind="unscattered").pixels
    assert attenuation.min() > 0.1  # light does come through
    np.testing.assert_allclose(attenuation[..., 0], attenuation[..., 1], rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(attenuation[..., 2], attenuation[..., 1], rtol=1e-6, atol=1e-9)
