"""Numbers osl/clothlight.h states that Python states too, read from both and compared (the shader
code that uses them is held to its NumPy twins by render tests: docs/architecture.md)."""

import math
import pathlib
import re

import numpy as np
import pytest

from clothlight.yarn_tables import GENERAL_MODE_MIN_WEIGHT
from precompute.optics import ballistic, lommel_seeliger
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


def header_list(name: str) -> np.ndarray:
    """The numbers of ``#define name {a, b, …}`` in the header (continued over lines)."""
    body = re.search(r"^#define\s+" + name + r"\s+\{([^}]*)\}", HEADER.read_text(), re.MULTILINE).group(1)
    return np.array([float(value) for value in body.replace("\\", " ").split(",")])


def test_the_header_sums_the_fuzz_over_the_gauss_legendre_nodes_of_its_numpy_twin():
    # cl_fuzz_albedo_at_view and cl_fuzz_hemispherical_transmittance sum over the nodes
    # precompute.optics.lommel_seeliger takes (fuzz_quadrature): numpy's leggauss mapped onto (0, 1).
    cosines, weights = lommel_seeliger.fuzz_quadrature()
    assert header_defines()["CL_FUZZ_ALBEDO_NODES"] == lommel_seeliger.FUZZ_ALBEDO_NODES == len(cosines)
    np.testing.assert_allclose(header_list("CL_FUZZ_NODE_COSINES"), cosines, rtol=1e-15)
    np.testing.assert_allclose(header_list("CL_FUZZ_NODE_WEIGHTS"), weights, rtol=1e-15)
    assert abs(np.sum(weights) - 1.0) < 1e-14  # a rule on (0, 1)
    # and a fuzz that scatters forward over the same midpoint azimuths
    assert header_defines()["CL_FUZZ_AZIMUTHS"] == lommel_seeliger.FUZZ_ALBEDO_AZIMUTHS


def test_the_header_tabulates_the_fuzzs_forward_lobe_as_its_numpy_twin():
    # cl_fuzz_general_lobes interpolates the lobe's albedos in θo between the same points
    # (lommel_seeliger.forward_lobe_table), of the same Beckmann slope
    defines = header_defines()
    assert defines["CL_FUZZ_FORWARD_SLOPE"] == lommel_seeliger.FUZZ_FORWARD_SLOPE
    assert defines["CL_FUZZ_FORWARD_POINTS"] == lommel_seeliger.FUZZ_FORWARD_POINTS
    _, albedo, excess = lommel_seeliger.forward_lobe_table()
    np.testing.assert_allclose(header_list("CL_FUZZ_FORWARD_ALBEDO"), albedo, rtol=1e-15)
    np.testing.assert_allclose(header_list("CL_FUZZ_FORWARD_EXCESS"), excess, rtol=1e-15, atol=1e-300)
