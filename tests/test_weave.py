"""Procedural woven geometry: drafts, closed tubes that do not intersect, shader attributes,
WIF drafts, export, and refusal of bad input by name."""

import math

import numpy as np
import pytest
import trimesh
from scipy.integrate import quad

from clothlight.weave import (
    BUILT_IN,
    WeaveParameterError,
    WeaveParameters,
    build_woven_mesh,
    crossing_gaps,
    export_mesh,
    format_wif,
    parse_wif,
    read_wif,
    satin,
    satin_moves,
    twill,
    validate_interlacing,
    weave_pattern,
    write_wif,
)


def repeat_params(name, **kwargs):
    """A sample one repeat plus one yarn wide, so every crossing kind of the pattern occurs."""
    rows, cols = weave_pattern(name).shape
    return WeaveParameters(interlacing=name, warp_count=cols + 1, weft_count=rows + 1, **kwargs)


# -- independent geometric checks --------------------------------------------------------------


def segments_cross_triangles(starts, ends, triangles):
    """True where any segment (S, 3)→(S, 3) crosses any triangle (T, 3, 3) (Möller–Trumbore), tested
    on the pairs whose bounding boxes overlap."""
    low = np.minimum(starts, ends)[:, None, :] <= triangles.max(axis=1)[None]
    high = np.maximum(starts, ends)[:, None, :] >= triangles.min(axis=1)[None]
    segment, triangle = np.nonzero(np.all(low & high, axis=-1))
    direction = ends[segment] - starts[segment]
    a, b, c = (triangles[triangle, k, :] for k in range(3))
    e1, e2 = b - a, c - a
    p = np.cross(direction, e2)
    det = np.sum(e1 * p, axis=-1)
    ok = np.abs(det) > 1e-18
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    t_vec = starts[segment] - a
    u = np.sum(t_vec * p, axis=-1) * inv
    q = np.cross(t_vec, e1)
    v = np.sum(direction * q, axis=-1) * inv
    t = np.sum(e2 * q, axis=-1) * inv
    return bool(np.any(ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t >= 0) & (t <= 1)))


def meshes_cross(mesh, params):
    """Whether an edge of any warp passes through a triangle of any weft or the other way round,
    checked near every crossing (the only place they can meet)."""
    warps, wefts = params.warp_count, params.weft_count
    a, b = params.cross_section_mm
    reach = a + b + params.spacing_mm / params.segments_per_crossing
    tubes = [mesh.yarn_mesh(y) for y in range(warps + wefts)]
    for warp in range(warps):
        for weft in range(wefts):
            x0 = mesh.centerlines[warps + weft][0, 0]
            y0 = mesh.centerlines[warp][0, 1]
            near = []
            for tube in (tubes[warp], tubes[warps + weft]):
                v = tube.vertices
                inside = (np.abs(v[:, 0] - x0) < reach) & (np.abs(v[:, 1] - y0) < reach)
                edges = tube.edges_unique[inside[tube.edges_unique].any(axis=1)]
                faces = tube.faces[inside[tube.faces].any(axis=1)]
                near.append((v[edges[:, 0]], v[edges[:, 1]], v[faces]))
            (s0, e0, t0), (s1, e1, t1) = near
            if segments_cross_triangles(s0, e0, t1) or segments_cross_triangles(s1, e1, t0):
                return True
    return False


def distance_to_polyline(points, polyline):
    """Euclidean distance from each point (P, d) to a polyline (K, d)."""
    a, b = polyline[:-1], polyline[1:]
    ab = b - a
    t = np.clip(np.einsum("pkd,kd->pk", points[:, None, :] - a[None], ab) / np.sum(ab * ab, axis=1), 0.0, 1.0)
    closest = a[None] + t[..., None] * ab[None]
    return np.linalg.norm(points[:, None, :] - closest, axis=-1).min(axis=1)


