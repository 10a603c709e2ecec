"""The cloth response (clothlight/garment/response.py) and a yarn's cloth measurement read off it
(clothlight/garment/response_measurement.py), without Blender: each patch's ρ is the mean over its
samples of what the shader's NumPy twins read at their lookups, the specular term is the
Cook–Torrance term times the share of lit yarn facing the sun, and the result is the same whatever
the threads and after a save and load."""

import dataclasses

import numpy as np
import pytest

from clothlight.garment.goniometry import SIDES
from clothlight.garment.response import SCHEMA, GarmentResponse, ResponseView, view_samples
from clothlight.garment.response_measurement import (
    YarnLookup,
    measurement_from_response,
    response_rho,
    response_specular,
    yarn_lookup,
)
from clothlight.validation.response import TableLayout
from clothlight.yarn_tables import yarn_tables_from_bake
from precompute.errors import ParameterError
from precompute.optics import ballistic
from precompute.optics.cook_torrance import cook_torrance
from precompute.tables.grids import AngularGrid
from precompute.tables.layout import interpolate_rho, interpolate_unscattered_rho

N_I, N_O = 3, 2
LAYOUT = TableLayout(5, 4, 33, 1.557, 0.2)
SHIPPED = "example_blends/tables/paper_2008"


def unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def random_view(rng, side, cell, samples=400):
    """A view whose samples look ρ up anywhere, a third of them inside an unscattered path's cone (the
    path toward the light for their exit direction, turned a little), so that ρ_u counts too."""
    exits = unit(rng.normal(size=(samples, 3)) * [1, 1, 0.5] + [0, 0, 0.6])
    incidence = unit(rng.normal(size=(samples, 3)))
    paths, _, _ = ballistic.unscattered_paths(exits, LAYOUT.index)
    near = slice(0, samples // 3)
    incidence[near] = unit(paths[near, 0] + 0.1 * rng.normal(size=(samples // 3, 3)))
    patches = N_I * N_I
    counted = rng.uniform(samples / patches + 5, samples, patches)
    return ResponseView(side, cell, rng.integers(0, patches, samples).astype(np.uint16),
                        rng.choice([0.25, 0.5, 1.0], samples).astype(np.float32), incidence.astype(np.float32),
                        exits.astype(np.float32), counted, counted * rng.uniform(0.5, 1.0, patches))


@pytest.fixture
def response():
    rng = np.random.default_rng(7)
    views = [random_view(rng, side, cell) for side in SIDES for cell in range(N_O * N_O)]
    return GarmentResponse(views, N_I, N_O, {"patch_mm": 1.0, "sample_size_mm": [30.0, 30.0],
                                             "half_thickness_mm": 0.2}, {"samples_per_side": 21, "render_seconds": 5.0})


@pytest.fixture
def yarn():
    rng = np.random.default_rng(3)
    side = LAYOUT.incidence_resolution * LAYOUT.exit_resolution
    return YarnLookup(rng.uniform(0.0, 0.3, (side, side, 3)), rng.uniform(0.0, 1.0, (LAYOUT.unscattered_samples, 3)),
                      LAYOUT, {"weight": 0.7, "slope": 0.5, "ior": 1.45})


def test_each_patch_holds_the_mean_of_what_the_shader_reads_at_its_samples(response, yarn):
    rho = response_rho(response, yarn)
    reached = 0
    for k, view in enumerate(response.views):
        wi, wo = view.incidence.astype(float), view.exit.astype(float)
        unscattered = interpolate_unscattered_rho(yarn.attenuation, LAYOUT.index, wi, wo, LAYOUT.unscattered_spread)
        reached += np.count_nonzero(unscattered[:, 0] > 0.0)
        per_sample = view.weight[:, None] * (interpolate_rho(yarn.atlas, LAYOUT.incidence_resolution, wi, wo)
                                             + unscattered)
        expected = np.stack([np.bincount(view.patch, per_sample[:, c], N_I * N_I) for c in range(3)], axis=-1)
        side, cell = SIDES[k // (N_O * N_O)], k % (N_O * N_O)
        np.testing.assert_allclose(rho[side][:, cell], expected / view.counted[:, None], rtol=1e-12, atol=1e-15)
    assert reached > len(response.views) * 50  # the unscattered light was looked up, not only ρ


def test_the_specular_term_is_cook_torrance_times_the_lit_yarn_facing_the_sun(response):
    term, visibility = response_specular(response, weight=0.7, slope=0.5, ior=1.45)
    toward_sun = AngularGrid("sphere", N_I).cell_centers()
    toward_camera = AngularGrid("hemisphere", N_O).cell_centers()
    for k, view in enumerate(response.views):
        side, cell = SIDES[k // (N_O * N_O)], k % (N_O * N_O)
        facing = np.bincount(view.patch, view.weight * (view.incidence[:, 2] > 0.0), N_I * N_I) / view.counted
        for i, sun in enumerate(toward_sun):
            f = 0.7 * cook_torrance(sun, toward_camera[cell], 0.5, 1.45) * max(sun[2], 0.0)
            if sun[2] > 0.0:
                assert visibility[side][i, cell] == pytest.approx(facing[i]) and f > 0.0
            else:  # lit from the other side: the shader marks no specular term there
                assert visibility[side][i, cell] == 0.0
            assert term[side][i, cell] == pytest.approx(f * visibility[side][i, cell], rel=1e-12, abs=1e-15)


def test_the_measurement_adds_the_specular_term_to_rho_and_keeps_the_response_shape(response, yarn):
    measured = measurement_from_response(response, yarn)
    rho = response_rho(response, yarn)
    term, visibility = response_specular(response, **yarn.specular)
    for side in SIDES:
        np.testing.assert_array_equal(measured.rho[side], rho[side] + term[side][..., None])
        np.testing.assert_array_equal(measured.specular_visibility[side], visibility[side])
        expected = [np.mean(v.covered / v.counted) for v in response.views if v.side == side]
        np.testing.assert_allclose(measured.coverage[side], expected)
    assert measured.specular_parameters == yarn.specular
    assert (measured.patch_mm, measured.sample_size_mm, measured.render_seconds) == (1.0, (30.0, 30.0), 5.0)


def lit_cells(response):
    """Per exit cell of each side: the side, the cell, the share of each incidence patch that is lit
    yarn facing the sun (N_i²), and the cosines with the cloth normal toward the sun (N_i²) and the camera."""
    toward_sun = AngularGrid("sphere", N_I).cell_centers()
    toward_camera = AngularGrid("hemisphere", N_O).cell_centers()
    for k, view in enumerate(response.views):
        cell = k % (N_O * N_O)
        facing = np.bincount(view.patch, view.weight * (view.incidence[:, 2] > 0.0), N_I * N_I) / view.counted
        yield SIDES[k // (N_O * N_O)], cell, facing, toward_sun[:, 2], toward_camera[cell, 2]


def test_the_fuzz_joins_rho_on_the_lit_yarn_facing_the_sun_and_not_the_specular_part(response, yarn):
    # the sun mode emits the fuzz with ρ, not as the marked specular term (cl_cloth_fuzz)
    fuzzy = measurement_from_response(response, dataclasses.replace(yarn, fuzz_albedo=0.2))
    plain = measurement_from_response(response, yarn)
    for side, cell, facing, mu_i, mu_o in lit_cells(response):
        mu_i = np.maximum(mu_i, 0.0)
        expected = np.where(mu_i > 0.0, 0.2 / (4 * np.pi * (mu_i + mu_o)) * mu_i, 0.0) * facing
        np.testing.assert_allclose(fuzzy.rho[side][:, cell] - plain.rho[side][:, cell], expected[:, None] * np.ones(3),
                                   rtol=1e-9, atol=1e-15)
    for side in SIDES:
        np.testing.assert_array_equal(fuzzy.specular[side], plain.specular[side])
    assert np.any(fuzzy.rho["front"] > plain.rho["front"])


def test_a_fuzz_of_depth_shades_the_yarns_rho_and_reflects_as_a_layer(response, yarn):
    # the sun mode: T ρ_yarn + f_layer cos θ_i on the lit yarn facing the sun, the sheen unshaded
    depth, albedo = 0.3, 0.2
    deep = measurement_from_response(response, dataclasses.replace(yarn, fuzz_albedo=albedo, fuzz_depth=depth))
    plain = measurement_from_response(response, yarn)
    rho = response_rho(response, yarn)
    for side, cell, facing, mu_i, mu_o in lit_cells(response):
        shade = np.exp(-depth * (1.0 / np.abs(mu_i) + 1.0 / mu_o))  # lit from behind, through the back's fuzz
        lit = np.maximum(mu_i, 0.0)
        layer = np.where(lit > 0.0, albedo * (1.0 - shade) / (4 * np.pi * (lit + mu_o)) * lit, 0.0) * facing
        specular = plain.rho[side][:, cell] - rho[side][:, cell]
        np.testing.assert_allclose(deep.rho[side][:, cell],
                                   rho[side][:, cell] * shade[:, None] + layer[:, None] + specular,
                                   rtol=1e-9, atol=1e-15)
    for side in SIDES:
        np.testing.assert_array_equal(deep.specular[side], plain.specular[side])
    assert np.any(deep.rho["front"] < plain.rho["front"])  # shaded, where the veneer only ever added


def test_the_measurement_is_the_same_bit_for_bit_whatever_the_threads_and_after_a_save(response, yarn, tmp_path):
    one = response_rho(response, yarn, threads=1)
    again = GarmentResponse.load(response.save(tmp_path / "response.npz"))
    assert again.metadata == response.metadata and again.shape == response.shape
    for threads in (2, 3):
        many = response_rho(again, yarn, threads=threads)
        for side in SIDES:
            assert np.array_equal(one[side], many[side])


def test_a_response_is_refused_with_views_missing_or_of_another_format(response, tmp_path):
    with pytest.raises(ParameterError, match="views"):
        GarmentResponse(response.views[:-1], N_I, N_O, response.shape)
    path = response.save(tmp_path / "response.npz")
    with np.load(path) as data:
        arrays = dict(data)
    arrays["schema"] = np.array(SCHEMA.replace("/1", "/0"))
    np.savez(tmp_path / "old.npz", **arrays)
    with pytest.raises(ParameterError, match="response"):
        GarmentResponse.load(tmp_path / "old.npz")


def test_a_view_keeps_the_lit_yarn_samples_of_its_patches():
    """From lookups as the shader writes them (0.5 + 0.5 ω, the incidence black where shadowed): a
    sample counts in its patch by its pixel's weight whatever it sees, covers it when it sees yarn,
    and is kept with its weight and decoded directions only when it is lit yarn."""
    wi, wo = unit(np.array([0.3, -0.2, 0.9])), unit(np.array([-0.1, 0.4, 0.8]))
    incidence = np.tile(0.5 + 0.5 * wi, (2, 3, 1))
    exits = np.tile(0.5 + 0.5 * wo, (2, 3, 1))
    incidence[0, 1] = 0.0  # shadowed by another yarn
    seen = np.array([[1.0, 1.0, 0.0], [1.0, 1.0, 1.0]])  # (0, 2): a gap
    index = np.array([[0, 0, 0], [1, -1, 4]])  # (1, 1): between patches; patch 4 is beyond N_i² = 4
    weight = np.array([[1.0, 0.5, 0.25], [0.75, 0.0, 1.0]])
    view = view_samples("back", 3, incidence, exits, seen, index, weight, patches=4)
    assert (view.side, view.exit_cell) == ("back", 3)
    np.testing.assert_array_equal(view.patch, [0, 1])
    np.testing.assert_array_equal(view.weight, [1.0, 0.75])
    np.testing.assert_allclose(view.incidence, [wi, wi], atol=1e-7)
    np.testing.assert_allclose(view.exit, [wo, wo], atol=1e-7)
    np.testing.assert_array_equal(view.counted, [1.75, 0.75, 0, 0])
    np.testing.assert_array_equal(view.covered, [1.5, 0.75, 0, 0])


def test_the_yarn_lookup_is_what_the_sun_mode_material_reads():
    tables = yarn_tables_from_bake(SHIPPED)
    yarn = yarn_lookup(tables)
    side = tables.incidence_resolution * tables.exit_resolution
    assert yarn.atlas.shape == (side, side, 3) and yarn.attenuation.shape == (tables.unscattered_samples, 3)
    assert yarn.layout == TableLayout(tables.incidence_resolution, tables.exit_resolution,
                                      tables.unscattered_samples, tables.host_index, ballistic.SUN_MODE_SPREAD_RAD)
    weight, slope = (tables.specular or {}).get("weight", 1.0), (tables.specular or {}).get("slope", 0.8)
    assert yarn.specular == {"weight": float(np.float32(weight)), "slope": float(np.float32(slope)),
                             "ior": float(np.float32(tables.host_index))}
