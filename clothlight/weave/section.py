"""A yarn's cross-section along its length: flattened where crossing yarns press it, relaxed between.

In cloth a yarn is flattened where the yarn it crosses presses on it and relaxes towards its free,
round shape between crossings (A. Kemp, "An extension of Peirce's cloth geometry to the treatment
of non-circular threads", J. Textile Inst. 49, T44, 1958, models the pressed section; the relaxed
one between is what nothing presses).  The section is an ellipse of semi-axes a(s) in the cloth
plane and b(s) across it, s the axial coordinate (mm).  At every crossing it is the given
``semi_axes_mm`` (a, b); with the relaxation r ∈ [0, 1] its flattening F = a/b relaxes between
neighbouring crossings k, k + 1 (at s_k, s_{k+1}) as

    F(s) = F^w(s),    w(s) = 1 − r·sin²(π·t),    t = (s − s_k)/(s_{k+1} − s_k),

keeping its area π·a·b:

    a(s) = a·F^(−(1 − w)/2),    b(s) = b·F^((1 − w)/2).

w is 1 at every crossing and 1 − r midway, blended by the same half cosine as the centreline's
height (:mod:`.centerline`: 1 − r·sin²(πt) is that blend between a crossing and the midpoint); r = 1
makes the yarn round, of radius √(a·b), midway, and r = 0 keeps (a, b) everywhere (the rigid
tubes, exactly).  The mean radius √(a(s)·b(s)) = √(a·b) does not change along the yarn, so neither
does the plies' twist rate (:func:`.plies.twist_rate`).  Beyond the first and last crossing, on
the yarn's flat end pieces, nothing relaxes it: it keeps (a, b), as pressed.
"""

from __future__ import annotations

import math

import numpy as np


def section_weight(knots: np.ndarray, s: np.ndarray, relaxation: float) -> np.ndarray:
    """w(s) of the module docstring: 1 at the crossings ``knots`` (K,) and beyond the end ones,
    1 − ``relaxation`` midway between neighbours, at axial coordinates ``s`` (any shape), mm."""
    if len(knots) < 2:
        return np.ones(np.shape(s))
    k = np.clip(np.searchsorted(knots, s, side="right") - 1, 0, len(knots) - 2)
    t = np.clip((s - knots[k]) / (knots[k + 1] - knots[k]), 0.0, 1.0)
    return 1.0 - relaxation * np.sin(np.pi * t) ** 2


def semi_axes_along(knots: np.ndarray, s: np.ndarray, semi_axes_mm: tuple[float, float], relaxation: float):
    """The section's semi-axes (a(s), b(s)), mm, at axial coordinates ``s`` (any shape) of a yarn
    crossing others at ``knots`` (module docstring)."""
    width, thickness = semi_axes_mm
    # F^((1 − w)/2) is exactly 1 at the crossings: there the section is (a, b) to the last bit
    stretch = (width / thickness) ** (0.5 * (1.0 - section_weight(knots, s, relaxation)))
    return width / stretch, thickness * stretch


def largest_semi_axes(semi_axes_mm: tuple[float, float], relaxation: float) -> tuple[float, float]:
    """The largest a(s) and the largest b(s) anywhere along a yarn, mm: w runs over [1 − r, 1],
    and a(s), b(s) are monotonic in w, so each is largest at a crossing or midway."""
    width, thickness = semi_axes_mm
    stretch = (width / thickness) ** (0.5 * relaxation)
    return max(width, width / stretch), max(thickness, thickness * stretch)


def thickness_slope(semi_axes_mm: tuple[float, float], relaxation: float, shortest_mm: float) -> float:
    """Bound on |db/ds| along a yarn whose neighbouring crossings lie at least ``shortest_mm``
    apart: db/ds = b(s)·(ln F / 2)·(−dw/ds), |dw/ds| = r·π·|sin 2πt|/Δ ≤ r·π/Δ (dimensionless)."""
    width, thickness = semi_axes_mm
    return (largest_semi_axes(semi_axes_mm, relaxation)[1] * abs(math.log(width / thickness)) / 2.0
            * relaxation * math.pi / shortest_mm)
