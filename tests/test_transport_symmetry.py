"""The yarn's mirror symmetries (precompute/transport/symmetry.py): the physics has them, a mirrored
run traces only one cell of each set of images and reflects its tallies exactly, and the standard
errors of sums over cells count a cell and its images as one set of paths."""

import dataclasses

import numpy as np
import pytest

from precompute.reference.prediction import transport_prediction
from precompute.transport import (
    TransportGrids,
    YarnGeometry,
    henyey_greenstein_medium,
    simulate_yarn,
    source_weights,
    yarn_brdf_at,
)
from precompute.transport.symmetry import CellSymmetry, yarn_mirrors

GEOMETRY = YarnGeometry(radius_mm=0.1, index=1.5)
#: n_along odd and N odd: both reflections, and cells on the mirror planes (their own images).
GRIDS = TransportGrids(n_around=8, n_along=3, angular_resolution=5)


def medium():
    """Forward scattering keeps the exits directional, so that a wrong reflection shows."""
    return henyey_greenstein_medium([0.95, 0.4], [0.7, 0.3], mu_t=[30.0, 60.0], wavelengths_nm=[500.0, 600.0])


@pytest.fixture(scope="module")
def unmirrored():
    return simulate_yarn(medium(), GEOMETRY, GRIDS, paths_per_cell=20_000, seed=4, mirror_symmetry=False)


@pytest.fixture(scope="module")
def mirrored():
    return simulate_yarn(medium(), GEOMETRY, GRIDS, paths_per_cell=20_000, seed=5)


def image_z(transport, reflect):
    """z-scores of every image cell's axial BSSRDF against its source's, reflected by ``reflect``."""
    values, errors = transport.axial_bssrdf(), transport.axial_bssrdf_stderr()
    z = []
    for cell, source, mirror in CellSymmetry.of_grids(GRIDS.n_around, GRIDS.n_along,
                                                      GRIDS.angular_resolution).images():
        index = reflect(mirror)
        a, b = values[cell], values[source][index]
        sigma = np.hypot(errors[cell], errors[source][index])
        z.append(((a - b) / sigma)[sigma > 0])
    return np.concatenate(z)


def test_every_cell_traced_shows_the_symmetry_within_noise(unmirrored):
    z = image_z(unmirrored, lambda mirror: np.ix_(mirror.around, mirror.cells))
    assert z.size > 2000
    assert np.mean(np.abs(z) < 3.0) > 0.97
    assert 0.5 < np.mean(z**2) < 1.5


def test_the_symmetry_check_detects_a_reflection_that_misses_the_directions(unmirrored):
    """Reflecting the offsets around but not the exit directions is what a frame mix-up would give."""
    wrong = image_z(unmirrored, lambda mirror: np.ix_(mirror.around, np.arange(len(mirror.cells))))
    assert np.mean(wrong**2) > 1.5


