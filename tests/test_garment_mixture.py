"""The garment's general-lighting closure mixture (clothlight.garment.tables.mixture_weights): its
gloss lobe carries the specular term alone and the other lobes the rest of ρ, so that the white,
narrow peak does not bend the coloured lobes."""

import numpy as np
import pytest

from clothlight.garment.tables import FIT_WEIGHTING, GARMENT_LOBES, SPECULAR_LOBE, mixture_error, mixture_weights
from precompute.tables import closure_fit
from precompute.tables.grids import AngularGrid
from precompute.tables.layout import brdf_atlas

N_I, N_O = 5, 6
#: A red cloth's diffuse albedo and a white specular term shaped unlike the gloss lobe (wider, stronger).
ALBEDO = np.array([0.3, 0.02, 0.01])
SHAPE = closure_fit.LobeShape(gloss_alpha=0.1)
SPECULAR_ALPHA, SPECULAR_WEIGHT = 0.3, 0.05


@pytest.fixture(scope="module")
def red_cloth():
    """ρ (n_in, n_out, 3) = a coloured diffuse lobe + a white specular term, and that term (n_in, n_out)."""
    lights = AngularGrid("sphere", N_I).cell_centers()
    views = AngularGrid("hemisphere", N_O).cell_centers()
    diffuse = np.stack([closure_fit.lobe_responses(view, lights, lobes=("diffuse",))[:, 0] for view in views], axis=1)
    specular = SPECULAR_WEIGHT * np.stack(
        [closure_fit.lobe_responses(view, lights, closure_fit.LobeShape(gloss_alpha=SPECULAR_ALPHA),
                                    lobes=("gloss",))[:, 0] for view in views], axis=1)
    return diffuse[..., None] * ALBEDO + specular[..., None], specular, views


def test_the_coloured_lobes_fit_the_cloth_without_its_specular_term(red_cloth):
    rho, specular, views = red_cloth
    weights, error = mixture_weights(rho, specular, N_I, SHAPE, views)
    diffuse = weights[:, GARMENT_LOBES.index("diffuse")]
    lit = diffuse.sum(axis=1) > 0
    assert lit.sum() >= len(views) // 2
    # the colour exactly; the level within the atlas' interpolation between cell centres
    np.testing.assert_allclose(diffuse[lit] / diffuse[lit, :1], np.broadcast_to(ALBEDO / ALBEDO[0], diffuse[lit].shape),
                               rtol=1e-6)
    np.testing.assert_allclose(diffuse[lit, 0], ALBEDO[0], rtol=0.05)
    gloss = weights[:, GARMENT_LOBES.index(SPECULAR_LOBE)]
    np.testing.assert_allclose(gloss[:, 0], gloss[:, 2])  # the specular term is white
    assert gloss.max() > 0 and error.shape == (len(views), 3)
    # fitted among the lobes to all of ρ (as before), the peak bends the blue diffuse weight
    joint, _ = closure_fit.fit_closure_weights(brdf_atlas(rho), N_I, SHAPE, lobes=GARMENT_LOBES, views=views,
                                               weighting=FIT_WEIGHTING)
    joint_diffuse = joint[lit, GARMENT_LOBES.index("diffuse")]
    assert np.max(np.abs(joint_diffuse[:, 2] / joint_diffuse[:, 0] / (ALBEDO[2] / ALBEDO[0]) - 1)) > 0.1


def test_the_mixture_error_is_the_fits_own_measure(red_cloth):
    rho, _, views = red_cloth
    weights, own = closure_fit.fit_closure_weights(brdf_atlas(rho), N_I, SHAPE, lobes=GARMENT_LOBES, views=views,
                                                   weighting=FIT_WEIGHTING)
    np.testing.assert_allclose(mixture_error(brdf_atlas(rho), N_I, weights, SHAPE, views), own, rtol=1e-9)
