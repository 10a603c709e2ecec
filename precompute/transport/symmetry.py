"""The yarn's mirror symmetries: which incidence cells need paths, and how the others' tallies follow.

An infinite circular cylinder lit on one source cell is unchanged by two reflections that also map
the source cell and every tally grid of :class:`.cylinder.TransportGrids` onto themselves:

* across the plane through the axis and the source cell's centre (ψ → Δψ − ψ): the offset around
  δ → −δ (mod n_around), and in every local frame (x = axis, y = n × t, z = n) y → −y;
* across the plane normal to the axis through the source cell's centre (z → Δ − z), where
  ``n_along`` is odd so that the axial bins map onto bins: bin k → n_along − 1 − k, the two
  overflow bins swap, and x → −x.

The BSSRDF obeys them exactly, S(g c, g δ, g k, g o) = S(c, δ, k, o) for each reflection g and for
their product (Fresnel boundaries, a phase function of the scattering angle only, a source uniform
over the cell), and so do the flux shares of an incidence cell.  A yarn run therefore traces one
incidence cell of each set the reflections map onto each other and writes the others' tallies as
mirror images of its own: with both reflections and an even angular resolution, a quarter of the
paths for the same error per cell (docs/transport.md, "Mirror symmetry").
"""

from __future__ import annotations

from collections import namedtuple
from dataclasses import dataclass

import numpy as np

from precompute.tables.grids import AngularGrid

#: A reflection as permutations of the tally grids' indices (each its own inverse): ``cells`` of the
#: incidence and exit hemisphere grids, the cells ``around``, the axial bins ``along`` (overflow too).
Mirror = namedtuple("Mirror", ["cells", "around", "along"])


def _cell_permutation(grid: AngularGrid, flip: np.ndarray) -> np.ndarray:
    """The hemisphere cell each cell's centre lands in when its direction is multiplied by ``flip``."""
    image = grid.cell_of(grid.cell_centers() * flip)
    if not np.array_equal(np.sort(image), np.arange(grid.n_cells)) or not np.array_equal(image[image],
                                                                                       np.arange(grid.n_cells)):
        raise AssertionError(f"the {grid.resolution}² hemisphere grid is not mirror-symmetric")
    return image


def _compose(first: Mirror, second: Mirror) -> Mirror:
    return Mirror(*(a[b] for a, b in zip(first, second)))


def yarn_mirrors(n_around: int, n_along: int, angular_resolution: int) -> tuple[Mirror, ...]:
    """The reflections of the module docstring that the grids allow, with their product, identity first."""
    grid = AngularGrid("hemisphere", angular_resolution)
    cells = np.arange(grid.n_cells)
    around = np.arange(n_around)
    along = np.arange(n_along + 2)
    identity = Mirror(cells, around, along)
    group = [identity, Mirror(_cell_permutation(grid, np.array([1.0, -1.0, 1.0])), (-around) % n_around, along)]
    if n_along % 2 == 1:
        axial = Mirror(_cell_permutation(grid, np.array([-1.0, 1.0, 1.0])), around,
                       np.concatenate([along[n_along - 1 :: -1], [n_along + 1, n_along]]))
        group += [axial, _compose(group[1], axial)]
    return tuple(group)


@dataclass(frozen=True, eq=False)
class CellSymmetry:
    """Which incidence cell's tallies each cell's are, and through which reflection.

    ``group``: the reflections (:func:`yarn_mirrors`, identity first); ``source`` (n_in,): the traced
    cell whose tallies, reflected by ``group[transform[c]]``, are cell c's (c itself, by the
    identity, where c is traced).  Each traced cell is the lowest-numbered of its images.
    """

    group: tuple[Mirror, ...]
    source: np.ndarray
    transform: np.ndarray

    @classmethod
    def of_grids(cls, n_around: int, n_along: int, angular_resolution: int) -> CellSymmetry:
        group = yarn_mirrors(n_around, n_along, angular_resolution)
        n_in = angular_resolution**2
        source = np.arange(n_in)
        transform = np.zeros(n_in, dtype=np.int64)
        for cell in range(n_in):
            if source[cell] != cell:
                continue  # an image of a lower cell
            for index, mirror in enumerate(group):
                image = mirror.cells[cell]
                if image != cell and source[image] == image:
                    source[image] = cell
                    transform[image] = index
        return cls(group, source, transform)

    @classmethod
    def none(cls, n_around: int, n_along: int, angular_resolution: int) -> CellSymmetry:
        """Every cell traced (no reflection used)."""
        n_in = angular_resolution**2
        identity = Mirror(np.arange(n_in), np.arange(n_around), np.arange(n_along + 2))
        return cls((identity,), np.arange(n_in), np.zeros(n_in, dtype=np.int64))

    @property
    def traced(self) -> np.ndarray:
        """Whether each cell is traced (n_in,) bool."""
        return self.source == np.arange(len(self.source))

    def images(self):
        """(cell, traced source, reflection) of every cell that is not traced."""
        for cell in np.flatnonzero(~self.traced):
            yield int(cell), int(self.source[cell]), self.group[self.transform[cell]]

    def orbit(self, cell: int):
        """(cell, reflection) of the traced ``cell`` and of every cell whose tallies are its images."""
        yield cell, self.group[0]
        for image in np.flatnonzero((self.source == cell) & ~self.traced):
            yield int(image), self.group[self.transform[image]]

    def fold_exits(self, values: np.ndarray) -> np.ndarray:
        """A linear functional of the axial exits, (n_in, n_around, n_out, …) like them, as one of the
        traced cells' exits only: each image cell's row reflected and added to its source's, image rows
        0.  Σ values · exits over all cells equals Σ folded · exits over the traced cells, and, since
        the traced cells' paths are independent, the variance of that sum is the sum of theirs."""
        folded = np.array(values, dtype=float)
        for cell, source, mirror in self.images():
            folded[source] += folded[cell][np.ix_(mirror.around, mirror.cells)]
            folded[cell] = 0.0
        return folded

    def copy_rows(self, values: np.ndarray) -> None:
        """Give every image cell its source's row of ``values`` (n_in, …), a quantity per cell that no
        reflection changes (flux shares, paths), in place."""
        for cell, source, _ in self.images():
            values[cell] = values[source]

    def reflect_exits(self, values: np.ndarray, *, axial: bool) -> None:
        """Write every image cell's exits as the reflection of its source's, in place: ``values``
        (n_in, n_around, n_along + 2, n_out, …) with ``axial``, else (n_in, n_around, n_out, …)."""
        for cell, source, mirror in self.images():
            if axial:
                values[cell] = values[source][np.ix_(mirror.around, mirror.along, mirror.cells)]
            else:
                values[cell] = values[source][np.ix_(mirror.around, mirror.cells)]
