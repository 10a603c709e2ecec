"""A fitted preset's specular term (its ``[fit]`` table) and its medium's sheen index reach the tables:
recorded in the summary and every header, part of the tables' cache key but not of the spectral one,
read back by the folder check and the yarn material's table files (the paper's defaults and the host
index for folders baked before)."""

import json

import numpy as np
import pytest

from precompute import bake as bake_module
from precompute.cache import entries as cache
from precompute.errors import ParameterError
from precompute.optics.cook_torrance import (
    DEFAULT_SLOPE,
    DEFAULT_WEIGHT,
    FIT_TABLE,
    cook_torrance_between,
    sheen_index,
)
from precompute.optics.medium import PRESET_DIR, load_preset_config, medium_from_dict
from precompute.tables.folder import (
    SPECULAR_FROM_PRESET,
    SPECULAR_KEY,
    SUMMARY_FILE,
    check_yarn_table_folder,
    default_specular,
    summary_specular,
)
from precompute.tables.exr import TableError, read_table
from tests.helpers import write_yarn_table_folder

#: A reduced grid, as tests/test_cache.py bakes.
SMALL = ["transport.angular_resolution=4", "transport.incidence_resolution=5",
         "transport.n_around=8", "transport.n_along=4"]
FITTED = {"specular_weight": 0.55, "specular_slope": 0.35}
N_I, N_O, LOBES, SAMPLES = 5, 4, 5, 9

#: A shipped preset without a [fit] table: the paper's medium (the others are fitted).
PLAIN_PRESET = "paper_2008"
#: A yarn of fibres in air (not shipped).
FIBRE_PRESET = PRESET_DIR / "experimental" / "fibre_cotton.toml"


def keys(configuration) -> tuple[str, str]:
    spectral = cache.cache_key(bake_module.spectral_inputs(configuration))
    return spectral, cache.cache_key(bake_module.table_inputs(spectral, configuration))


def test_the_default_record_is_the_papers_from_the_cook_torrance_twin():
    assert default_specular() == {"weight": DEFAULT_WEIGHT, "slope": DEFAULT_SLOPE, "fuzz_albedo": 0.0,
                                  "source": f"default (paper §6: m = {DEFAULT_SLOPE:g})"}
    assert bake_module.FIT_DEFAULTS == {"specular_weight": DEFAULT_WEIGHT, "specular_slope": DEFAULT_SLOPE,
                                        "fuzz_albedo": 0.0, "fuzz_depth": 0.0, "fuzz_asymmetry": 0.0,
                                        "fuzz_tint_red": 1.0, "fuzz_tint_blue": 1.0, "fuzz_flatness": 0.0}


def paper_medium():
    config, base_dir = load_preset_config(PLAIN_PRESET)
    return medium_from_dict(config, base_dir)


def test_a_fit_table_is_recorded_as_such_and_checked():
    medium = paper_medium()
    index = {"index": pytest.approx(1.557)}
    assert bake_module.specular_settings({}, medium) == {**default_specular(), **index}
    assert bake_module.specular_settings({FIT_TABLE: {}}, medium) == {**default_specular(), **index}
    assert bake_module.specular_settings({FIT_TABLE: FITTED}, medium) == {"weight": 0.55, "slope": 0.35, **index,
                                                                          "fuzz_albedo": 0.0,
                                                                          "source": SPECULAR_FROM_PRESET}
    with_fuzz = bake_module.specular_settings({FIT_TABLE: {**FITTED, "fuzz_albedo": 0.1}}, medium)
    assert with_fuzz["fuzz_albedo"] == 0.1 and with_fuzz["source"] == SPECULAR_FROM_PRESET
    assert "fuzz_depth" not in with_fuzz  # a veneer: the record (and the tables' key) as before depths
    deep = bake_module.specular_settings({FIT_TABLE: {**FITTED, "fuzz_albedo": 0.1, "fuzz_depth": 0.3}}, medium)
    assert deep == {**with_fuzz, "fuzz_depth": 0.3}
    partial = bake_module.specular_settings({FIT_TABLE: {"specular_weight": 0.2}}, medium)
    assert (partial["weight"], partial["slope"]) == (0.2, DEFAULT_SLOPE)
    assert partial["source"].startswith(SPECULAR_FROM_PRESET) and "specular_slope: default" in partial["source"]
    for table, name in (({"specular_slop": 0.3}, "fit.specular_slop"), ({"specular_slope": 0.0}, "fit.specular_slope"),
                        ({"specular_weight": -0.1}, "fit.specular_weight"),
                        ({"specular_weight": True}, "fit.specular_weight"),
                        ({"specular_slope": float("nan")}, "fit.specular_slope"),
                        ({"specular_slope": "rough"}, "fit.specular_slope")):
        with pytest.raises(ParameterError, match=name.replace(".", r"\.")):
            bake_module.specular_settings({FIT_TABLE: table}, medium)
    with pytest.raises(ParameterError, match="fit"):
        bake_module.specular_settings({FIT_TABLE: 0.5}, medium)


