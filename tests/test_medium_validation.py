"""Bad medium input fails loudly: the error names the parameter, its value and what is allowed."""

import copy
import math
import re

import numpy as np
import pytest

from precompute.__main__ import main
from precompute.errors import ParameterError
from precompute.optics.medium import (
    PRESET_DIR,
    MediumParameters,
    RefractiveIndex,
    WavelengthGrid,
    load_preset,
    load_preset_config,
    medium_from_dict,
    preset_names,
    read_spectrum_csv,
)
from precompute.optics.coefficients import medium_optics

BASE, BASE_DIR = load_preset_config("paper_2008")


def build(edit, base_dir=BASE_DIR) -> MediumParameters:
    config = copy.deepcopy(BASE)
    edit(config)
    return medium_from_dict(config, base_dir)


def expect_error(edit, name: str, allowed_part: str = "", base_dir=BASE_DIR) -> ParameterError:
    with pytest.raises(ParameterError) as info:
        params = build(edit, base_dir)
        medium_optics(params)  # some checks (coverage of the grid) need the wavelengths
    error = info.value
    assert error.name == name
    assert allowed_part in error.allowed
    message = str(error)
    assert name in message and error.allowed in message
    return error


def set_in(path, value):
    def edit(config):
        table = config
        for key in path[:-1]:
            table = table[key]
        table[path[-1]] = value

    return edit


# ---- indices, sizes, fractions --------------------------------------------------------------------


@pytest.mark.parametrize("value", [0.0, -1.5, math.nan, math.inf])
def test_host_index_must_be_positive_and_finite(value):
    error = expect_error(set_in(["host", "refractive_index"], value), "host.refractive_index.n", "> 0")
    assert error.value is value


@pytest.mark.parametrize("value", [0.0, -1.61, math.nan])
def test_particle_index_must_be_positive(value):
    expect_error(set_in(["particles", 0, "refractive_index"], value), "particles[scatterers].refractive_index.n", "> 0")


def test_particle_extinction_index_must_not_be_negative():
    expect_error(
        set_in(["particles", 0, "refractive_index"], [1.61, -0.01]), "particles[scatterers].refractive_index.k", "≥ 0"
    )


def test_host_must_not_have_a_complex_index():
    expect_error(set_in(["host", "refractive_index"], [1.557, 0.01]), "host.refractive_index.k", "absorption_per_mm")


@pytest.mark.parametrize("value", [0.0, -150.0, math.nan, "150", 1e9, math.inf])
def test_diameter_must_be_positive(value):
    expect_error(set_in(["particles", 0, "diameter_nm"], value), "particles[scatterers].diameter_nm", "[1, 100000] nm")


@pytest.mark.parametrize("value", [0.0, -0.1, 0.74, 0.9, math.nan])
def test_volume_fraction_must_lie_in_the_open_interval(value):
    error = expect_error(
        set_in(["particles", 0, "volume_fraction"], value), "particles[scatterers].volume_fraction", "(0, 0.74)"
    )
    assert error.value is value


def test_total_volume_fraction_must_stay_below_close_packing():
    def edit(config):
        config["particles"] = [dict(config["particles"][0], name=name, volume_fraction=0.4) for name in ("a", "b")]

    expect_error(edit, "particles[*].volume_fraction (sum)", "< 0.74")


@pytest.mark.parametrize("sigma", [1.0, 0.5, 3.0])
def test_log_normal_width_is_checked(sigma):
    def edit(config):
        particle = config["particles"][0]
        del particle["diameter_nm"]
        particle.update(median_diameter_nm=150.0, geometric_sigma=sigma)

    expect_error(edit, "particles[scatterers].geometric_sigma", "(1, 2.5]")


def test_size_must_be_given_exactly_once():
    expect_error(set_in(["particles", 0, "median_diameter_nm"], 100.0), "particles[scatterers].diameter_nm", "not both")

    def no_size(config):
        del config["particles"][0]["diameter_nm"]

    expect_error(no_size, "particles[scatterers].diameter_nm", "a diameter")


# ---- wavelength grid ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "values, allowed",
    [
        ([], "non-empty"),
        ([400.0, 390.0, 500.0], "strictly increasing"),
        ([400.0, 400.0], "strictly increasing"),
        ([400.0, math.nan], "finite"),
    ],
)
def test_explicit_wavelength_grid_must_be_non_empty_and_increasing(values, allowed):
    expect_error(set_in(["wavelengths"], {"values_nm": values}), "wavelengths.values_nm", allowed)


def test_explicit_wavelength_grid_is_used():
    params = build(set_in(["wavelengths"], {"values_nm": [450.0, 500.0, 650.0]}))
    np.testing.assert_array_equal(medium_optics(params).wavelengths_nm, [450.0, 500.0, 650.0])


