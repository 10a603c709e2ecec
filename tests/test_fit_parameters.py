"""The fit's pieces without an optimiser: the free-parameter table (round trips, bounds inside the
medium's, refusals), the objective's views and target ratios, the fitted preset's TOML, and the
vectorised Cook–Torrance against its scalar twin."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from precompute import bounds
from precompute.optics.cook_torrance import cook_torrance, cook_torrance_between, direction, specular_from_config
from precompute.errors import InputError, ParameterError
from precompute.fit.objective import Objective, parse_target_ratios, split_views
from precompute.fit.parameters import (
    DYE_SHARE_PATH,
    PARAMETERS,
    MissingSpeciesError,
    UnknownFitParameterError,
    apply,
    initial_values,
    parse_free,
)
from precompute.fit.report import to_toml
from precompute.bounds import FIBRE_DIAMETER_UM
from precompute.optics.medium import (
    MAX_FIBRE_VOLUME_FRACTION,
    MAX_VOLUME_FRACTION,
    load_preset_config,
    medium_from_dict,
)
from tests.test_fibre_optics import FIBRE_COTTON
from tests.test_fit_optimise import preset_with_voids, real_fabric_views, synthetic_brdf


@pytest.mark.parametrize("name", list(PARAMETERS))
def test_unit_mapping_round_trips_and_spans_the_range(name):
    p = PARAMETERS[name]
    assert p.from_unit(0.0) == pytest.approx(p.low) and p.from_unit(1.0) == pytest.approx(p.high)
    for u in (0.0, 0.1, 0.37, 0.5, 0.93, 1.0):
        assert p.to_unit(p.from_unit(u)) == pytest.approx(u, abs=1e-12)
    if p.log:  # log scale: the middle of [0, 1] is the geometric mean
        assert p.from_unit(0.5) == pytest.approx(math.sqrt(p.low * p.high))
    assert p.at_bound(p.low) == "lower" and p.at_bound(p.high) == "upper"
    assert p.at_bound(p.from_unit(0.5)) is None


@pytest.mark.parametrize("name", list(PARAMETERS))
def test_fit_ranges_lie_within_what_the_medium_accepts(name):
    p = PARAMETERS[name]
    assert p.low < p.high
    if p.path == "fibres.volume_fraction":
        assert 0 < p.low and p.high < MAX_FIBRE_VOLUME_FRACTION
    elif p.path.endswith("volume_fraction"):
        assert 0 < p.low and p.high < MAX_VOLUME_FRACTION
    if p.path == "fibres.diameter_um":
        FIBRE_DIAMETER_UM.check(p.low)
        FIBRE_DIAMETER_UM.check(p.high)
    if p.path.endswith("diameter_nm"):
        bounds.PARTICLE_DIAMETER_NM.check(p.low * p.scale)
        bounds.PARTICLE_DIAMETER_NM.check(p.high * p.scale)
    if p.path == "yarn.radius_mm":
        bounds.YARN_RADIUS_MM.check(p.low)
        bounds.YARN_RADIUS_MM.check(p.high)
    if p.path == "dye.weight_percent":
        assert 0 <= p.low and p.high < 100
    # either end, written into a preset, loads (the sum of fractions aside)
    config, base_dir = load_preset_config(FIBRE_COTTON) if p.path.startswith("fibres.") else preset_with_voids()
    if p.path == DYE_SHARE_PATH:
        config["dye"]["spectrum_csv"] = ["congo_red.csv", "red_dye_band_model.csv"]
    for value in (p.low, p.high):
        new, keywords = apply(config, None, {name: value})
        if p.is_specular:
            assert keywords[p.path] == value
        else:
            assert p.get(new) == pytest.approx(value)
            if sum(t["volume_fraction"] for t in new.get("particles", [])) < MAX_VOLUME_FRACTION:
                medium_from_dict(new, base_dir)


def test_apply_sets_the_preset_paths_and_leaves_the_input_alone():
    config, _ = preset_with_voids()
    new, keywords = apply(config, None, {"void_fraction": 0.1, "void_diameter_um": 2.5, "scatterer_diameter_nm": 300,
                                         "dye_weight_percent": 4.0, "yarn_radius_mm": 0.2, "specular_slope": 0.3})
    voids = next(t for t in new["particles"] if t["name"] == "voids")
    scatterers = next(t for t in new["particles"] if t["name"] == "scatterers")
    assert voids["volume_fraction"] == 0.1 and voids["diameter_nm"] == 2500.0
    assert scatterers["diameter_nm"] == 300.0
    assert new["dye"]["weight_percent"] == 4.0 and new["yarn"]["radius_mm"] == 0.2
    assert keywords == {"specular_weight": 1.0, "specular_slope": 0.3, "fuzz_albedo": 0.0, "fuzz_depth": 0.0,
                        "fuzz_asymmetry": 0.0, "fuzz_tint_red": 1.0, "fuzz_tint_blue": 1.0,
                        "fuzz_flatness": 0.0}  # the shader's defaults
    assert next(t for t in config["particles"] if t["name"] == "voids")["volume_fraction"] == 0.02
    assert config["dye"]["weight_percent"] == 3.0


def test_the_dye_share_mixes_two_dyes_and_is_refused_for_one():
    config, base_dir = preset_with_voids()
    with pytest.raises(MissingSpeciesError, match="two dye spectra"):
        apply(config, None, {"dye_share": 0.3})
    config["dye"]["spectrum_csv"] = ["congo_red.csv", "red_dye_band_model.csv"]
    assert PARAMETERS["dye_share"].get(config) == 0.5  # no shares written: an even mixture
    new, _ = apply(config, None, {"dye_share": 0.3})
    assert new["dye"]["shares"] == pytest.approx([0.7, 0.3])
    # the mixture's absorption is the shares' sum of the two dyes' (precompute.optics.medium)
    congo_red_only = {**new, "dye": {**new["dye"], "shares": [1.0, 0.0]}}
    mixed, alone = (medium_from_dict(c, base_dir).dye for c in (new, congo_red_only))
    assert not np.allclose(mixed.mass_absorption_cm2_per_g, alone.mass_absorption_cm2_per_g)


def test_unknown_parameter_names_the_allowed_ones():
    with pytest.raises(UnknownFitParameterError) as caught:
        parse_free("void_fraction,void_colour")
    assert isinstance(caught.value, InputError)
    assert "void_colour" in str(caught.value)
    for name in PARAMETERS:
        assert name in str(caught.value)
    with pytest.raises(ParameterError, match="each parameter once"):
        parse_free("dye_weight_percent,dye_weight_percent")
    with pytest.raises(ParameterError):
        parse_free(" , ")
    assert [p.name for p in parse_free(["specular_slope", "void_fraction"])] == ["specular_slope", "void_fraction"]


def test_a_preset_without_voids_is_refused_with_the_table_to_add():
    config, _ = load_preset_config("paper_2008")
    with pytest.raises(MissingSpeciesError) as caught:
        initial_values(parse_free("void_fraction"), config)
    message = str(caught.value)
    assert "voids" in message and "[[particles]]" in message and "scatterers" in message
    # the red cotton's scatterers and dye are there
    start = initial_values(parse_free("scatterer_fraction,scatterer_diameter_nm,dye_weight_percent"), config)
    assert start == {"scatterer_fraction": 0.14, "scatterer_diameter_nm": 150.0, "dye_weight_percent": 3.0}


def test_start_values_are_clipped_into_the_fit_range_and_specular_read_from_fit_table():
    config, _ = preset_with_voids(specular_weight=0.4)
    config["dye"]["weight_percent"] = 0.0
    assert initial_values(parse_free("dye_weight_percent"), config)["dye_weight_percent"] == 0.1
    assert specular_from_config(config) == {"specular_weight": 0.4, "specular_slope": 0.8, "fuzz_albedo": 0.0,
                                            "fuzz_depth": 0.0, "fuzz_asymmetry": 0.0, "fuzz_tint_red": 1.0,
                                            "fuzz_tint_blue": 1.0, "fuzz_flatness": 0.0}


class Measured:
    """A measurement of the synthetic cloth at the real fabrics' views (what split_views and Objective read)."""

    angles_deg = np.array(real_fabric_views(), float)
    rgb = synthetic_brdf(real_fabric_views(), 0.05, 2.0, 0.6, 0.35)