def test_the_sheen_of_a_yarn_of_fibres_in_air_reflects_at_the_fibres_index():
    # No refracting yarn surface (host index 1): the fibres reflect the sheen.  Any other yarn
    # reflects it from its boundary, at the host's index (the paper's case).
    config, base_dir = load_preset_config(FIBRE_PRESET)
    in_air = medium_from_dict(config, base_dir)
    assert in_air.host.refractive_index.n == 1.0
    assert sheen_index(in_air) == pytest.approx(in_air.fibres.refractive_index.n)
    assert bake_module.bake_configuration(FIBRE_PRESET).specular["index"] == pytest.approx(1.557)
    in_resin = medium_from_dict({**config, "host": {"refractive_index": 1.4}}, base_dir)
    assert sheen_index(in_resin) == pytest.approx(1.4)
    assert sheen_index(paper_medium()) == pytest.approx(1.557)
    # A sheen at index 1 would be none: the Cook–Torrance term is there only at the fibres' index.
    up = np.array([0.0, 0.0, 1.0])
    assert cook_torrance_between(up, up, 0.3, 1.0) == 0.0 < cook_torrance_between(up, up, 0.3, sheen_index(in_air))


def test_the_specular_term_keys_the_tables_not_the_simulation():
    config, _ = load_preset_config(PLAIN_PRESET)
    plain = bake_module.bake_configuration(config, SMALL, paths_per_cell=100)
    fitted = bake_module.bake_configuration({**config, FIT_TABLE: FITTED}, SMALL, paths_per_cell=100)
    overridden = bake_module.bake_configuration(PLAIN_PRESET, [*SMALL, "fit.specular_weight=0.55",
                                                               "fit.specular_slope=0.35"], paths_per_cell=100)
    other = bake_module.bake_configuration({**config, FIT_TABLE: {**FITTED, "specular_slope": 0.5}}, SMALL,
                                           paths_per_cell=100)
    assert plain.specular == {**default_specular(), "index": pytest.approx(1.557)}
    assert fitted.specular == overridden.specular == {"weight": 0.55, "slope": 0.35, "index": pytest.approx(1.557),
                                                      "fuzz_albedo": 0.0, "source": SPECULAR_FROM_PRESET}
    assert bake_module.spectral_inputs(fitted) == bake_module.spectral_inputs(plain)
    (plain_spectral, plain_tables), (fitted_spectral, fitted_tables) = keys(plain), keys(fitted)
    assert fitted_spectral == plain_spectral == keys(other)[0]
    assert len({plain_tables, fitted_tables, keys(other)[1]}) == 3
    assert keys(overridden) == keys(fitted)
    # MediumParameters take [fit] overrides as they take [transport] and [bake] ones.
    assert bake_module.bake_configuration(plain.medium, [*SMALL, "fit.specular_slope=0.35"]).specular["slope"] == 0.35


@pytest.mark.slow  # a (tiny) Monte-Carlo transport, as tests/test_cache.py's bakes
def test_a_bake_records_the_fit_in_its_summary_and_headers_on_the_same_simulation(tmp_path, monkeypatch):
    runs = []
    real = bake_module.simulate_yarn
    monkeypatch.setattr(bake_module, "simulate_yarn", lambda *a, **k: runs.append(1) or real(*a, **k))
    fitted = bake_module.bake(PLAIN_PRESET, [*SMALL, *(f"fit.{k}={v}" for k, v in FITTED.items())],
                              paths_per_cell=100, cache_dir=tmp_path)
    plain = bake_module.bake(PLAIN_PRESET, SMALL, paths_per_cell=100, cache_dir=tmp_path)
    assert len(runs) == 1 and fitted.simulated and not plain.simulated and not plain.cache_hit
    assert fitted.folder != plain.folder and fitted.summary["spectral_key"] == plain.summary["spectral_key"]
    assert fitted.summary[SPECULAR_KEY] == {"weight": 0.55, "slope": 0.35, "index": pytest.approx(1.557),
                                            "fuzz_albedo": 0.0, "source": SPECULAR_FROM_PRESET}
    assert plain.summary[SPECULAR_KEY] == {**default_specular(), "index": pytest.approx(1.557)}
    for result in (fitted, plain):
        for kind in bake_module.TABLE_FILES:
            assert read_table(result.table(kind)).metadata[SPECULAR_KEY] == result.summary[SPECULAR_KEY]
        checked = check_yarn_table_folder(result.folder)
        assert summary_specular(checked.summary, result.folder) == result.summary[SPECULAR_KEY]
    # The same tables again: a cache hit, fit or not; the colour tables of both are the same pixels.
    assert bake_module.bake(PLAIN_PRESET, [*SMALL, "fit.specular_weight=0.55", "fit.specular_slope=0.35"],
                            paths_per_cell=100, cache_dir=tmp_path).cache_hit
    np.testing.assert_array_equal(read_table(fitted.brdf_table).pixels, read_table(plain.brdf_table).pixels)


