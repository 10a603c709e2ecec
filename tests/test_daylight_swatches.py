"""The daylight swatches' quadrature (scripts/daylight_swatches.py): 2 ∫ g(μ) μ dμ over the sky it keeps."""

from __future__ import annotations

import importlib.util
import math
import pathlib

import numpy as np
import pytest

_PATH = pathlib.Path(__file__).resolve().parents[1] / "scripts" / "daylight_swatches.py"
_SPEC = importlib.util.spec_from_file_location("daylight_swatches", _PATH)
daylight_swatches = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(daylight_swatches)


def test_the_rule_averages_over_the_cosine_weighted_sky_it_keeps():
    theta, weights = daylight_swatches.daylight_rule()
    assert theta.max() <= daylight_swatches.MAX_INCIDENCE_DEG and theta.min() > 0.0
    assert weights.sum() == pytest.approx(1.0) and (weights > 0).all()
    low = math.cos(math.radians(daylight_swatches.MAX_INCIDENCE_DEG))
    mu = np.cos(np.radians(theta))
    # a Lambertian cloth keeps its BRDF; g = μ^k integrates as the cosine-weighted mean over μ ∈ [low, 1]
    for k in range(2 * daylight_swatches.NODES - 1):
        exact = ((1 - low ** (k + 2)) / (k + 2)) / ((1 - low**2) / 2)
        assert weights @ mu**k == pytest.approx(exact, rel=1e-12)


def test_no_node_lines_the_sun_up_with_the_camera():
    # the unscattered light's cone (0.05 rad) about the normal view must hold no node, front or behind
    theta, _ = daylight_swatches.daylight_rule()
    assert np.radians(theta.min()) > 0.05