def test_views_split_into_the_plane_of_incidence_and_the_held_out_perpendicular_plane():
    views = real_fabric_views()
    split = split_views(Measured)
    perpendicular = np.array([v[3] == 90 for v in views])
    np.testing.assert_array_equal(split.held_out, perpendicular)
    np.testing.assert_array_equal(split.fit, ~perpendicular)
    light_side = np.array([v[3] == 180 and v[2] > 0 for v in views])
    np.testing.assert_array_equal(split.signed_view_deg[light_side], -Measured.angles_deg[light_side, 2])
    assert split.incidences == [0.0, 30.0, 45.0, 60.0]
    # the forward model's frame: light at φi = 180°; a file with the light at φi = 0 is turned to it
    turned = Measured.angles_deg.copy()
    turned[:, 1] = 0.0
    turned[:, 3] = (turned[:, 3] + 180.0) % 360.0

    class Turned(Measured):
        angles_deg = turned

    assert split_views(Turned).forward_views == split.forward_views
    assert split.normal_views().sum() == 4  # θi 0: θo 0 and 10 (both sides) in plane, 10 perpendicular
    assert all(Measured.angles_deg[split.normal_views(), 0] == 0)


def test_objective_is_the_rms_over_channels_of_per_channel_relative_rms():
    objective = Objective(Measured)
    assert objective(Measured.rgb) == 0.0
    scaled = Measured.rgb * np.array([1.1, 1.0, 1.0])  # red 10 % high: e_R = 0.1, others 0
    assert objective(scaled) == pytest.approx(0.1 / math.sqrt(3))
    # the green of a red cloth counts as much as its red, whatever its level
    assert objective(Measured.rgb * np.array([1.0, 1.1, 1.0])) == pytest.approx(objective(scaled))
    with pytest.raises(RuntimeError, match="shape"):
        objective(Measured.rgb[:-1])
    targets = Objective(Measured, target_ratios={"B/R": 0.5})
    assert targets(Measured.rgb) > objective(Measured.rgb)


