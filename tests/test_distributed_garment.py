"""The cloth measurement on a dask cluster: each worker renders views in a scene of its own, and
the measurement is the one rendered in this process, bit for bit."""

from __future__ import annotations

import pathlib

import numpy as np
import pytest

pytest.importorskip("distributed")
bpy = pytest.importorskip("bpy")

from clothlight.blender.garment.measure import GoniometerSettings, measure_cloth  # noqa: E402
from clothlight.garment.goniometry import SIDES  # noqa: E402
from clothlight.yarn_tables import yarn_tables_from_bake  # noqa: E402

pytestmark = pytest.mark.slow

YARN_BAKE = pathlib.Path(__file__).resolve().parents[1] / "example_blends" / "tables" / "paper_2008"
SETTINGS = GoniometerSettings(incidence_resolution=3, exit_resolution=2, pixels_per_patch=8, samples=2)


def test_a_measurement_on_two_local_workers_is_the_one_rendered_here(tmp_path):
    tables = yarn_tables_from_bake(YARN_BAKE)
    here = measure_cloth(tables, SETTINGS, render_dir=tmp_path)
    reports = []
    spread = measure_cloth(tables, SETTINGS, render_dir=tmp_path, scheduler="local", table_folder=YARN_BAKE,
                           progress=lambda done, total, what: reports.append((done, total)))
    for name in ("rho", "specular", "specular_visibility", "coverage"):
        for side in SIDES:
            assert np.array_equal(getattr(here, name)[side], getattr(spread, name)[side]), (name, side)
    assert np.any(here.rho["front"] > 0)
    assert (spread.specular_parameters, spread.patch_mm, spread.sample_size_mm, spread.half_thickness_mm) == \
        (here.specular_parameters, here.patch_mm, here.sample_size_mm, here.half_thickness_mm)
    views = 2 * SETTINGS.exit_resolution ** 2
    assert sorted(reports) == [(done, views) for done in range(1, views + 1)]


def test_a_cluster_needs_the_yarn_bake_folder(tmp_path):
    from precompute.errors import ParameterError

    with pytest.raises(ParameterError, match="table_folder"):
        measure_cloth(yarn_tables_from_bake(YARN_BAKE), SETTINGS, render_dir=tmp_path, scheduler="local")


def test_a_response_on_two_local_workers_is_the_one_rendered_here(tmp_path):
    """The cloth response's lookups (clothlight/garment/response.py) render on the cluster too: each
    worker in a response scene of its own, the samples the same bit for bit."""
    from clothlight.blender.garment.measure import measure_response

    tables = yarn_tables_from_bake(YARN_BAKE)
    here = measure_response(tables, SETTINGS, samples_per_side=9, render_dir=tmp_path)
    spread = measure_response(tables, SETTINGS, samples_per_side=9, render_dir=tmp_path, scheduler="local",
                              table_folder=YARN_BAKE)
    assert here.sample_count > 0 and here.shape == spread.shape
    for mine, theirs in zip(here.views, spread.views):
        assert (mine.side, mine.exit_cell) == (theirs.side, theirs.exit_cell)
        for name in ("patch", "weight", "incidence", "exit", "counted", "covered"):
            assert np.array_equal(getattr(mine, name), getattr(theirs, name)), name
