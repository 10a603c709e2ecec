"""The cloth response traced without Blender (clothlight/garment/traced_response.py): a regular
weave's tile is its sample's own geometry, the tile and the whole sample trace the same samples,
the response is the same bit for bit whatever the threads, and what it sees is the weave's: its
coverage along the normal, every seen point lit when the sun is behind the camera; and the share of
yarn light that meets another yarn, which scales the light between yarns with the density.  Its
agreement with the Cycles measurement is in test_garment_response_render.py."""

import dataclasses

import numpy as np
import pytest
from scipy.spatial import cKDTree

from clothlight.garment import between_yarns
from clothlight.garment.goniometry import plan_sample
from clothlight.garment.tables import lost_to_yarns
from clothlight.garment.traced_response import (
    WovenTracer,
    periodic_repeat_mm,
    tile_of,
    trace_response,
    trace_view,
    yarn_to_yarn_share,
)
from clothlight.weave import WeaveParameters, build_woven_mesh
from clothlight.weave.patterns import twill

VALIDATION_WEAVE = WeaveParameters(warp_count=12, weft_count=12)
#: Small gonioreflectometer settings: N_i, N_o, samples along a patch's side, pixels a patch.
N_I, N_O, SAMPLES, PIXELS = 3, 3, 15, 10


@pytest.mark.parametrize("weave", [VALIDATION_WEAVE, WeaveParameters(warp_count=16, weft_count=16,
                                                                     interlacing=twill(2, 2))],
                         ids=["plain", "twill"])
def test_a_regular_weaves_tile_is_its_samples_own_geometry_moved_by_whole_periods(weave):
    sample = dataclasses.replace(weave, warp_count=48, weft_count=48)
    period = periodic_repeat_mm(sample)
    tile = tile_of(sample, period, reach_mm=1.0)
    assert tile.warp_count < sample.warp_count
    sample_vertices = build_woven_mesh(sample).vertices
    tile_vertices = build_woven_mesh(tile).vertices
    # Away from the tile's yarn ends (caps, and its last ring), where rays never go.
    inner = np.all(np.abs(tile_vertices[:, :2]) < tile.warp_count * weave.spacing_mm / 2.0 - weave.spacing_mm,
                   axis=1)
    tree = cKDTree(sample_vertices)
    for shift in ((0, 0), (period, 0), (-3 * period, 2 * period)):
        distance, _ = tree.query(tile_vertices[inner] + [*shift, 0.0])
        assert distance.max() < 1e-9
    # Half a period off, the weave is another: the check above can fail.
    distance, _ = tree.query(tile_vertices[inner] + [period / 2.0, 0.0, 0.0])
    assert distance.max() > 1e-3


def test_an_irregular_weave_or_plies_are_traced_whole():
    assert periodic_repeat_mm(VALIDATION_WEAVE) == pytest.approx(1.0)
    assert periodic_repeat_mm(dataclasses.replace(VALIDATION_WEAVE, spacing_jitter=0.05)) is None
    assert periodic_repeat_mm(dataclasses.replace(VALIDATION_WEAVE, ply_count=2)) is None


@pytest.fixture(scope="module")
def plan():
    return plan_sample(VALIDATION_WEAVE, N_I, N_O, PIXELS, 1)


def test_the_tile_and_the_whole_sample_trace_the_same_samples(plan):
    tiled, whole = WovenTracer(plan, N_I, N_O), WovenTracer(plan, N_I, N_O, tile=False)
    assert tiled.period is not None and whole.period is None and len(tiled.faces) < len(whole.faces) / 3
    for side, cell in (("front", 4), ("front", 0), ("back", 7)):
        a = trace_view(tiled, side, cell, N_O, SAMPLES, 11)
        b = trace_view(whole, side, cell, N_O, SAMPLES, 11)
        np.testing.assert_allclose(a.counted, b.counted)
        np.testing.assert_allclose(a.covered, b.covered, atol=1e-3 * a.counted.max())
        # The same lit samples, up to a ray that grazes a triangle's edge in float32.
        assert abs(len(a.patch) - len(b.patch)) <= 2e-3 * len(a.patch)
        for name in ("incidence", "exit"):
            first, second = np.sort(getattr(a, name), axis=0), np.sort(getattr(b, name), axis=0)
            shared = min(len(first), len(second))
            assert np.quantile(np.abs(first[:shared] - second[:shared]), 0.99) < 1e-4