def test_target_ratios_parse_and_refuse():
    assert parse_target_ratios("B/R=0.08,G/R=0.011") == {"B/R": 0.08, "G/R": 0.011}
    assert parse_target_ratios(" B / R = 0.5 ") == {"B/R": 0.5}
    assert parse_target_ratios(None) == {}
    for bad in ("B/R", "B/R=0", "B/R=-1", "X/R=0.1", "R/R=1", "B/R=nan", "B/R=0.1,B/R=0.2", ""):
        with pytest.raises(ParameterError, match="--target-ratios"):
            parse_target_ratios(bad)


def test_toml_writer_round_trips_a_preset():
    config, _ = load_preset_config("paper_2008")
    config["particles"].append({"name": "voids \"air\"", "refractive_index": {"n": [1.0, 1.0],
                                "wavelengths_nm": [390.0, 730.0]}, "diameter_nm": 1e-3 * 2, "volume_fraction": 0.02})
    config["transport"] = {"paths_per_cell": 2000, "incidence_resolution": "auto"}
    config["fit"] = {"specular_weight": 0.6, "flag": True}
    assert tomllib.loads(to_toml(config)) == config


def test_vectorised_cook_torrance_matches_the_scalar_twin():
    rng = np.random.default_rng(4)
    lights = direction(rng.uniform(0, 89, 200), rng.uniform(0, 360, 200))
    views = direction(rng.uniform(0, 89, 200), rng.uniform(0, 360, 200))
    for m in (0.1, 0.35, 0.8):
        expected = [cook_torrance_between(light, view, m) for light, view in zip(lights, views)]
        np.testing.assert_allclose(cook_torrance(lights, views, m), expected, rtol=1e-9, atol=1e-12)
    # normal incidence and view, and a direction below the plane
    up = np.array([0.0, 0.0, 1.0])
    assert cook_torrance(up, up, 0.8) == pytest.approx(cook_torrance_between(up, up, 0.8))
    assert cook_torrance(up, -up, 0.8) == 0.0


def test_results_become_standard_json():
    import json

    from precompute.outputs import json_ready

    value = {"a": [np.float32(0.5), math.nan, (np.int64(3), True)], "b": {"c": math.inf, "d": "text", "e": None}}
    ready = json_ready(value)
    assert ready == {"a": [0.5, None, [3, True]], "b": {"c": None, "d": "text", "e": None}}
    assert type(ready["a"][0]) is float and type(ready["a"][2][0]) is int and ready["a"][2][1] is True
    json.dumps(ready, allow_nan=False)  # no NaN or infinity left
