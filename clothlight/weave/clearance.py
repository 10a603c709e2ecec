"""How far apart crossing yarns stay: the vertical gap between a warp and a weft tube.

Only a warp and a weft that cross can touch: parallel neighbours are separated sideways (each
tube stays within its semi-axis ``a`` of its own vertical plane, and 2a < spacing), and a warp
and a weft meet only inside the square |x − xᵢ| < a, |y − yⱼ| < a around their crossing.  Where
the section relaxes between crossings (:mod:`.section`: a(s), b(s) along the axial coordinate s),
``a`` here is the largest a(s), and the square the one of that half-width.

Inside that square both tubes are vertical intervals.  The cross-section of a tube is an ellipse
with semi-axes ``a`` (in the cloth plane, across the yarn) and ``b`` (perpendicular to the yarn in
its vertical plane), so at lateral offset η from its axis a tube is the band of half-width
w(η) = b·√(1 − η²/a²) on either side of its centreline, measured along the centreline's normal
(see :mod:`.centerline`).  The band's upper and lower edges are the offset curves
(s ∓ w·z′/L, z ± w/L) with L = √(1 + z′²); they are graphs over the axial coordinate as long as
w·κ < 1 (the tube does not fold onto itself, checked by :class:`.WeaveParameters`).  The gap
at a point of the square is how far the lower tube's top stays below the upper tube's bottom;
its minimum over the square is negative exactly when the solids intersect.

A relaxing section is a band of half-width w(η, s) = b(s)·√(1 − η²/a(s)²).  Its edge pinches to
the centreline where a(s) falls to |η|, and there the offset curve turns back along s (it is no
graph), so the band is taken from the tube that encloses it: the ellipse of semi-axes (max a,
b(s)) at every s, w̄(η, s) = b(s)·√(1 − η²/max a²) ≥ w(η, s).  That is exact at every crossing
(where a(s) = a is the largest, for a yarn flatter than round) and can only understate the gap
between them.  Its edges are graphs while w̄·κ + |dw̄/ds| < 1 (the abscissa s ∓ w̄·z′/L grows at
1 ∓ …: d(w̄·sin θ)/ds = w̄′·sin θ + w̄·κ, θ the centreline's slope angle), which
:class:`.WeaveParameters` checks with the largest b(s), the largest curvature and the bound of
:func:`.section.thickness_slope`.

The triangle mesh differs from these exact tubes: its ring vertices lie on the exact surface,
but along the yarn it follows chords between rings, which on the inside of a bend stand proud of
the exact surface by up to κ·L²/8 (L the ring spacing).  Given the tessellation, the band edges
are taken from the ring vertices and joined by straight lines, as the mesh joins them — the gap
of the mesh as built.  (Around the yarn the mesh's polygon is inscribed in the ring's ellipse,
which lies in the enclosing one above, so taking that half-width there can only understate the
gap.)

The profile near a crossing depends only on the signs of the two crossings either side (a band
never reaches further than max a + max b < 3/2 spacing along the yarn; the section relaxes the
same way between every two crossings of a regular weave), so every crossing of the repeat
is evaluated once with its neighbourhood taken periodically.  A sample cut from the cloth only
loses neighbours, and a yarn running flat at its end stays further from the crossing yarn than
one changing sides, so the repeat's gaps bound the sample's.

Plies (:mod:`.plies`) lie inside their yarn's tube, so the tubes' gaps bound theirs; their mesh's
chords add only the twist's part to the envelope's, and the chord of a helix lies inside its
cylinder (towards the yarn's axis), so the mesh check of the tubes holds for the ply meshes too.
An irregular sample (:mod:`.irregularity`) has no repeat: :func:`sample_gaps` evaluates every
crossing of it, with the same band edges along its uneven centrelines.
"""

from __future__ import annotations

import numpy as np

from .centerline import knot_height, ring_positions, unit_height
from .section import largest_semi_axes, semi_axes_along

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
                segments: int | None, relaxation: float):
    """Lower and upper edges (Q, Q) of one yarn's band at axial offsets ``q`` from its crossing
    (first index) and lateral offsets ``q`` (second index), mm: of the exact tube when
    ``segments`` is None, else of its mesh with ``segments`` rings per spacing; its section
    relaxed by ``relaxation`` between crossings (:mod:`.section`), enclosed as the module says."""
    width, thickness = largest_semi_axes(semi_axes_mm, relaxation)
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
    knots = spacing_mm * (np.arange(len(window)) - NEIGHBOURHOOD)
    along = semi_axes_along(knots, s, semi_axes_mm, relaxation)[1]
    half = along[None, :] * np.sqrt(np.clip(1.0 - (q / width) ** 2, 0.0, None))[:, None]    # (lateral, s)
    lower = np.empty((len(q), len(half)))
    upper = np.empty_like(lower)
    for column, w in enumerate(half):
        lower[:, column] = np.interp(q, s + w * dz / length, z - w / length)
        upper[:, column] = np.interp(q, s - w * dz / length, z + w / length)
    return lower, upper