def depth_inside_tube(points, centerline, lateral_axis, semi_axes):
    """How deep points lie inside an elliptical tube around a planar centreline whose plane is
    normal to ``lateral_axis`` (0: x, 1: y); ≤ 0 outside.  At lateral offset η the tube is the
    set within b·√(1 − η²/a²) of the centreline in its plane."""
    a, b = semi_axes
    eta = points[:, lateral_axis] - centerline[0, lateral_axis]
    keep = 1 - lateral_axis
    depth = np.full(len(points), -np.inf)
    within = np.abs(eta) < a  # only these can be inside; the distances of the rest cost the most
    half = b * np.sqrt(1.0 - (eta[within] / a) ** 2)
    depth[within] = half - distance_to_polyline(points[within][:, [keep, 2]], centerline[:, [keep, 2]])
    return depth


def deepest_penetration(params):
    """Deepest any vertex of any yarn lies inside a crossing yarn's exact tube, mm.

    Vertices lie on the exact surface; the crossing yarn's centreline is taken from a 64-times
    finer sweep, so the polyline is exact to ~1e-6 mm."""
    fine = build_woven_mesh(WeaveParameters(
        interlacing=params.interlacing, warp_count=params.warp_count, weft_count=params.weft_count,
        spacing_mm=params.spacing_mm, semi_axes_mm=params.cross_section_mm,
        crimp_amplitude_mm=params.crimp_amplitudes_mm, segments_per_crossing=64))
    mesh = build_woven_mesh(params)
    deepest = -np.inf
    warps = params.warp_count
    for yarn in range(warps + params.weft_count):
        points = mesh.vertices[mesh.yarn_id == yarn]
        others = range(warps, warps + params.weft_count) if yarn < warps else range(warps)
        for other in others:
            lateral = 0 if other >= warps else 1   # a weft's plane is normal to x, a warp's to y
            depth = depth_inside_tube(points, fine.centerlines[other], lateral, params.cross_section_mm)
            deepest = max(deepest, float(depth.max()))
    return deepest


# -- every built-in pattern --------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(BUILT_IN))
def test_every_built_in_pattern_gives_closed_yarns_that_do_not_intersect(name):
    params = repeat_params(name)
    mesh = build_woven_mesh(params)
    assert len(mesh.yarn_faces) == params.warp_count + params.weft_count
    for yarn in range(len(mesh.yarn_faces)):
        tube = mesh.yarn_mesh(yarn)
        assert tube.is_watertight and tube.is_winding_consistent
        assert tube.euler_number == 2          # a closed tube: a sphere topologically
        assert tube.volume > 0                 # faces point outward
    assert not meshes_cross(mesh, params)
    assert params.minimum_gap_mm > 0


def test_the_clearance_checks_see_a_yarn_pushed_into_another():
    """The two checks above report a crossing once one weft is raised by its thickness (into the
    warps it passes under)."""
    params = repeat_params("plain")
    mesh = build_woven_mesh(params)
    weft = params.warp_count
    mesh.vertices[mesh.yarn_id == weft, 2] += 2 * params.cross_section_mm[1]
    assert meshes_cross(mesh, params)
    points = mesh.vertices[mesh.yarn_id == weft]
    depths = [depth_inside_tube(points, mesh.centerlines[warp], 1, params.cross_section_mm).max()
              for warp in range(params.warp_count)]
    assert max(depths) > 0.5 * params.cross_section_mm[1]


@pytest.mark.parametrize("name", ["plain", "twill_3_1", "satin_8"])
def test_no_vertex_enters_a_crossing_yarn(name):
    """The brief's check: every surface point stays a radius away from the other yarns' axes."""
    params = repeat_params(name)
    assert deepest_penetration(params) < 0.0


