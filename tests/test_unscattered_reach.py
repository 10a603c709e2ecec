"""How the yarn material reads the unscattered light's table (clothlight/yarn_tables.py): the general
mode's reach, the path length beyond which a path weighs less than the shader's floor."""

import math

import numpy as np
import pytest

from clothlight.yarn_tables import GENERAL_MODE_MIN_WEIGHT, attenuation_reach
from precompute import ballistic
from precompute.table_layout import interpolate_attenuation


def test_the_reach_is_where_the_attenuation_falls_below_the_general_modes_floor_for_good():
    floor = GENERAL_MODE_MIN_WEIGHT
    table = np.exp(-np.outer(ballistic.attenuation_lengths(), [3.0, 1.5, 1.0]))[None]
    reach = attenuation_reach(table)
    step = ballistic.MAX_LENGTH_OVER_RADIUS / (ballistic.ATTENUATION_SAMPLES - 1)
    assert interpolate_attenuation(table, reach - step).max() >= floor
    beyond = np.linspace(reach, 2.0 * ballistic.MAX_LENGTH_OVER_RADIUS, 500)
    assert interpolate_attenuation(table, beyond).max() < floor
    assert reach == pytest.approx(math.log(1.0 / floor), abs=step)  # the slowest channel, e^{-ℓ}
    assert attenuation_reach(np.full((1, ballistic.ATTENUATION_SAMPLES, 3), 0.5 * floor)) == 0.0
    clear = np.exp(-np.outer(ballistic.attenuation_lengths(), [0.1, 0.1, 0.1]))[None]
    assert attenuation_reach(clear) == math.inf
