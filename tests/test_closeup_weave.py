"""Close-up geometry without Blender: plies twisted at the preset's angle, inside their yarn and clear
of the yarns they cross; seeded irregularity that makes every repeat its own and stays clear; and
refusal of bad settings by name (issue 46)."""

import dataclasses
import math

import numpy as np
import pytest

from clothlight.weave import WeaveParameterError, WeaveParameters, build_woven_mesh
from clothlight.weave.closeup import sheeting_weave
from clothlight.weave.plies import ply_disc
from precompute.optics.medium import load_preset
from tests.test_weave import depth_inside_tube, meshes_cross

pytestmark = pytest.mark.filterwarnings("error")

#: A plied, irregular plain weave: the close-up's ingredients on a sample small enough to check
#: every crossing by brute force.
PLIED = dict(interlacing="plain", warp_count=5, weft_count=5, ply_count=2, twist_angle_deg=24.0,
             crimp_amplitude_mm=0.11, spacing_jitter=0.05, height_jitter=0.1, ply_radius_jitter=0.2, seed=7)


def tube_rings(mesh, params, yarn, ply):
    """Ring vertices (n, around, 3) of one ply of one yarn."""
    points = mesh.vertices[(mesh.yarn_id == yarn) & (mesh.ply_index == ply)]
    return points[:-2].reshape(-1, params.segments_around, 3)   # the two cap centres come last


def ply_phase(mesh, params, yarn, ply):
    """Angle of a ply's centre about its yarn's axis at every ring, unwrapped, measured from the
    geometry in the unit disc of the envelope (0 on the +B side, π/2 on top), and the arc length."""
    centre = mesh.centerlines[yarn]
    offsets = tube_rings(mesh, params, yarn, ply).mean(axis=1) - centre
    tangent = np.gradient(centre, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    binormal = np.array([0.0, 1.0, 0.0]) if yarn < params.warp_count else np.array([1.0, 0.0, 0.0])
    normal = np.cross(tangent, binormal)
    width, thickness = params.cross_section_mm
    phase = np.unwrap(np.arctan2(np.sum(offsets * normal, 1) / thickness, offsets @ binormal / width))
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(centre, axis=0), axis=1))])
    return phase, arc


# -- plies and twist ------------------------------------------------------------------------------


@pytest.mark.parametrize("plies", [2, 3, 4])
def test_every_yarn_is_made_of_closed_ply_tubes(plies):
    # fine rings: a ply's rings turn with it, and the mesh between two turned rings bulges a little
    params = WeaveParameters(interlacing="twill_2_1", warp_count=4, weft_count=4, ply_count=plies,
                             twist_angle_deg=30.0, segments_per_crossing=32, segments_around=32)
    mesh = build_woven_mesh(params)
    yarns = params.warp_count + params.weft_count
    assert len(mesh.tube_faces) == yarns * plies and len(mesh.yarn_faces) == yarns
    assert sorted(set(mesh.ply_index.tolist())) == list(range(plies))
    single = build_woven_mesh(dataclasses.replace(params, ply_count=1))
    _, towards_axis, across = ply_disc(plies)
    for yarn in range(yarns):
        tube = mesh.yarn_mesh(yarn)
        assert tube.is_watertight and tube.is_winding_consistent
        assert tube.body_count == plies and tube.euler_number == 2 * plies
        # across the yarn each ply is the envelope's section scaled by its semi-axes: together
        # they fill P·ρ·ρ_t of the yarn's volume
        ratio = tube.volume / single.yarn_mesh(yarn).volume
        assert ratio == pytest.approx(plies * towards_axis * across, rel=2e-3)


@pytest.mark.parametrize("plies, angle", [(2, 24.0), (3, 12.0), (2, 40.0), (4, 33.0)])
def test_plies_wind_at_the_given_twist_angle(plies, angle):
    """The helix angle measured on the geometry: a ply's centre turns about the yarn axis at
    dφ/du, so its crest, at the envelope's radius R, makes tan θ = R·dφ/du with the axis."""
    params = WeaveParameters(warp_count=3, weft_count=6, ply_count=plies, twist_angle_deg=angle,
                             segments_per_crossing=16)
    mesh = build_woven_mesh(params)
    radius = math.sqrt(math.prod(params.cross_section_mm))
    for yarn in (0, params.warp_count + 1):
        phases = []
        for ply in range(plies):
            phase, arc = ply_phase(mesh, params, yarn, ply)
            rate = np.gradient(phase, arc)
            # right-handed (Z twist), steadily, at the given angle everywhere along the yarn
            assert np.degrees(np.arctan(radius * rate)) == pytest.approx(angle, abs=0.05)
            phases.append(phase[0])
        # the plies share the turn evenly
        spread = np.diff(np.sort(np.mod(phases, 2 * np.pi)))
        np.testing.assert_allclose(spread, 2 * np.pi / plies, atol=1e-9)