def test_elliptical_yarns_are_closed_and_clear_and_too_flat_ones_are_refused():
    flat = dict(interlacing="twill_2_1", warp_count=4, weft_count=4, semi_axes_mm=(0.16, 0.06))
    # the exact tubes clear, but 8 chords per spacing would cut into the crossing yarns
    with pytest.raises(WeaveParameterError, match="segments_per_crossing") as refused:
        WeaveParameters(**flat)
    finer = int(str(refused.value).split("≥ ")[1].split()[0])
    params = WeaveParameters(**flat, segments_per_crossing=finer)
    mesh = build_woven_mesh(params)
    assert all(mesh.yarn_mesh(y).is_watertight for y in range(8))
    assert not meshes_cross(mesh, params)
    assert deepest_penetration(params) < 0.0
    # the cross-section really is the ellipse: a ring at a crossing spans twice the semi-axes
    ring = mesh.vertices[: params.segments_around] - mesh.centerlines[0][0]
    np.testing.assert_allclose(np.ptp(ring[:, 1]) / 2, 0.16)
    np.testing.assert_allclose(np.ptp(ring[:, 2]) / 2, 0.06)
    # wider still, a yarn cannot bend down within the width of the yarn it crosses
    with pytest.raises(WeaveParameterError, match="semi_axes_mm"):
        WeaveParameters(semi_axes_mm=(0.18, 0.05))


# -- clearance -----------------------------------------------------------------------------


def test_gap_at_an_isolated_crossing_is_the_crimp_minus_the_thickness():
    """Far apart, yarns only come close at the crossing: gap = h_warp + h_weft − 2b."""
    gaps = crossing_gaps(weave_pattern("plain"), 2.0, (0.1, 0.08), (0.05, 0.13))
    np.testing.assert_allclose(gaps, 0.05 + 0.13 - 2 * 0.08, atol=1e-12)


def test_largest_radius_in_the_error_is_tight():
    """The radius the error offers clears, and only just: centrelines of round yarns 0.5 % thicker
    (with their derived crimp, built here around thinner yarns) come closer than 2r."""
    fine = dict(segments_per_crossing=64, warp_count=3, weft_count=3)
    with pytest.raises(WeaveParameterError, match="yarn_radius_mm") as refused:
        WeaveParameters(yarn_radius_mm=0.2, **fine)
    largest = float(str(refused.value).split("at most ")[1].split(" mm")[0])
    assert 0.1 < largest < 0.2
    WeaveParameters(yarn_radius_mm=largest, **fine)
    for factor in (0.995, 1.005):
        radius = factor * largest
        probe = build_woven_mesh(WeaveParameters(yarn_radius_mm=0.05, crimp_amplitude_mm=1.02 * radius, **fine))
        warps, wefts = probe.centerlines[:3], probe.centerlines[3:]
        closest = min(np.linalg.norm(w[:, None] - f[None], axis=-1).min() for w in warps for f in wefts)
        assert (closest > 2 * radius) == (factor < 1)


def test_round_yarn_gaps_agree_with_centreline_distances():
    """For round yarns the tubes meet exactly when the centrelines come closer than 2r."""
    radius = 0.1
    for spacing in (0.41, 0.43, 0.47, 0.6):
        params = WeaveParameters(spacing_mm=spacing, yarn_radius_mm=radius, warp_count=3, weft_count=3,
                                 segments_per_crossing=128)
        mesh = build_woven_mesh(params)
        warp, weft = mesh.centerlines[1], mesh.centerlines[4]
        distance = np.linalg.norm(warp[:, None, :] - weft[None, :, :], axis=-1).min() - 2 * radius
        assert params.minimum_gap_mm == pytest.approx(distance, abs=3e-4)


# -- attributes and frame ------------------------------------------------------------------


