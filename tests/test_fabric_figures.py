"""Issue 43's figures of a cloth against a fabric (precompute/fit/figures.py), the raw-data curves'
views in the fit (held-out diagonals) and in the forward model's renders (clothlight/fit/forward.py)."""

import numpy as np
import pytest

from clothlight.fit.forward import rig_views, sample_azimuths
from precompute.optics.measured_sample import DEFAULT_SAMPLE_AZIMUTHS_DEG
from precompute.errors import ParameterError
from precompute.fit.figures import (band_penalty, band_ratios, diffuse_shortfall, fabric_figures, main_channel,
                                    off_specular_views, parse_band, view_index)
from precompute.fit.objective import split_views

pytestmark = pytest.mark.filterwarnings("ignore::RuntimeWarning")


class RawCurves:
    """The raw-data curves' views (θi 0…60° × θo 0…80° × φo 0/45/90/135/180°, light at φi 180°) with a
    red cloth's BRDF: diffuse (B/R 0.08, G/R 0.12) plus a white lobe about the mirror direction."""

    angles_deg = np.array([(ti, 180.0, to, po) for ti in (0, 15, 30, 45, 60) for to in range(0, 81, 10)
                           for po in ((0.0,) if to == 0 else (0.0, 45.0, 90.0, 135.0, 180.0))], float)
    rgb = None


def red_cloth(angles_deg, backscatter=1.0):
    a = np.radians(angles_deg)
    wi = np.stack([np.sin(a[:, 0]) * np.cos(a[:, 1]), np.sin(a[:, 0]) * np.sin(a[:, 1]), np.cos(a[:, 0])], -1)
    wo = np.stack([np.sin(a[:, 2]) * np.cos(a[:, 3]), np.sin(a[:, 2]) * np.sin(a[:, 3]), np.cos(a[:, 2])], -1)
    mirror = wi * np.array([-1.0, -1.0, 1.0])
    lobe = 0.02 * np.exp(-(1.0 - np.sum(mirror * wo, -1)) / 0.01)
    toward_light = np.sum(wi * wo, -1)
    diffuse = 0.05 * (1.0 + (backscatter - 1.0) * np.clip(toward_light, 0.0, 1.0) ** 8)
    return diffuse[:, None] * np.array([1.0, 0.12, 0.08]) + lobe[:, None]


RawCurves.rgb = red_cloth(RawCurves.angles_deg)


def test_the_plane_of_incidence_is_fitted_and_every_other_azimuth_held_out():
    views = split_views(RawCurves)
    azimuth = RawCurves.angles_deg[:, 3]
    in_plane = (azimuth == 0.0) | (azimuth == 180.0)
    np.testing.assert_array_equal(views.fit, in_plane)
    np.testing.assert_array_equal(views.held_out, ~in_plane)
    assert set(azimuth[views.held_out]) == {45.0, 90.0, 135.0}


def test_the_figures_of_a_cloth_against_itself_and_against_a_changed_one():
    views = split_views(RawCurves)
    same = fabric_figures(RawCurves.rgb, RawCurves.rgb, views)
    assert same["plane_of_incidence"]["pooled"] == 0.0 and same["held_out"]["per_channel"] == 0.0
    assert [b["model_over_measured"] for b in same["backscatter"]] == [[1.0, 1.0, 1.0]] * 3
    assert same["off_specular"]["B/R"]["model_over_measured"] == pytest.approx([1.0, 1.0, 1.0])
    # a cloth with backscatter toward the light and half the blue
    other = red_cloth(RawCurves.angles_deg, backscatter=2.0) * np.array([1.0, 1.0, 0.5])
    figures = fabric_figures(other, RawCurves.rgb, views, swatches=np.array([[1.0, 1.0, 1.0], [0.3, 0.3, 0.3]]))
    at_60_60 = figures["backscatter"][0]
    assert (at_60_60["theta_i_deg"], at_60_60["theta_v_deg"]) == (60.0, -60.0)
    assert at_60_60["model_over_measured"][0] > 1.5
    assert figures["off_specular"]["B/R"]["model_over_measured"][2] == pytest.approx(0.5)
    assert figures["off_specular"]["G/R"]["model_over_measured"][0] == pytest.approx(1.0, abs=0.01)
    assert figures["back_over_front"] == pytest.approx(0.3)
    # half the blue: per channel that is a 50 % miss of one channel in three; pooled, blue barely counts
    bluer = fabric_figures(RawCurves.rgb * np.array([1.0, 1.0, 0.5]), RawCurves.rgb, views)["plane_of_incidence"]
    assert bluer["B"] == pytest.approx(0.5) and bluer["per_channel"] == pytest.approx(0.5 / np.sqrt(3.0))
    assert bluer["pooled"] < 0.3 * bluer["per_channel"]


def test_the_diffuse_shortfall_is_the_lambertian_light_a_cloth_lacks():
    views = split_views(RawCurves)
    lacking = np.array([0.01, 0.004, 0.0])
    short = diffuse_shortfall(RawCurves.rgb - lacking, RawCurves.rgb, views)
    np.testing.assert_allclose(short, lacking, atol=1e-12)
    restored = fabric_figures(RawCurves.rgb - lacking + short, RawCurves.rgb, views)
    assert restored["plane_of_incidence"]["per_channel"] == pytest.approx(0.0, abs=1e-12)
    # a cloth with light to spare lacks none; one that lacks it only off the plane is not credited with it
    assert diffuse_shortfall(RawCurves.rgb * 1.2, RawCurves.rgb, views).tolist() == [0.0, 0.0, 0.0]
    off_plane = RawCurves.rgb - np.where(np.asarray(views.held_out, bool)[:, None], 0.02, 0.0)
    assert diffuse_shortfall(off_plane, RawCurves.rgb, views).tolist() == [0.0, 0.0, 0.0]
    # the least-squares constant: any other one leaves each channel further from the measurement
    noisy = RawCurves.rgb * (1.0 + 0.1 * np.sin(np.arange(len(RawCurves.rgb))))[:, None] - lacking
    best = fabric_figures(noisy + diffuse_shortfall(noisy, RawCurves.rgb, views), RawCurves.rgb, views)
    for nudge in (-0.001, 0.001):
        worse = fabric_figures(noisy + diffuse_shortfall(noisy, RawCurves.rgb, views) + nudge, RawCurves.rgb, views)
        assert all(worse["plane_of_incidence"][c] > best["plane_of_incidence"][c] for c in "RG")