def test_the_crest_of_a_ply_runs_at_the_twist_angle_along_a_float():
    """Independently of the frame: along a satin's flat float the outermost line of a ply (its
    vertices farthest from the yarn axis) is a helix whose angle to the axis is the twist angle."""
    angle = 30.0
    params = WeaveParameters(interlacing="satin_8", warp_count=2, weft_count=9, ply_count=2,
                             twist_angle_deg=angle, segments_per_crossing=32, segments_around=96)
    mesh = build_woven_mesh(params)
    centre = mesh.centerlines[0]
    level = np.flatnonzero(np.abs(np.gradient(centre[:, 2], centre[:, 0])) < 1e-12)
    runs = np.split(level, np.flatnonzero(np.diff(level) > 1) + 1)
    flat = max(runs, key=len)                                  # the float, seven picks long
    assert len(flat) > 5 * params.segments_per_crossing
    rings = tube_rings(mesh, params, 0, 0)[flat]
    radial = rings - centre[flat, None]
    crest = rings[np.arange(len(flat)), np.argmax(np.linalg.norm(radial[..., 1:], axis=-1), axis=1)]
    run = np.diff(crest, axis=0)
    around = np.linalg.norm(run[:, 1:], axis=1)
    step = run[:, 0]
    inner = slice(2, -2)     # away from the float's ends, where it starts to bend
    measured = np.degrees(np.arctan(around[inner].sum() / step[inner].sum()))
    assert measured == pytest.approx(angle, abs=0.2)   # the crest vertex moves in steps of 360°/96


def test_an_untwisted_single_ply_is_the_plain_tube():
    params = WeaveParameters(interlacing="twill_2_2", warp_count=4, weft_count=4, semi_axes_mm=(0.14, 0.08))
    twisted = dataclasses.replace(params, twist_angle_deg=40.0)
    np.testing.assert_array_equal(build_woven_mesh(params).vertices, build_woven_mesh(twisted).vertices)


# -- clearance ------------------------------------------------------------------------------------


def test_plies_stay_inside_their_yarn_and_clear_of_the_yarns_they_cross():
    params = WeaveParameters(**PLIED)
    mesh = build_woven_mesh(params)
    # the exact centrelines, from a sweep 8 times finer of the same seeded sample
    fine = build_woven_mesh(dataclasses.replace(params, segments_per_crossing=64, ply_count=1))
    warps, yarns = params.warp_count, params.warp_count + params.weft_count
    for yarn in range(yarns):
        points = mesh.vertices[mesh.yarn_id == yarn]
        lateral = 1 if yarn < warps else 0
        own = depth_inside_tube(points, fine.centerlines[yarn], lateral, params.cross_section_mm)
        assert own.min() > -1e-6                                 # inside its own envelope
        for other in (range(warps, yarns) if yarn < warps else range(warps)):
            depth = depth_inside_tube(points, fine.centerlines[other], 1 - lateral, params.cross_section_mm)
            assert depth.max() < 0.0                             # outside every crossing yarn
    assert not meshes_cross(mesh, params)
    assert params.minimum_gap_mm > 0


def test_the_checks_see_a_ply_pushed_into_a_crossing_yarn():
    """The brute-force checks above can fail: one weft's plies lifted by a thickness are found."""
    params = WeaveParameters(**PLIED)
    mesh = build_woven_mesh(params)
    weft = params.warp_count
    mesh.vertices[mesh.yarn_id == weft, 2] += 2 * params.cross_section_mm[1]
    assert meshes_cross(mesh, params)


# -- irregularity ---------------------------------------------------------------------------------


