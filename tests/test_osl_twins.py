"""Numbers osl/clothlight.h states that Python states too, read from both and compared (the shader
code that uses them is held to its NumPy twins by render tests: docs/architecture.md)."""

import math
import pathlib
import re

import pytest

from clothlight.yarn_tables import GENERAL_MODE_MIN_WEIGHT
from precompute.optics import ballistic
from precompute.tables.closure_fit import LOBES

HEADER = pathlib.Path(__file__).resolve().parents[1] / "osl" / "clothlight.h"


def header_defines() -> dict[str, float]:
    return {name: float(value) for name, value in
            re.findall(r"^#define\s+(CL_\w+)\s+([-+0-9.eE]+)\s*$", HEADER.read_text(), re.MULTILINE)}


def test_the_header_states_the_lobe_count_and_the_unscattered_paths_as_python():
    defines = header_defines()
    assert defines["CL_LOBE_COUNT"] == len(LOBES)
    assert defines["CL_UNSCATTERED_ORDERS"] == ballistic.ORDERS
    assert defines["CL_UNSCATTERED_MAX_LENGTH"] == ballistic.MAX_LENGTH_OVER_RADIUS
    assert defines["CL_CONE_CUTOFF"] == ballistic.CONE_CUTOFF
    assert defines["CL_UNSCATTERED_MIN_FACTOR"] == GENERAL_MODE_MIN_WEIGHT
    assert defines["CL_QUARTER_PI"] == pytest.approx(math.pi / 4, rel=1e-15)
