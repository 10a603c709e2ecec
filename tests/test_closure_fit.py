"""The closure-mixture fit that lets the yarn shader work under any lighting."""

import numpy as np
import pytest

from precompute.tables.closure_fit import (
    LOBES,
    MIN_LOBE_SHARE,
    LobeShape,
    evaluate_closure_mixture,
    fit_closure_weights,
    incidence_samples,
    lobe_responses,
)
from precompute.errors import ParameterError
from precompute.tables.grids import AngularGrid
from precompute.tables.layout import brdf_atlas, interpolate_rho

N_I, N_O = 12, 4


def atlas_of(function):
    """The BRDF atlas of ``function(view, light) -> (…, 3)`` sampled at the cell centres."""
    lights = AngularGrid("sphere", N_I).cell_centers()
    views = AngularGrid("hemisphere", N_O).cell_centers()
    rho = np.stack([function(view, lights) for view in views], axis=1)
    return brdf_atlas(rho), views


def test_samples_are_uniform_in_solid_angle():
    samples = incidence_samples(AngularGrid("sphere", 6), 3)
    assert samples.shape == (6 * 6 * 9, 3)
    np.testing.assert_allclose(np.linalg.norm(samples, axis=1), 1.0)
    # The mean of a uniform sample of the sphere is near 0 and its second moments are 1/3.
    np.testing.assert_allclose(samples.mean(axis=0), 0.0, atol=0.01)
    np.testing.assert_allclose((samples**2).mean(axis=0), 1 / 3, atol=0.01)


def test_a_smooth_mixture_is_recovered():
    true = np.zeros((len(LOBES), 3))
    true[LOBES.index("diffuse")] = [0.5, 0.2, 0.1]
    true[LOBES.index("translucent")] = [0.3, 0.0, 0.2]
    atlas, _ = atlas_of(lambda view, lights: lobe_responses(view, lights) @ true)
    weights, error = fit_closure_weights(atlas, N_I)
    assert weights.shape == (N_O * N_O, len(LOBES), 3)
    assert weights.min() >= 0.0
    # The bilinear table of two clamped cosines is close to them but not exact near the horizon.
    np.testing.assert_allclose(weights[:, :2, :], np.broadcast_to(true[:2], weights[:, :2, :].shape), atol=0.05)
    assert np.abs(weights[:, 2:, :]).max() < 0.1
    # The residual left is the table's own bilinear blur of the cosines' kink at the horizon
    # (0.058 at N_i = 12), well below the 0.17 of a fibre cone fitted with its own lobe.
    assert np.median(error) < 0.1


def test_a_minor_lobe_is_left_out_and_its_light_refitted():
    """A fibre cone of 0.5 % of the mixture adds no closure: its weight is exactly zero in every
    channel and the diffuse and translucent lobes, refitted without it, keep the energy; a cone of
    5 % stays."""
    shape = LobeShape(reflection_longitudinal=0.3, reflection_azimuthal=0.6)
    main = np.zeros((len(LOBES), 3))
    main[LOBES.index("diffuse")] = [0.5, 0.4, 0.3]
    main[LOBES.index("translucent")] = [0.3, 0.3, 0.3]
    cone = np.zeros_like(main)
    cone[LOBES.index("fibre_reflection")] = 1.0
    fibre = LOBES.index("fibre_reflection")
    for share, kept in ((0.5 * MIN_LOBE_SHARE, False), (5 * MIN_LOBE_SHARE, True)):
        true = main + share * main.sum() / 3 * cone
        atlas, views = atlas_of(lambda view, lights, true=true: lobe_responses(view, lights, shape) @ true)
        weights, _ = fit_closure_weights(atlas, N_I, shape)
        assert np.all(weights[:, fibre, :] > 0) if kept else np.all(weights[:, fibre, :] == 0)
        shares = weights.mean(axis=2) / weights.mean(axis=2).sum(axis=1, keepdims=True)
        assert np.all((shares == 0) | (shares >= MIN_LOBE_SHARE))
        lights = incidence_samples(AngularGrid("sphere", N_I), 3)
        for view, w in zip(views, weights):
            fitted = evaluate_closure_mixture(w, view, lights, shape).mean(axis=0)
            exact = (lobe_responses(view, lights, shape) @ true).mean(axis=0)
            np.testing.assert_allclose(fitted, exact, rtol=0.05)


