"""Flyaway fibres: the short fibre ends that leave a spun yarn's surface (its hairiness).

Each yarn of a sample sends out, on average, ``flyaway_density_per_mm`` fibres per mm of its
length (a Poisson count), rooted at uniformly drawn places along the yarn and around its envelope,
the section there (:mod:`.section`: it relaxes between crossings) (:mod:`.closeup` gives the
defaults and their sources).  A fibre leaves the surface along the
surface's twist helix — at the twist angle θ to the yarn axis, the direction its fibres run in —
either way along the yarn, lifted off the surface by an angle drawn in [10°, 40°]; its length is
exponential with mean ``flyaway_length_mm`` (the short-hair regime of Barella & Manich 1993), and
it bends as a random walk, each of its ``SEGMENTS`` steps turning it by a normal angle of rms
``flyaway_curl_per_mm`` × the step.  Its first point lies inside its yarn, a third of the yarn's
half-thickness below the surface, so that it grows out of the yarn.

A fibre stops before the first place where it would enter a yarn, its own included: every point
and every quarter of every step stays outside each yarn's envelope grown by the fibre's radius
(:func:`inside_any_yarn`); a fibre left with fewer than two steps is dropped.  Everything is drawn
from the sample's seed (streams of its own beside :mod:`.irregularity`'s), so a seed gives the
same fibres every time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .centerline import knot_height
from .layout import SampleLayout, sample_layout
from .section import largest_semi_axes, semi_axes_along

#: Steps along every fibre.
SEGMENTS = 8
#: Sub-steps of each step at which a fibre is checked against the yarns.
CHECKS_PER_SEGMENT = 4
#: Range of the angle at which a fibre lifts off the yarn's surface, degrees.
LIFT_RANGE_DEG = (10.0, 40.0)
#: How deep below the surface a fibre starts, in units of the yarn's half-thickness.
ROOT_DEPTH = 1.0 / 3.0
#: The random streams of the fibres under the sample's seed (after :mod:`.irregularity`'s 1–3).
_COUNT_STREAM, _FIBRE_STREAM = 4, 5


@dataclass(frozen=True, eq=False)
class FlyawayFibres:
    """Polylines of the flyaway fibres of a sample, mm (the weave's coordinates).

    Attributes
    ----------
    points
        (N, 3): every fibre's points, fibre after fibre, root first.
    counts
        (F,): points of each fibre (≥ 3).
    yarn_id
        (F,): the yarn each fibre grows from (the mesh's numbering: warps, then wefts).
    radius_mm
        The fibres' radius (the medium's, :func:`.fibre_optics.fibre_radius_mm`).
    """

    points: np.ndarray
    counts: np.ndarray
    yarn_id: np.ndarray
    radius_mm: float

    def fibres(self) -> list[np.ndarray]:
        """Every fibre's points, (n, 3) each."""
        return np.split(self.points, np.cumsum(self.counts)[:-1])


def _families(layout: SampleLayout):
    """(knots, heights, lateral positions, warp?) of the warps, then the wefts."""
    return ((layout.weft_x, layout.warp_heights, layout.warp_y, True),
            (layout.weft_knots, layout.weft_heights, layout.weft_x, False))


def inside_any_yarn(points: np.ndarray, layout: SampleLayout, semi_axes_mm: tuple[float, float],
                    spacing_mm: float, margin_mm: float = 0.0, samples: int = 65,
                    relaxation: float = 0.0) -> np.ndarray:
    """(P,) booleans: whether each point (P, 3), mm, lies inside a yarn's envelope grown by
    ``margin_mm`` (semi-axes a(s) + margin, b(s) + margin; the section at the crossings
    ``semi_axes_mm``, relaxing between them by ``relaxation``, :mod:`.section`).  At lateral offset
    η from its vertical plane a yarn is the set within w(η) of its centreline in that plane (w the
    section's half-height at η, :mod:`.clearance`): the point is inside when it lies within w of one
    of ``samples`` points of the centreline within reach, w taken at that point's section, which
    misses at most Δs²/(8·w) (Δs their spacing: below 10⁻⁵ mm here)."""
    largest = largest_semi_axes(semi_axes_mm, relaxation)
    reach_width, reach = largest[0] + margin_mm, largest[1] + margin_mm
    offsets = np.linspace(-reach, reach, samples)
    inside = np.zeros(len(points), dtype=bool)
    for knots, heights, lateral, warp in _families(layout):
        along = points[:, 0] if warp else -points[:, 1]
        across = points[:, 1] if warp else points[:, 0]
        eta = across[None, :] - lateral[:, None]                              # (Y, P)
        within = (along >= knots[0] - spacing_mm / 2) & (along <= knots[-1] + spacing_mm / 2)
        yarn, point = np.nonzero((np.abs(eta) < reach_width) & within[None, :])
        s = along[point, None] + offsets                                        # (pairs, samples)
        z, _ = knot_height(knots, heights[yarn], s)
        distance = np.sqrt((s - along[point, None]) ** 2 + (z - points[point, 2, None]) ** 2)
        width, thickness = semi_axes_along(knots, s, semi_axes_mm, relaxation)
        width, thickness = width + margin_mm, thickness + margin_mm
        half = thickness * np.sqrt(np.clip(1.0 - (eta[yarn, point, None] / width) ** 2, 0.0, None))
        inside[point[(distance < half).any(axis=1)]] = True
    return inside


def _perpendicular_turn(direction: np.ndarray, angles: np.ndarray, rng) -> np.ndarray:
    """Unit directions (F, 3) turned from ``direction`` (F, 3) by ``angles`` (F,) radians about
    a random axis square to it."""
    random = rng.normal(size=direction.shape)
    axis = random - np.sum(random * direction, axis=1, keepdims=True) * direction
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    turned = np.cos(angles)[:, None] * direction + np.sin(angles)[:, None] * axis
    return turned / np.linalg.norm(turned, axis=1, keepdims=True)


def _roots(params, rng, count: int, knots, heights, lateral, warp: bool, yarn: np.ndarray):
    """Root points, outward normals and twist-helix directions (F, 3) of ``count`` fibres on the
    yarns ``yarn`` (indices into this family), on the section where each is rooted (:mod:`.section`),
    and that section's half-thickness (F, 1), mm."""
    spacing = params.spacing_mm
    s = rng.uniform(knots[0] - spacing / 2, knots[-1] + spacing / 2, count)
    psi = rng.uniform(0.0, 2.0 * np.pi, count)
    width, thickness = (axis[:, None] for axis in
                        semi_axes_along(knots, s, params.cross_section_mm, params.section_relaxation))
    z, dz = knot_height(knots, heights[yarn], s[:, None])
    z, dz = z[:, 0], dz[:, 0]
    length = np.sqrt(1.0 + dz**2)
    if warp:
        centre = np.stack([s, lateral[yarn], z], -1)
        tangent = np.stack([np.ones(count), np.zeros(count), dz], -1) / length[:, None]
        binormal = np.array([0.0, 1.0, 0.0])
    else:
        centre = np.stack([lateral[yarn], -s, z], -1)
        tangent = np.stack([np.zeros(count), -np.ones(count), dz], -1) / length[:, None]
        binormal = np.array([1.0, 0.0, 0.0])
    normal = np.cross(tangent, binormal)
    cos, sin = np.cos(psi)[:, None], np.sin(psi)[:, None]
    surface = centre + width * cos * binormal + thickness * sin * normal
    outward = cos / width * binormal + sin / thickness * normal
    outward /= np.linalg.norm(outward, axis=1, keepdims=True)
    around = -sin * width * binormal + cos * thickness * normal
    around /= np.linalg.norm(around, axis=1, keepdims=True)
    twist = math.radians(params.twist_angle_deg)
    helix = math.cos(twist) * tangent + math.sin(twist) * around
    return surface, outward, helix, thickness


def flyaway_fibres(params, settings, radius_mm: float, layout: SampleLayout | None = None) -> FlyawayFibres:
    """The flyaway fibres of radius ``radius_mm`` of the sample ``params`` (a
    :class:`.params.WeaveParameters`) with the close-up ``settings`` (a
    :class:`.closeup.CloseupSettings`): module docstring."""
    layout = sample_layout(params) if layout is None else layout
    count_rng = np.random.default_rng((settings.seed, _COUNT_STREAM))
    rng = np.random.default_rng((settings.seed, _FIBRE_STREAM))
    radius = radius_mm
    all_points, all_counts, all_yarns = [], [], []
    offset = 0
    for knots, heights, lateral, warp in _families(layout):
        yarns = len(heights)
        extent = knots[-1] - knots[0] + params.spacing_mm
        counts = count_rng.poisson(settings.flyaway_density_per_mm * extent, yarns)
        yarn = np.repeat(np.arange(yarns), counts)
        total = len(yarn)
        if total:
            surface, outward, helix, thickness = _roots(params, rng, total, knots, heights, lateral, warp, yarn)
            way = np.where(rng.uniform(size=total) < 0.5, -1.0, 1.0)[:, None]
            lift = np.radians(rng.uniform(*LIFT_RANGE_DEG, total))[:, None]
            direction = np.cos(lift) * way * helix + np.sin(lift) * outward
            step = rng.exponential(settings.flyaway_length_mm, total) / SEGMENTS
            # the fibre leaves the surface at its own radius and a half above it: clear of the yarn
            points = [surface - ROOT_DEPTH * thickness * outward, surface + 1.5 * radius * outward]
            for _ in range(SEGMENTS - 1):
                points.append(points[-1] + step[:, None] * direction)
                direction = _perpendicular_turn(direction, rng.normal(0.0, settings.flyaway_curl_per_mm * step), rng)
            points = np.stack(points, axis=1)                                      # (F, SEGMENTS + 1, 3)
            kept = _steps_clear(points, layout, params, radius)
            for fibre in np.flatnonzero(kept >= 2):
                all_points.append(points[fibre, :kept[fibre] + 1])
                all_counts.append(kept[fibre] + 1)
                all_yarns.append(offset + yarn[fibre])
        offset += yarns
    return FlyawayFibres(
        points=np.concatenate(all_points) if all_points else np.zeros((0, 3)),
        counts=np.array(all_counts, dtype=np.int64), yarn_id=np.array(all_yarns, dtype=np.int32),
        radius_mm=radius)


def _steps_clear(points: np.ndarray, layout: SampleLayout, params, radius: float) -> np.ndarray:
    """(F,) how many steps of each fibre, from its surface point on, stay outside every yarn at
    every check (the step from the buried root to the surface is its first, always kept)."""
    fibres, count = points.shape[:2]
    fractions = np.arange(1, CHECKS_PER_SEGMENT + 1) / CHECKS_PER_SEGMENT
    start, end = points[:, 1:-1], points[:, 2:]                                    # steps 2 …
    checks = start[:, :, None] + fractions[:, None] * (end - start)[:, :, None]    # (F, S, C, 3)
    inside = inside_any_yarn(checks.reshape(-1, 3), layout, params.cross_section_mm, params.spacing_mm, radius,
                             relaxation=params.section_relaxation)
    blocked = inside.reshape(fibres, count - 2, CHECKS_PER_SEGMENT).any(axis=2)
    first = np.where(blocked.any(axis=1), blocked.argmax(axis=1), count - 2)
    return 1 + first
