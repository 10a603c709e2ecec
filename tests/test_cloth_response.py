"""The cloth response's linear map (clothlight/validation/response.py) against the shader's NumPy
twins; its agreement with full Cycles sweeps is in test_cloth_response_render.py."""

import numpy as np
import pytest

from clothlight.validation.response import ClothResponse, ResponseView, TableLayout
from precompute.errors import ParameterError
from precompute.tables.layout import interpolate_rho, interpolate_unscattered_rho
from tests.helpers import cook_torrance_between, direction


def _random_view(rng, count: int) -> ResponseView:
    incidence = rng.normal(size=(count, 3))
    exit_ = rng.normal(size=(count, 3))
    exit_[:, 2] = np.abs(exit_[:, 2])
    unit = np.linalg.norm
    return ResponseView(30.0, 20.0, 0.0, 0.0, incidence / unit(incidence, axis=1, keepdims=True),
                        exit_ / unit(exit_, axis=1, keepdims=True), samples_per_side=16)


def test_the_linear_map_equals_the_twins_summed_over_the_samples(tmp_path):
    rng = np.random.default_rng(3)
    view = _random_view(rng, 200)
    response = ClothResponse([view])
    layout = TableLayout(5, 4, 33, 1.557, 0.2)
    atlas = rng.uniform(0.0, 1.0, size=(20, 20, 3))
    attenuation = rng.uniform(0.0, 1.0, size=(33, 3))
    model = response.cloth_brdf(atlas, attenuation, layout, specular_weight=0.7, specular_slope=0.5)
    lookup = interpolate_rho(atlas, 5, view.incidence, view.exit)
    lookup += interpolate_unscattered_rho(attenuation, 1.557, view.incidence, view.exit, 0.2)
    lit_faces = np.count_nonzero(view.incidence[:, 2] > 0)
    specular = 0.7 * cook_torrance_between(view.toward_sun, view.toward_camera, 0.5, 1.557) * view.toward_sun[2]
    expected = (lookup.sum(axis=0) + specular * lit_faces) * view.calibration
    np.testing.assert_allclose(model[0], expected, rtol=1e-9)
    # and it is stored and read back whole
    again = ClothResponse.load(response.save(tmp_path / "response.npz"))
    np.testing.assert_allclose(again.cloth_brdf(atlas, attenuation, layout, specular_weight=0.7, specular_slope=0.5),
                               model, rtol=1e-6)
    # the fuzz adds its Lommel–Seeliger term on the same lit faces as the sheen (cl_cloth_fuzz)
    fuzzy = response.cloth_brdf(atlas, attenuation, layout, specular_weight=0.7, specular_slope=0.5, fuzz_albedo=0.2)
    fuzz = 0.2 / (4 * np.pi * (view.toward_sun[2] + view.toward_camera[2])) * view.toward_sun[2]
    np.testing.assert_allclose(fuzzy[0] - model[0], fuzz * lit_faces * view.calibration, rtol=1e-9)
    # a fuzz of optical depth τ shades the yarn's light by exp(−τ (1/μi + 1/μo)) about the cloth normal
    # and reflects as a layer that deep (1 − that of the law); the sheen it leaves as it is
    deep = response.cloth_brdf(atlas, attenuation, layout, specular_weight=0.7, specular_slope=0.5, fuzz_albedo=0.2,
                               fuzz_depth=0.4)
    shade = np.exp(-0.4 * (1 / view.toward_sun[2] + 1 / view.toward_camera[2]))
    np.testing.assert_allclose(deep[0], (lookup.sum(axis=0) * shade + (specular + fuzz * (1 - shade)) * lit_faces)
                               * view.calibration, rtol=1e-9)


def test_the_view_directions_follow_the_rig_conventions():
    view = ResponseView(45.0, -30.0, 0.0, 0.0, np.zeros((0, 3)), np.zeros((0, 3)), 8)
    np.testing.assert_allclose(view.toward_sun, direction(45.0, 180.0), atol=1e-12)
    np.testing.assert_allclose(view.toward_camera, direction(30.0, 180.0), atol=1e-12)
    across = ResponseView(45.0, 30.0, 90.0, 0.0, np.zeros((0, 3)), np.zeros((0, 3)), 8)
    np.testing.assert_allclose(across.toward_camera, direction(30.0, 90.0), atol=1e-12)


def test_a_table_of_another_layout_is_refused():
    response = ClothResponse([_random_view(np.random.default_rng(0), 10)])
    with pytest.raises(ParameterError, match="atlas"):
        response.cloth_brdf(np.zeros((10, 10, 3)), None, TableLayout(5, 4, 33, 1.557, 0.2),
                            specular_weight=1.0, specular_slope=0.8)
