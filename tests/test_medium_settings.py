"""A medium's settings three ways (clothlight/medium_settings.py), without Blender: a preset's keys,
a bake request's overrides and the panel's values map into each other and back."""

import pytest

from clothlight.medium_settings import (
    BASE_MEDIUM_NUMBERS,
    CUSTOM_BASE,
    exposed_values,
    medium_keys,
    preset_config,
    request_overrides,
    shown_key,
    takes_dye_series,
    typed_number,
)
from precompute.optics.medium import PRESET_DIR, preset_names


def test_a_request_read_into_panel_values_asks_for_the_same_bake_again():
    config = preset_config("voided_red_cotton")
    overrides = (("dye.weight_percent", 2.5), ("particles.1.volume_fraction", 0.1), ("fit.specular_slope", 0.4))
    values, fitted = exposed_values(config, overrides)
    # the panel shows the dye and the first species; the voids' fraction and the sheen stay fitted values
    assert values["dye_weight_percent"] == 2.5
    assert values["particle_volume_fraction"] == pytest.approx(0.14)
    assert values["yarn_radius_mm"] == pytest.approx(0.1)
    assert fitted == {"particles.1.volume_fraction": 0.1, "fit.specular_slope": 0.4}
    assert sorted(request_overrides(config, values, fitted.items())) == sorted(overrides)


def test_a_value_as_the_panel_stores_it_is_no_override():
    config = preset_config("voided_red_cotton")
    values, fitted = exposed_values(config, ())
    single_precision = {prop: float(f"{value:.9g}") + 1e-10 for prop, value in values.items()}
    assert request_overrides(config, single_precision) == ()
    assert typed_number(0.14000000059604645) == 0.14
    # a fitted value equal to the preset's asks for nothing either
    assert request_overrides(config, values, [("particles.1.volume_fraction", 0.083)]) == ()


def test_the_exposed_keys_follow_what_the_preset_has():
    red = medium_keys(preset_config("voided_red_cotton"))
    assert red == {"yarn_radius_mm": "yarn.radius_mm", "dye_weight_percent": "dye.weight_percent",
                   "particle_diameter_nm": "particles.0.diameter_nm",
                   "particle_volume_fraction": "particles.0.volume_fraction"}
    assert "dye_weight_percent" not in medium_keys(preset_config("delustred_polyester"))
    assert shown_key("particles.1.volume_fraction", preset_config("voided_red_cotton")) == "voids.volume_fraction"
    assert shown_key("dye.weight_percent", preset_config("voided_red_cotton")) == "dye.weight_percent"


@pytest.mark.parametrize("name, takes", [("voided_red_cotton", True), ("paper_2008", True), ("undyed_cotton", False),
                                         ("blue_cotton", True), ("pink_felt", True),
                                         (str(PRESET_DIR / "experimental" / "fibre_cotton.toml"), False)])
def test_the_dye_range_is_offered_where_the_bake_can_reweight_the_dye(name, takes):
    # the bake's dye series reweights absorption along paths it traced once: a dye in randomly oriented
    # fibres changes their index, hence their scattering, and the bake refuses it
    # (precompute.bake.check_dye_series); in fibres along the yarn axis it only absorbs inside them
    from precompute.bake import bake_configuration, check_dye_series
    from precompute.errors import ParameterError

    config = preset_config(name)
    assert takes_dye_series(config) == takes
    if not takes:
        with pytest.raises(ParameterError, match="dye_series"):
            check_dye_series(bake_configuration(name), (0.5, 5.0))


def test_every_base_medium_has_a_number_of_its_own_that_saved_files_keep():
    # Blender stores the Base Medium as its item's number: one per shipped preset and the custom file
    assert set(BASE_MEDIUM_NUMBERS) == set(preset_names()) | {CUSTOM_BASE}
    assert len(set(BASE_MEDIUM_NUMBERS.values())) == len(BASE_MEDIUM_NUMBERS)
    # the ten presets of files saved before the numbers were frozen hold their sorted positions of then
    frozen = sorted(name for name, number in BASE_MEDIUM_NUMBERS.items() if number < 10)
    assert [BASE_MEDIUM_NUMBERS[name] for name in frozen] == list(range(10))
