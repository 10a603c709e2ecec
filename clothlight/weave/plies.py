"""Plies twisted into a yarn: the yarn's envelope filled by ``ply_count`` tubes wound about its axis.

A plied yarn is ``P`` single yarns twisted together.  In the yarn's cross-section (the unit disc
of its envelope) the plies are ``P`` equal discs touching their neighbours and the envelope:

    ply radius  ρ = sin(π/P) / (1 + sin(π/P)),   their centres at  c = 1 − ρ  from the axis,

(P = 3: ρ = 0.464), one disc filling the envelope for a single yarn.  Two plies pressed together
flatten against each other: there each ply is an ellipse of semi-axes ρ = ½ towards the axis and
1/√2 across, the widest that stays in its half of the disc (a point at angle t on it lies at
r² = 1 − (½ − ρ_t²)(1 − cos t)² ≤ 1 from the axis for ρ_t ≤ 1/√2), so that a two-ply yarn seen from
any side covers 71 % of its width, not the half two round plies would.  (With three or more, a ply
wider across than ρ would cross into its neighbours' wedges.)  The envelope is the yarn's
cross-section, an ellipse of semi-axes ``a`` (in the cloth plane) and ``b`` (across it) in the
sweep frame of :mod:`.geometry` (binormal B, normal N); the unit disc maps onto it by
(x, y) ↦ a·x·B + b·y·N, so in a flattened yarn the plies flatten with it, and every ply lies inside
the envelope: the envelope's clearance checks hold for the plies.  Across the yarn, that is: a ply's
section by the plane square to the yarn's axis is this ellipse (its own section, square to its
helical axis, is narrower by the cosine of its helix angle).  Where the envelope flattens at the
crossings and relaxes between them (:mod:`.section`), the map takes each ring's own (a, b), so the
plies flatten and relax with it and stay inside it at every ring.

Twist: ply ``k`` sits at the angle φₖ(u) = 2πk/P + ω·u about the axis, u the arc length along the
yarn's centreline.  The twist angle θ is the helix angle at the yarn's surface (the preset's
``yarn.twist_angle_deg``, the textile definition tan θ = π·d·T for a yarn of diameter d and T
turns per unit length): a point at the envelope's radius R turning at ω travels the helix
tan θ = R·ω, so ω = tan θ / R.  A ply's outermost line (its crest) runs at that radius, so its
grooves follow the twist angle; R is the envelope's mean radius √(a·b), the same all along a yarn
whose section relaxes between crossings (that keeps its area).  φ grows from B towards
N, and (B, N, T) is right-handed: the plies make a right-handed helix, a Z twist.
"""

from __future__ import annotations

import math

import numpy as np


def ply_disc(ply_count: int) -> tuple[float, float, float]:
    """Where the plies of a ``ply_count``-ply yarn sit in the unit disc of its envelope: (distance
    of a ply's centre from the axis, its semi-axis towards the axis, its semi-axis across), in
    units of the envelope's radius (module docstring)."""
    if ply_count == 1:
        return 0.0, 1.0, 1.0
    sine = math.sin(math.pi / ply_count)
    radius = sine / (1.0 + sine)
    return 1.0 - radius, radius, (math.sqrt(0.5) if ply_count == 2 else radius)


def twist_rate(twist_angle_deg: float, semi_axes_mm):
    """Turns of the plies about the yarn axis per length of yarn, rad/mm: ω = tan θ / √(a·b)
    (module docstring); semi-axes as numbers, mm, or arrays of them (an array of rates)."""
    return math.tan(math.radians(twist_angle_deg)) / np.sqrt(semi_axes_mm[0] * semi_axes_mm[1])


def ply_rings(center: np.ndarray, binormal: np.ndarray, normal: np.ndarray, arc_mm: np.ndarray,
              semi_axes_mm, ply_count: int, twist_angle_deg: float,
              radius_factors: np.ndarray, segments_around: int):
    """Ring vertices and centre paths of the plies of yarns swept along their centrelines.

    Parameters
    ----------
    center, normal
        (Y, n, 3): the centrelines at their n rings, mm, and the sweep frame's unit normal there.
    binormal
        (3,): the sweep frame's binormal, the same everywhere along the yarns (:mod:`.geometry`).
    arc_mm
        (Y, n): arc length along each centreline at its rings, mm.
    semi_axes_mm
        The envelope's semi-axes (in the cloth plane, across it) at every ring, mm: two arrays
        (Y, n), or two numbers for a section that never changes.  Their product, the section's
        area, is the same at every ring (:mod:`.section`), so the plies turn at one rate.
    ply_count, twist_angle_deg
        Plies per yarn and the twist angle at the yarn's surface, degrees.
    radius_factors
        (Y, P, n): factor in (0, 1] on each ply's radius at each ring (irregularity); the centre
        stays where it is, so a thinner ply stays inside the envelope.
    segments_around
        Vertices around each ply.

    Returns
    -------
    rings (Y, P, n, segments_around, 3) and ply centres (Y, P, n, 3), mm.  Around a ply, vertex m
    sits at the angle 2πm/segments_around from the ply's outermost point (its crest) on, turning
    the way the plies do; a single ply's vertex 0 stays on the B side, as on an untwisted tube.
    """
    width, thickness = (np.broadcast_to(axis, arc_mm.shape)[:, None, :, None] for axis in semi_axes_mm)
    centre_distance, towards_axis, across_axis = ply_disc(ply_count)
    phase = (2.0 * np.pi * np.arange(ply_count) / ply_count)[None, :, None] \
        + twist_rate(twist_angle_deg, (width, thickness))[..., 0] * arc_mm[:, None, :]   # (Y, P, n)
    if ply_count == 1:
        phase = np.zeros_like(phase)     # one ply fills the envelope: nothing turns
    psi = 2.0 * np.pi * np.arange(segments_around) / segments_around
    radial = towards_axis * radius_factors[..., None] * np.cos(psi)                    # (Y, P, n, around)
    tangential = across_axis * radius_factors[..., None] * np.sin(psi)
    cos, sin = np.cos(phase)[..., None], np.sin(phase)[..., None]
    across = (centre_distance + radial) * cos - tangential * sin
    up = (centre_distance + radial) * sin + tangential * cos
    rings = (center[:, None, :, None, :] + (width * across)[..., None] * binormal
             + (thickness * up)[..., None] * normal[:, None, :, None, :])
    centres = (center[:, None] + (width[..., 0] * centre_distance * np.cos(phase))[..., None] * binormal
               + (thickness[..., 0] * centre_distance * np.sin(phase))[..., None] * normal[:, None])
    return rings, centres
