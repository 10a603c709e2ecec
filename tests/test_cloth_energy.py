"""The woven sample path-traced on the cloth gonioreflectometer (clothlight/blender/garment/path_traced.py):
the reference that the light between yarns in the cloth tables is checked against
(benchmarks/bench_cloth_energy.py)."""

from __future__ import annotations

import pathlib

import numpy as np
import pytest

from clothlight.garment.tables import coverage_along
from precompute.tables.grids import AngularGrid

bpy = pytest.importorskip("bpy")

from clothlight.blender.garment.measure import GoniometerSettings  # noqa: E402
from clothlight.blender.garment.path_traced import measure_path_traced  # noqa: E402
from clothlight.yarn_tables import yarn_tables_from_bake  # noqa: E402

pytestmark = [pytest.mark.blender, pytest.mark.render]

YARN_BAKE = pathlib.Path(__file__).resolve().parents[1] / "example_blends" / "tables" / "paper_2008"
SETTINGS = GoniometerSettings(incidence_resolution=3, exit_resolution=3, pixels_per_patch=8, samples=8)


def test_light_between_yarns_only_adds_and_the_cloth_keeps_energy(tmp_path):
    """A sun along the normal: with light between yarns every exit cell is at least as bright as
    with the first yarn alone (the same seed: the same first bounce), the red that the yarns send on
    gains, and reflected + transmitted + open weave stays below what arrives.  The open weave is
    the validation weave's: 0.36 of the cloth seen along the normal."""
    tables = yarn_tables_from_bake(YARN_BAKE)
    measured = {bounces: measure_path_traced(tables, (0.0, 0.0, 1.0), SETTINGS, bounces=bounces,
                                             render_dir=tmp_path / str(bounces)) for bounces in (False, True)}
    exits = AngularGrid("hemisphere", SETTINGS.exit_resolution)
    weight = exits.cell_centers()[:, 2] * exits.cell_solid_angle
    energy = {bounces: sum(weight @ m["rho"][side] for side in m["rho"]) for bounces, m in measured.items()}
    for side in ("front", "back"):
        assert np.all(measured[True]["rho"][side] >= measured[False]["rho"][side] - 1e-6)
        np.testing.assert_array_equal(measured[True]["coverage"][side], measured[False]["coverage"][side])
    assert energy[True][0] > energy[False][0] > 0.0
    open_weave = 1.0 - float(coverage_along(measured[True]["coverage"]["front"], np.array([0.0, 0.0, 1.0])))
    assert open_weave == pytest.approx(0.36, abs=0.03)
    assert np.all(energy[True] + open_weave < 1.0)
