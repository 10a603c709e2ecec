"""The close-up's defaults and its flyaway fibres, without Blender: the [closeup] table read and
checked by name, the sheeting default's cover, fibres that leave their yarn along the twist and stay
clear of every yarn, and the hair BSDF's absorption derived from the dye (issue 46)."""

import dataclasses
import math

import numpy as np
import pytest

from clothlight.weave import WeaveParameters
from clothlight.weave.closeup import SHEETING_COVER_FACTOR, CloseupSettings, closeup_settings, sheeting_weave
from clothlight.weave.fibre_optics import (
    LEAST_TRANSMITTANCE,
    fibre_absorption_per_mm,
    fibre_radius_mm,
    hair_absorption_coefficient,
)
from clothlight.weave.flyaways import flyaway_fibres
from precompute.errors import ParameterError
from precompute.optics.medium import PRESET_DIR, load_preset, load_preset_config, preset_names
from precompute.tables.color import spectral_to_rgb
from tests.test_closeup_weave import RELAXED, ring_semi_axes

#: A small plied, irregular sample with the default fibres.
SMALL = dict(warp_count=5, weft_count=5)


@pytest.fixture(scope="module", params=["default", "relaxed"])
def sample(request):
    """The default close-up's weave, and one whose section relaxes three quarters of the way to round
    between crossings (there a fibre rooted on the pressed section would start outside its yarn)."""
    params = sheeting_weave(**SMALL) if request.param == "default" else WeaveParameters(**RELAXED)
    settings = CloseupSettings()
    return params, settings, flyaway_fibres(params, settings, 0.0075)


# -- the [closeup] table and the default weave --------------------------------------------------------


def test_every_shipped_preset_has_a_valid_closeup():
    for name in preset_names():
        settings = closeup_settings(load_preset_config(name)[0])
        params = sheeting_weave(name, warp_count=3, weft_count=3)
        yarn = load_preset(name).yarn
        assert (params.ply_count, params.twist_angle_deg) == (yarn.ply_count, yarn.twist_angle_deg)
        assert (params.spacing_jitter, params.seed) == (settings.spacing_jitter, settings.seed)


@pytest.mark.parametrize("table, name", [
    ({"flyaway_density": 3.0}, "closeup.flyaway_density"),
    ({"flyaway_density_per_mm": -1.0}, "closeup.flyaway_density_per_mm"),
    ({"flyaway_length_mm": 0.0}, "closeup.flyaway_length_mm"),
    ({"flyaway_curl_per_mm": float("inf")}, "closeup.flyaway_curl_per_mm"),
    ({"height_jitter": 1.0}, "closeup.height_jitter"),
    ({"seed": "7"}, "closeup.seed"),
])
def test_a_bad_closeup_table_is_refused_by_name(table, name):
    with pytest.raises(ParameterError) as refusal:
        closeup_settings({"closeup": table})
    assert refusal.value.name == name


def test_the_default_close_up_covers_the_cloth_as_sheeting_does():
    """Peirce: round yarns of diameter d at K = 14 cover 14/28 of the cloth per system, 0.75 both
    together; the flattened default covers more, the validation's open sample less."""
    params = sheeting_weave()
    d = 2 * load_preset("voided_red_cotton").yarn.radius_mm
    peirce = d / params.spacing_mm
    assert peirce == pytest.approx(SHEETING_COVER_FACTOR / 28)
    assert params.cover_factor > 1 - (1 - peirce) ** 2 == pytest.approx(0.75)
    assert WeaveParameters().cover_factor < 0.75
    assert params.ply_count == 2 and params.minimum_gap_mm > 0


# -- flyaway fibres -----------------------------------------------------------------------------------


def test_fibres_grow_from_every_yarn_at_about_the_given_density(sample):
    params, settings, fibres = sample
    yarns = params.warp_count + params.weft_count
    assert set(fibres.yarn_id.tolist()) == set(range(yarns))
    assert np.all(fibres.counts >= 3) and fibres.counts.sum() == len(fibres.points)
    # the Poisson draw before trimming: all roots, kept or not, come at the density per mm of yarn
    none_trimmed = flyaway_fibres(params, dataclasses.replace(settings, flyaway_length_mm=1e-3), 0.0075)
    expected = settings.flyaway_density_per_mm * yarns * params.sample_size_mm[0]
    assert len(fibres.counts) < len(none_trimmed.counts)
    assert abs(len(none_trimmed.counts) - expected) < 4 * math.sqrt(expected)


def test_fibres_are_seeded_and_reproducible(sample):
    params, settings, fibres = sample
    again = flyaway_fibres(params, settings, 0.0075)
    np.testing.assert_array_equal(again.points, fibres.points)
    other = flyaway_fibres(params, dataclasses.replace(settings, seed=1), 0.0075)
    assert len(other.points) != len(fibres.points) or not np.allclose(other.points, fibres.points)


def depth_inside_section_tube(points, centerline, lateral_axis, widths, thicknesses):
    """How deep points lie inside a tube around a planar centreline (n, 3) whose plane is normal to
    ``lateral_axis`` (0: x, 1: y), its section the ellipse of semi-axes ``widths``, ``thicknesses``
    (n,) at each centreline point; ≤ 0 outside.  At lateral offset η the tube is the set within
    b·√(1 − η²/a²) of the centreline in its plane, taken at each point of a fine centreline (the
    depth between two points is missed by at most Δs²/(8·b))."""
    eta = points[:, lateral_axis, None] - centerline[None, :, lateral_axis]
    keep = 1 - lateral_axis
    half = thicknesses * np.sqrt(np.clip(1.0 - (eta / widths) ** 2, 0.0, None))
    distance = np.linalg.norm(points[:, None, [keep, 2]] - centerline[None, :, [keep, 2]], axis=-1)
    return np.where(np.abs(eta) < widths, half - distance, -np.inf).max(axis=1)