def crossing_gaps(interlacing: np.ndarray, spacing_mm: float, semi_axes_mm: tuple[float, float],
                  amplitudes_mm: tuple[float, float], segments_per_crossing: int | None = None,
                  resolution: int = 49, relaxation: float = 0.0) -> np.ndarray:
    """Smallest vertical gap (mm) between the warp and the weft at every crossing of the repeat.

    Parameters
    ----------
    interlacing
        Boolean (R, C) matrix, True where warp ``j`` passes over weft ``i``.
    spacing_mm
        Centre-to-centre distance of neighbouring yarns, mm.
    semi_axes_mm
        Cross-section semi-axes (in the cloth plane, across it) at the crossings, mm.
    amplitudes_mm
        Warp and weft crimp amplitudes, mm.
    segments_per_crossing
        None: the gap between the exact tubes; an integer: between their triangle meshes with
        that many segments per spacing along the yarn.
    resolution
        Grid points across the square where the two tubes overlap in plan (odd, so the crossing
        itself is one of them).
    relaxation
        How far the section relaxes towards round between crossings, 0–1 (:mod:`.section`).

    Valid while no tube folds onto itself (half-thickness × centreline curvature < 1), which
    :class:`.WeaveParameters` checks first.

    Returns
    -------
    (R, C) array: negative where the tubes intersect.  At a crossing that both yarns leave on
    both sides it is h_warp + h_weft − 2b at the crossing point, unless the bends come closer.
    """
    width = largest_semi_axes(semi_axes_mm, relaxation)[0]
    q = np.linspace(-width, width, resolution)
    warp_windows = _windows(interlacing.T).transpose(1, 0, 2)   # [i, j, :] along warp j
    weft_windows = _windows(~interlacing)                       # [i, j, :] along weft i
    ids, edges = [], []
    for windows, amplitude in ((warp_windows, amplitudes_mm[0]), (weft_windows, amplitudes_mm[1])):
        unique, inverse = np.unique(windows.reshape(-1, windows.shape[-1]), axis=0, return_inverse=True)
        ids.append(inverse.reshape(interlacing.shape))
        edges.append([_band_edges(window, amplitude, spacing_mm, semi_axes_mm, q, segments_per_crossing, relaxation)
                      for window in unique])
    pairs, inverse = np.unique(np.stack(ids, -1).reshape(-1, 2), axis=0, return_inverse=True)
    pair_gaps = np.empty(len(pairs))
    for n, (warp_id, weft_id) in enumerate(pairs):
        warp_low, warp_high = edges[0][warp_id]   # [x, y]
        weft_low, weft_high = edges[1][weft_id]   # [y, x]
        pair_gaps[n] = np.maximum(warp_low - weft_high.T, weft_low.T - warp_high).min()
    return pair_gaps[inverse.reshape(interlacing.shape)]


def minimum_gap(interlacing: np.ndarray, spacing_mm: float, semi_axes_mm: tuple[float, float],
                amplitudes_mm: tuple[float, float], segments_per_crossing: int | None = None,
                relaxation: float = 0.0) -> float:
    """Smallest vertical gap (mm) between crossing yarns anywhere in the weave (see
    :func:`crossing_gaps`); negative when yarns intersect."""
    return float(crossing_gaps(interlacing, spacing_mm, semi_axes_mm, amplitudes_mm, segments_per_crossing,
                               relaxation=relaxation).min())


def _interpolate_rows(x: np.ndarray, xp: np.ndarray, fp: np.ndarray) -> np.ndarray:
    """np.interp row by row: ``x`` (M, Q) at the increasing abscissae ``xp`` (M, n) of ``fp``
    (M, n), in one call, each row shifted clear of the others."""
    low, high = min(x.min(), xp.min()), max(x.max(), xp.max())
    shift = (high - low + 1.0) * np.arange(len(x))[:, None]
    return np.interp((x + shift).ravel(), (xp + shift).ravel(), fp.ravel()).reshape(x.shape)


