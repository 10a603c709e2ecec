"""A shade recipe in a preset: several dyes in one fibre (precompute.optics.medium.dye_mixture_spectrum),
the colour arithmetic a target colour is matched with (precompute.tables.color), and the recipe's
preset content (clothlight.fit.colour_match.recipe_config)."""

import copy

import numpy as np
import pytest

from clothlight.fit.colour_match import RECIPE_DYES, parse_srgb, recipe_config
from precompute.errors import ParameterError
from precompute.optics.coefficients import medium_optics
from precompute.optics.medium import DATA_DIR, load_preset_config, medium_from_dict, read_spectrum_csv
from precompute.tables.color import delta_e_2000, linear_rgb_to_lab, linear_to_srgb, srgb_to_linear_rgb


def voided_red_cotton() -> dict:
    return copy.deepcopy(load_preset_config("voided_red_cotton")[0])


def with_dye(**dye) -> dict:
    config = voided_red_cotton()
    config["dye"] = {"weight_percent": 1.0, "fiber_density_g_per_cm3": 1.52, **dye}
    return config


def test_a_mixture_absorbs_as_the_sum_of_its_dyes():
    recipe = with_dye(spectrum_csv=["congo_red.csv", "evans_blue.csv", "curcumin.csv"], shares=[0.6, 0.1, 0.3])
    mixed = medium_optics(medium_from_dict(recipe)).mu_a
    undyed = medium_optics(medium_from_dict(voided_red_cotton()).with_dye(0.0)).mu_a
    alone = [medium_optics(medium_from_dict(with_dye(spectrum_csv=name, weight_percent=share))).mu_a - undyed
             for name, share in (("congo_red.csv", 0.6), ("evans_blue.csv", 0.1), ("curcumin.csv", 0.3))]
    np.testing.assert_allclose(mixed - undyed, sum(alone), rtol=1e-9)
    source = medium_from_dict(recipe).dye.source
    assert "0.6 congo_red.csv" in source and "0.3 curcumin.csv" in source


def test_a_single_dye_reads_as_before_and_a_one_dye_list_equals_it():
    one = medium_from_dict(voided_red_cotton()).dye
    wavelengths, epsilon = read_spectrum_csv(DATA_DIR / "congo_red.csv", "x")
    assert one.mass_absorption_cm2_per_g == epsilon and one.source == "congo_red.csv"
    listed = medium_from_dict(with_dye(spectrum_csv=["congo_red.csv"], shares=[1.0])).dye
    np.testing.assert_allclose(listed.mass_absorption_cm2_per_g, epsilon)


@pytest.mark.parametrize("dye, expected", [
    ({"spectrum_csv": ["congo_red.csv", "curcumin.csv"], "shares": [0.5, 0.4]}, "sum to 1"),
    ({"spectrum_csv": ["congo_red.csv", "curcumin.csv"], "shares": [1.0]}, "one per dye.spectrum_csv"),
    ({"spectrum_csv": ["congo_red.csv", "curcumin.csv"]}, "one per dye.spectrum_csv"),
    ({"spectrum_csv": ["congo_red.csv", "curcumin.csv"], "shares": [1.2, -0.2]}, "≥ 0"),
    ({"spectrum_csv": "congo_red.csv", "shares": [1.0]}, "absent for one dye"),
    ({"spectrum_csv": []}, "a list of them"),
    ({"spectrum_csv": ["congo_red.csv", "no_such_dye.csv"], "shares": [0.5, 0.5]}, r"spectrum_csv\[1\]"),
])
def test_a_bad_mixture_is_refused_naming_the_key(dye, expected):
    with pytest.raises(ParameterError, match=expected):
        medium_from_dict(with_dye(**dye))


def test_recipe_config_writes_a_preset_that_reads_back_as_the_recipe():
    config = recipe_config(voided_red_cotton(), [0.2, 0.0, 0.05, 0.3])
    assert config["dye"]["spectrum_csv"] == [RECIPE_DYES[0], RECIPE_DYES[2]]  # a dye at 0 % is left out
    assert config["dye"]["shares"] == pytest.approx([0.8, 0.2])
    medium = medium_from_dict(config)
    assert medium.dye.weight_percent == pytest.approx(0.25) and medium.host.absorption_per_mm == 0.3
    with pytest.raises(ParameterError, match="some dye"):
        recipe_config(voided_red_cotton(), [0.0, 0.0, 0.0, 0.3])
    with pytest.raises(ParameterError, match="recipe"):
        recipe_config(voided_red_cotton(), [0.2, 0.1, 0.0])


def test_srgb_colours_parse_and_convert_both_ways():
    np.testing.assert_allclose(parse_srgb("#ff8000"), [1.0, 128 / 255, 0.0])
    np.testing.assert_allclose(parse_srgb("0.2, 0.4,0.6"), [0.2, 0.4, 0.6])
    for bad in ("#ff80", "red", "1.2,0,0", "0,0", "nan,0,0"):
        with pytest.raises(ParameterError, match="--target"):
            parse_srgb(bad)
    srgb = np.array([0.7, 0.2, 0.35])
    np.testing.assert_allclose(linear_to_srgb(srgb_to_linear_rgb(srgb)), srgb, atol=1e-9)
    assert srgb_to_linear_rgb([0.5, 0.5, 0.5])[0] == pytest.approx(0.21404, abs=1e-5)  # IEC 61966-2-1
    np.testing.assert_allclose(linear_rgb_to_lab([1.0, 1.0, 1.0]), [100.0, 0.0, 0.0], atol=1e-3)


def test_ciede2000_reproduces_sharma_wu_dalal_test_data():
    # Sharma, Wu & Dalal (2005), Table 1, pairs 1, 7 and 17
    pairs = [([50.0, 2.6772, -79.7751], [50.0, 0.0, -82.7485], 2.0425),
             ([50.0, 0.0, 0.0], [50.0, -1.0, 2.0], 2.3669),
             ([50.0, 2.5, 0.0], [73.0, 25.0, -18.0], 27.1492)]
    for lab_a, lab_b, expected in pairs:
        assert float(delta_e_2000(lab_a, lab_b)) == pytest.approx(expected, abs=1e-4)


def test_atlas_pixel_cells_names_the_cell_each_atlas_pixel_holds():
    from precompute.tables.layout import atlas_pixel_cells, brdf_atlas

    n_i, n_o = 3, 4
    incidence, exit = np.meshgrid(np.arange(n_i**2), np.arange(n_o**2), indexing="ij")
    rho = np.stack([incidence, exit], axis=-1).astype(float)  # each cell holds its own indices
    atlas = brdf_atlas(rho)
    pixels = np.arange(atlas.shape[0] * atlas.shape[1])
    cells = atlas_pixel_cells(pixels, n_i, n_o)
    np.testing.assert_array_equal(cells[0], atlas[..., 0].ravel())
    np.testing.assert_array_equal(cells[1], atlas[..., 1].ravel())


def test_a_recipes_own_spectrum_beside_its_toml_is_written_absolute_and_a_shipped_one_by_name(tmp_path):
    from precompute.fit.report import absolute_data_files

    (tmp_path / "my_dye.csv").write_text((DATA_DIR / "curcumin.csv").read_text())
    config = with_dye(spectrum_csv=["congo_red.csv", "my_dye.csv"], shares=[0.5, 0.5])
    absolute_data_files(config, tmp_path)
    assert config["dye"]["spectrum_csv"] == ["congo_red.csv", str((tmp_path / "my_dye.csv").resolve())]
    medium_from_dict(config, tmp_path / "elsewhere")  # reads the same from any folder