def test_fibres_start_inside_their_yarn_and_then_stay_clear_of_every_yarn(sample):
    """Against every yarn as built: the section of each ring measured on a fine single-ply mesh of the
    sample (the default's section relaxes between crossings)."""
    params, settings, fibres = sample
    from clothlight.weave import build_woven_mesh

    fine_params = dataclasses.replace(params, segments_per_crossing=64, ply_count=1, ply_radius_jitter=0.0)
    fine = build_woven_mesh(fine_params)
    sections = [ring_semi_axes(fine, fine_params, yarn)[:2] for yarn in range(len(fine.centerlines))]
    assert max(np.ptp(widths) for widths, _ in sections) > 0.005       # the section does change along a yarn
    warps = params.warp_count
    for fibre, yarn in zip(fibres.fibres(), fibres.yarn_id):
        lateral = 1 if yarn < warps else 0
        assert depth_inside_section_tube(fibre[:1], fine.centerlines[yarn], lateral, *sections[yarn])[0] > 0
        # every point from the surface on, and the steps between them, outside every yarn
        steps = fibre[1:, None] + np.linspace(0, 1, 5)[:, None] * np.diff(fibre[1:], axis=0, append=fibre[-1:])[:, None]
        points = steps.reshape(-1, 3)
        for other, centre in enumerate(fine.centerlines):
            axial = 0 if other < warps else 1
            # the tubes end in flat caps: beyond them nothing is inside (the helper would round them)
            low, high = sorted((centre[0, axial], centre[-1, axial]))
            between = (points[:, axial] >= low) & (points[:, axial] <= high)
            depth = depth_inside_section_tube(points[between], centre, 1 - axial, *sections[other])
            assert depth.max(initial=-np.inf) < 0


def test_fibres_leave_along_the_twist_helix():
    """A fibre's first step, in the plane tangent to its yarn's surface, runs at the twist angle to
    the yarn's axis (either way along it).  The surface's normal is read off the fibre (from its
    buried root through its first point), the axis off a finely swept centreline."""
    from clothlight.weave import build_woven_mesh

    for angle in (0.0, 24.0, 40.0):
        params = sheeting_weave(warp_count=4, weft_count=4, twist_angle_deg=angle)
        fibres = flyaway_fibres(params, CloseupSettings(flyaway_curl_per_mm=0.0), 0.0075)
        centrelines = build_woven_mesh(dataclasses.replace(params, segments_per_crossing=128, ply_count=1)).centerlines
        measured = []
        for fibre, yarn in zip(fibres.fibres(), fibres.yarn_id):
            normal = (fibre[1] - fibre[0]) / np.linalg.norm(fibre[1] - fibre[0])
            step = fibre[2] - fibre[1]
            in_plane = step - (step @ normal) * normal
            centre = centrelines[yarn]
            ring = np.argmin(np.linalg.norm(centre - fibre[0], axis=1))
            axis = np.gradient(centre, axis=0)[ring]
            axis /= np.linalg.norm(axis)
            cosine = abs(in_plane @ axis) / np.linalg.norm(in_plane)
            measured.append(math.degrees(math.acos(min(cosine, 1.0))))
        assert len(measured) > 50
        np.testing.assert_allclose(measured, angle, atol=0.5)   # the nearest ring of a 128-segment sweep


# -- the fibres' colour ---------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["voided_red_cotton", "blue_cotton", "paper_2008", "undyed_cotton",
                                  str(PRESET_DIR / "experimental" / "fibre_cotton.toml")])   # a medium of fibres
def test_hair_absorption_passes_the_dyed_fibres_colour(name):
    """Cycles attenuates by exp(−σ·chord) with the chord in fibre radii: straight through a fibre
    (chord 2) σ gives back the colour of the fibre's spectral transmittance, and it follows the dye."""
    medium = load_preset(name)
    sigma = hair_absorption_coefficient(medium)
    radius = fibre_radius_mm(medium)
    spectral = np.exp(-fibre_absorption_per_mm(medium) * 2 * radius)
    rgb = spectral_to_rgb(spectral, medium.wavelengths.values)
    np.testing.assert_allclose(np.exp(-2 * sigma), np.clip(rgb, 1e-6, 1), rtol=1e-9, atol=1e-12)
    assert np.all(sigma >= 0)
    thicker = hair_absorption_coefficient(medium, 2 * radius)
    if medium.dye is None:
        # grey: no channel favoured, and σ = μₐ·r exactly
        np.testing.assert_allclose(sigma, sigma[0], atol=1e-9)
        np.testing.assert_allclose(thicker, 2 * sigma, atol=1e-9)
    else:
        absorbing = (sigma > 1e-6) & (sigma < -np.log(LEAST_TRANSMITTANCE) / 2 - 1e-9)   # not clipped black
        assert np.all(thicker[absorbing] > sigma[absorbing])


def test_a_red_dye_absorbs_green_and_blue_more_than_red():
    sigma = hair_absorption_coefficient(load_preset("voided_red_cotton"))
    assert sigma[0] < sigma[1] and sigma[0] < sigma[2]
    blue = hair_absorption_coefficient(load_preset("blue_cotton"))
    assert blue[2] < blue[0]
