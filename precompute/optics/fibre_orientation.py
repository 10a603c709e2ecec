"""Fibres lying along the yarn: the direction-dependent extinction of a medium of oriented fibres (issue 43).

The fibres of a spun yarn follow helices about its axis: at radius r of a yarn of radius R whose surface
fibres lie at the twist's helix angle α_R, ``tan α = (r / R) tan α_R`` (Hearle, Grosberg & Backer,
"Structural Mechanics of Fibers, Yarns, and Fabrics", Wiley 1969, ch. 4: the idealised helical yarn),
and migration and hairiness spread them about that (here a Gaussian angle of σ = ``spread``).  Taken
the same at every point of the cross-section (the helix angle at a radius drawn uniformly over its area,
at a uniform azimuth about the axis), the medium is homogeneous and its fibres' axes have one
distribution t ~ D.

A fibre of diameter d and length ℓ presents ``d ℓ sin ∠(ω, t)`` to light along ω, and a volume fraction
φ of fibres holds ``4φ / (π d²)`` of fibre length per volume, so the extinction coefficient is::

    μt(ω) = (4φ / (π d)) ⟨sin ∠(ω, t)⟩_D

(the geometric cross-section: the diffraction that a dense packing suppresses is left out, as for
randomly oriented fibres, :mod:`.fibre`; with D uniform on the sphere ⟨sin⟩ = π/4 and μt = φ/d, the
random fibres' value).  ⟨sin⟩ depends only on |ω · z| (D is symmetric about the axis z) and is
tabulated here on a uniform grid of it from :data:`AXIS_SAMPLES` axes of D, so that the transport and the
unscattered light read one table.  What a collision does is traced by the transport
(:mod:`precompute.transport._fibres`), which draws the fibres' axes from the same D.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from precompute.errors import ParameterError

#: The orientations a ``[fibres]`` table may give: ``random`` (the Mie proxy of :mod:`.fibre`), or
#: ``yarn_axis`` (this module).
RANDOM_ORIENTATION = "random"
FIBRE_ORIENTATIONS = (RANDOM_ORIENTATION, "yarn_axis")
#: Points of the ⟨sin⟩ table over |cos| to the axis on [0, 1].
SINE_TABLE_SIZE = 129
#: Axes of D the table averages over (a fixed stream: the table is a deterministic function of D).
AXIS_SAMPLES = 1 << 16
_AXIS_SEED = 20081


@dataclass(frozen=True, eq=False)
class OrientedFibres:
    """A medium of fibres oriented along the yarn (module docstring), as the transport needs it.

    ``extinction_per_mm``: 4φ/(πd), 1/mm; ``relative_index``: the fibres' index over the host's;
    ``radius_mm``: the fibres' radius; ``helix_angle_deg``: the surface fibres' angle to the yarn axis;
    ``spread_deg``: σ of the spread about the helix; ``absorption_per_mm`` (L,): μa inside a fibre;
    ``roughness_deg``: σ of the blur of the direction a fibre sends light in (:mod:`precompute.transport._fibres`).
    """

    extinction_per_mm: float
    relative_index: float
    radius_mm: float
    helix_angle_deg: float
    spread_deg: float
    absorption_per_mm: np.ndarray
    roughness_deg: float = 0.0
    #: ⟨sin ∠(ω, t)⟩ at |ω · z| uniform on [0, 1] (:func:`mean_sine_table`)
    mean_sine: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        for name in ("extinction_per_mm", "relative_index", "radius_mm"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ParameterError(f"oriented fibres {name}", value, "a finite number > 0")
        if not 0.0 <= self.helix_angle_deg < 90.0:
            raise ParameterError("oriented fibres helix_angle_deg", self.helix_angle_deg, "[0, 90) degrees")
        for name in ("spread_deg", "roughness_deg"):
            if not 0.0 <= getattr(self, name) <= 90.0:
                raise ParameterError(f"oriented fibres {name}", getattr(self, name), "[0, 90] degrees")
        absorption = np.ascontiguousarray(np.atleast_1d(np.asarray(self.absorption_per_mm, float)))
        if absorption.ndim != 1 or not np.all(np.isfinite(absorption)) or np.any(absorption < 0):
            raise ParameterError("oriented fibres absorption_per_mm", self.absorption_per_mm, "finite values ≥ 0")
        object.__setattr__(self, "absorption_per_mm", absorption)
        object.__setattr__(self, "mean_sine", mean_sine_table(self.helix_angle_deg, self.spread_deg))

    def parameters(self) -> np.ndarray:
        """The transport kernel's ``fibre_params`` (:mod:`precompute.transport._fibres`)."""
        return np.array([self.extinction_per_mm, self.relative_index, self.radius_mm,
                         math.tan(math.radians(self.helix_angle_deg)), math.radians(self.spread_deg),
                         math.radians(self.roughness_deg)])

    def extinction(self, cos_to_axis) -> np.ndarray:
        """μt (1/mm) along directions at ``cos_to_axis`` to the yarn axis (the table read linearly)."""
        grid = np.linspace(0.0, 1.0, len(self.mean_sine))
        return self.extinction_per_mm * np.interp(np.abs(np.asarray(cos_to_axis, float)), grid, self.mean_sine)

    @property
    def across_axis_extinction_per_mm(self) -> float:
        """μt across the yarn axis, 1/mm: the unscattered light's, which crosses a yarn across it."""
        return float(self.extinction(0.0))


