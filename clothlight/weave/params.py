"""Parameters of a woven sample, with units.

Default: a plain weave like the paper's measured red cotton (§3.1, Figure 1), with round yarns
of the red-cotton preset's radius (0.1 mm) at 0.5 mm spacing.  The paper gives no yarn spacing;
0.5 mm (20 ends/cm) is a coarse shirting, chosen so round yarns do not intersect where they bend
between crossings (a tighter weave needs flatter, elliptical yarns, as real cloth has).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .errors import WeaveParameterError
from .patterns import plain, validate_interlacing

#: Vertical clearance added to the crimp so yarns touching at a crossing do not share surface.
CROSSING_CLEARANCE = 0.02


@dataclass(frozen=True)
class WeaveParameters:
    """A woven sample.

    Attributes
    ----------
    interlacing
        Boolean matrix, True where a warp passes over a weft (rows: wefts, columns: warps).
    warp_count, weft_count
        Number of warp (along x) and weft (along y) yarns in the sample.
    spacing_mm
        Centre-to-centre distance of neighbouring yarns, mm (the same for warp and weft).
    semi_axes_mm
        Yarn cross-section semi-axes (in the cloth plane, across it), mm; equal for round yarns.
    crimp_amplitude_mm
        Height of a yarn centreline above (below) the cloth's mid-plane where it passes over
        (under) a crossing, mm.  None: derived from the interlacing and the yarn thickness, the
        least that keeps crossing yarns apart.
    segments_per_crossing, segments_around
        Tessellation along a yarn between neighbouring crossings, and around its cross-section.
    """

    interlacing: np.ndarray = field(default_factory=plain)
    warp_count: int = 8
    weft_count: int = 8
    spacing_mm: float = 0.5
    semi_axes_mm: tuple[float, float] = (0.1, 0.1)
    crimp_amplitude_mm: float | None = None
    segments_per_crossing: int = 8
    segments_around: int = 12

    def __post_init__(self):
        object.__setattr__(self, "interlacing", validate_interlacing(self.interlacing))
        for name in ("warp_count", "weft_count"):
            value = getattr(self, name)
            if not isinstance(value, (int, np.integer)) or value < 1:
                raise WeaveParameterError(name, value, "an integer ≥ 1")
        for name, low in (("segments_per_crossing", 2), ("segments_around", 3)):
            value = getattr(self, name)
            if not isinstance(value, (int, np.integer)) or value < low:
                raise WeaveParameterError(name, value, f"an integer ≥ {low}")
        if not (isinstance(self.spacing_mm, (int, float)) and math.isfinite(self.spacing_mm) and self.spacing_mm > 0):
            raise WeaveParameterError("spacing_mm", self.spacing_mm, "> 0")
        if len(self.semi_axes_mm) != 2 or not all(math.isfinite(a) and a > 0 for a in self.semi_axes_mm):
            raise WeaveParameterError("semi_axes_mm", self.semi_axes_mm, "two lengths > 0 (mm)")
        width, thickness = self.semi_axes_mm
        if 2.0 * width >= self.spacing_mm:
            raise WeaveParameterError("semi_axes_mm", self.semi_axes_mm,
                                      f"a width 2·{width} below spacing_mm = {self.spacing_mm}: neighbouring yarns would intersect")
        amplitude = self.crimp_amplitude
        if amplitude < thickness * (1.0 + CROSSING_CLEARANCE) - 1e-12:
            raise WeaveParameterError("crimp_amplitude_mm", self.crimp_amplitude_mm,
                                      f"≥ {thickness * (1 + CROSSING_CLEARANCE):.4g} mm (the yarn thickness): crossing yarns would intersect")
        # Where a yarn changes sides it passes between two crossing yarns: round yarns need room
        # for that bend (centre-line curvature against the crossing yarn's radius).
        if self.spacing_mm < math.pi * math.sqrt(2.0) * amplitude * max(1.0, width / thickness) ** 0.5:
            raise WeaveParameterError("spacing_mm", self.spacing_mm,
                                      f"≥ {math.pi * math.sqrt(2) * amplitude:.4g} mm for a crimp of {amplitude:.4g} mm: "
                                      "yarns would cut through the yarns they pass between")

    @property
    def crimp_amplitude(self) -> float:
        """Crimp amplitude in mm (derived unless given)."""
        if self.crimp_amplitude_mm is not None:
            return float(self.crimp_amplitude_mm)
        return self.semi_axes_mm[1] * (1.0 + CROSSING_CLEARANCE)

    @property
    def sample_size_mm(self) -> tuple[float, float]:
        """Extent of the sample along x (warp direction) and y (weft direction), mm."""
        return self.weft_count * self.spacing_mm, self.warp_count * self.spacing_mm
