"""Where every yarn of a sample lies and how high it passes each crossing, irregularity included.

Regular places (:mod:`.geometry`'s layout): warp end ``j`` at y = (warp_count/2 − j − ½)·spacing,
weft pick ``i`` at x = (i + ½ − weft_count/2)·spacing; a yarn's centreline passes a crossing at
+h where it goes over, −h where it goes under (h its crimp amplitude).  The seeded jitters of
:mod:`.irregularity` move each yarn across and each crossing up or down.  A warp's crossings
lie at the picks' x, a weft's (along its axial coordinate s = −y) at the ends' −y: every yarn
of one system has the same knots, which is what :mod:`.centerline` blends between.
"""

from __future__ import annotations

from dataclasses import dataclass
import numpy as np

from .centerline import over_grid, regular_knots
from .irregularity import crossing_height_offsets, yarn_position_offsets


@dataclass(frozen=True, eq=False)
class SampleLayout:
    """Positions and crossing heights of a sample's yarns, mm.

    Attributes
    ----------
    warp_y
        (warp_count,): y of every warp end (decreasing with j).
    weft_x
        (weft_count,): x of every weft pick (increasing with i): the knots along every warp.
    warp_heights
        (warp_count, weft_count): height of warp j's centreline where it crosses pick i.
    weft_heights
        (weft_count, warp_count): height of weft i's centreline where it crosses end j.
    """

    warp_y: np.ndarray
    weft_x: np.ndarray
    warp_heights: np.ndarray
    weft_heights: np.ndarray

    @property
    def weft_knots(self) -> np.ndarray:
        """Axial coordinates (s = −y) of the crossings along every weft pick, increasing."""
        return -self.warp_y


def sample_layout(params, jitter_scale: float = 1.0) -> SampleLayout:
    """The yarns of ``params`` (a :class:`.params.WeaveParameters`, whose checks use this layout)
    where they lie, with its seeded irregularity: its spacing and height jitters times
    ``jitter_scale`` (how the clearance check looks for the largest that fits)."""
    warp_count, weft_count, spacing = params.warp_count, params.weft_count, params.spacing_mm
    warp_offsets, weft_offsets = yarn_position_offsets(params.seed, warp_count, weft_count,
                                                       jitter_scale * params.spacing_jitter, spacing)
    lift = crossing_height_offsets(params.seed, weft_count, warp_count, jitter_scale * params.height_jitter,
                                   params.cross_section_mm[1])
    over = over_grid(params.interlacing, warp_count, weft_count)                 # (picks, ends)
    warp_amplitude, weft_amplitude = params.crimp_amplitudes_mm
    return SampleLayout(
        warp_y=-regular_knots(warp_count, spacing) + warp_offsets,
        weft_x=regular_knots(weft_count, spacing) + weft_offsets,
        warp_heights=(np.where(over, warp_amplitude, -warp_amplitude) + lift).T,
        weft_heights=np.where(over, -weft_amplitude, weft_amplitude) + lift,
    )
