"""The cloth response (clothlight/validation/response.py): the sun-mode sweep as a linear map of the
yarn tables agrees with the full Cycles sweep, per view, on three different media."""

import numpy as np
import pytest

from clothlight.validation.response import TableLayout
from clothlight.yarn_tables import yarn_tables_from_bake
from precompute.optics import ballistic
from precompute.tables.grids import AngularGrid
from precompute.tables.layout import brdf_atlas
from tests.helpers import write_yarn_table_folder

bpy = pytest.importorskip("bpy")

from clothlight.blender.validation.response_render import measure_response  # noqa: E402
from clothlight.blender.validation.rig import RigSettings  # noqa: E402
from clothlight.blender.validation.run import run_validation  # noqa: E402

pytestmark = pytest.mark.render

SHIPPED_TABLES = "example_blends/tables/paper_2008"
INCIDENCES = (0.0, 45.0)
VIEWS = (-30.0, 0.0, 45.0)


def _read(path):
    import OpenEXR

    with OpenEXR.File(str(path)) as exr:
        return np.array(next(iter(exr.parts[0].channels.values())).pixels)[..., :3]


def _layout(tables) -> TableLayout:
    return TableLayout(tables.incidence_resolution, tables.exit_resolution, tables.unscattered_samples,
                       tables.host_index, ballistic.SUN_MODE_SPREAD_RAD)


def _media(folder):
    """Three media: the shipped thin red cotton (its caustics in the unscattered table), a thick
    one (a smooth, broad ρ of another colour, no unscattered light) and a peaked, translucent one."""
    shipped = yarn_tables_from_bake(SHIPPED_TABLES)
    n_i, n_o = shipped.incidence_resolution, shipped.exit_resolution
    lobes = _read(shipped.lobe_path)
    wi = AngularGrid("sphere", n_i).cell_centers()
    wo = AngularGrid("hemisphere", n_o).cell_centers()
    cos_i, cos_o = wi[:, None, 2], wo[None, :, 2]
    broad = (0.05 + 0.02 * np.clip(cos_i, 0, 1) * cos_o)[..., None] * np.array([0.9, 0.3, 0.2])
    peaked = (0.02 + 0.4 * np.exp(8.0 * (np.sum(-wi[:, None, :] * wo[None, :, :], axis=-1) - 1.0)))[..., None] \
        * np.array([0.3, 0.5, 0.8])
    zero_light = np.zeros((1, shipped.unscattered_samples, 3))
    translucent = np.exp(-0.3 * ballistic.attenuation_lengths())[None, :, None] * np.array([0.8, 0.5, 0.2])
    thick = write_yarn_table_folder(folder / "thick", brdf_atlas(broad), lobes, zero_light,
                                    incidence_resolution=n_i, exit_resolution=n_o, cache_key="a1" * 32)
    peak = write_yarn_table_folder(folder / "peaked", brdf_atlas(peaked), lobes, translucent,
                                   incidence_resolution=n_i, exit_resolution=n_o, cache_key="b2" * 32)
    return {"thin": shipped, "thick": yarn_tables_from_bake(thick), "peaked": yarn_tables_from_bake(peak)}


def test_the_response_reproduces_the_sweep_within_one_percent_per_view_on_three_media(tmp_path):
    media = _media(tmp_path)
    views = [(theta_i, theta_v, 0.0, 0.0) for theta_i in INCIDENCES for theta_v in VIEWS]
    response = measure_response(media["thin"], views, resolution=128, supersampling=4)
    settings = RigSettings(incidences_deg=INCIDENCES, views_deg=VIEWS)
    for name, tables in media.items():
        results = run_validation(None, tmp_path / "sweeps" / name, materials=("yarn",),
                                 tables_dir=tables.brdf_path.parent, swatches=False, settings=settings)
        sweep = {(v["theta_i_deg"], v["theta_v_deg"]): np.array(v["brdf_rgb"])
                 for v in results["materials"]["yarn"]["views"]}
        model = response.cloth_brdf(_read(tables.brdf_path), _read(tables.unscattered_path), _layout(tables),
                                    specular_weight=1.0, specular_slope=0.8)
        for (theta_i, theta_v, _, _), rgb in zip(response.angles(), model):
            np.testing.assert_allclose(rgb, sweep[(theta_i, theta_v)], rtol=0.01,
                                       err_msg=f"{name} at θi {theta_i}, θv {theta_v}")


def test_perpendicular_views_and_a_turned_sample_see_the_whole_patch(tmp_path):
    tables = yarn_tables_from_bake(SHIPPED_TABLES)
    views = [(30.0, 40.0, 90.0, 0.0), (30.0, 40.0, 90.0, 90.0), (30.0, -40.0, 0.0, 90.0)]
    response = measure_response(tables, views, resolution=32, supersampling=2)
    for view in response.views:
        # Every lit sample looks at the yarn from outside, and the lit share of the patch is large.
        assert np.all(view.exit[:, 2] >= -1e-3)
        assert len(view.incidence) > 0.3 * view.samples_per_side**2
    # The perpendicular view sees the camera on +y: the exit directions differ from the in-plane ones.
    assert not np.allclose(response.views[0].exit.mean(axis=0), response.views[2].exit.mean(axis=0), atol=0.05)