def test_wavelength_range_is_checked():
    expect_error(set_in(["wavelengths", "stop_nm"], 380.0), "wavelengths.stop_nm", "≥ start_nm")
    expect_error(set_in(["wavelengths", "step_nm"], 0.0), "wavelengths.step_nm", "> 0")
    expect_error(set_in(["wavelengths", "step_nm"], 7.0), "wavelengths.step_nm", "divisor")
    expect_error(set_in(["wavelengths", "values_nm"], [400.0, 500.0]), "wavelengths.values_nm", "not both")


def test_default_wavelength_grid_is_the_papers():
    np.testing.assert_array_equal(WavelengthGrid().values, np.arange(390.0, 731.0, 10.0))


def test_tabulated_index_must_cover_the_grid():
    table = {"wavelengths_nm": [400.0, 700.0], "n": [1.56, 1.55]}
    expect_error(set_in(["host", "refractive_index"], table), "host.refractive_index.wavelengths_nm", "covering")
    with pytest.raises(ParameterError, match="one per wavelength"):
        RefractiveIndex(n=(1.5, 1.6, 1.7), wavelengths_nm=(400.0, 700.0))


# ---- dye --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("value", [-1.0, 100.0, math.nan])
def test_dye_weight_percent_is_checked(value):
    expect_error(set_in(["dye", "weight_percent"], value), "dye.weight_percent", "[0, 100)")


def test_fiber_density_must_be_positive():
    expect_error(set_in(["dye", "fiber_density_g_per_cm3"], 0.0), "dye.fiber_density_g_per_cm3", "> 0")


@pytest.mark.parametrize(
    "rows, allowed",
    [
        (["400,10", "500,", "600,30"], "two values"),
        (["400,10", "500", "600,30"], "two values"),
        (["400,10", "500,-3", "600,30"], "≥ 0"),
        (["400,10", "500,nan", "600,30"], "finite"),
        (["400,10", "500,lots", "600,30"], "numbers"),
        (["400,10", "390,20", "600,30"], "strictly increasing"),
        (["400,10"], "at least two"),
    ],
)
def test_user_dye_csv_is_validated(tmp_path, rows, allowed):
    path = tmp_path / "dye.csv"
    path.write_text("# a user's dye\nwavelength_nm,epsilon\n" + "\n".join(rows) + "\n")
    with pytest.raises(ParameterError) as info:
        build(set_in(["dye", "spectrum_csv"], str(path)))
    error = info.value
    assert error.name.startswith("dye.spectrum_csv") and allowed in error.allowed
    assert "dye.csv" in str(error)


def test_user_dye_csv_must_cover_the_grid(tmp_path):
    path = tmp_path / "narrow.csv"
    path.write_text("wavelength_nm,epsilon\n400,10\n700,20\n")
    expect_error(set_in(["dye", "spectrum_csv"], str(path)), "dye.spectrum_csv wavelengths", "covering")


def test_user_dye_csv_is_used(tmp_path):
    path = tmp_path / "flat.csv"
    path.write_text("wavelength_nm,epsilon\n380,1000\n740,1000\n")
    optics = medium_optics(build(set_in(["dye", "spectrum_csv"], str(path))))
    # ε = 1000 cm²/g at 3 % in 1.52 g/cm³: μa = 1000 · 0.03 · 1.52 / 10 per mm, on top of no particle absorption.
    np.testing.assert_allclose(optics.mu_a, 1000 * 0.03 * 1.52 / 10)
    assert read_spectrum_csv(path, "dye.spectrum_csv") == ((380.0, 740.0), (1000.0, 1000.0))


def test_missing_dye_csv_is_reported():
    expect_error(set_in(["dye", "spectrum_csv"], "no_such_dye.csv"), "dye.spectrum_csv", "existing CSV")


# ---- tables, keys, yarn, medium settings -------------------------------------------------------------


@pytest.mark.parametrize(
    "path, name",
    [
        (["host", "colour"], "host.colour"),
        (["particles", 0, "radius_nm"], "particles[0].radius_nm"),
        (["dye", "percent"], "dye.percent"),
        (["yarn", "twist"], "yarn.twist"),
        (["medium", "model"], "medium.model"),
        (["wavelengths", "count"], "wavelengths.count"),
        (["lighting"], "preset.lighting"),
    ],
)
def test_unknown_keys_are_rejected(path, name):
    expect_error(set_in(path, 1.0), name, "one of the keys")


def test_transport_and_bake_tables_belong_to_the_bake():
    def edit(config):
        config["transport"] = {"photons": 10, "anything": "goes"}
        config["bake"] = {"resolution": 8}

    assert build(edit).name == "paper_2008"


