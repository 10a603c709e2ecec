"""The validation rig measures the close-up sample (issue 46): plies, twist, irregularity and the
sheeting's density, at tiny settings (32 px, 2 samples).

With a yarn table of constant ρ = L/E⊥ and no sheen every lit yarn point sends L = ρ·E, so the
cloth's BRDF is ρ × (the share of the patch that shows lit yarn) / cos θi: positive, at most
ρ × coverage / cos θi (equal to it seen along the light, where every yarn point seen is lit), and of
ρ's colour exactly (docs/validation.md, "From pixels to the BRDF").
The rig measures the sample's mesh only: the flyaway fibres, a curves object of their own, are not
measured (scripts/compare_closeup_sweep.py, docs/closeups.md).
"""

import math
import pathlib

import numpy as np
import pytest

from clothlight.weave.closeup import sheeting_weave
from precompute.optics.ballistic import ATTENUATION_SAMPLES
from precompute.tables.closure_fit import LOBES
from tests.helpers import write_yarn_table_folder

bpy = pytest.importorskip("bpy")

from clothlight.blender.flyaway_object import build_flyaway_object  # noqa: E402
from clothlight.blender.sample_object import build_sample_object  # noqa: E402
from clothlight.blender.validation.rig import RigSettings  # noqa: E402
from clothlight.blender.validation.run import run_validation  # noqa: E402
from clothlight.weave.closeup import CloseupSettings  # noqa: E402

pytestmark = pytest.mark.render

REPO = pathlib.Path(__file__).resolve().parents[1]
SHIPPED_TABLES = REPO / "example_blends" / "tables" / "paper_2008"
CONSTANT_RHO = np.array([0.2, 0.1, 0.05])
TINY = RigSettings(incidences_deg=(0.0, 60.0), views_deg=(-60.0, 0.0, 30.0, 70.0), resolution=32, samples=2)


@pytest.fixture(scope="module")
def constant_bake(tmp_path_factory):
    """A bake folder whose yarn BRDF is the constant ρ = L/E⊥ = CONSTANT_RHO, an opaque yarn."""
    n_i, n_o, lobes = 5, 4, len(LOBES)
    return write_yarn_table_folder(
        tmp_path_factory.mktemp("bake"), np.broadcast_to(CONSTANT_RHO, (n_i * n_o, n_i * n_o, 3)),
        np.zeros((n_o, lobes * n_o, 3)), np.zeros((1, ATTENUATION_SAMPLES, 3)),
        incidence_resolution=n_i, exit_resolution=n_o, optional=False)


def fresh_file():
    bpy.ops.wm.read_homefile(use_empty=True)


def sweep(sample, out, tables, specular_weight=None):
    """The yarn material's views of a tiny sweep of ``sample`` (a weave, an object or None)."""
    results = run_validation(sample, out, materials=("yarn",), tables_dir=tables, settings=TINY, swatches=False,
                             scheduler=None, specular_weight=specular_weight)
    views = results["materials"]["yarn"]["views"]
    assert [(v["theta_i_deg"], v["theta_v_deg"]) for v in views] == [
        (i, v) for i in TINY.incidences_deg for v in TINY.views_deg]
    return views


def test_the_close_up_measures_a_positive_brdf_of_the_tables_colour_bounded_by_its_coverage(tmp_path, constant_bake):
    fresh_file()
    closeup = sweep(sheeting_weave("voided_red_cotton"), tmp_path / "closeup", constant_bake, specular_weight=0.0)
    plain = sweep(None, tmp_path / "plain", constant_bake, specular_weight=0.0)
    for view in closeup:
        brdf = np.array(view["brdf_rgb"])
        assert np.all(np.isfinite(brdf)) and np.all(brdf > 0), view
        lit_share = brdf * math.cos(math.radians(view["theta_i_deg"])) / CONSTANT_RHO
        np.testing.assert_allclose(lit_share, lit_share[0], rtol=1e-4)  # ρ's colour: no other light
        assert 0.05 < lit_share[0] <= view["coverage"] * (1 + 1e-4), view
        if view["theta_v_deg"] == -view["theta_i_deg"]:  # seen along the light: every yarn point seen is lit
            assert lit_share[0] == pytest.approx(view["coverage"], rel=1e-4), view
    # the sheeting covers more of the cloth than the plain tubes seen from above (0.77 against 0.64 at 128 px,
    # 0.76 against 0.69 at 32 px)
    normal = {(v["theta_i_deg"], v["theta_v_deg"]): v["coverage"] for v in plain}
    for view in closeup:
        if view["theta_v_deg"] == 0.0:
            assert view["coverage"] > normal[(view["theta_i_deg"], 0.0)] + 0.03


def test_the_rig_measures_a_close_up_objects_yarns_not_its_flyaway_fibres(tmp_path, constant_bake):
    fresh_file()
    weave = sheeting_weave("voided_red_cotton")
    sample = build_sample_object(weave)
    fibres = build_flyaway_object(sample, weave, CloseupSettings(), "voided_red_cotton")
    assert fibres is not None and fibres.parent == sample
    from_object = sweep(sample, tmp_path / "object", constant_bake)
    fresh_file()
    from_weave = sweep(weave, tmp_path / "weave", constant_bake)
    np.testing.assert_allclose([v["brdf_rgb"] for v in from_object], [v["brdf_rgb"] for v in from_weave], rtol=1e-5)


def test_the_close_up_in_a_baked_yarn_material_gives_a_finite_positive_brdf_in_every_view(tmp_path):
    fresh_file()
    for view in sweep(sheeting_weave("voided_red_cotton"), tmp_path, SHIPPED_TABLES):
        brdf = np.array(view["brdf_rgb"])
        assert np.all(np.isfinite(brdf)) and np.all(brdf > 0) and view["coverage"] > 0.5, view