@pytest.fixture(scope="module")
def traced():
    return trace_response(VALIDATION_WEAVE, N_I, N_O, samples_per_side=SAMPLES, pixels_per_patch=PIXELS)


def test_the_response_is_the_same_bit_for_bit_whatever_the_threads(traced):
    again = trace_response(VALIDATION_WEAVE, N_I, N_O, samples_per_side=SAMPLES, pixels_per_patch=PIXELS, threads=1)
    for first, second in zip(traced.views, again.views):
        for name in ("patch", "weight", "incidence", "exit", "counted", "covered"):
            assert np.array_equal(getattr(first, name), getattr(second, name)), name
    other_seed = trace_response(VALIDATION_WEAVE, N_I, N_O, samples_per_side=SAMPLES, pixels_per_patch=PIXELS,
                                seed=1)
    assert not np.array_equal(other_seed.views[0].exit, traced.views[0].exit)


def test_seen_along_the_normal_the_cloth_is_covered_as_its_yarns_project():
    """Round yarns of radius 0.1 mm, 0.5 mm apart both ways: 1 − (1 − 0.4)² = 0.64 of the cloth (the
    weave detail render measures 0.6405).  N_o odd puts an exit cell's centre on the normal."""
    response = trace_response(VALIDATION_WEAVE, N_I, N_O, samples_per_side=41, pixels_per_patch=PIXELS)
    normal = (N_O * N_O) // 2
    for side in ("front", "back"):
        assert response.coverage()[side][normal] == pytest.approx(0.64, abs=0.006)


def test_with_the_sun_behind_the_camera_every_seen_point_is_lit(traced):
    """The sun along the view sees what the camera sees: no shadow where the camera looks (the
    normal-incidence region, the normal exit cell), and the directions are the sun's in the yarn frame."""
    normal_view = traced.views[(N_O * N_O) // 2]
    normal_sun = (N_I * N_I) // 2
    in_patch = normal_view.patch == normal_sun
    lit = np.sum(normal_view.weight[in_patch])
    assert lit == pytest.approx(normal_view.covered[normal_sun], rel=5e-3)
    difference = np.abs(normal_view.incidence[in_patch] - normal_view.exit[in_patch]).max(axis=1)
    assert np.quantile(difference, 0.99) < 1e-3  # but at silhouettes, where the view is clamped onto the tables


def test_the_share_of_yarn_light_meeting_another_yarn_grows_with_the_thread_count():
    """Yarns packed closer see more of each other; the validation weave keeps its path-traced q, and
    another density scales it by the two weaves' shares (a 14 threads/cm sample path-traced implied
    0.158 where this gives 0.154, docs/garment.md)."""
    shares = [yarn_to_yarn_share(dataclasses.replace(VALIDATION_WEAVE, spacing_mm=10.0 / n)) for n in (12, 16, 24)]
    assert shares[0] < shares[1] < shares[2] < 1.0
    assert yarn_to_yarn_share(VALIDATION_WEAVE) == yarn_to_yarn_share(VALIDATION_WEAVE)
    assert lost_to_yarns(None) == (between_yarns.LOST_TO_YARNS, {"scaled_by_geometry": False})
    assert lost_to_yarns(VALIDATION_WEAVE)[0] == between_yarns.LOST_TO_YARNS
    sparse, how = lost_to_yarns(dataclasses.replace(VALIDATION_WEAVE, spacing_mm=10.0 / 12))
    assert sparse == pytest.approx(between_yarns.LOST_TO_YARNS * shares[0] / how["yarn_to_yarn_share"]
                                   ["validation_weave"])
    assert sparse < between_yarns.LOST_TO_YARNS


def test_without_embree_every_weave_keeps_the_validation_weaves_q(monkeypatch):
    from clothlight.garment import tables

    monkeypatch.setattr(tables, "tracing_available", lambda: False)
    assert lost_to_yarns(dataclasses.replace(VALIDATION_WEAVE, spacing_mm=10.0 / 12)) == (
        between_yarns.LOST_TO_YARNS, {"scaled_by_geometry": False})