def test_a_fibre_cone_goes_to_the_fibre_lobe():
    shape = LobeShape(reflection_longitudinal=0.3, reflection_azimuthal=0.6)
    albedo = np.array([0.6, 0.3, 0.1])

    def cone(view, lights):
        return lobe_responses(view, lights, shape)[..., [LOBES.index("fibre_reflection")]] * albedo

    atlas, views = atlas_of(cone)
    weights, error = fit_closure_weights(atlas, N_I, shape)
    share = weights[:, LOBES.index("fibre_reflection"), 0] / weights[:, :, 0].sum(axis=1)
    assert np.median(share) > 0.7
    assert np.median(error[:, 0]) < 0.2
    # The mixture puts the light on the cone: at the cone direction it is brighter than across it.
    view = views[5]
    on_cone = np.array([-view[0], view[1], np.sqrt(max(0.0, 1 - view[0] ** 2 - view[1] ** 2))])
    across = np.array([view[0], -view[1], view[2]]) if abs(view[0]) > 0.2 else np.array([0.9, 0.0, 0.44])
    rebuilt = evaluate_closure_mixture(weights[5], view, np.stack([on_cone, across]), shape)
    assert rebuilt[0, 0] > rebuilt[1, 0]


def test_fit_reports_the_error_of_what_it_cannot_represent():
    # A narrow spot lit from a fixed direction off every lobe's axis is not in the mixture's span.
    spot = np.array([0.6, -0.6, -0.53]) / np.linalg.norm([0.6, -0.6, -0.53])

    def narrow(view, lights):
        return np.repeat(np.exp((lights @ spot - 1.0) / 0.01)[:, None], 3, axis=1)

    atlas, views = atlas_of(narrow)
    weights, error = fit_closure_weights(atlas, N_I)
    assert weights.min() >= 0.0
    table_at_spot = interpolate_rho(atlas, N_I, spot, views)[:, 0]
    rebuilt_at_spot = np.array([evaluate_closure_mixture(w, v, spot)[0] for w, v in zip(weights, views)])
    assert np.all(rebuilt_at_spot < 0.5 * table_at_spot)
    assert np.median(error) > 0.1


def test_absolute_weighting_trades_the_dark_incidences_for_the_bright_ones():
    """A bright narrow peak on a dark diffuse floor, which the mixture cannot both follow: each
    weighting leaves the smaller residual of its own kind (both are exact least squares), and
    the absolute one comes closer at the peak."""
    peak = np.array([0.0, 0.0, 1.0])

    def peaked(view, lights):
        floor = 0.02 * lobe_responses(view, lights, lobes=("diffuse",))[..., 0]
        return np.repeat((floor + 2.0 * np.exp((lights @ peak - 1.0) / 0.05))[:, None], 3, axis=1)

    atlas, views = atlas_of(peaked)
    lights = incidence_samples(AngularGrid("sphere", N_I), 3)
    residuals = {}
    for weighting in ("relative", "absolute"):
        weights, _ = fit_closure_weights(atlas, N_I, weighting=weighting)
        view = views[0]
        target = interpolate_rho(atlas, N_I, lights, np.broadcast_to(view, lights.shape))[:, 0]
        fit = evaluate_closure_mixture(weights[0], view, lights)[:, 0]
        relative = (fit - target) / (target + target.mean())
        at_peak = evaluate_closure_mixture(weights[0], view, peak)[0] - peaked(view, peak[None])[0, 0]
        residuals[weighting] = (np.sum((fit - target) ** 2), np.sum(relative**2), abs(at_peak))
    assert residuals["absolute"][0] <= residuals["relative"][0] * (1 + 1e-9)
    assert residuals["relative"][1] <= residuals["absolute"][1] * (1 + 1e-9)
    assert residuals["absolute"][2] < residuals["relative"][2]
    with pytest.raises(ParameterError, match="weighting"):
        fit_closure_weights(atlas, N_I, weighting="squared")


def test_fit_refuses_bad_tables_and_shapes():
    with pytest.raises(ParameterError, match="atlas"):
        fit_closure_weights(np.ones((10, 4, 3)), N_I)
    with pytest.raises(ParameterError, match="atlas"):
        fit_closure_weights(-np.ones((N_I * N_O, N_I * N_O, 3)), N_I)
    with pytest.raises(ParameterError, match="retroreflection_alpha"):
        LobeShape(retroreflection_alpha=0.0)
