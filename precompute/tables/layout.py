"""How the yarn tables are laid out as images, and how a shader reads them back.

The layout is specified in docs/table-spec.md; ``osl/clothlight.h`` reads it
(``cl_yarn_rho``, ``cl_tile_lookup``) and :func:`interpolate_rho` is its exact
NumPy twin, used to check the shader and by anything that evaluates a table
outside Blender.

BRDF atlas
    ``N_i × N_i`` tiles, one per incidence cell of ``AngularGrid("sphere", N_i)``;
    incidence cell ``(i, j)`` (flat ``j·N_i + i``) is the tile in column ``i``
    and row ``j`` counted from the top.  Each tile is ``N_o × N_o`` pixels, one
    per exit cell of ``AngularGrid("hemisphere", N_o)``; exit cell ``(p, q)`` is
    pixel column ``p`` and row ``q`` of the tile.  Image size ``N_i·N_o`` square.
Unscattered-light attenuation
    one row of ``M`` pixels: pixel ``m`` holds the RGB transmittance of a path of length
    ``ℓ/R = m · ℓ_max / (M − 1)`` inside the yarn (:mod:`precompute.optics.ballistic`).
Lobe atlas
    one row of ``K`` tiles of ``N_o × N_o`` pixels: tile ``k`` holds the weight
    of closure lobe ``k`` (:mod:`precompute.tables.closure_fit`) for every exit cell.

Pixel centres are cell centres in the equal-area square.  Images are stored
top row first (``t = 0`` is the top row for OSL ``texture()``).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from precompute.optics import ballistic
from precompute.errors import ParameterError
from precompute.tables.grids import AngularGrid


def _check_square(count: int, name: str) -> int:
    n = int(round(np.sqrt(count)))
    if n * n != count:
        raise ParameterError(name, count, "a square number of cells (N × N grid)")
    return n


def brdf_atlas(rho: np.ndarray) -> np.ndarray:
    """Pack ``rho`` (N_i², N_o², C) into the BRDF atlas image (N_i·N_o, N_i·N_o, C), top row first."""
    rho = np.asarray(rho)
    n_i = _check_square(rho.shape[0], "rho incidence cells")
    n_o = _check_square(rho.shape[1], "rho exit cells")
    channels = rho.shape[2]
    # (j, i, q, p, c) -> rows (j, q), columns (i, p)
    tiles = rho.reshape(n_i, n_i, n_o, n_o, channels)
    return tiles.transpose(0, 2, 1, 3, 4).reshape(n_i * n_o, n_i * n_o, channels)


def atlas_pixel_cells(pixels, incidence_resolution: int, exit_resolution: int) -> tuple[np.ndarray, np.ndarray]:
    """The (incidence cell, exit cell) of ρ each flat atlas pixel index holds (:func:`brdf_atlas`'s layout)."""
    side = incidence_resolution * exit_resolution
    row, column = np.divmod(np.asarray(pixels, np.int64), side)
    (j, q), (i, p) = np.divmod(row, exit_resolution), np.divmod(column, exit_resolution)
    return j * incidence_resolution + i, q * exit_resolution + p


def rho_from_brdf_atlas(atlas: np.ndarray, incidence_resolution: int) -> np.ndarray:
    """Inverse of :func:`brdf_atlas`."""
    atlas = np.asarray(atlas)
    n_i = incidence_resolution
    if atlas.shape[0] != atlas.shape[1] or atlas.shape[0] % n_i:
        raise ParameterError("atlas shape", atlas.shape, f"square, a multiple of {n_i} pixels per side")
    n_o = atlas.shape[0] // n_i
    channels = atlas.shape[2]
    tiles = atlas.reshape(n_i, n_o, n_i, n_o, channels).transpose(0, 2, 1, 3, 4)
    return tiles.reshape(n_i * n_i, n_o * n_o, channels)


def lobe_atlas(weights: np.ndarray) -> np.ndarray:
    """Pack closure weights (N_o², K, C) into the lobe atlas image (N_o, K·N_o, C)."""
    weights = np.asarray(weights)
    n_o = _check_square(weights.shape[0], "weights exit cells")
    lobes, channels = weights.shape[1], weights.shape[2]
    tiles = weights.reshape(n_o, n_o, lobes, channels)  # (q, p, k, c)
    return tiles.transpose(0, 2, 1, 3).reshape(n_o, lobes * n_o, channels)


def weights_from_lobe_atlas(atlas: np.ndarray, lobe_count: int) -> np.ndarray:
    """Inverse of :func:`lobe_atlas`."""
    atlas = np.asarray(atlas)
    n_o = atlas.shape[0]
    if atlas.shape[1] != lobe_count * n_o:
        raise ParameterError("lobe atlas shape", atlas.shape, f"({n_o}, {lobe_count}·{n_o}, C)")
    tiles = atlas.reshape(n_o, lobe_count, n_o, atlas.shape[2]).transpose(0, 2, 1, 3)
    return tiles.reshape(n_o * n_o, lobe_count, atlas.shape[2])


def _tile_taps(tile_col, tile_row, tile_size, s, t):
    """The four atlas pixels (rows, columns, (…, 4) int) and bilinear weights (…, 4) that
    ``cl_tile_lookup`` blends in one tile through OSL ``texture()``: between pixel centres, with
    (s, t) held inside the tile's outermost pixel centres."""
    half = 0.5 / tile_size
    x = np.clip(s, half, 1.0 - half) * tile_size - 0.5
    y = np.clip(t, half, 1.0 - half) * tile_size - 0.5
    x0 = np.clip(np.floor(x).astype(int), 0, tile_size - 1)
    y0 = np.clip(np.floor(y).astype(int), 0, tile_size - 1)
    x1 = np.minimum(x0 + 1, tile_size - 1)
    y1 = np.minimum(y0 + 1, tile_size - 1)
    ax, ay = x - x0, y - y0
    row0 = tile_row * tile_size
    col0 = tile_col * tile_size
    rows = np.stack([row0 + y0, row0 + y0, row0 + y1, row0 + y1], axis=-1)
    columns = np.stack([col0 + x0, col0 + x1, col0 + x0, col0 + x1], axis=-1)
    weights = np.stack([(1 - ax) * (1 - ay), ax * (1 - ay), (1 - ax) * ay, ax * ay], axis=-1)
    return rows, columns, weights


def _bilinear_in_tile(atlas, tile_col, tile_row, tile_size, s, t):
    """One tile of ``atlas`` read at (s, t) as ``cl_tile_lookup`` reads it (:func:`_tile_taps`)."""
    rows, columns, weights = _tile_taps(tile_col, tile_row, tile_size, s, t)
    return np.einsum("...k,...kc->...c", weights, atlas[rows, columns])


def interpolate_exit_tile(tile: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """A per-exit-cell quantity (one ``N_o × N_o`` tile, (N_o, N_o, C)) at exit directions ``wo``
    (…, 3), interpolated as the shader reads a tile: (…, C)."""
    tile = np.asarray(tile, float)
    st = AngularGrid("hemisphere", tile.shape[0]).direction_to_square(np.asarray(wo, float))
    return _bilinear_in_tile(tile, 0, 0, tile.shape[0], st[..., 0], st[..., 1])


def incidence_corners(incidence_resolution: int, wi: np.ndarray):
    """The four incidence cells the shader blends for light from ``wi`` (…, 3) and their bilinear
    weights: tile columns, tile rows (…, 4) int and weights (…, 4), between the cells' centres,
    clamped at the square's border (step 2 of docs/table-spec.md)."""
    n_i = incidence_resolution
    st = AngularGrid("sphere", n_i).direction_to_square(wi)
    fx = np.clip(st[..., 0] * n_i - 0.5, 0.0, n_i - 1.0)
    fy = np.clip(st[..., 1] * n_i - 0.5, 0.0, n_i - 1.0)
    i0 = np.floor(fx).astype(int)
    j0 = np.floor(fy).astype(int)
    i1 = np.minimum(i0 + 1, n_i - 1)
    j1 = np.minimum(j0 + 1, n_i - 1)
    ax, ay = fx - i0, fy - j0
    columns = np.stack([i0, i1, i0, i1], axis=-1)
    rows = np.stack([j0, j0, j1, j1], axis=-1)
    weights = np.stack([(1 - ax) * (1 - ay), ax * (1 - ay), (1 - ax) * ay, ax * ay], axis=-1)
    return columns, rows, weights


def rho_taps(incidence_resolution: int, exit_resolution: int, wi: np.ndarray, wo: np.ndarray):
    """The 16 atlas pixels that the shader blends for ρ(ω_i, ω_o) and their weights: flat pixel
    indices ``row · (N_i·N_o) + column`` (…, 16) and weights (…, 16) summing to 1.  ρ is linear in
    the atlas, so these taps are all a renderer's use of the table (:func:`interpolate_rho`): the
    four incidence corners (:func:`incidence_corners`), each a tile read bilinearly between its
    pixel centres (:func:`_tile_taps`)."""
    n_i, n_o = incidence_resolution, exit_resolution
    wi, wo = np.broadcast_arrays(np.asarray(wi, float), np.asarray(wo, float))
    st_i = AngularGrid("sphere", n_i).direction_to_square(wi).reshape(-1, 2)
    st_o = AngularGrid("hemisphere", n_o).direction_to_square(wo).reshape(-1, 2)
    index = np.empty((len(st_i), 16), np.int64)
    weights = np.empty((len(st_i), 16))
    _rho_taps_kernel(st_i, st_o, n_i, n_o, index, weights)
    return index.reshape(wi.shape[:-1] + (16,)), weights.reshape(wi.shape[:-1] + (16,))


@numba.njit(cache=True)
def _rho_taps_kernel(st_i, st_o, n_i, n_o, index, weights):
    """:func:`rho_taps` from the square coordinates of ω_i and ω_o, with the arithmetic of
    :func:`incidence_corners` and :func:`_tile_taps` (the same values, bit for bit)."""
    half = 0.5 / n_o
    for p in range(st_i.shape[0]):
        fx = min(max(st_i[p, 0] * n_i - 0.5, 0.0), n_i - 1.0)
        fy = min(max(st_i[p, 1] * n_i - 0.5, 0.0), n_i - 1.0)
        i0, j0 = int(math.floor(fx)), int(math.floor(fy))
        i1, j1 = min(i0 + 1, n_i - 1), min(j0 + 1, n_i - 1)
        ax, ay = fx - i0, fy - j0
        corner_columns = (i0, i1, i0, i1)
        corner_rows = (j0, j0, j1, j1)
        corner_weights = ((1 - ax) * (1 - ay), ax * (1 - ay), (1 - ax) * ay, ax * ay)
        x = min(max(st_o[p, 0], half), 1.0 - half) * n_o - 0.5
        y = min(max(st_o[p, 1], half), 1.0 - half) * n_o - 0.5
        x0 = min(max(int(math.floor(x)), 0), n_o - 1)
        y0 = min(max(int(math.floor(y)), 0), n_o - 1)
        x1, y1 = min(x0 + 1, n_o - 1), min(y0 + 1, n_o - 1)
        bx, by = x - x0, y - y0
        tap_x = (x0, x1, x0, x1)
        tap_y = (y0, y0, y1, y1)
        tap_weights = ((1 - bx) * (1 - by), bx * (1 - by), (1 - bx) * by, bx * by)
        for k in range(4):
            row0, column0 = corner_rows[k] * n_o, corner_columns[k] * n_o
            for m in range(4):
                index[p, 4 * k + m] = (row0 + tap_y[m]) * (n_i * n_o) + column0 + tap_x[m]
                weights[p, 4 * k + m] = corner_weights[k] * tap_weights[m]


def interpolate_rho(atlas: np.ndarray, incidence_resolution: int, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """ρ(ω_i, ω_o) from a BRDF atlas exactly as the shader interpolates it.

    ``wi`` (…, 3) any unit direction, ``wo`` (…, 3) with z ≥ 0, both in the
    yarn frame.  Bilinear between the four nearest incidence-cell centres
    (clamped at the square's border), bilinear between exit-cell centres.
    """
    atlas = np.asarray(atlas, float)
    index, weights = rho_taps(incidence_resolution, atlas.shape[0] // incidence_resolution, wi, wo)
    return np.einsum("...k,...kc->...c", weights, atlas.reshape(-1, atlas.shape[2])[index])


def attenuation_taps(samples: int, length_over_radius):
    """The two pixels of an attenuation table of ``samples`` pixels that the shader blends at path
    lengths ``length_over_radius`` (…): lower pixel index (…) int and the upper one's weight (…)."""
    x = np.clip(np.asarray(length_over_radius, float) / ballistic.MAX_LENGTH_OVER_RADIUS, 0.0, 1.0) * (samples - 1)
    lower = np.minimum(np.floor(x).astype(int), samples - 2)
    return lower, x - lower


def interpolate_attenuation(table: np.ndarray, length_over_radius) -> np.ndarray:
    """The unscattered light's transmittance (…, C) at path lengths ``length_over_radius`` (…) from
    its table (1, M, C) (or (M, C)), as ``cl_unscattered_attenuation`` reads it: linear between
    pixel centres, held at the ends."""
    table = np.asarray(table, float).reshape(-1, np.shape(table)[-1])
    lower, fraction = attenuation_taps(table.shape[0], length_over_radius)
    fraction = fraction[..., None]
    return table[lower] * (1.0 - fraction) + table[lower + 1] * fraction


def interpolate_unscattered_rho(table: np.ndarray, index: float, wi: np.ndarray, wo: np.ndarray,
                                spread_rad: float) -> np.ndarray:
    """ρ_u(ω_i, ω_o) (…, C), 1/sr, from the attenuation table exactly as the shader forms it
    (``cl_unscattered_rho``): :func:`precompute.optics.ballistic.unscattered_rho` on the tabulated colour."""
    return ballistic.unscattered_rho(wi, wo, index, lambda length: interpolate_attenuation(table, length), spread_rad)