def test_attributes_have_the_documented_shapes_and_ranges():
    params = WeaveParameters(interlacing="twill_2_1", warp_count=3, weft_count=4)
    mesh = build_woven_mesh(params)
    n = len(mesh.vertices)
    assert mesh.vertices.shape == (n, 3) and mesh.faces.shape[1] == 3
    for array, width in ((mesh.uv, 2), (mesh.tangent, 3), (mesh.cloth_normal, 3)):
        assert array.shape == (n, width)
    assert mesh.yarn_id.shape == mesh.is_warp.shape == (n,) and mesh.is_warp.dtype == bool
    np.testing.assert_allclose(np.linalg.norm(mesh.tangent, axis=1), 1.0)
    np.testing.assert_array_equal(mesh.cloth_normal, np.tile([0, 0, 1.0], (n, 1)))
    assert np.all((mesh.uv[:, 1] >= 0) & (mesh.uv[:, 1] < 1))
    assert sorted(set(mesh.yarn_id.tolist())) == list(range(7))
    np.testing.assert_array_equal(mesh.is_warp, mesh.yarn_id < 3)
    # warps run along x within their semi-axis of their plane y = const; wefts along y
    for yarn in range(7):
        v, t = mesh.vertices[mesh.yarn_id == yarn], mesh.tangent[mesh.yarn_id == yarn]
        lateral = 1 if yarn < 3 else 0
        assert np.ptp(v[:, lateral]) <= 2 * params.cross_section_mm[0] + 1e-12
        steepest = params.crimp_amplitudes_mm[0] * math.pi / params.spacing_mm
        assert np.all(np.abs(t[:, 1 - lateral]) >= 1 / math.hypot(1, steepest) - 1e-12)
    assert mesh.vertices[:, 0].min() == pytest.approx(-params.sample_size_mm[0] / 2)
    assert mesh.vertices[:, 1].max() == pytest.approx(params.sample_size_mm[1] / 2)


def test_tangent_u_and_v_follow_the_geometry():
    params = WeaveParameters(warp_count=3, weft_count=3, segments_around=8)
    mesh = build_woven_mesh(params)
    # a sweep 8 times finer gives the centreline's direction at the same rings by differences
    fine = build_woven_mesh(WeaveParameters(warp_count=3, weft_count=3, segments_per_crossing=64))
    around = params.segments_around
    for yarn, centre in enumerate(mesh.centerlines):
        start = int(np.flatnonzero(mesh.yarn_id == yarn)[0])
        rings = len(centre)
        ring_tangent = mesh.tangent[start:start + rings * around:around]
        direction = np.gradient(fine.centerlines[yarn], axis=0)[::8]
        direction /= np.linalg.norm(direction, axis=1, keepdims=True)
        np.testing.assert_allclose(fine.centerlines[yarn][::8], centre)
        assert np.min(np.sum(ring_tangent * direction, axis=1)) > 1 - 1e-4   # 1° at a curvature jump
        # u is the arc length of the centreline, mm
        u = mesh.uv[start:start + rings * around:around, 0]
        arc = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(centre, axis=0), axis=1))])
        np.testing.assert_allclose(u, arc)
        # v is the angle around the yarn: 0.25 on top, 0.75 underneath, both in the yarn's
        # vertical plane and square to its axis
        offsets = mesh.vertices[start:start + rings * around].reshape(rings, around, 3) - centre[:, None]
        v = mesh.uv[start:start + rings * around, 1].reshape(rings, around)
        lateral = 1 if yarn < 3 else 0
        for quarter, sign in ((0.25, 1), (0.75, -1)):
            column = np.flatnonzero(v[0] == quarter)[0]
            offset = offsets[:, column]
            np.testing.assert_allclose(offset[:, lateral], 0.0, atol=1e-15)
            np.testing.assert_allclose(np.sum(offset * ring_tangent, axis=1), 0.0, atol=1e-15)
            np.testing.assert_allclose(np.linalg.norm(offset, axis=1), params.cross_section_mm[1])
            assert np.all(sign * offset[:, 2] > 0)


