"""Procedural woven geometry: patterns, watertight yarns that do not intersect, shader attributes."""

import numpy as np
import pytest
import trimesh

from clothlight.weave import (
    BUILT_IN,
    WeaveParameterError,
    WeaveParameters,
    build_woven_mesh,
    minimum_clearance,
    satin,
    twill,
    validate_interlacing,
    weave_pattern,
)


@pytest.mark.parametrize("name", sorted(BUILT_IN))
def test_every_built_in_pattern_gives_closed_separate_yarns(name):
    params = WeaveParameters(interlacing=weave_pattern(name), warp_count=6, weft_count=6)
    mesh = build_woven_mesh(params)
    assert len(mesh.yarn_faces) == 12
    for yarn in range(12):
        tube = mesh.yarn_mesh(yarn)
        assert tube.is_watertight and tube.is_winding_consistent
        assert tube.volume > 0  # faces point outward
    assert minimum_clearance(mesh, params) > 0.0


def test_patterns_interlace_as_their_drafts_say():
    assert validate_interlacing(twill(2, 1)).sum(axis=1).tolist() == [2, 2, 2]
    z, s = twill(2, 2, "Z"), twill(2, 2, "S")
    for row in range(3):  # the diagonal climbs right for Z, left for S
        np.testing.assert_array_equal(z[row + 1], np.roll(z[row], 1))
        np.testing.assert_array_equal(s[row + 1], np.roll(s[row], -1))
    s5 = satin(5)
    assert (~s5).sum(axis=0).tolist() == [1] * 5 and (~s5).sum(axis=1).tolist() == [1] * 5
    # no two interlacings of a satin touch, even diagonally
    rows, cols = np.nonzero(~s5)
    for r, c in zip(rows, cols):
        assert not (~s5)[(r + 1) % 5, (c + 1) % 5] and not (~s5)[(r + 1) % 5, (c - 1) % 5]


def test_yarns_go_over_and_under_as_the_matrix_says():
    params = WeaveParameters(warp_count=2, weft_count=2, segments_per_crossing=4)
    mesh = build_woven_mesh(params)
    warp0 = mesh.centerlines[0]  # runs along x at y = -spacing/2, crossings at x = ±spacing/2
    at_crossing = warp0[np.argmin(np.abs(warp0[:, 0] + params.spacing_mm / 2))]
    assert at_crossing[2] == pytest.approx(params.crimp_amplitude)  # matrix[0, 0]: warp over weft 0
    weft0 = mesh.centerlines[2]
    assert weft0[np.argmin(np.abs(weft0[:, 1] + params.spacing_mm / 2))][2] == pytest.approx(-params.crimp_amplitude)


def test_attributes_follow_the_geometry():
    params = WeaveParameters(interlacing=weave_pattern("twill_2_1"), warp_count=3, weft_count=3)
    mesh = build_woven_mesh(params)
    n = len(mesh.vertices)
    for array, width in ((mesh.uv, 2), (mesh.tangent, 3), (mesh.cloth_normal, 3)):
        assert array.shape == (n, width)
    np.testing.assert_allclose(np.linalg.norm(mesh.tangent, axis=1), 1.0)
    assert np.all((mesh.uv[:, 1] >= 0) & (mesh.uv[:, 1] < 1))
    np.testing.assert_array_equal(mesh.cloth_normal, np.tile([0, 0, 1.0], (n, 1)))
    assert set(mesh.yarn_id.tolist()) == set(range(6)) and mesh.is_warp.sum() == np.sum(mesh.yarn_id < 3)
    # the tangent points along the centreline; u grows with arc length
    warp = mesh.centerlines[0]
    direction = np.diff(warp, axis=0)
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    ring_tangents = mesh.tangent[: len(warp) * params.segments_around : params.segments_around]
    assert np.min(np.sum(ring_tangents[1:] * direction, axis=1)) > 0.98
    u = mesh.uv[: len(warp) * params.segments_around : params.segments_around, 0]
    assert np.all(np.diff(u) > 0)


def test_sweep_has_no_twist():
    """Vertex k of every ring lies on the same side of its centreline: the frame never rotates."""
    params = WeaveParameters(warp_count=2, weft_count=4, segments_around=8)
    mesh = build_woven_mesh(params)
    around = params.segments_around
    warp = mesh.centerlines[0]
    rings = mesh.vertices[: len(warp) * around].reshape(len(warp), around, 3) - warp[:, None, :]
    # vertex 0 points along the warp's in-plane binormal (+y), vertex around/4 along T × B (up)
    tangent = np.gradient(warp, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    up = np.cross(tangent, [0.0, 1.0, 0.0])
    np.testing.assert_allclose(rings[:, 0], np.tile([0, params.semi_axes_mm[0], 0], (len(warp), 1)), atol=1e-12)
    np.testing.assert_allclose(np.sum(rings[:, around // 4] * up, axis=1), params.semi_axes_mm[1], rtol=0.02)


def test_export_for_other_renderers(tmp_path):
    mesh = build_woven_mesh(WeaveParameters(warp_count=2, weft_count=2))
    for suffix in ("ply", "obj"):
        path = tmp_path / f"sample.{suffix}"
        mesh.to_trimesh().export(path)
        loaded = trimesh.load(path, process=False, force="mesh")
        assert len(loaded.faces) == len(mesh.faces)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"warp_count": 0}, "warp_count"),
        ({"weft_count": -2}, "weft_count"),
        ({"semi_axes_mm": (0.3, 0.1)}, "semi_axes_mm"),
        ({"spacing_mm": 0.2}, "spacing_mm"),
        ({"crimp_amplitude_mm": 0.05}, "crimp_amplitude_mm"),
        ({"interlacing": np.zeros((0, 0))}, "interlacing"),
        ({"interlacing": [[1, 2], [0, 1]]}, "interlacing"),
        ({"interlacing": [[1, 1], [0, 0]]}, "interlacing weft row"),
        ({"interlacing": [[1, 0], [1, 0]]}, "interlacing warp column"),
    ],
)
def test_bad_input_is_refused_by_name(kwargs, name):
    with pytest.raises(WeaveParameterError, match=name):
        WeaveParameters(**kwargs)


def test_unknown_pattern_names_the_choices():
    with pytest.raises(WeaveParameterError, match="plain"):
        weave_pattern("herringbone")