def folder(path, **options):
    rng = np.random.default_rng(3)
    brdf = 10.0 ** rng.uniform(-4.0, 0.0, (N_I * N_O, N_I * N_O, 3))
    return write_yarn_table_folder(path, brdf, rng.uniform(0.0, 1.0, (N_O, LOBES * N_O, 3)),
                                   rng.uniform(0.0, 1.0, (1, SAMPLES, 3)), incidence_resolution=N_I,
                                   exit_resolution=N_O, **options)


RECORDED = {"weight": 0.55, "slope": 0.35, "index": 1.3, "source": SPECULAR_FROM_PRESET}


def test_the_table_files_carry_the_recorded_specular_or_the_defaults(tmp_path):
    from clothlight.yarn_tables import yarn_tables_from_bake

    recorded = yarn_tables_from_bake(folder(tmp_path / "fitted", specular=RECORDED))
    older = yarn_tables_from_bake(folder(tmp_path / "older"))
    # a record without the fuzz (baked before bakes recorded it): none
    assert recorded.specular == {**RECORDED, "fuzz_albedo": 0.0}
    assert recorded.specular_index == RECORDED["index"] != recorded.host_index
    # baked before bakes recorded it, or before they recorded its index: the host's
    assert older.specular == {**default_specular(), "index": older.host_index}
    without_index = {key: value for key, value in RECORDED.items() if key != "index"}
    assert yarn_tables_from_bake(folder(tmp_path / "no index", specular=without_index)).specular_index == 1.557


def rewrite_summary(path, **changes):
    summary = json.loads((path / SUMMARY_FILE).read_text())
    summary.update(changes)
    (path / SUMMARY_FILE).write_text(json.dumps(summary))


@pytest.mark.parametrize("specular, reason", [
    ({**RECORDED, "slope": 0.5}, "header specular"),  # the tables were baked with another one
    ({**RECORDED, "slope": 0.0}, "specular .* is not an object"),
    ({**RECORDED, "index": 0.9}, "specular .* is not an object"),  # no Fresnel factor below 1
    ({**RECORDED, "fuzz_albedo": 1.5}, "specular .* is not an object"),  # more light than it receives
    ({**RECORDED, "fuzz_depth": -0.1}, "specular .* is not an object"),
    ({"weight": 0.55, "slope": 0.35}, "specular .* is not an object"),
    ("fitted", "specular .* is not an object"),
])
def test_a_summary_whose_specular_is_not_the_tables_or_malformed_is_refused(tmp_path, specular, reason):
    path = folder(tmp_path / "fitted", specular=RECORDED)
    rewrite_summary(path, specular=specular)
    with pytest.raises(TableError, match=reason):
        check_yarn_table_folder(path)


def test_a_summary_that_drops_the_record_of_tables_that_have_one_is_refused(tmp_path):
    path = folder(tmp_path / "fitted", specular=RECORDED)
    summary = json.loads((path / SUMMARY_FILE).read_text())
    del summary[SPECULAR_KEY]
    (path / SUMMARY_FILE).write_text(json.dumps(summary))
    with pytest.raises(TableError, match="header specular"):
        check_yarn_table_folder(path)


@pytest.mark.parametrize("path", sorted([*PRESET_DIR.glob("*.toml"), *(PRESET_DIR / "experimental").glob("*.toml")]),
                         ids=lambda p: p.stem)
def test_every_preset_loads_and_its_fit_is_what_its_bake_records(path):
    # presets loaded by their path, shipped and experimental: the medium, the dye mixture and the [fit]
    # terms the bake records
    config, base_dir = load_preset_config(path)
    record = bake_module.specular_settings(config, medium_from_dict(config, base_dir))
    fit = config.get(FIT_TABLE, {})
    for key, recorded in (("specular_weight", "weight"), ("specular_slope", "slope"), ("fuzz_albedo", "fuzz_albedo"),
                          ("fuzz_depth", "fuzz_depth")):
        if key in fit:
            assert record[recorded] == fit[key], key
