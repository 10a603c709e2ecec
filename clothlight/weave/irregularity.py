"""Seeded irregularity of a woven sample: no two repeats of a real cloth are alike.

A loom never places two threads exactly a spacing apart, a crossing sits a little higher or lower
than its neighbours where the yarns bunch, and a spun yarn is thicker and thinner along its length
(its "evenness", measured as the CV of its mass per length, ~12–18 % for ring-spun cotton: Uster
Statistics).  Three jitters model that, each a fraction of the length it varies and each drawn
uniformly in [−1, 1] × that fraction (bounded, so that the clearance checks can hold for every
draw):

- ``spacing_jitter``: every yarn's position across the cloth moves by up to that fraction of the
  spacing;
- ``height_jitter``: every crossing (warp and weft together) moves up or down by up to that
  fraction of the yarn's half-thickness, so the gap at the crossing itself is kept;
- ``ply_radius_jitter``: every ply of every yarn is thinner at each crossing by up to that
  fraction of its radius, blended between crossings as the centreline is (:mod:`.centerline`);
  plies only ever get thinner, so that each stays inside its yarn's envelope (:mod:`.plies`).

Each jitter draws from its own stream of ``numpy.random.default_rng((seed, stream))``, so one
seed gives the same sample on every machine, and changing one jitter leaves the others' draws as
they were.
"""

from __future__ import annotations

import numpy as np

#: The random stream of each jitter under one seed (fixed: they are part of what a seed means).
_POSITION_STREAM, _HEIGHT_STREAM, _PLY_RADIUS_STREAM = 1, 2, 3


def _symmetric_uniform(seed: int, stream: int, shape: tuple[int, ...]) -> np.ndarray:
    """Draws uniform in [−1, 1) of ``shape`` from the stream ``stream`` of ``seed``."""
    return np.random.default_rng((seed, stream)).uniform(-1.0, 1.0, shape)


def yarn_position_offsets(seed: int, warp_count: int, weft_count: int, spacing_jitter: float,
                          spacing_mm: float) -> tuple[np.ndarray, np.ndarray]:
    """How far every warp end (across y) and every weft pick (across x) lies from its regular
    place, mm: (warp_count,) and (weft_count,) arrays within ± spacing_jitter · spacing_mm."""
    draws = _symmetric_uniform(seed, _POSITION_STREAM, (warp_count + weft_count,))
    offsets = spacing_jitter * spacing_mm * draws
    return offsets[:warp_count], offsets[warp_count:]


def crossing_height_offsets(seed: int, weft_count: int, warp_count: int, height_jitter: float,
                            half_thickness_mm: float) -> np.ndarray:
    """How far every crossing (weft pick i, warp end j) lies above its regular height, mm:
    (weft_count, warp_count) within ± height_jitter · half_thickness_mm."""
    return height_jitter * half_thickness_mm * _symmetric_uniform(seed, _HEIGHT_STREAM, (weft_count, warp_count))


def ply_radius_factors(seed: int, warp_count: int, weft_count: int, ply_count: int,
                       ply_radius_jitter: float) -> tuple[np.ndarray, np.ndarray]:
    """Factor on the ply radius of every ply of every yarn at each of its crossings, in
    [1 − ply_radius_jitter, 1]: (warp_count, ply_count, weft_count) for the warp ends (a warp
    crosses every pick) and (weft_count, ply_count, warp_count) for the weft picks."""
    shape = (warp_count + weft_count, ply_count, max(warp_count, weft_count))
    factors = 1.0 - ply_radius_jitter * 0.5 * (_symmetric_uniform(seed, _PLY_RADIUS_STREAM, shape) + 1.0)
    return factors[:warp_count, :, :weft_count], factors[warp_count:, :, :warp_count]