def _crossing_band_edges(knots: np.ndarray, heights: np.ndarray, crossing: np.ndarray, s: np.ndarray,
                         semi_axes_mm: tuple[float, float], q: np.ndarray, relaxation: float):
    """Lower and upper band edges (N, Q, Q) of N yarns near one crossing each, as
    :func:`_band_edges` but along irregular centrelines: ``heights`` (N, K) at the shared
    ``knots`` (K,), the crossing at axial ``crossing`` (N,), the edges taken at the axial
    samples ``s`` (N, n) (dense: the exact tube; the rings: the mesh) and read at axial and
    lateral offsets ``q`` from the crossing (indices [n, axial, lateral])."""
    width = largest_semi_axes(semi_axes_mm, relaxation)[0]
    z, dz = knot_height(knots, heights, s)
    length = np.sqrt(1.0 + dz**2)
    thickness = semi_axes_along(knots, s, semi_axes_mm, relaxation)[1][:, None, :]     # (N, 1, n)
    half = thickness * np.sqrt(np.clip(1.0 - (q / width) ** 2, 0.0, None))[None, :, None]   # (N, Q lateral, n)
    along = (s - crossing[:, None])[:, None, :]                                   # (N, 1, n)
    tilt, rise = (dz / length)[:, None, :], (1.0 / length)[:, None, :]
    axial = np.broadcast_to(q, (len(s) * len(q), len(q)))
    edges = []
    for sign in (-1.0, 1.0):    # lower, upper
        xp = (along - sign * half * tilt).reshape(-1, s.shape[1])
        fp = (z[:, None, :] + sign * half * rise).reshape(-1, s.shape[1])
        edges.append(_interpolate_rows(axial, xp, fp).reshape(len(s), len(q), len(q)).transpose(0, 2, 1))
    return edges


def sample_gaps(layout, semi_axes_mm: tuple[float, float], spacing_mm: float,
                segments_per_crossing: int | None = None, resolution: int = 49, batch: int = 16,
                relaxation: float = 0.0) -> np.ndarray:
    """Smallest vertical gap (mm) between the warp and the weft at every crossing of a sample whose
    yarns lie irregularly (a :class:`.layout.SampleLayout`): every crossing is its own, so each is
    evaluated, ``batch`` at a time.  As :func:`crossing_gaps` otherwise: the exact tubes when
    ``segments_per_crossing`` is None, else their meshes, whose rings :func:`.centerline.ring_positions`
    places; the section relaxed by ``relaxation`` between the layout's own crossings.  Returns
    (weft_count, warp_count), negative where the tubes intersect."""
    width, thickness = largest_semi_axes(semi_axes_mm, relaxation)
    reach = width + thickness
    q = np.linspace(-width, width, resolution)
    picks, ends = layout.weft_heights.shape
    pick, end = (index.ravel() for index in np.indices((picks, ends)))
    families = []
    for knots, heights, yarn, crossing in ((layout.weft_x, layout.warp_heights, end, pick),
                                           (layout.weft_knots, layout.weft_heights, pick, end)):
        if segments_per_crossing is None:
            local = np.linspace(-reach, reach, 16 * resolution + 1)
            s = knots[crossing][:, None] + local
        else:
            rings = ring_positions(knots, spacing_mm, segments_per_crossing)
            first = -(-segments_per_crossing // 2)       # the ring on the first knot
            span = (NEIGHBOURHOOD + 1) * segments_per_crossing
            index = first + crossing[:, None] * segments_per_crossing + np.arange(-span, span + 1)
            s = rings[np.clip(index, 0, len(rings) - 1)]
        families.append((knots, heights[yarn], knots[crossing], s))
    gaps = np.empty(len(pick))
    for start in range(0, len(pick), batch):
        part = slice(start, start + batch)
        (warp_low, warp_high), (weft_low, weft_high) = (
            _crossing_band_edges(knots, heights[part], at[part], s[part], semi_axes_mm, q, relaxation)
            for knots, heights, at, s in families)
        swapped_low, swapped_high = weft_low.transpose(0, 2, 1), weft_high.transpose(0, 2, 1)
        gaps[part] = np.maximum(warp_low - swapped_high, swapped_low - warp_high).min(axis=(1, 2))
    return gaps.reshape(picks, ends)


def sample_curvature(layout) -> float:
    """Largest curvature (1/mm) of any centreline of an irregular sample: between crossings at
    distance Δ with heights z₀, z₁ it is |z₀ − z₁|/2 · π²/Δ² where the slope is zero."""
    largest = 0.0
    for knots, heights in ((layout.weft_x, layout.warp_heights), (layout.weft_knots, layout.weft_heights)):
        if len(knots) > 1:
            largest = max(largest, float((np.abs(np.diff(heights, axis=1)) / 2 * np.pi**2 / np.diff(knots)**2).max()))
    return largest