def test_sweep_frame_never_rotates_about_the_yarn():
    """Vertex k of every ring points the same way around the yarn as in the ring before: the
    angle between consecutive offsets, seen along the tangent, is zero everywhere (no seam)."""
    params = WeaveParameters(interlacing="satin_5", warp_count=6, weft_count=6, semi_axes_mm=(0.14, 0.08))
    mesh = build_woven_mesh(params)
    around = params.segments_around
    for yarn, centre in enumerate(mesh.centerlines):
        start = int(np.flatnonzero(mesh.yarn_id == yarn)[0])
        rings = len(centre)
        offsets = mesh.vertices[start:start + rings * around].reshape(rings, around, 3) - centre[:, None]
        tangent = mesh.tangent[start:start + rings * around:around]
        axis = tangent[1:] + tangent[:-1]
        axis /= np.linalg.norm(axis, axis=1, keepdims=True)
        here, there = offsets[:-1, 0], offsets[1:, 0]
        here = here - np.sum(here * axis, 1, keepdims=True) * axis
        there = there - np.sum(there * axis, 1, keepdims=True) * axis
        twist = np.arctan2(np.sum(np.cross(here, there) * axis, 1), np.sum(here * there, 1))
        assert np.max(np.abs(twist)) < 1e-9


def test_corner_uv_closes_the_seam():
    mesh = build_woven_mesh(WeaveParameters(warp_count=2, weft_count=2))
    corners = mesh.corner_uv()
    side = np.ones(len(mesh.faces), bool)
    for start, stop in mesh.yarn_faces:
        side[stop - 2 * mesh.segments_around:stop] = False
    v = corners[side, :, 1]
    assert np.ptp(v, axis=1).max() == pytest.approx(1 / mesh.segments_around)
    assert (v == 1.0).any()
    np.testing.assert_array_equal(corners[..., 0], mesh.uv[mesh.faces, 0])


def test_edge_topology_lists_every_edge_once():
    mesh = build_woven_mesh(WeaveParameters(interlacing="twill_2_2", warp_count=3, weft_count=2))
    edges, corner_edges = mesh.edge_topology()
    corners = np.stack([mesh.faces, np.roll(mesh.faces, -1, axis=1)], -1)
    np.testing.assert_array_equal(np.sort(edges[corner_edges], axis=-1), np.sort(corners, axis=-1))
    assert len(np.unique(np.sort(edges, axis=1), axis=0)) == len(edges)
    assert len(edges) == len(mesh.to_trimesh().edges_unique)


# -- the weave itself ----------------------------------------------------------------------


def test_yarns_go_over_and_under_as_the_matrix_says():
    params = WeaveParameters(interlacing="twill_3_1", warp_count=4, weft_count=4)
    mesh = build_woven_mesh(params)
    over = np.zeros((4, 4), bool)
    for j in range(4):
        warp = mesh.centerlines[j]
        for i in range(4):
            weft = mesh.centerlines[4 + i]
            x, y = weft[0, 0], warp[0, 1]
            warp_z = warp[np.argmin(np.abs(warp[:, 0] - x)), 2]
            weft_z = weft[np.argmin(np.abs(weft[:, 1] - y)), 2]
            over[i, j] = warp_z > weft_z
    np.testing.assert_array_equal(over, np.tile(twill(3, 1), (1, 1)))


@pytest.mark.parametrize("direction", ["Z", "S"])
def test_twill_diagonal_shows_its_direction_on_the_face(direction):
    """Seen from +z with the warp (x) pointing up, right is −y: a Z twill's warp floats climb to
    the right, an S twill's to the left."""
    params = WeaveParameters(interlacing=twill(2, 2, direction), warp_count=8, weft_count=8)
    mesh = build_woven_mesh(params)
    p = params.spacing_mm
    top = {}
    for j in range(8):
        warp = mesh.centerlines[j]
        for i in range(8):
            x = mesh.centerlines[8 + i][0, 0]
            top[round(x / p - 0.5), round(warp[0, 1] / p - 0.5)] = warp[np.argmin(np.abs(warp[:, 0] - x)), 2] > 0
    right = -1 if direction == "Z" else 1          # y step of the diagonal per pick up
    shifted = [top[x, y] == top[x + 1, y + right] for (x, y) in top if (x + 1, y + right) in top]
    against = [top[x, y] == top[x + 1, y - right] for (x, y) in top if (x + 1, y - right) in top]
    assert all(shifted) and not all(against)


