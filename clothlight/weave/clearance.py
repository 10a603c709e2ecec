"""How far apart crossing yarns stay: the vertical gap between a warp and a weft tube.

Only a warp and a weft that cross can touch: parallel neighbours are separated sideways (each
tube stays within its semi-axis ``a`` of its own vertical plane, and 2a < spacing), and a warp
and a weft meet only inside the square |x − xᵢ| < a, |y − yⱼ| < a around their crossing.

Inside that square both tubes are vertical intervals.  The cross-section of a tube is an ellipse
with semi-axes ``a`` (in the cloth plane, across the yarn) and ``b`` (perpendicular to the yarn in
its vertical plane), so at lateral offset η from its axis a tube is the band of half-width
w(η) = b·√(1 − η²/a²) on either side of its centreline, measured along the centreline's normal
(see :mod:`.centerline`).  The band's upper and lower edges are the offset curves
(s ∓ w·z′/L, z ± w/L) with L = √(1 + z′²); they are graphs over the axial coordinate as long as
w·κ < 1 (the tube does not fold onto itself, checked by :class:`.WeaveParameters`).  The gap
at a point of the square is how far the lower tube's top stays below the upper tube's bottom;
its minimum over the square is negative exactly when the solids intersect.

The triangle mesh differs from these exact tubes: its ring vertices lie on the exact surface,
but along the yarn it follows chords between rings, which on the inside of a bend stand proud of
the exact surface by up to κ·L²/8 (L the ring spacing).  Given the tessellation, the band edges
are taken from the ring vertices and joined by straight lines, as the mesh joins them — the gap
of the mesh as built.  (Around the yarn the mesh's polygon is inscribed in the ellipse, so taking
the exact half-width there can only understate the gap.)

The profile near a crossing depends only on the signs of the two crossings either side (a band
never reaches further than a + b < 3/2 spacing along the yarn), so every crossing of the repeat
is evaluated once with its neighbourhood taken periodically.  A sample cut from the cloth only
loses neighbours, and a yarn running flat at its end stays further from the crossing yarn than
one changing sides, so the repeat's gaps bound the sample's.
"""

from __future__ import annotations

import numpy as np

from .centerline import unit_height

#: Crossings either side of a crossing that shape the yarns near it (see the module docstring).
NEIGHBOURHOOD = 2


def _windows(over: np.ndarray) -> np.ndarray:
    """(R, C, 2·NEIGHBOURHOOD + 1) signs of the yarn along each row of ``over`` around every
    crossing, periodic."""
    offsets = np.arange(-NEIGHBOURHOOD, NEIGHBOURHOOD + 1)
    cols = over.shape[1]
    index = (np.arange(cols)[:, None] + offsets[None, :]) % cols
    return np.where(over[:, index], 1.0, -1.0)


def _band_edges(window: np.ndarray, amplitude_mm: float, spacing_mm: float, semi_axes_mm, q: np.ndarray,
                segments: int | None):
    """Lower and upper edges (Q, Q) of one yarn's band at axial offsets ``q`` from its crossing
    (first index) and lateral offsets ``q`` (second index), mm: of the exact tube when
    ``segments`` is None, else of its mesh with ``segments`` rings per spacing."""
    width, thickness = semi_axes_mm
    reach = width + thickness
    if segments is None:
        s = np.linspace(-reach, reach, 16 * len(q) + 1)
    else:
        step = spacing_mm / segments                    # a ring sits on every crossing
        rings = int(np.ceil(reach / step)) + 1
        s = step * np.arange(-rings, rings + 1)
    height, slope = unit_height(window, s / spacing_mm + NEIGHBOURHOOD)
    z = amplitude_mm * height
    dz = amplitude_mm * slope / spacing_mm
    length = np.sqrt(1.0 + dz**2)
    half = thickness * np.sqrt(np.clip(1.0 - (q / width) ** 2, 0.0, None))
    lower = np.empty((len(q), len(half)))
    upper = np.empty_like(lower)
    for column, w in enumerate(half):
        lower[:, column] = np.interp(q, s + w * dz / length, z - w / length)
        upper[:, column] = np.interp(q, s - w * dz / length, z + w / length)
    return lower, upper


def crossing_gaps(interlacing: np.ndarray, spacing_mm: float, semi_axes_mm: tuple[float, float],
                  amplitudes_mm: tuple[float, float], segments_per_crossing: int | None = None,
                  resolution: int = 49) -> np.ndarray:
    """Smallest vertical gap (mm) between the warp and the weft at every crossing of the repeat.

    Parameters
    ----------
    interlacing
        Boolean (R, C) matrix, True where warp ``j`` passes over weft ``i``.
    spacing_mm
        Centre-to-centre distance of neighbouring yarns, mm.
    semi_axes_mm
        Cross-section semi-axes (in the cloth plane, across it), mm.
    amplitudes_mm
        Warp and weft crimp amplitudes, mm.
    segments_per_crossing
        None: the gap between the exact tubes; an integer: between their triangle meshes with
        that many segments per spacing along the yarn.
    resolution
        Grid points across the square where the two tubes overlap in plan (odd, so the crossing
        itself is one of them).

    Valid while no tube folds onto itself (half-thickness × centreline curvature < 1), which
    :class:`.WeaveParameters` checks first.

    Returns
    -------
    (R, C) array: negative where the tubes intersect.  At a crossing that both yarns leave on
    both sides it is h_warp + h_weft − 2b at the crossing point, unless the bends come closer.
    """
    width = semi_axes_mm[0]
    q = np.linspace(-width, width, resolution)
    warp_windows = _windows(interlacing.T).transpose(1, 0, 2)   # [i, j, :] along warp j
    weft_windows = _windows(~interlacing)                       # [i, j, :] along weft i
    ids, edges = [], []
    for windows, amplitude in ((warp_windows, amplitudes_mm[0]), (weft_windows, amplitudes_mm[1])):
        unique, inverse = np.unique(windows.reshape(-1, windows.shape[-1]), axis=0, return_inverse=True)
        ids.append(inverse.reshape(interlacing.shape))
        edges.append([_band_edges(window, amplitude, spacing_mm, semi_axes_mm, q, segments_per_crossing)
                      for window in unique])
    pairs, inverse = np.unique(np.stack(ids, -1).reshape(-1, 2), axis=0, return_inverse=True)
    pair_gaps = np.empty(len(pairs))
    for n, (warp_id, weft_id) in enumerate(pairs):
        warp_low, warp_high = edges[0][warp_id]   # [x, y]
        weft_low, weft_high = edges[1][weft_id]   # [y, x]
        pair_gaps[n] = np.maximum(warp_low - weft_high.T, weft_low.T - warp_high).min()
    return pair_gaps[inverse.reshape(interlacing.shape)]


def minimum_gap(interlacing: np.ndarray, spacing_mm: float, semi_axes_mm: tuple[float, float],
                amplitudes_mm: tuple[float, float], segments_per_crossing: int | None = None) -> float:
    """Smallest vertical gap (mm) between crossing yarns anywhere in the weave (see
    :func:`crossing_gaps`); negative when yarns intersect."""
    return float(crossing_gaps(interlacing, spacing_mm, semi_axes_mm, amplitudes_mm, segments_per_crossing).min())
