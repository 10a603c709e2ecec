"""Numba kernel of :func:`.goniometry.patch_weights_at`: which patch each pixel sees, counted on a
lattice of sub-pixel points (the inputs are checked and laid out there)."""

from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True)
def lattice_patch_counts(columns, rows, subsamples, image_half_width, image_half_height, pixel_mm, pixel_height_mm,
                         origin, right, up, layout_origin, pitch_mm, grid, half_patch_over_pitch):
    """Per pixel (``columns``, ``rows``, (P,) int): the patch its lattice points fall in (−1: none)
    and how many do, and whether some pixel reaches two patches.  A lattice point (column + dx,
    row + dy) crosses the mid-plane at ``origin + a right + b up`` (a, b its image coordinates
    from the centre, mm; ``right``, ``up`` the image axes slid onto the mid-plane), in the patch of
    :meth:`.goniometry.RegionLayout.patch_of`."""
    count = len(columns)
    index = np.full(count, -1, np.int64)
    hits = np.zeros(count, np.int64)
    two_patches = False
    for p in range(count):
        for j in range(subsamples):
            dy = (j + 0.5) / subsamples
            b = (image_half_height - (rows[p] + dy)) * pixel_height_mm
            for i in range(subsamples):
                dx = (i + 0.5) / subsamples
                a = ((columns[p] + dx) - image_half_width) * pixel_mm
                x = origin[0] + a * right[0] + b * up[0]
                y = origin[1] + a * right[1] + b * up[1]
                local_x = (x - layout_origin[0]) / pitch_mm + grid / 2.0
                local_y = (y - layout_origin[1]) / pitch_mm + grid / 2.0
                cell_x, cell_y = math.floor(local_x), math.floor(local_y)
                if (abs(local_x - cell_x - 0.5) <= half_patch_over_pitch
                        and abs(local_y - cell_y - 0.5) <= half_patch_over_pitch
                        and 0 <= cell_x < grid and 0 <= cell_y < grid):
                    patch = int(cell_y) * grid + int(cell_x)
                    if index[p] >= 0 and index[p] != patch:
                        two_patches = True
                    index[p] = patch
                    hits[p] += 1
    return index, hits, two_patches
