"""The measured sample's weave (``[sample]``): read and checked by name, built as a woven sample,
recorded by the bake and keyed into the fit's cloth response."""

from __future__ import annotations

import json

import numpy as np
import pytest

from clothlight.fit import forward
from clothlight.weave.record import weave_record
from clothlight.weave.sample_weaves import SAMPLE_SIDE_MM, sample_weave
from precompute import bake as bake_module
from precompute.errors import ParameterError
from precompute.optics.measured_sample import (DEFAULT_SAMPLE_AZIMUTHS_DEG, SAMPLE_WEAVES, sample_azimuths_deg,
                                              sample_weave_name)
from precompute.optics.medium import load_preset_config, medium_from_dict
from precompute.tables.exr import TableError
from precompute.tables.folder import (SAMPLE_AZIMUTHS_RECORD_KEY, SAMPLE_WEAVE_KEY, summary_sample_table,
                                      summary_sample_weave)
from tests.helpers import write_yarn_table_folder

#: The raw-data curves' widest view and light (views to 80°, light to 75°), which need the wide sample.
WIDE_VIEWS = [(75.0, 180.0, 80.0, 0.0), (0.0, 180.0, 10.0, 90.0)]


def test_a_preset_names_its_sample_weave_or_gets_the_open_one():
    assert sample_weave_name({}) == "open"
    assert sample_weave_name({"sample": {"weave": "sheeting"}}) == "sheeting"
    with pytest.raises(ParameterError, match=r"sample\.weave.*satin.*open, sheeting"):
        sample_weave_name({"sample": {"weave": "satin"}})
    with pytest.raises(ParameterError, match=r"sample\.spacing_mm"):
        sample_weave_name({"sample": {"weave": "sheeting", "spacing_mm": 0.3}})
    with pytest.raises(ParameterError, match="sample"):
        sample_weave_name({"sample": "sheeting"})


def test_the_medium_reads_a_preset_with_a_sample_table():
    config, base = load_preset_config("voided_red_cotton")
    assert medium_from_dict({**config, "sample": {"weave": "sheeting"}}, base) == medium_from_dict(config, base)


@pytest.mark.parametrize("radius_mm", [0.1, 0.12])
def test_the_sheeting_sample_is_packed_sheeting_of_the_yarn_about_ten_millimetres_wide(radius_mm):
    weave = sample_weave("sheeting", radius_mm)
    assert weave.spacing_mm == pytest.approx(0.4 * radius_mm / 0.1)  # Peirce's K = 14
    width, thickness = weave.cross_section_mm
    assert width / thickness == pytest.approx(1.6) and width * thickness == pytest.approx(0.9 * radius_mm**2)
    assert weave.cover_factor == pytest.approx(0.84, abs=0.01)
    assert weave.ply_count == 1 and not weave.is_irregular
    assert weave.sample_size_mm[0] == pytest.approx(SAMPLE_SIDE_MM, rel=0.05)
    assert sample_weave("open", radius_mm) is None
    for name in SAMPLE_WEAVES:  # every name the presets may give has a sample (an unknown one raises)
        sample_weave(name, radius_mm)


@pytest.mark.parametrize("radius_mm", [0.1, 0.12])
def test_the_pressed_sample_is_the_sheeting_yarn_pressed_flat_with_no_gap(radius_mm):
    sheeting, pressed = sample_weave("sheeting", radius_mm), sample_weave("pressed", radius_mm)
    width, thickness = pressed.cross_section_mm
    assert width / thickness == pytest.approx(5.0)
    assert width * thickness == pytest.approx(np.prod(sheeting.cross_section_mm))  # the same yarn, pressed
    assert pressed.section_relaxation == 0.0  # flat all along, not only where the yarns cross
    assert pressed.spacing_mm == pytest.approx(4.6 * radius_mm)
    assert pressed.cover_factor > 0.99 > sheeting.cover_factor
    assert pressed.ply_count == 1 and not pressed.is_irregular
    assert pressed.sample_size_mm[0] == pytest.approx(SAMPLE_SIDE_MM, rel=0.05)