def test_patterns_interlace_as_their_drafts_say():
    assert validate_interlacing(twill(2, 1)).sum(axis=0).tolist() == [2, 2, 2]
    assert satin_moves(5) == (2, 3) and satin_moves(8) == (3, 5)
    for harness, move in ((5, 2), (5, 3), (8, 3), (8, 5)):
        s = ~satin(harness, move)
        assert s.sum(axis=0).tolist() == [1] * harness and s.sum(axis=1).tolist() == [1] * harness
        rows, cols = np.nonzero(s)
        for r, c in zip(rows, cols):  # no two interlacings touch, even diagonally
            for dc in (-1, 0, 1):
                assert not s[(r + 1) % harness, (c + dc) % harness]
    np.testing.assert_array_equal(satin(5, warp_faced=False), ~satin(5))
    basket = weave_pattern("basket")
    assert basket.shape == (4, 4) and (basket[0] == basket[1]).all() and (basket[:, 0] == basket[:, 1]).all()
    np.testing.assert_array_equal(weave_pattern("twill_2_2", direction="S"), twill(2, 2, "S"))
    np.testing.assert_array_equal(weave_pattern("satin_8", move=5), satin(8, 5))


def test_crimp_follows_the_interlacing():
    """Crimp (yarn length over cloth length − 1) is the arc length of the half-cosine path:
    plain weave changes sides at every crossing, twills and satins less often."""
    h, p = 0.102, 0.5
    per_change, _ = quad(lambda x: math.sqrt(1 + (h * math.pi / p * math.sin(math.pi * x / p)) ** 2), 0, p)
    plain_crimp = WeaveParameters().crimp_percent
    assert plain_crimp[0] == pytest.approx((per_change / p - 1) * 100, rel=1e-6)
    assert plain_crimp[0] == pytest.approx(plain_crimp[1])
    twill_crimp = WeaveParameters(interlacing="twill_2_1").crimp_percent[0]
    satin_crimp = WeaveParameters(interlacing="satin_8").crimp_percent[0]
    assert twill_crimp == pytest.approx(plain_crimp[0] * 2 / 3, rel=1e-6)   # 2 changes in 3
    assert plain_crimp[0] > twill_crimp > satin_crimp > 0
    # a flatter override lowers it
    assert WeaveParameters(crimp_amplitude_mm=(0.02, 0.2)).crimp_percent[0] < plain_crimp[0]


def test_sample_size_sets_the_counts():
    params = WeaveParameters.for_sample_size((2.0, 3.0), spacing_mm=0.5)
    assert (params.weft_count, params.warp_count) == (4, 6)
    assert params.sample_size_mm == (2.0, 3.0)
    with pytest.raises(WeaveParameterError, match="sample_size_mm"):
        WeaveParameters.for_sample_size((2.2, 3.0))


# -- WIF drafts ----------------------------------------------------------------------------

STRAIGHT_DRAW_TWILL = """\
; a 2/2 twill on four shafts, straight draw, in WIF 1.1
[WIF]
Version=1.1
Date=April 20, 1997
Developers=wif@mhsoft.com
Source Program=hand

[CONTENTS]
WEAVING=true
WARP=true
WEFT=true
THREADING=true
TIEUP=true
TREADLING=true

[TEXT]
Title=straight twill

[WEAVING]
Shafts=4
Treadles=4
Rising Shed=true

[WARP]
Threads=8
Spacing=0.05
Units=centimeters

[WEFT]
Threads=4
Spacing=0.02
Units=inches

[THREADING]
1=1
2=2
3=3
4=4
5=1
6=2
7=3
8=4

[TIEUP]
1=1,2
2=2,3
3=3,4
4=4,1

[TREADLING]
1=1
2=2
3=3
4=4
"""


