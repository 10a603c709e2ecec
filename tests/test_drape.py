"""The draped cloth the garment examples wear (clothlight/blender/garment/drape.py): it drapes over
its form with folds wider than the simulation's grid, not crumpled zig-zags, and keeps its UVs."""

from __future__ import annotations

import math

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
import bmesh  # noqa: E402

from clothlight.blender.garment.drape import DEFAULT_CUTS, draped_cloth  # noqa: E402

pytestmark = [pytest.mark.blender, pytest.mark.slow]


def test_the_default_drape_folds_smoothly_over_its_form_and_keeps_its_uv_map():
    bpy.ops.wm.read_homefile(use_empty=True)
    cloth, form = draped_cloth(bpy.context.scene)
    bm = bmesh.new()
    try:
        bm.from_mesh(cloth.data)
        bm.normal_update()
        fold_deg = np.degrees([edge.calc_face_angle(0.0) for edge in bm.edges if len(edge.link_faces) == 2])
        heights = np.array([(cloth.matrix_world @ vertex.co).z for vertex in bm.verts])
    finally:
        bm.free()
    assert len(cloth.data.polygons) == DEFAULT_CUTS**2 and not cloth.modifiers
    # Crumpled zig-zags fold neighbouring cells onto each other (the Cotton preset as it is: a quarter
    # of the edges above 30°, up to 177°); a drape folds over several cells.
    assert np.mean(fold_deg > 30.0) < 0.05 and fold_deg.max() < 60.0
    radius = max(form.dimensions) / 2.0
    assert heights.max() == pytest.approx(radius, abs=0.05)  # resting on the form's top (at the origin) …
    assert heights.min() < -0.5 * radius  # … and hanging down its sides
    uv = np.array([loop.uv[:] for loop in cloth.data.uv_layers["UVMap"].data])
    assert uv.min() == pytest.approx(0.0) and uv.max() == pytest.approx(1.0)
    assert not math.isnan(heights.sum())