def fibre_axes(helix_angle_deg: float, spread_deg: float, count: int, rng: np.random.Generator) -> np.ndarray:
    """``count`` fibre axes (count, 3) drawn from D (module docstring), the yarn axis z."""
    tan_a = math.tan(math.radians(helix_angle_deg)) * np.sqrt(rng.random(count))
    cos_a = 1.0 / np.sqrt(1.0 + tan_a**2)
    beta = 2.0 * math.pi * rng.random(count)
    axes = np.stack([tan_a * cos_a * np.cos(beta), tan_a * cos_a * np.sin(beta), cos_a], axis=-1)
    if spread_deg > 0.0:
        angle = np.abs(rng.standard_normal(count)) * math.radians(spread_deg)
        axes = _turned(axes, angle, 2.0 * math.pi * rng.random(count))
    return axes


@functools.lru_cache(maxsize=64)
def mean_sine_table(helix_angle_deg: float, spread_deg: float, size: int = SINE_TABLE_SIZE) -> np.ndarray:
    """⟨sin ∠(ω, t)⟩ over D at |ω · z| = 0 … 1 in ``size`` uniform steps (module docstring), read-only:
    kept per (helix, spread), since a fit's candidates that change neither share it (0.1 s to average)."""
    axes = fibre_axes(helix_angle_deg, spread_deg, AXIS_SAMPLES, np.random.default_rng(_AXIS_SEED))
    cos_axis = np.linspace(0.0, 1.0, size)
    directions = np.stack([np.sqrt(1.0 - cos_axis**2), np.zeros(size), cos_axis], axis=-1)
    cosines = directions @ axes.T
    table = np.sqrt(np.clip(1.0 - cosines**2, 0.0, 1.0)).mean(axis=1)
    table.flags.writeable = False
    return table


def _turned(axes: np.ndarray, angle: np.ndarray, azimuth: np.ndarray) -> np.ndarray:
    """Each unit vector of ``axes`` turned by ``angle`` (radians) toward the azimuth ``azimuth`` about it."""
    helper = np.where(np.abs(axes[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    e1 = np.cross(axes, helper)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(axes, e1)
    sin_angle = np.sin(angle)[:, None]
    return (np.cos(angle)[:, None] * axes
            + sin_angle * (np.cos(azimuth)[:, None] * e1 + np.sin(azimuth)[:, None] * e2))