def test_axial_bins_reflect_onto_each_other(unmirrored):
    """Light that goes up the axis exits above the source; its image across the cross-section exits
    below, bin for bin: the reflected profile along the axis agrees, the unreflected one does not."""
    symmetry = CellSymmetry.of_grids(GRIDS.n_around, GRIDS.n_along, GRIDS.angular_resolution)
    axial = symmetry.group[2]
    n = GRIDS.angular_resolution
    cell = (n // 2) * n  # s = 0 edge, middle row: light arriving from −x, going up the axis (+z)
    profile = unmirrored.bssrdf[cell].sum(axis=(0, 2, 3))
    image = unmirrored.bssrdf[axial.cells[cell]].sum(axis=(0, 2, 3))
    above, below = GRIDS.n_along + 1, GRIDS.n_along
    assert profile[above] > 2 * profile[below] and image[below] > 2 * image[above]
    # 20 000 paths: a few % of noise per bin
    np.testing.assert_allclose(image[axial.along], profile, rtol=0.15)
    assert np.max(np.abs(image / profile - 1.0)) > 0.5


def test_a_mirrored_run_traces_a_quarter_and_reflects_exactly(mirrored, unmirrored):
    symmetry = mirrored.symmetry
    assert len(symmetry.group) == 4
    # 25 cells: 1 its own image under both reflections, 8 on one mirror plane, 16 in sets of four
    assert symmetry.traced.sum() == 1 + 4 + 4
    assert mirrored.traced_paths == 9 * 20_000
    assert np.all(mirrored.paths_per_cell == 20_000)
    assert mirrored.events < 0.5 * unmirrored.events
    for cell, source, mirror in symmetry.images():
        np.testing.assert_array_equal(mirrored.bssrdf[cell],
                                      mirrored.bssrdf[source][np.ix_(mirror.around, mirror.along, mirror.cells)])
        np.testing.assert_array_equal(mirrored.bssrdf_axial_second_moment[cell],
                                      mirrored.bssrdf_axial_second_moment[source][np.ix_(mirror.around, mirror.cells)])
        for name in ("specular", "exit_fraction", "absorbed_fraction", "albedo_rel_stderr"):
            np.testing.assert_array_equal(getattr(mirrored, name)[cell], getattr(mirrored, name)[source])
    # the same expectation as tracing every cell
    sigma = np.hypot(mirrored.exit_fraction * mirrored.albedo_rel_stderr,
                     unmirrored.exit_fraction * unmirrored.albedo_rel_stderr)
    z = (mirrored.exit_fraction - unmirrored.exit_fraction) / sigma
    assert np.all(np.abs(z[symmetry.traced]) < 4.5)


def test_mirrors_are_involutions_that_commute():
    for grids in ((8, 3, 5), (32, 3, 12), (6, 2, 4)):
        group = yarn_mirrors(*grids)
        assert len(group) == (4 if grids[1] % 2 else 2)
        for g in group:
            for h in group:
                for a, b in zip(g, h):
                    np.testing.assert_array_equal(a[b], b[a])
            for permutation in g:
                np.testing.assert_array_equal(permutation[permutation], np.arange(len(permutation)))


def test_folding_keeps_every_linear_functional(mirrored):
    """Σ A · S over all cells equals Σ fold(A) · S over the traced cells, for any A."""
    rng = np.random.default_rng(1)
    axial = mirrored.axial_bssrdf()
    functional = rng.normal(size=axial.shape[:3] + (2,))
    folded = mirrored.symmetry.fold_exits(functional)
    assert np.all(folded[~mirrored.symmetry.traced] == 0.0)
    whole = np.einsum("cdok,cdol->kl", functional, axial)
    traced = np.einsum("cdok,cdol->kl", folded, axial)
    np.testing.assert_allclose(traced, whole, rtol=1e-12)


def test_brdf_error_counts_images_as_the_same_paths(mirrored):
    """Eq. (5)'s standard error equals, at every output, the variance of the functional folded onto the
    traced cells; treating the images as independent cells gives a different (too small) error where
    images read the same bin: exit cells on the mirror planes."""
    directions = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.3, 0.4, np.sqrt(0.75)]])
    rho, stderr = yarn_brdf_at(mirrored, directions)
    symmetry = mirrored.symmetry
    weights = source_weights(mirrored, directions)
    axial = mirrored.axial_bssrdf()
    moment = mirrored.bssrdf_axial_second_moment.astype(float)
    n_out = axial.shape[2]
    for d in range(len(directions)):
        for out in (0, n_out // 2, 7):
            functional = np.zeros(axial.shape[:3])
            functional[:, :, out] = weights[d]
            folded = symmetry.fold_exits(functional)[..., None]
            part = (folded * axial).sum(axis=(1, 2))
            second = (folded**2 * moment).sum(axis=(1, 2))
            variance = (np.maximum(second - part**2, 0.0) / (mirrored.paths_per_cell[:, None] - 1)).sum(axis=0)
            np.testing.assert_allclose(stderr[d, out], np.sqrt(variance), rtol=1e-9)
    centre = n_out // 2  # the exit cell that both reflections map to itself
    _, independent = yarn_brdf_at(dataclasses.replace(mirrored, symmetry=CellSymmetry.none(
        GRIDS.n_around, GRIDS.n_along, GRIDS.angular_resolution)), directions[:1])
    assert np.all(stderr[0, centre] > 1.02 * independent[0, centre])


def test_prediction_error_counts_images_as_the_same_paths(mirrored):
    """The reference prediction's error (a sum over all cells) is the folded one: larger than the sum
    over cells taken as independent, which the images are not, in the middle bins, where a path's images
    add to the same bin (11 % larger at seed 5).  In the outer bins they add to the other side's bin, and
    the two errors differ only by the covariance of a path's exits into one or the other: the same within
    0.02 % at seed 5."""
    light = np.array([0.0, 0.0, 1.0])
    folded = transport_prediction(mirrored, light, bins=4, sub_positions=4)
    independent = transport_prediction(dataclasses.replace(mirrored, symmetry=CellSymmetry.none(
        GRIDS.n_around, GRIDS.n_along, GRIDS.angular_resolution)), light, bins=4, sub_positions=4)
    np.testing.assert_array_equal(folded.rho, independent.rho)
    assert np.all(folded.rho_stderr[1:-1] > 1.05 * independent.rho_stderr[1:-1])
    np.testing.assert_allclose(folded.rho_stderr[[0, -1]], independent.rho_stderr[[0, -1]], rtol=0.01)