def test_wif_draft_weaves_what_the_loom_would():
    draft = parse_wif(STRAIGHT_DRAW_TWILL)
    # pick i lifts shafts i+1 and i+2: end j rises when (j − i) mod 4 < 2, a Z 2/2 twill
    np.testing.assert_array_equal(draft.interlacing, np.tile(twill(2, 2, "Z"), (1, 2)))
    assert draft.title == "straight twill"
    assert draft.warp_spacing_mm == pytest.approx(0.5) and draft.weft_spacing_mm == pytest.approx(0.508)
    sinking = parse_wif(STRAIGHT_DRAW_TWILL.replace("Rising Shed=true", "Rising Shed=false"))
    np.testing.assert_array_equal(sinking.interlacing, ~draft.interlacing)
    lifted = STRAIGHT_DRAW_TWILL.split("[TIEUP]")[0] + "[LIFTPLAN]\n1=1,2\n2=2,3\n3=3,4\n4=4,1\n"
    np.testing.assert_array_equal(parse_wif(lifted).interlacing, draft.interlacing)


@pytest.mark.parametrize("name", sorted(BUILT_IN))
def test_wif_round_trip(name, tmp_path):
    matrix = weave_pattern(name)
    path = write_wif(matrix, tmp_path / f"{name}.wif", spacing_mm=0.4)
    draft = read_wif(path)
    np.testing.assert_array_equal(draft.interlacing, matrix)
    assert draft.warp_spacing_mm == pytest.approx(0.4)


def test_wif_round_trip_of_an_irregular_matrix():
    rng = np.random.default_rng(7)
    while True:
        matrix = rng.random((7, 9)) < 0.5
        try:
            validate_interlacing(matrix)
            break
        except WeaveParameterError:
            continue
    np.testing.assert_array_equal(parse_wif(format_wif(matrix)).interlacing, matrix)


def test_bad_wif_is_refused_by_name(tmp_path):
    with pytest.raises(WeaveParameterError, match=r"\[THREADING\]"):
        parse_wif("[WIF]\nVersion=1.1\n")
    unthreaded = STRAIGHT_DRAW_TWILL.replace("8=4\n\n[TIEUP]", "8=0\n\n[TIEUP]")
    with pytest.raises(WeaveParameterError, match=r"interlacing end \(column\) 7"):
        parse_wif(unthreaded)
    with pytest.raises(WeaveParameterError, match=r"\[TIEUP\] 2"):
        parse_wif(STRAIGHT_DRAW_TWILL.replace("2=2,3", "2=2,x"))
    with pytest.raises(WeaveParameterError, match="Units"):
        parse_wif(STRAIGHT_DRAW_TWILL.replace("Units=inches", "Units=furlongs"))
    with pytest.raises(WeaveParameterError, match="path"):
        read_wif(tmp_path / "missing.wif")


# -- export --------------------------------------------------------------------------------


def test_ply_export_keeps_geometry_and_attributes(tmp_path):
    mesh = build_woven_mesh(WeaveParameters(interlacing="twill_2_1", warp_count=3, weft_count=3))
    path = export_mesh(mesh, tmp_path / "sample.ply")
    loaded = trimesh.load(path, process=False, force="mesh")
    np.testing.assert_array_equal(loaded.faces, mesh.faces)
    np.testing.assert_allclose(loaded.vertices, mesh.vertices, atol=1e-5)
    assert loaded.is_watertight
    raw = loaded.metadata["_ply_raw"]["vertex"]["data"]
    np.testing.assert_allclose(raw["u"].ravel(), mesh.uv[:, 0], rtol=1e-6)
    np.testing.assert_allclose(raw["v"].ravel(), mesh.uv[:, 1], atol=1e-7)
    np.testing.assert_allclose(np.stack([raw[f"tangent_{c}"].ravel() for c in "xyz"], -1), mesh.tangent, atol=1e-6)
    np.testing.assert_array_equal(raw["yarn_id"].ravel(), mesh.yarn_id)
    np.testing.assert_array_equal(raw["is_warp"].ravel().astype(bool), mesh.is_warp)


