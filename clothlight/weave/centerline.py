"""Crimped yarn centrelines: over and under the crossing yarns as the interlacing matrix says.

A yarn's centreline lies in the vertical plane through its axis.  Along its axial coordinate
``s`` (mm) it is ``h · H(s)``: the crimp amplitude ``h`` (mm) times a unit height profile that
is +1 at every crossing where the yarn passes over, −1 where it passes under, and between two
neighbouring crossings blends by a half cosine,

    H = (a + b)/2 + (a − b)/2 · cos(π t),    t ∈ [0, 1] from the crossing with sign a to b,

so the slope is zero at every crossing and the path is smooth (C¹, C^∞ between crossings).  A
float (the same sign at neighbouring crossings) stays flat.  Beyond the first and last crossing
a yarn runs flat for half a spacing, to its end.  Paper §3.1 (Figure 1) shows such a plain weave.
"""

from __future__ import annotations

import math

import numpy as np


def over_grid(interlacing: np.ndarray, warp_count: int, weft_count: int) -> np.ndarray:
    """(weft_count, warp_count) booleans, True where warp ``j`` passes over weft ``i``: the
    interlacing matrix repeated over the sample."""
    rows, cols = interlacing.shape
    return interlacing[np.arange(weft_count)[:, None] % rows, np.arange(warp_count)[None, :] % cols]


def ring_positions(knots: np.ndarray, spacing_mm: float, segments: int) -> np.ndarray:
    """Axial coordinates (mm) of the rings swept along a yarn whose crossings lie at ``knots``.

    ``knots`` (K,): increasing axial coordinates of the yarn's crossings, mm (evenly spaced by
    ``spacing_mm`` in a regular weave, jittered in an irregular one).  Every crossing gets a ring
    (that is where crossing yarns come closest), ``segments`` segments span each interval between
    neighbouring crossings, and ⌈segments/2⌉ each end piece of half a spacing beyond the first and
    last crossing.
    """
    half = -(-segments // 2)
    start = np.linspace(knots[0] - spacing_mm / 2.0, knots[0], half + 1)[:-1]
    steps = np.linspace(0.0, 1.0, segments + 1)[:-1]
    middle = np.concatenate([(knots[:-1, None] + np.diff(knots)[:, None] * steps).ravel(), knots[-1:]])
    end = np.linspace(knots[-1], knots[-1] + spacing_mm / 2.0, half + 1)[1:]
    return np.concatenate([start, middle, end])


def regular_knots(crossings: int, spacing_mm: float) -> np.ndarray:
    """Axial coordinates (mm) of ``crossings`` evenly spaced crossings centred on 0: crossing ``k``
    at (k + ½)·spacing − crossings·spacing/2."""
    return (np.arange(crossings) + 0.5 - crossings / 2.0) * spacing_mm


def knot_height(knots: np.ndarray, heights: np.ndarray, s: np.ndarray):
    """Centreline height z and its slope dz/ds at axial coordinates ``s``, blending the heights at
    the crossings by half cosines (module docstring) between knots that need not be evenly spaced.

    ``knots`` (K,): increasing axial coordinates of a yarn's crossings; ``heights`` (..., K): the
    centreline's height at each; ``s`` (n,) or (..., n): where to evaluate (outside the first and
    last knot the yarn runs flat).  Returns arrays (..., n) in the units of ``heights`` and
    ``heights`` per unit of ``s``.
    """
    count = heights.shape[-1]
    if count == 1:
        flat = np.broadcast_to(heights[..., :1], np.broadcast_shapes(heights.shape[:-1] + (1,), s.shape)).astype(float)
        return flat, np.zeros_like(flat)
    k = np.clip(np.searchsorted(knots, s, side="right") - 1, 0, count - 2)
    gap = knots[k + 1] - knots[k]
    t = np.clip((s - knots[k]) / gap, 0.0, 1.0)
    if k.ndim < heights.ndim:
        k = np.broadcast_to(k, heights.shape[:-1] + k.shape)
    a, b = np.take_along_axis(heights, k, -1), np.take_along_axis(heights, k + 1, -1)
    height = 0.5 * (a + b) + 0.5 * (a - b) * np.cos(np.pi * t)
    slope = -0.5 * (a - b) * np.pi * np.sin(np.pi * t) / gap
    slope = np.where((s <= knots[0]) | (s >= knots[-1]), 0.0, slope)
    return height, slope


def unit_height(signs: np.ndarray, crossing: np.ndarray):
    """Unit height profile H and its derivative dH/dc at crossing coordinates ``crossing``.

    ``signs`` (..., K): +1 over, −1 under, at crossings c = 0 … K−1 of each yarn; ``crossing``
    (n,): where to evaluate, in units of the spacing from crossing 0 (values outside [0, K−1]
    lie on the flat end pieces).  Returns arrays (..., n); divide dH/dc by the spacing for dH/ds.
    """
    return knot_height(np.arange(signs.shape[-1], dtype=float), signs.astype(float), crossing)


def max_curvature(amplitude_mm: float, spacing_mm: float) -> float:
    """Largest curvature (1/mm) of a crimped centreline: at a crossing between two changes of
    side, |d²z/ds²| = h·π²/p² where the slope is zero."""
    return amplitude_mm * math.pi**2 / spacing_mm**2


def crimp_percent(interlacing: np.ndarray, spacing_mm: float, amplitudes_mm: tuple[float, float],
                  samples: int = 64) -> tuple[float, float]:
    """Mean warp and weft crimp over one repeat, percent: (yarn length − cloth length) / cloth
    length · 100, the textile definition (ASTM D3883), from the crimped paths above."""
    result = []
    for over, amplitude in ((interlacing.T, amplitudes_mm[0]), (~interlacing, amplitudes_mm[1])):
        # one repeat along each yarn, with the next repeat's first crossing to close the period
        signs = np.where(np.concatenate([over, over[:, :1]], axis=1), 1.0, -1.0)
        crossing = np.linspace(0.0, signs.shape[1] - 1, (signs.shape[1] - 1) * samples + 1)
        _, slope = unit_height(signs, crossing)
        dz_ds = amplitude * slope / spacing_mm
        integrand = np.sqrt(1.0 + dz_ds**2)
        # trapezoid rule over the uniform samples
        length = spacing_mm / samples * (integrand.sum(axis=1) - 0.5 * (integrand[:, 0] + integrand[:, -1]))
        cloth = spacing_mm * (signs.shape[1] - 1)
        result.append(float(np.mean(length / cloth - 1.0) * 100.0))
    return result[0], result[1]