@pytest.mark.parametrize(
    "path, value, name, allowed",
    [
        (["yarn", "radius_mm"], 0.0, "yarn.radius_mm", "[0.001, 10] mm"),
        (["yarn", "radius_mm"], 11.0, "yarn.radius_mm", "[0.001, 10] mm"),
        (["yarn", "ply_count"], 0, "yarn.ply_count", "[1, 6]"),
        (["yarn", "ply_count"], 2.5, "yarn.ply_count", "an integer"),
        (["yarn", "ply_count"], True, "yarn.ply_count", "an integer"),
        (["yarn", "twist_angle_deg"], 60.0, "yarn.twist_angle_deg", "[0, 60) °"),
        (["yarn", "twist_angle_deg"], -1.0, "yarn.twist_angle_deg", "[0, 60) °"),
        (["yarn", "twist_angle_deg"], float("nan"), "yarn.twist_angle_deg", "[0, 60) °"),
        (["host", "refractive_index"], 0.5, "host.refractive_index.n", "[1, 10]"),
        (["host", "refractive_index"], 12.0, "host.refractive_index.n", "[1, 10]"),
        (["wavelengths", "step_nm"], 1e-6, "wavelengths.step_nm", "at most 1001 wavelengths"),
        (["particles", 0, "diameter_nm"], 2e5, "particles[scatterers].diameter_nm", "[1, 100000] nm"),
        (["yarn", "cross_section"], "square", "yarn.cross_section", "'circle' or 'ellipse'"),
        (["yarn", "semi_axes_mm"], [0.12, 0.08], "yarn.semi_axes_mm", "absent"),
        (["medium", "dependent_scattering"], "mie-dependent", "medium.dependent_scattering", "percus-yevick"),
        (["medium", "phase_samples"], 10, "medium.phase_samples", "[201, 200001]"),
        (["medium", "phase_samples"], 2001.5, "medium.phase_samples", "integer"),
        (["medium", "phase_samples"], "automatic", "medium.phase_samples", "'auto'"),
    ],
)
def test_yarn_and_medium_settings_are_checked(path, value, name, allowed):
    expect_error(set_in(path, value), name, allowed)


def test_elliptical_yarn_needs_its_semi_axes():
    expect_error(set_in(["yarn", "cross_section"], "ellipse"), "yarn.semi_axes_mm", "two semi-axes")

    def ellipse(config):
        config["yarn"].update(cross_section="ellipse", semi_axes_mm=[0.12, 0.08])

    assert build(ellipse).yarn.semi_axes_mm == (0.12, 0.08)


def test_coarse_explicit_phase_grid_is_an_error_not_a_silent_loss():
    def big_particles(config):
        config["wavelengths"] = {"values_nm": [550.0]}
        config["particles"][0]["diameter_nm"] = 3000.0
        config["medium"]["phase_samples"] = 2001

    error = expect_error(big_particles, "medium.phase_samples", "forward-peaked")
    assert error.value == 2001 and '"auto"' in error.allowed
    needed = int(re.match(r"≥ (\d+)", error.allowed).group(1))

    def finer(config):
        big_particles(config)
        config["medium"]["phase_samples"] = needed

    optics = medium_optics(build(finer))
    assert optics.cos_theta.size == needed and optics.mu_s[0] > 0 and optics.phase_grid == "uniform-cos"


def test_phase_samples_default_to_auto_which_fits_the_particles():
    def big_particles(config):
        config["wavelengths"] = {"values_nm": [550.0]}
        config["particles"][0]["diameter_nm"] = 3000.0

    params = build(big_particles)
    assert params.phase_samples == "auto" and params.to_dict()["phase_samples"] == "auto"
    optics = medium_optics(params)
    assert optics.phase_grid == "uniform-angle" and optics.mu_s[0] > 0
    assert build(set_in(["medium", "phase_samples"], "auto")).phase_samples == "auto"
    # the paper's medium keeps the default grid, uniform in cos θ
    red = medium_optics(load_preset("paper_2008"))
    assert (red.phase_grid, red.phase_samples) == ("uniform-cos", 2001)


def test_shipped_presets_all_load():
    assert "paper_2008" in preset_names() and len(preset_names()) >= 4
    for name in preset_names():
        params = load_preset(name)
        assert params.name == name and params.yarn.radius_mm > 0
        assert params.to_dict()["name"] == name


def test_unknown_preset_and_bad_toml(tmp_path):
    with pytest.raises(ParameterError, match="paper_2008"):
        load_preset("no_such_preset")
    broken = tmp_path / "broken.toml"
    broken.write_text("[host\nrefractive_index = 1.5\n")
    with pytest.raises(ParameterError, match="valid TOML"):
        load_preset(broken)


def test_command_exits_2_and_names_the_parameter(tmp_path, capsys):
    config = tmp_path / "bad.toml"
    text = (PRESET_DIR / "paper_2008.toml").read_text().replace("volume_fraction = 0.14", "volume_fraction = 0.8")
    config.write_text(text)
    assert main(["optics", "--config", str(config)]) == 2
    err = capsys.readouterr().err
    assert "particles[scatterers].volume_fraction" in err and "0.8" in err and "(0, 0.74)" in err