def test_obj_export_carries_seam_correct_uvs(tmp_path):
    mesh = build_woven_mesh(WeaveParameters(warp_count=2, weft_count=2))
    path = export_mesh(mesh, tmp_path / "sample.obj")
    loaded = trimesh.load(path, process=False, force="mesh", maintain_order=True)
    assert len(loaded.faces) == len(mesh.faces)
    np.testing.assert_allclose(loaded.vertices[loaded.faces], mesh.vertices[mesh.faces], atol=1e-7)
    np.testing.assert_allclose(loaded.visual.uv[loaded.faces], mesh.corner_uv(), atol=1e-7)
    merged = trimesh.Trimesh(loaded.vertices, loaded.faces)   # welding the seam copies closes it
    assert merged.is_watertight
    with pytest.raises(WeaveParameterError, match="path"):
        export_mesh(mesh, tmp_path / "sample.stl")


# -- bad input -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"warp_count": 0}, "warp_count"),
        ({"weft_count": -2}, "weft_count"),
        ({"warp_count": 2.0}, "warp_count"),
        ({"weft_count": True}, "weft_count"),
        ({"spacing_mm": 0.0}, "spacing_mm"),
        ({"spacing_mm": float("nan")}, "spacing_mm"),
        ({"yarn_radius_mm": -0.1}, "yarn_radius_mm"),
        ({"yarn_radius_mm": 0.3}, "yarn_radius_mm"),               # wider than the spacing
        ({"yarn_radius_mm": 0.2}, "yarn_radius_mm"),               # cannot bend past its neighbours
        ({"semi_axes_mm": (0.3, 0.1)}, "semi_axes_mm"),
        ({"semi_axes_mm": (0.1,)}, "semi_axes_mm"),
        ({"semi_axes_mm": (0.2, 0.2)}, "semi_axes_mm"),
        ({"yarn_radius_mm": 0.1, "semi_axes_mm": (0.1, 0.1)}, "semi_axes_mm"),
        ({"crimp_amplitude_mm": 0.05}, "crimp_amplitude_mm"),     # crossing yarns would touch
        ({"crimp_amplitude_mm": (0.3, 0.0)}, "crimp_amplitude_mm"),  # too steep a bend
        ({"crimp_amplitude_mm": -0.2}, "crimp_amplitude_mm"),
        ({"crimp_amplitude_mm": "high"}, "crimp_amplitude_mm"),
        ({"segments_around": 2}, "segments_around"),
        ({"segments_around": 257}, r"segments_around.*\[3, 256\]"),
        ({"warp_count": 1001}, r"warp_count.*\[1, 1000\]"),
        ({"weft_count": 2.0}, "weft_count"),
        ({"warp_count": 1000, "weft_count": 1000}, r"at most 2e\+07 vertices"),  # a 10⁸-vertex mesh
        ({"segments_per_crossing": 1}, "segments_per_crossing"),
        ({"segments_per_crossing": 4}, "segments_per_crossing"),  # chords would cut into crossing yarns
        ({"interlacing": np.zeros((0, 0))}, "interlacing"),
        ({"interlacing": [1, 0, 1]}, "interlacing"),
        ({"interlacing": [[1, 2], [0, 1]]}, "interlacing"),
        ({"interlacing": [[1, 1], [0, 0]]}, r"interlacing pick \(row\) 0"),
        ({"interlacing": [[1, 0], [1, 0]]}, r"interlacing end \(column\) 0"),
        ({"interlacing": "herringbone"}, "pattern"),
    ],
)
def test_bad_input_is_refused_by_name(kwargs, name):
    with pytest.raises(WeaveParameterError, match=name) as refused:
        WeaveParameters(**kwargs)
    assert isinstance(refused.value, ValueError)
    assert "allowed" in str(refused.value)


def test_bad_pattern_options_are_refused_by_name():
    with pytest.raises(WeaveParameterError, match="satin move"):
        satin(8, 2)
    with pytest.raises(WeaveParameterError, match="satin harness"):
        satin(6)
    with pytest.raises(WeaveParameterError, match="twill direction"):
        twill(2, 1, "X")
    with pytest.raises(WeaveParameterError, match="twill_2_1 option"):
        weave_pattern("twill_2_1", move=3)
