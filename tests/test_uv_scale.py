"""The weave's scale on a garment: one UV unit's length on the mesh (clothlight/garment/uv_scale.py)."""

from __future__ import annotations

import numpy as np
import pytest

from clothlight.garment.uv_scale import millimetres_per_uv, weave_repeats_per_uv


def grid(width_mm: float, height_mm: float, uv_width: float, uv_height: float, cells: int = 4):
    """A flat width × height rectangle (mm) in triangles, its UVs spanning uv_width × uv_height."""
    corners, uvs = [], []
    for i in range(cells):
        for j in range(cells):
            quad = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]
            for triangle in ((0, 1, 2), (0, 2, 3)):
                points = [quad[k] for k in triangle]
                corners.append([(a / cells * width_mm, b / cells * height_mm, 0.0) for a, b in points])
                uvs.append([(a / cells * uv_width, b / cells * uv_height) for a, b in points])
    return np.array(corners), np.array(uvs)


def rotation(angle: float, axis: int) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    other = [k for k in range(3) if k != axis]
    matrix = np.eye(3)
    matrix[np.ix_(other, other)] = [[c, -s], [s, c]]
    return matrix


def test_a_rectangle_gives_its_size_over_its_uv_span_along_u_and_v():
    corners, uvs = grid(1200.0, 800.0, 1.0, 0.5)
    assert millimetres_per_uv(corners, uvs) == pytest.approx((1200.0, 1600.0))
    assert weave_repeats_per_uv(corners, uvs, repeat_mm=0.8) == pytest.approx(1500.0)


def test_the_scale_does_not_depend_on_where_the_mesh_is_or_how_it_is_turned():
    corners, uvs = grid(300.0, 300.0, 2.0, 2.0)
    turned = corners @ (rotation(0.7, 0) @ rotation(-1.1, 2)).T + np.array([5.0, -40.0, 12.0])
    assert millimetres_per_uv(turned, uvs) == pytest.approx(millimetres_per_uv(corners, uvs))
    # Turning the UV map instead mixes u and v: a square cloth keeps its scale along both.
    uv_turned = (uvs - 1.0) @ rotation(0.4, 2)[:2, :2].T
    assert millimetres_per_uv(corners, uv_turned) == pytest.approx((150.0, 150.0))


def test_a_curved_mesh_is_measured_on_its_surface_not_its_shadow():
    """A half cylinder of radius R unwrapped along its arc: u spans πR on the surface, 2R across."""
    radius, length, steps = 100.0, 50.0, 64
    angles, us = np.linspace(0.0, np.pi, steps + 1), np.linspace(0.0, 1.0, steps + 1)
    corners, uvs = [], []
    for a0, a1, u0, u1 in zip(angles[:-1], angles[1:], us[:-1], us[1:]):
        ring = [(radius * np.cos(a), radius * np.sin(a)) for a in (a0, a1)]
        quad = [(*ring[0], 0.0), (*ring[1], 0.0), (*ring[1], length), (*ring[0], length)]
        quad_uv = [(u0, 0.0), (u1, 0.0), (u1, 1.0), (u0, 1.0)]
        for triangle in ((0, 1, 2), (0, 2, 3)):
            corners.append([quad[k] for k in triangle])
            uvs.append([quad_uv[k] for k in triangle])
    per_u, per_v = millimetres_per_uv(corners, uvs)
    assert per_u == pytest.approx(np.pi * radius, rel=1e-3) and per_v == pytest.approx(length)


def test_collapsed_triangles_of_the_uv_map_are_left_out_and_a_map_without_area_is_refused():
    corners, uvs = grid(100.0, 100.0, 1.0, 1.0)
    collapsed = uvs.copy()
    collapsed[:4] = 0.25  # four triangles on one UV point
    assert millimetres_per_uv(corners, collapsed) == pytest.approx((100.0, 100.0))
    with pytest.raises(ValueError, match="unwrap"):
        millimetres_per_uv(corners, np.zeros_like(uvs))
    with pytest.raises(ValueError, match="repeat_mm"):
        weave_repeats_per_uv(corners, uvs, repeat_mm=0.0)
    with pytest.raises(ValueError, match=r"\(n, 3, 2\)"):
        millimetres_per_uv(corners, uvs[:, :2])
