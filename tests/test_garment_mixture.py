"""The garment's general-lighting closure mixture (clothlight.garment.tables.mixture_weights): its
gloss lobe carries the specular term alone and the other lobes the rest of ρ, so that the white,
narrow peak does not bend the coloured lobes; the gloss lobe's weight gives the Cook–Torrance term
about its peak, however narrow the peak is against the tables' grid."""

import numpy as np
import pytest

from clothlight.garment.tables import (
    FIT_WEIGHTING,
    GARMENT_LOBES,
    SPECULAR_LOBE,
    gloss_weights,
    mixture_error,
    mixture_weights,
)
from precompute.optics.cook_torrance import cook_torrance
from precompute.tables import closure_fit, cycles_closures
from precompute.tables.grids import AngularGrid
from precompute.tables.layout import brdf_atlas, interpolate_rho

N_I, N_O = 5, 6
#: A red cloth's diffuse albedo and a white Cook–Torrance term (the yarns' specular, §5.2) whose
#: visibility falls toward grazing light.
ALBEDO = np.array([0.3, 0.02, 0.01])
SPECULAR = {"weight": 0.05, "slope": 0.3, "ior": 1.5}
SHAPE = closure_fit.LobeShape(gloss_alpha=SPECULAR["slope"])


def visibility_of(lights):
    return 0.9 - 0.4 * (1.0 - lights[..., 2]) ** 2


def specular_term(lights, views):
    """w_s f_CT cos θ_i V, 1/sr."""
    return (SPECULAR["weight"] * cook_torrance(lights, views, SPECULAR["slope"], SPECULAR["ior"])
            * np.maximum(lights[..., 2], 0.0) * visibility_of(lights))


@pytest.fixture(scope="module")
def red_cloth():
    """ρ (n_in, n_out, 3) = a coloured diffuse lobe + a white specular term; that term and its
    visibility (n_in, n_out); the exit cells' centres."""
    lights = AngularGrid("sphere", N_I).cell_centers()[:, None, :]
    views = AngularGrid("hemisphere", N_O).cell_centers()
    diffuse = np.stack([closure_fit.lobe_responses(view, lights[:, 0], lobes=("diffuse",))[:, 0] for view in views],
                       axis=1)
    specular = specular_term(lights, views[None, :, :])
    visibility = np.broadcast_to(visibility_of(lights), specular.shape)
    return diffuse[..., None] * ALBEDO + specular[..., None], specular, visibility, views


def test_the_coloured_lobes_fit_the_cloth_without_its_specular_term(red_cloth):
    rho, specular, visibility, views = red_cloth
    weights, error = mixture_weights(rho, specular, visibility, SPECULAR, N_I, SHAPE, views)
    coloured = weights[:, [GARMENT_LOBES.index(k) for k in GARMENT_LOBES if k != SPECULAR_LOBE]]
    diffuse = weights[:, GARMENT_LOBES.index("diffuse")]
    lit = diffuse.sum(axis=1) > 0
    assert lit.sum() >= len(views) // 2
    # each lobe the colour exactly; their albedos (a weight is its lobe's albedo) the level within the
    # atlas' interpolation between cell centres, which the uniform lobe partly takes up
    shown = coloured[:, :, 0] > 1e-6 * coloured[:, :, 0].max()
    np.testing.assert_allclose(coloured[shown] / coloured[shown][:, :1],
                               np.broadcast_to(ALBEDO / ALBEDO[0], coloured[shown].shape), rtol=1e-6)
    np.testing.assert_allclose(coloured[lit, :, 0].sum(axis=1), ALBEDO[0], rtol=0.1)
    gloss = weights[:, GARMENT_LOBES.index(SPECULAR_LOBE)]
    np.testing.assert_allclose(gloss[:, 0], gloss[:, 2])  # the specular term is white
    assert gloss.max() > 0 and error.shape == (len(views), 3)
    # fitted among the lobes to all of ρ (as before), the peak bends the blue diffuse weight
    joint, _ = closure_fit.fit_closure_weights(brdf_atlas(rho), N_I, SHAPE, lobes=GARMENT_LOBES, views=views,
                                               weighting=FIT_WEIGHTING)
    joint_diffuse = joint[lit, GARMENT_LOBES.index("diffuse")]
    assert np.max(np.abs(joint_diffuse[:, 2] / joint_diffuse[:, 0] / (ALBEDO[2] / ALBEDO[0]) - 1)) > 0.1


def test_the_mixture_error_is_the_fits_own_measure(red_cloth):
    rho, _, _, views = red_cloth
    others = [k for k in GARMENT_LOBES if k != SPECULAR_LOBE]
    fitted, own = closure_fit.fit_closure_weights(brdf_atlas(rho), N_I, SHAPE, lobes=tuple(others), views=views,
                                                  weighting=FIT_WEIGHTING)
    weights = np.zeros((len(views), len(GARMENT_LOBES), 3))
    weights[:, [GARMENT_LOBES.index(k) for k in others]] = fitted
    np.testing.assert_allclose(mixture_error(brdf_atlas(rho), N_I, weights, SHAPE, views, SPECULAR["ior"]), own,
                               rtol=1e-9)


@pytest.mark.parametrize("slope", [0.094, 0.3])  # voided_red_cotton's narrow peak, between cells 16–20° apart
def test_the_gloss_lobe_gives_the_specular_term_about_its_peak(red_cloth, slope):
    """The gloss lobe (Cycles' Metallic BSDF, the yarns' index) times its weight against w_s f_CT
    cos θ_i V, V as the sun mode reads it (bilinear in the table), at lights within a fraction of the
    lobe's width of the mirror direction: V changes little there."""
    _, _, visibility, views = red_cloth
    specular = {**SPECULAR, "slope": slope}
    weights = gloss_weights(visibility, specular, N_I, views)
    atlas = brdf_atlas(np.asarray(visibility)[..., None])
    for view, weight in zip(views[views[:, 2] > 0.5], weights[views[:, 2] > 0.5]):  # V steep near grazing
        mirror = view * np.array([-1.0, -1.0, 1.0])
        off = np.array([mirror + 0.25 * slope * np.array([dx, dy, 0.0]) for dx, dy in ((1, 0), (0, 1), (-1, -1))])
        off /= np.linalg.norm(off, axis=1, keepdims=True)
        lobe = weight * cycles_closures.beckmann_conductor_eval(np.array([0.0, 0.0, 1.0]), view, off, slope,
                                                                specular["ior"])
        exact = (specular["weight"] * cook_torrance(off, view, slope, specular["ior"]) * off[:, 2]
                 * interpolate_rho(atlas, N_I, off, np.broadcast_to(view, off.shape))[:, 0])
        np.testing.assert_allclose(lobe, exact, rtol=0.05)