def test_the_bands_read_the_backscatter_in_the_main_channel_and_the_off_specular_colour():
    views = split_views(RawCurves)
    assert main_channel(RawCurves.rgb) == 0  # a red cloth
    same = band_ratios(RawCurves.rgb, RawCurves.rgb, views)
    assert set(same) == {"backscatter 60/-60", "backscatter 60/-40", "backscatter 45/-60", "B/R", "G/R"}
    assert all(v == pytest.approx(1.0) for v in same.values())
    assert band_penalty(RawCurves.rgb, RawCurves.rgb, views, (0.85, 1.15)) == 0.0
    # the backscatter views 1.6 times as bright in red, 3 times in green and blue: only red, the main channel, counts
    other = RawCurves.rgb.copy()
    for theta_i, theta_v in ((60.0, -60.0), (60.0, -40.0), (45.0, -60.0)):
        other[view_index(views, theta_i, theta_v)] *= np.array([1.6, 3.0, 3.0])
    ratios = band_ratios(other, RawCurves.rgb, views)
    assert [ratios[f"backscatter {v}"] for v in ("60/-60", "60/-40", "45/-60")] == pytest.approx([1.6] * 3)
    # 1.3 times the blue everywhere: B/R's median 1.3, G/R's 1; outside 0.85–1.15 by ln(1.3/1.15) in one of five
    bluer = RawCurves.rgb * np.array([1.0, 1.0, 1.3])
    assert band_ratios(bluer, RawCurves.rgb, views)["B/R"] == pytest.approx(1.3)
    assert band_penalty(bluer, RawCurves.rgb, views, (0.85, 1.15)) == pytest.approx(
        np.log(1.3 / 1.15) / np.sqrt(5.0))
    assert band_penalty(bluer, RawCurves.rgb, views, (0.7, 1.35)) == 0.0
    # below the band counts as above it does
    assert band_penalty(RawCurves.rgb * np.array([1.0, 1.0, 0.7]), RawCurves.rgb, views, (0.85, 1.15)) == \
        pytest.approx(np.log(0.85 / 0.7) / np.sqrt(5.0))


@pytest.mark.parametrize("text", ["1.1,0.9", "0.9", "0,1.1", "0.9,1", "a,b", "0.9,inf", "0.8,1.1,1.2"])
def test_a_band_is_low_below_one_below_high(text):
    with pytest.raises(ParameterError, match="--hold-bands"):
        parse_band(text)


def test_a_band_reads_from_text_or_a_pair():
    assert parse_band("0.85,1.15") == (0.85, 1.15) == parse_band([0.85, 1.15])


def test_off_specular_views_keep_away_from_the_mirror_and_the_normal():
    views = split_views(RawCurves)
    off = off_specular_views(views)
    theta_i, signed = views.angles_deg[off, 0], views.signed_view_deg[off]
    assert np.all(theta_i <= 45.0) and np.all(np.abs(signed) >= 20.0) and np.all(np.abs(signed - theta_i) >= 20.0)
    assert view_index(views, 30.0, 50.0) is not None and not off[view_index(views, 30.0, 40.0)]
    assert view_index(views, 75.0, -60.0) is None


def test_views_at_any_azimuth_reach_the_rig_square_to_the_weave():
    views = rig_views([(45.0, 180.0, 30.0, 180.0), (45.0, 180.0, 30.0, 0.0), (45.0, 180.0, 30.0, 45.0),
                       (45.0, 180.0, 30.0, 315.0), (45.0, 180.0, 30.0, 135.0), (45.0, 180.0, 30.0, 270.0)])
    assert views == [(45.0, -30.0, 0.0), (45.0, 30.0, 0.0), (45.0, 30.0, 45.0), (45.0, 30.0, 45.0),
                     (45.0, 30.0, 135.0), (45.0, 30.0, 90.0)]
    for _, _, phi_v in views:
        camera_on_sample = sorted((phi_v + alpha) % 180.0 for alpha in sample_azimuths(phi_v))
        assert camera_on_sample == [0.0, 90.0]
    # views in the plane or across it are rendered as before
    assert sample_azimuths(0.0) == DEFAULT_SAMPLE_AZIMUTHS_DEG == sample_azimuths(90.0)


def test_a_dye_series_is_refused_for_fibres_whose_dye_changes_their_scattering(tmp_path):
    from clothlight.fit.forward import build_forward_model
    from precompute.errors import ParameterError
    from precompute.optics.medium import load_preset_config
    from tests.test_fibre_optics import FIBRE_COTTON

    config, base = load_preset_config(FIBRE_COTTON)
    with pytest.raises(ParameterError, match="--dye-series"):  # before any render
        build_forward_model([(0.0, 180.0, 0.0, 0.0)], config, base, cache_dir=tmp_path, dye_range=(0.1, 10.0))