def test_the_bake_records_a_named_sample_weave_and_keys_its_tables_by_it():
    config, _ = load_preset_config("voided_red_cotton")
    plain = bake_module.bake_configuration(config)
    sheeting = bake_module.bake_configuration({**config, "sample": {"weave": "sheeting"}})
    assert plain.sample_weave is None and sheeting.sample_weave == "sheeting"
    # the tables of a preset without the table keep their key; the simulation is shared
    assert SAMPLE_WEAVE_KEY not in bake_module.table_inputs("k", plain)
    assert bake_module.table_inputs("k", sheeting)[SAMPLE_WEAVE_KEY] == "sheeting"
    assert bake_module.spectral_inputs(plain) == bake_module.spectral_inputs(sheeting)
    with pytest.raises(ParameterError, match=r"sample\.weave"):
        bake_module.bake_configuration({**config, "sample": {"weave": "twill"}})


def test_a_bake_summary_names_its_sample_weave_or_the_open_one(tmp_path):
    assert summary_sample_weave({}, tmp_path) == "open"
    assert summary_sample_weave({SAMPLE_WEAVE_KEY: "sheeting"}, tmp_path) == "sheeting"
    with pytest.raises(TableError, match="summary.json.*satin"):
        summary_sample_weave({SAMPLE_WEAVE_KEY: "satin"}, tmp_path)


class _Rendered(Exception):
    pass


@pytest.fixture
def response_inputs(monkeypatch, tmp_path):
    """What cloth_response would render and key (its store stood in for: no Blender)."""
    seen = []

    def store(cache_dir, kind, key, inputs, write):
        seen.append(inputs)
        raise _Rendered

    monkeypatch.setattr(forward, "store", store)

    def inputs(**kwargs):
        with pytest.raises(_Rendered):
            forward.cloth_response(WIDE_VIEWS, cache_dir=tmp_path, **kwargs)
        return seen[-1]

    return inputs


def test_the_response_is_keyed_by_the_sample_weave_it_renders(response_inputs):
    wide = response_inputs()
    assert wide["sample_yarns"] == [20, 20] and "sample_weave" not in wide
    sheeting = response_inputs(weave=sample_weave("sheeting", 0.1))
    assert "sample_yarns" not in sheeting
    assert sheeting["sample_weave"]["spacing_mm"] == pytest.approx(0.4)
    assert sheeting["sample_weave"]["semi_axes_mm"] == pytest.approx([0.12, 0.075])


def test_the_forward_model_renders_the_weave_its_preset_names(monkeypatch):
    weaves = []

    def cloth_response(views, *, weave=None, **kwargs):
        weaves.append(weave)
        raise _Rendered

    monkeypatch.setattr(forward, "cloth_response", cloth_response)
    config, base = load_preset_config("voided_red_cotton")
    for table in ({}, {"sample": {"weave": "sheeting"}}):
        with pytest.raises(_Rendered):
            forward.build_forward_model(WIDE_VIEWS, {**config, **table}, base)
    assert weaves[0] is None
    assert weave_record(weaves[1]) == weave_record(sample_weave("sheeting", 0.1))


def test_the_validation_of_a_bake_renders_the_sample_weave_it_records(tmp_path):
    from clothlight.validation.framing import tables_sample_weave

    n_i, n_o, samples = 3, 3, 8
    rng = np.random.default_rng(0)
    folder = write_yarn_table_folder(tmp_path / "bake", rng.uniform(0.0, 1.0, (n_i * n_o, n_i * n_o, 3)),
                                     rng.uniform(0.0, 1.0, (n_o, 2 * n_o, 3)), rng.uniform(0.0, 1.0, (1, samples, 3)),
                                     incidence_resolution=n_i, exit_resolution=n_o)
    assert tables_sample_weave(folder) is None  # a summary that names none (its medium records no yarn)
    summary_file = folder / "summary.json"
    summary = json.loads(summary_file.read_text())
    summary["medium"] = {"yarn": {"radius_mm": 0.12}}
    summary_file.write_text(json.dumps({**summary, SAMPLE_WEAVE_KEY: "sheeting"}))
    assert weave_record(tables_sample_weave(folder)) == weave_record(sample_weave("sheeting", 0.12))