def repeat_cells(mesh, params, size):
    """The geometry of every repeat (size × size crossings) of a plain sample, each translated to
    its own origin: {(row, column): sorted vertices}."""
    cells = {}
    spacing = params.spacing_mm
    half = params.sample_size_mm[0] / 2
    for row in range(params.weft_count // size):
        for column in range(params.warp_count // size):
            origin = np.array([-half + row * size * spacing, half - (column + 1) * size * spacing])
            inside = np.all((mesh.vertices[:, :2] >= origin + spacing / 2)
                            & (mesh.vertices[:, :2] < origin + (size - 0.5) * spacing), axis=1)
            cells[row, column] = mesh.vertices[inside] - np.append(origin, 0.0)
    return cells


def test_every_repeat_of_an_irregular_sample_is_its_own():
    regular = WeaveParameters(warp_count=6, weft_count=6, ply_count=2, twist_angle_deg=0.0)
    irregular = WeaveParameters(**PLIED | dict(warp_count=6, weft_count=6, twist_angle_deg=0.0))
    for params, alike in ((regular, True), (irregular, False)):
        cells = repeat_cells(build_woven_mesh(params), params, 2)
        first = cells.pop((0, 0))
        for cell in cells.values():
            same = cell.shape == first.shape and np.allclose(cell, first, atol=1e-12)
            assert same == alike


def test_irregularity_is_seeded_and_reproducible():
    params = WeaveParameters(**PLIED)
    again = build_woven_mesh(WeaveParameters(**PLIED)).vertices
    np.testing.assert_array_equal(build_woven_mesh(params).vertices, again)
    other = build_woven_mesh(dataclasses.replace(params, seed=8)).vertices
    assert other.shape == again.shape and not np.allclose(other, again)


def test_each_jitter_moves_what_it_names_and_nothing_else():
    base = WeaveParameters(**PLIED | dict(spacing_jitter=0.0, height_jitter=0.0, ply_radius_jitter=0.0))
    regular = build_woven_mesh(base)
    warps = base.warp_count
    for name in ("spacing_jitter", "height_jitter", "ply_radius_jitter"):
        params = dataclasses.replace(base, **{name: PLIED[name]})
        mesh = build_woven_mesh(params)
        lateral = np.array([c[0, 1] if n < warps else c[0, 0] for n, c in enumerate(mesh.centerlines)])
        regular_lateral = np.array([c[0, 1] if n < warps else c[0, 0] for n, c in enumerate(regular.centerlines)])
        heights = np.concatenate([c[:, 2] for c in mesh.centerlines])
        regular_heights = np.concatenate([c[:, 2] for c in regular.centerlines])
        moved_across = np.abs(lateral - regular_lateral).max()
        assert (moved_across > 0) == (name == "spacing_jitter")
        assert moved_across <= PLIED["spacing_jitter"] * base.spacing_mm
        if name == "height_jitter":
            assert 0 < np.abs(heights - regular_heights).max() <= PLIED["height_jitter"] * base.cross_section_mm[1]
        elif name == "ply_radius_jitter":
            np.testing.assert_array_equal(heights, regular_heights)
            # the plies only get thinner: each ring's spread about its centre shrinks or stays
            for yarn in (0, warps):
                for ply in range(base.ply_count):
                    spread = np.ptp(tube_rings(mesh, params, yarn, ply), axis=1).max(axis=1)
                    regular_spread = np.ptp(tube_rings(regular, base, yarn, ply), axis=1).max(axis=1)
                    ratio = spread / regular_spread
                    assert ratio.max() <= 1 + 1e-12 and ratio.min() >= 1 - PLIED["ply_radius_jitter"] - 1e-12
                    assert ratio.min() < 0.97


def test_a_jitter_that_would_make_yarns_meet_is_refused_naming_what_fits():
    too_much = dict(PLIED, crimp_amplitude_mm=None, height_jitter=0.6)
    with pytest.raises(WeaveParameterError) as refusal:
        WeaveParameters(**too_much)
    message = str(refusal.value)
    assert "spacing_jitter, height_jitter" in message and "at most (" in message
    largest = [float(x) for x in message.split("at most (")[1].split(")")[0].split(",")]
    fits = WeaveParameters(**dict(too_much, spacing_jitter=largest[0], height_jitter=largest[1]))
    assert fits.minimum_gap_mm > 0


@pytest.mark.parametrize("kwargs, name, allowed", [
    (dict(ply_count=0), "ply_count", "[1, 6]"),
    (dict(ply_count=2.0), "ply_count", "an integer"),
    (dict(twist_angle_deg=60.0), "twist_angle_deg", "[0, 60) °"),
    (dict(twist_angle_deg=-5.0), "twist_angle_deg", "[0, 60) °"),
    (dict(spacing_jitter=0.5), "spacing_jitter", "[0, 0.5)"),
    (dict(height_jitter=-0.1), "height_jitter", "[0, 1)"),
    (dict(ply_radius_jitter=1.0), "ply_radius_jitter", "[0, 1)"),
    (dict(ply_radius_jitter=float("nan")), "ply_radius_jitter", "[0, 1)"),
    (dict(seed=-1), "seed", "an integer"),
    (dict(seed=1.5), "seed", "an integer"),
])
def test_bad_close_up_settings_are_refused_by_name(kwargs, name, allowed):
    with pytest.raises(WeaveParameterError) as refusal:
        WeaveParameters(**kwargs)
    assert refusal.value.name == name and allowed in str(refusal.value)


def test_the_presets_plies_and_twist_build():
    """The medium's own [yarn] values are what the close-up takes (one twist parameter per preset)."""
    yarn = load_preset("voided_red_cotton").yarn
    params = WeaveParameters(warp_count=3, weft_count=3, ply_count=yarn.ply_count, twist_angle_deg=yarn.twist_angle_deg)
    assert params.ply_count == 2 and params.twist_angle_deg == pytest.approx(24.0)
    assert len(build_woven_mesh(params).tube_faces) == 12


# -- a section pressed at the crossings, relaxed between ---------------------------------------------


def ring_semi_axes(mesh, params, yarn):
    """Every ring of a single-ply yarn measured on the mesh: its semi-axes along B and across it in
    the ring's plane (n,), (n,), and that plane's unit normal N (n, 3), from the ring's vertices at
    φ = 0 and π/2 (segments_around a multiple of 4 puts vertices on both axes)."""
    binormal = np.array([0.0, 1.0, 0.0]) if yarn < params.warp_count else np.array([1.0, 0.0, 0.0])
    offsets = tube_rings(mesh, params, yarn, 0) - mesh.centerlines[yarn][:, None]
    top = offsets[:, params.segments_around // 4]
    return np.abs(offsets[:, 0] @ binormal), np.linalg.norm(top, axis=1), top / np.linalg.norm(top, axis=1)[:, None]


#: A relaxing section on a plied, jittered plain weave that clears.
RELAXED = dict(PLIED, semi_axes_mm=(0.12, 0.075), crimp_amplitude_mm=0.085, spacing_mm=0.5, segments_per_crossing=16,
               segments_around=16, section_relaxation=0.75)


@pytest.mark.parametrize("jittered", [False, True])
def test_a_relaxed_section_is_pressed_at_the_crossings_and_rounder_between(jittered):
    single = dict(ply_count=1, ply_radius_jitter=0.0)
    params = WeaveParameters(**RELAXED | single | ({} if jittered else dict(spacing_jitter=0.0, height_jitter=0.0)))
    mesh = build_woven_mesh(params)
    a, b = params.cross_section_mm
    r, segments = params.section_relaxation, params.segments_per_crossing
    first = -(-segments // 2)                      # the ring on the first crossing
    for yarn in (0, params.warp_count + 2):
        width, thickness, _ = ring_semi_axes(mesh, params, yarn)
        crossings = first + segments * np.arange(params.weft_count if yarn < params.warp_count else params.warp_count)
        np.testing.assert_allclose(width[crossings], a, rtol=1e-12)
        np.testing.assert_allclose(thickness[crossings], b, rtol=1e-12)
        midway = crossings[:-1] + segments // 2
        # rounder, as the flattening F^(1 − r) says, and of the same area
        np.testing.assert_allclose(width[midway] / thickness[midway], (a / b) ** (1 - r), rtol=1e-9)
        np.testing.assert_allclose(width[midway] * thickness[midway], a * b, rtol=1e-9)
        # pressed flat on the end pieces beyond the first and last crossing
        np.testing.assert_allclose(width[:first], a, rtol=1e-12)
        np.testing.assert_allclose(thickness[crossings[-1]:], b, rtol=1e-12)


def test_no_relaxation_keeps_the_section_everywhere():
    rigid = dict(RELAXED, section_relaxation=0.0)
    mesh = build_woven_mesh(WeaveParameters(**rigid))
    default = {key: value for key, value in rigid.items() if key != "section_relaxation"}
    np.testing.assert_array_equal(mesh.vertices, build_woven_mesh(WeaveParameters(**default)).vertices)
    params = WeaveParameters(**rigid | dict(ply_count=1, ply_radius_jitter=0.0))
    single = build_woven_mesh(params)
    for yarn in (0, params.warp_count):
        width, thickness, _ = ring_semi_axes(single, params, yarn)
        np.testing.assert_allclose(width, 0.12, rtol=1e-12)
        np.testing.assert_allclose(thickness, 0.075, rtol=1e-12)


def test_relaxed_plies_stay_inside_their_envelope_and_clear_of_the_yarns_they_cross():
    params = WeaveParameters(**RELAXED)
    mesh = build_woven_mesh(params)
    envelope = build_woven_mesh(dataclasses.replace(params, ply_count=1, ply_radius_jitter=0.0))
    for yarn in (0, 1, params.warp_count, params.warp_count + 3):
        width, thickness, normal = ring_semi_axes(envelope, params, yarn)
        binormal = np.array([0.0, 1.0, 0.0]) if yarn < params.warp_count else np.array([1.0, 0.0, 0.0])
        for ply in range(params.ply_count):
            offsets = tube_rings(mesh, params, yarn, ply) - envelope.centerlines[yarn][:, None]
            x = offsets @ binormal / width[:, None]
            y = np.sum(offsets * normal[:, None], axis=-1) / thickness[:, None]
            assert (x**2 + y**2).max() <= 1 + 1e-9
    assert np.ptp(width) > 0.01                                   # the envelope did change along the yarn
    assert not meshes_cross(mesh, params)
    assert params.minimum_gap_mm > 0


def test_a_relaxation_that_makes_yarns_meet_is_refused_naming_what_fits():
    """At the sheeting's density a yarn relaxed to round between crossings is too thick where it bends
    under the yarn it crosses: refused by name, with the largest relaxation that clears; the mesh of
    the refused one (built past the check) does cut into the crossing yarns, the offered one's not."""
    dense = dict(interlacing="plain", warp_count=4, weft_count=4, spacing_mm=0.4, semi_axes_mm=(0.12, 0.075),
                 crimp_amplitude_mm=0.08475, segments_per_crossing=16, segments_around=16)
    WeaveParameters(**dense)                                      # the rigid section clears
    with pytest.raises(WeaveParameterError) as refusal:
        WeaveParameters(**dense, section_relaxation=1.0)
    assert refusal.value.name == "section_relaxation" and "at most " in str(refusal.value)
    largest = float(str(refusal.value).split("at most ")[1].split()[0])
    assert 0.0 < largest < 1.0
    fits = WeaveParameters(**dense, section_relaxation=largest)
    assert fits.minimum_gap_mm > 0 and not meshes_cross(build_woven_mesh(fits), fits)
    object.__setattr__(fits, "section_relaxation", 1.0)
    assert meshes_cross(build_woven_mesh(fits), fits)


@pytest.mark.parametrize("value", [-0.1, 1.5, float("nan")])
def test_a_relaxation_out_of_range_is_refused_by_name(value):
    with pytest.raises(WeaveParameterError) as refusal:
        WeaveParameters(section_relaxation=value)
    assert refusal.value.name == "section_relaxation" and "[0, 1]" in str(refusal.value)



@pytest.mark.parametrize("interlacing", ["plain", "twill_2_2", "twill_3_1"])
def test_the_close_up_default_relaxes_its_section_between_crossings_and_clears(interlacing):
    params = sheeting_weave(warp_count=5, weft_count=5, interlacing=interlacing)
    assert 0 < params.section_relaxation <= 1
    width, _, _ = ring_semi_axes(build_woven_mesh(dataclasses.replace(params, ply_count=1, ply_radius_jitter=0.0)),
                                 params, 0)
    assert width.max() - width.min() > 0.005                     # narrower between crossings than at them, mm
    mesh = build_woven_mesh(params)
    assert not meshes_cross(mesh, params)
    assert params.minimum_gap_mm > 0


@pytest.mark.parametrize("interlacing", ["plain", "twill_2_2", "twill_3_1"])
@pytest.mark.parametrize("yarns", [12, 24])
def test_the_close_up_default_clears_at_sizes_where_a_larger_relaxation_does_not(interlacing, yarns):
    """The relaxation that clears depends on the sample's size (it draws more jitters): 0.375 clears
    16 × 16 but not 12 × 12, 0.5 not 24 × 24; the default must clear them all."""
    params = sheeting_weave(warp_count=yarns, weft_count=yarns, interlacing=interlacing)
    assert params.minimum_gap_mm > 0
    with pytest.raises(WeaveParameterError) as refusal:
        dataclasses.replace(params, section_relaxation=0.375 if yarns == 12 else 0.5)
    assert refusal.value.name == "section_relaxation"
