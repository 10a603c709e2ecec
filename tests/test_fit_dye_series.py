"""The fit's forward model for a dye-only fit: one transport for the dye range, every candidate's
tables read from it (clothlight.fit.forward.DyeSeriesForwardModel), against the per-candidate one."""

import copy

import numpy as np
import pytest

from precompute.errors import ParameterError
from clothlight.fit.forward import DyeSeriesForwardModel, ForwardModel
from precompute.optics.medium import PRESET_DIR, load_preset_config

pytestmark = pytest.mark.slow

SMALL = {"n_around": 8, "n_along": 4, "angular_resolution": 4}


def preset_at_dye(name: str, dye: float) -> dict:
    config = copy.deepcopy(load_preset_config(name)[0])
    config.pop("fit")
    config["transport"] = dict(SMALL)
    config["dye"]["weight_percent"] = dye
    return config


def voided_red_cotton(dye: float) -> dict:
    return preset_at_dye("voided_red_cotton", dye)


@pytest.fixture(scope="module")
def series_model():
    return DyeSeriesForwardModel(None, 0, PRESET_DIR, (0.1, 3.0), relative_error=0.015, seed=2)


@pytest.mark.parametrize("name, dye_range, dyes, error", [
    ("voided_red_cotton", (0.1, 3.0), (0.1, 0.8, 3.0), 0.015),
    # dye in fibres along the yarn axis, their absorption reweighted: at 0.015 two fresh transports of
    # these small grids differ by up to 6 % in red, at 0.007 by 3 %
    ("indigo_cotton", (0.5, 8.0), (0.5, 2.0, 8.0), 0.007),
])
def test_candidates_read_from_one_series_agree_with_their_own_transport(name, dye_range, dyes, error):
    series_model = DyeSeriesForwardModel(None, 0, PRESET_DIR, dye_range, relative_error=error, seed=2)
    per_candidate = ForwardModel(None, 0, PRESET_DIR)
    previous = None
    for dye in dyes:
        atlas, attenuation, layout = series_model.tables(preset_at_dye(name, dye), relative_error=0.08, seed=0)
        fresh, fresh_attenuation, fresh_layout = per_candidate.tables(preset_at_dye(name, dye), relative_error=error,
                                                                      seed=5)
        assert layout == fresh_layout
        np.testing.assert_allclose(attenuation, fresh_attenuation, rtol=1e-12)
        main = int(np.argmax(fresh.sum(axis=tuple(range(fresh.ndim - 1)))))  # the yarn's colour: R, or B
        for read in ((atlas.sum(), fresh.sum()), (atlas[..., main].sum(), fresh[..., main].sum())):
            assert abs(read[0] / read[1] - 1) < 0.03, (dye, main, read)
        if previous is not None:
            assert atlas.sum() < previous  # more dye, darker
        previous = atlas.sum()
    first = series_model._series
    middle = preset_at_dye(name, float(np.sqrt(dye_range[0] * dye_range[1])))
    series_model.tables(middle, relative_error=0.08, seed=9)
    assert series_model._series is first  # another dye amount: the same series, no transport
    again = series_model.tables(middle, relative_error=0.02, seed=1)[0]
    np.testing.assert_array_equal(again, series_model.tables(middle, relative_error=0.08, seed=3)[0])


def test_another_medium_starts_a_new_series_and_a_dye_outside_is_refused(series_model):
    series_model.tables(voided_red_cotton(1.0), relative_error=0.08, seed=0)
    first = series_model._series
    thinner = voided_red_cotton(1.0)
    thinner["yarn"]["radius_mm"] = 0.08
    series_model.tables(thinner, relative_error=0.08, seed=0)
    assert series_model._series is not first
    with pytest.raises(ParameterError, match="dye.weight_percent"):
        series_model.tables(voided_red_cotton(4.0), relative_error=0.08, seed=0)
