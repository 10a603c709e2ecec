"""The closure-mixture fit that lets the yarn shader work under any lighting."""

import math

import numpy as np
import pytest

from precompute.closure_fit import (
    cell_averaged_lobes,
    closure_lobe_directions,
    evaluate_closure_mixture,
    fit_closure_weights,
)
from precompute.errors import ParameterError
from precompute.grids import AngularGrid


def test_lobe_directions_are_unit_and_distinct():
    lobes = closure_lobe_directions()
    assert lobes.shape == (14, 3)
    np.testing.assert_allclose(np.linalg.norm(lobes, axis=1), 1.0)
    assert len({tuple(np.round(v, 6)) for v in lobes}) == 14


def test_a_clamped_cosine_lobe_integrates_to_its_albedo():
    # ∫ max(0, m·ω)/π cos-free dω over the sphere = 1: a lobe of weight w returns albedo w under uniform light.
    grid = AngularGrid("sphere", 24)
    design = cell_averaged_lobes(grid, closure_lobe_directions(), subsamples=3)
    np.testing.assert_allclose(design.sum(axis=0) * grid.cell_solid_angle, 1.0, rtol=2e-3)


def test_an_exact_mixture_is_recovered():
    grid = AngularGrid("sphere", 8)
    rng = np.random.default_rng(3)
    true_weights = rng.random((5, 14, 3)) * (rng.random((5, 14, 3)) < 0.4)
    design = cell_averaged_lobes(grid, closure_lobe_directions())
    rho = np.einsum("ik,ekc->iec", design, true_weights)
    weights, relative_rms = fit_closure_weights(rho, grid)
    assert weights.min() >= 0.0
    np.testing.assert_allclose(np.einsum("ik,ekc->iec", design, weights), rho, atol=1e-9)
    assert relative_rms.max() < 1e-6


def test_fit_reports_the_error_of_what_it_cannot_represent():
    grid = AngularGrid("sphere", 8)
    centers = grid.cell_centers()
    # A narrow lobe is not a sum of clamped cosines: the fit error must say so.
    narrow = np.exp(-((1.0 - centers[:, 2]) / 0.02))[:, None, None] / math.pi
    weights, relative_rms = fit_closure_weights(narrow, grid)
    assert relative_rms[0, 0] > 0.2
    recon = evaluate_closure_mixture(weights, centers)[:, 0, 0]
    assert np.all(recon >= 0.0)


def test_fit_refuses_tables_of_the_wrong_shape():
    with pytest.raises(ParameterError, match="rho"):
        fit_closure_weights(np.ones((10, 4, 3)), AngularGrid("sphere", 8))