def test_a_preset_names_the_sample_azimuths_or_gets_the_warp_square_and_across():
    assert sample_azimuths_deg({}) == DEFAULT_SAMPLE_AZIMUTHS_DEG == (0.0, 90.0)
    assert sample_azimuths_deg({"sample": {"weave": "pressed"}}) == (0.0, 90.0)
    named = {"sample": {"weave": "pressed", "azimuths_deg": [0, 45, 90, 135]}}
    assert sample_azimuths_deg(named) == (0.0, 45.0, 90.0, 135.0)
    assert sample_weave_name(named) == "pressed"  # the weave's reader takes the azimuths' key
    for bad in ([], [0, 180], [-45, 0], [90, 0], [0, 0], "0, 90", [True], [0, float("nan")]):
        with pytest.raises(ParameterError, match=r"sample\.azimuths_deg"):
            sample_azimuths_deg({"sample": {"azimuths_deg": bad}})


def test_the_bake_records_named_sample_azimuths_and_a_summary_gives_them_back(tmp_path):
    config, _ = load_preset_config("red_cotton")
    plain = bake_module.bake_configuration(config)
    four = {**config, "sample": {**config["sample"], "azimuths_deg": [0, 45, 90, 135]}}
    turned = bake_module.bake_configuration(four)
    assert plain.sample_azimuths_deg is None and turned.sample_azimuths_deg == (0.0, 45.0, 90.0, 135.0)
    # a preset that names none keeps its tables' key
    assert SAMPLE_AZIMUTHS_RECORD_KEY not in bake_module.table_inputs("k", plain)
    summary = bake_module.table_inputs("k", turned)
    assert summary[SAMPLE_AZIMUTHS_RECORD_KEY] == [0.0, 45.0, 90.0, 135.0]
    table = summary_sample_table(summary, tmp_path)
    assert sample_azimuths_deg({"sample": table}) == (0.0, 45.0, 90.0, 135.0)
    assert sample_weave_name({"sample": table}) == "pressed"
    assert summary_sample_table({}, tmp_path) == {"weave": "open"}
    with pytest.raises(TableError, match="summary.json.*sample_azimuths_deg"):
        summary_sample_table({SAMPLE_AZIMUTHS_RECORD_KEY: [90, 0]}, tmp_path)


def test_every_view_is_rendered_at_each_named_azimuth_turned_as_the_default_ones(response_inputs):
    azimuths = (0.0, 45.0, 90.0, 135.0)
    views = response_inputs(azimuths_deg=azimuths)["views"]
    default = response_inputs()["views"]
    assert len(views) == 2 * len(default)
    # the views in the plane of incidence and across it at every azimuth, a diagonal view's turned by 45°
    plane, across = [v[3] for v in views if v[2] == 0.0], [v[3] for v in views if v[2] == 90.0]
    assert plane[:4] == list(azimuths) and across == list(azimuths)
    assert forward.sample_azimuths(45.0, azimuths) == (-45.0, 0.0, 45.0, 90.0)
    # the default's renders are among them, at the same angles (the weave at the same angles to the light)
    assert set(default) <= set(views)


def test_the_forward_model_averages_the_cloth_over_the_named_azimuths(monkeypatch):
    calls = {}

    def cloth_response(views, *, azimuths_deg, **kwargs):
        calls["azimuths"] = azimuths_deg
        return object()

    monkeypatch.setattr(forward, "cloth_response", cloth_response)
    config, base = load_preset_config("red_cotton")
    named = {**config, "sample": {**config["sample"], "azimuths_deg": [0, 45, 90, 135]}}
    model = forward.build_forward_model(WIDE_VIEWS, named, base)
    assert calls["azimuths"] == (0.0, 45.0, 90.0, 135.0) and model.azimuth_count == 4
    rows = model.view_count * 4  # views, then the swatches, each at the four azimuths in turn
    per_render = np.arange(rows * 3, dtype=float).reshape(rows, 3)
    expected = per_render.reshape(model.view_count, 4, 3).mean(axis=1)
    assert np.allclose(model._mean_over_azimuths(per_render), expected)
    assert np.allclose(expected[0], per_render[:4].mean(axis=0))
    assert forward.build_forward_model(WIDE_VIEWS, config, base).azimuth_count == 2
