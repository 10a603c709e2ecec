"""Parameters of a woven sample, with units, checked so that the yarns cannot intersect.

Default: a plain weave like the paper's measured red cotton (§3.1, Figure 1) with round yarns
(§3.2: "a cylinder with a circle in its base") of radius 0.1 mm, the red-cotton preset's radius
(Peirce's diameter for an Ne 20 cotton yarn, see precompute/presets/voided_red_cotton.toml).  The paper
gives no thread spacing; 0.5 mm (20 threads/cm, a medium-weight cotton sheeting) is assumed.

Yarns keep their cross-section everywhere (the paper's rigid cylinders) unless it relaxes
between crossings (``section_relaxation``, :mod:`.section`), so they need room to change sides:
round yarns of 0.1 mm cannot pass over and under each other closer than about 0.40 mm, and a
flat elliptical yarn (``semi_axes_mm``, §7) must bend down within the width of the yarn it
crosses, which limits how wide it can be (e.g. 0.17 mm × 0.047 mm at 0.5 mm).  Every
set of parameters is checked against the exact tubes (:mod:`.clearance`), and a refusal names
the largest cross-section of the same shape that fits.  A yarn of several plies twisted at the
medium's twist angle (:mod:`.plies`) fills the same tube, so the same checks hold for its plies;
an irregular sample (:mod:`.irregularity`) is checked crossing by crossing, and a refusal names
the largest jitters that fit for its seed.  A section that relaxes between crossings is checked
the same way, with its largest width and thickness where those bound it, and a relaxation that
makes yarns meet where the rigid section clears is refused naming the largest that fits.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from numbers import Integral, Real

import numpy as np

from precompute.bounds import YARN_PLY_COUNT, YARN_TWIST_ANGLE_DEG
from precompute.bounds import Bound as _Bound
from precompute.errors import ParameterError

from .centerline import crimp_percent, max_curvature
from .clearance import crossing_gaps, sample_curvature, sample_gaps
from .errors import WeaveParameterError
from .layout import sample_layout
from .section import largest_semi_axes, thickness_slope
from .patterns import plain, validate_interlacing, weave_pattern

#: Radius of a round yarn when neither ``yarn_radius_mm`` nor ``semi_axes_mm`` is given, mm.
DEFAULT_YARN_RADIUS_MM = 0.1
#: Derived crimp amplitude over the yarn's half-thickness: the 2 % keeps crossing yarns from
#: sharing surface (coincident faces render as noise).
CROSSING_CLEARANCE = 0.02

#: The integer settings' ranges, read by the API (below) and the Weave panel (clothlight/blender/properties.py).
COUNT_BOUNDS = {
    "warp_count": _Bound("warp_count", 1, 1000, integer=True),
    "weft_count": _Bound("weft_count", 1, 1000, integer=True),
    "segments_per_crossing": _Bound("segments_per_crossing", 2, 256, integer=True),
    "segments_around": _Bound("segments_around", 3, 256, integer=True),
}
#: The plies and their twist: the medium's own bounds (one parameter per preset, ``[yarn]``).
PLY_BOUNDS = {
    "ply_count": YARN_PLY_COUNT,
    "twist_angle_deg": YARN_TWIST_ANGLE_DEG,
}
#: The irregularity's ranges (fractions, see :mod:`.irregularity`) and its seed; a jitter that the
#: clearance checks refuse for a given weave is refused naming the largest that fits.
IRREGULARITY_BOUNDS = {
    "spacing_jitter": _Bound("spacing_jitter", 0.0, 0.5, high_open=True),
    "height_jitter": _Bound("height_jitter", 0.0, 1.0, high_open=True),
    "ply_radius_jitter": _Bound("ply_radius_jitter", 0.0, 1.0, high_open=True),
    "seed": _Bound("seed", 0, 2**32 - 1, integer=True),
}
#: How far the section relaxes between crossings (a fraction, :mod:`.section`).
SECTION_BOUNDS = {
    "section_relaxation": _Bound("section_relaxation", 0.0, 1.0),
}
#: Vertices a sample may have: 2·10⁷ is a mesh of ~2 GB in Blender (and what Cycles builds from it).
MAX_VERTICES = 20_000_000


def _is_integer(value) -> bool:
    return isinstance(value, Integral) and not isinstance(value, bool)


def _is_length(value) -> bool:
    return isinstance(value, Real) and not isinstance(value, bool) and math.isfinite(value) and value > 0


@dataclass(frozen=True, eq=False)
class WeaveParameters:
    """A woven sample.  Coordinates: mm, cloth in the x-y plane, macroscopic normal +z, warp
    yarns along x, weft yarns along y (see :mod:`.geometry`).

    Attributes
    ----------
    interlacing
        Boolean matrix, True where a warp passes over a weft (rows: picks, columns: ends; see
        :mod:`.patterns`), or a built-in pattern name (``weave_pattern``).  Repeats over the sample.
    warp_count, weft_count
        Number of warp and weft yarns in the sample (≥ 1).
    spacing_mm
        Centre-to-centre distance of neighbouring yarns, warp and weft alike, mm.
    yarn_radius_mm
        Radius of a round yarn, mm.  Give this or ``semi_axes_mm``; neither: 0.1 mm.
    semi_axes_mm
        Elliptical cross-section (paper §7): semi-axis in the cloth plane, semi-axis across it, mm;
        where the section relaxes, the one at every crossing.
    crimp_amplitude_mm
        Height of a yarn's centreline above (below) the cloth's mid-plane where it passes over
        (under) a crossing, mm: one value for both systems or (warp, weft).  None: derived, the
        least that clears the crossing yarns, (1 + CROSSING_CLEARANCE) × the half-thickness for
        both; the interlacing then decides where each yarn is up or down, hence its crimp
        percentage (:attr:`crimp_percent`).
    segments_per_crossing, segments_around
        Tessellation: segments along a yarn per spacing (≥ 2), and around its cross-section (≥ 3)
        or each ply's.  Near the clearance limit more segments along may be needed, so that the
        mesh's chords do not cut into the crossing yarns; a refusal says how many.
    ply_count, twist_angle_deg
        Plies per yarn, twisted about its axis at this helix angle at the yarn's surface, degrees
        (:mod:`.plies`): the medium preset's ``yarn.ply_count`` and ``yarn.twist_angle_deg``.
        1 ply: the plain tube, whatever the angle.
    spacing_jitter, height_jitter, ply_radius_jitter, seed
        Seeded irregularity (:mod:`.irregularity`): fractions of the spacing, of the yarn's
        half-thickness and of the ply radius by which yarn positions, crossing heights and ply
        radii vary.  All 0: the regular weave, every repeat alike.
    section_relaxation
        How far the section relaxes towards the round section of its area midway between
        crossings, a fraction in [0, 1] (:mod:`.section`, after Kemp 1958): 0 keeps the
        cross-section everywhere (the rigid tubes); r flattens it to the given one at every
        crossing and to a/b = (a/b)^(1 − r) midway, the area and the plies' twist rate unchanged;
        1 makes it round midway.
    """

    interlacing: np.ndarray = field(default_factory=plain)
    warp_count: int = 8
    weft_count: int = 8
    spacing_mm: float = 0.5
    yarn_radius_mm: float | None = None
    semi_axes_mm: tuple[float, float] | None = None
    crimp_amplitude_mm: float | tuple[float, float] | None = None
    segments_per_crossing: int = 8
    segments_around: int = 12
    ply_count: int = 1
    twist_angle_deg: float = 0.0
    spacing_jitter: float = 0.0
    height_jitter: float = 0.0
    ply_radius_jitter: float = 0.0
    seed: int = 0
    section_relaxation: float = 0.0

    def __post_init__(self):
        matrix = weave_pattern(self.interlacing) if isinstance(self.interlacing, str) else self.interlacing
        matrix = validate_interlacing(matrix)
        matrix.flags.writeable = False
        object.__setattr__(self, "interlacing", matrix)
        for name, bound in (COUNT_BOUNDS | PLY_BOUNDS | IRREGULARITY_BOUNDS | SECTION_BOUNDS).items():
            value = getattr(self, name)
            try:
                bound.check(value)
            except ParameterError:
                raise WeaveParameterError(name, value, bound.allowed()) from None
        if self.vertex_estimate > MAX_VERTICES:
            raise WeaveParameterError(
                "warp_count, weft_count, segments_per_crossing, segments_around, ply_count",
                (self.warp_count, self.weft_count, self.segments_per_crossing, self.segments_around, self.ply_count),
                f"a mesh of at most {MAX_VERTICES:.0e} vertices (these make ~{self.vertex_estimate:.2g})")
        if not _is_length(self.spacing_mm):
            raise WeaveParameterError("spacing_mm", self.spacing_mm, "a finite length > 0 (mm)")
        self._check_cross_section()
        self._check_crimp()
        self._check_clearance()
        self._check_irregular_clearance()

    # -- derived quantities ---------------------------------------------------------------

    @property
    def vertex_estimate(self) -> int:
        """Vertices of the sample's mesh, at most: every ply's rings of ``segments_around``, one
        run of ``segments_per_crossing`` per crossing and one more."""
        crossings = self.warp_count * (self.weft_count + 1) + self.weft_count * (self.warp_count + 1)
        return crossings * self.segments_per_crossing * self.segments_around * self.ply_count

    @property
    def is_irregular(self) -> bool:
        """Whether yarns or crossings move off their regular places (the ply radius alone keeps
        every yarn's envelope, hence its clearance, as it is)."""
        return self.spacing_jitter > 0.0 or self.height_jitter > 0.0

    @property
    def cross_section_mm(self) -> tuple[float, float]:
        """Semi-axes (in the cloth plane, across it) of the yarn cross-section, mm."""
        if self.semi_axes_mm is not None:
            return float(self.semi_axes_mm[0]), float(self.semi_axes_mm[1])
        radius = DEFAULT_YARN_RADIUS_MM if self.yarn_radius_mm is None else float(self.yarn_radius_mm)
        return radius, radius

    @property
    def crimp_amplitudes_mm(self) -> tuple[float, float]:
        """Warp and weft crimp amplitudes, mm (derived unless given)."""
        if self.crimp_amplitude_mm is None:
            derived = self.cross_section_mm[1] * (1.0 + CROSSING_CLEARANCE)
            return derived, derived
        if isinstance(self.crimp_amplitude_mm, Real):
            return float(self.crimp_amplitude_mm), float(self.crimp_amplitude_mm)
        return float(self.crimp_amplitude_mm[0]), float(self.crimp_amplitude_mm[1])

    @property
    def crimp_percent(self) -> tuple[float, float]:
        """Mean warp and weft crimp, percent: how much longer a yarn is than the cloth it spans."""
        return crimp_percent(self.interlacing, self.spacing_mm, self.crimp_amplitudes_mm)

    @property
    def minimum_gap_mm(self) -> float:
        """Smallest vertical gap between the exact tubes of crossing yarns anywhere in the weave,
        mm (> 0; the mesh's gap at this tessellation, also checked, can be a little smaller).
        Plies lie inside their yarn's tube (:mod:`.plies`), so theirs is at least as large.  An
        irregular sample's: over every crossing of the sample."""
        if self.is_irregular:
            return float(sample_gaps(sample_layout(self), self.cross_section_mm, self.spacing_mm,
                                     relaxation=self.section_relaxation).min())
        return float(crossing_gaps(self.interlacing, self.spacing_mm, self.cross_section_mm,
                                   self.crimp_amplitudes_mm, relaxation=self.section_relaxation).min())

    @property
    def cover_factor(self) -> float:
        """Fractional cover of the cloth seen from above, 0–1: each system covers the share 2a/p
        of the cloth (a the yarn's half-width, p the spacing), and the two together
        1 − (1 − 2a/p)² (Peirce 1937; :mod:`.closeup` compares it with real sheeting).  a is the
        width at the crossings: a section that relaxes between them (``section_relaxation``) is
        narrower there, and covers that much less."""
        share = 2.0 * self.cross_section_mm[0] / self.spacing_mm
        return 1.0 - (1.0 - share) ** 2

    @property
    def sample_size_mm(self) -> tuple[float, float]:
        """Extent of the sample along x (the warp direction) and y (the weft direction), mm."""
        return self.weft_count * self.spacing_mm, self.warp_count * self.spacing_mm

    @classmethod
    def for_sample_size(cls, sample_size_mm: tuple[float, float], **kwargs) -> "WeaveParameters":
        """Parameters whose sample measures ``sample_size_mm`` (along x, along y), mm: the yarn
        counts follow from the spacing, which must divide the size (nothing is rounded)."""
        spacing = kwargs.get("spacing_mm", cls.spacing_mm)
        if not _is_length(spacing):
            raise WeaveParameterError("spacing_mm", spacing, "a finite length > 0 (mm)")
        try:
            along_x, along_y = sample_size_mm
        except (TypeError, ValueError):
            raise WeaveParameterError("sample_size_mm", sample_size_mm, "two lengths (along x, along y), mm") from None
        counts = []
        for size in (along_x, along_y):
            count = round(size / spacing) if _is_length(size) else 0
            if count < 1 or abs(count * spacing - size) > 1e-9 * max(size, spacing):
                near = max(1, count) * spacing
                raise WeaveParameterError("sample_size_mm", sample_size_mm,
                                          f"whole multiples of spacing_mm = {spacing:g} mm (e.g. {near:g})")
            counts.append(count)
        for name in ("warp_count", "weft_count"):
            if name in kwargs:
                raise WeaveParameterError(name, kwargs[name], "absent: sample_size_mm sets it")
        return cls(weft_count=counts[0], warp_count=counts[1], **kwargs)

    # -- checks ----------------------------------------------------------------------------

    @property
    def _cross_section_name(self) -> str:
        return "semi_axes_mm" if self.semi_axes_mm is not None else "yarn_radius_mm"

    @property
    def _cross_section_value(self):
        if self.semi_axes_mm is not None:
            return self.semi_axes_mm
        return self.yarn_radius_mm if self.yarn_radius_mm is not None else DEFAULT_YARN_RADIUS_MM

    def _check_cross_section(self):
        if self.semi_axes_mm is not None:
            if self.yarn_radius_mm is not None:
                raise WeaveParameterError("semi_axes_mm", self.semi_axes_mm,
                                          f"None when yarn_radius_mm (= {self.yarn_radius_mm!r}) is given: "
                                          "one or the other")
            axes = self.semi_axes_mm
            if isinstance(axes, str) or not hasattr(axes, "__len__") or len(axes) != 2 \
                    or not all(_is_length(a) for a in axes):
                raise WeaveParameterError("semi_axes_mm", axes, "two finite lengths > 0 (mm)")
        elif self.yarn_radius_mm is not None and not _is_length(self.yarn_radius_mm):
            raise WeaveParameterError("yarn_radius_mm", self.yarn_radius_mm, "a finite length > 0 (mm)")
        width = self.cross_section_mm[0]
        if 2.0 * width >= self.spacing_mm:
            raise WeaveParameterError(self._cross_section_name, self._cross_section_value,
                                      f"a width 2·{width:g} mm below spacing_mm = {self.spacing_mm:g} mm: "
                                      "neighbouring parallel yarns would intersect")
        widest = largest_semi_axes(self.cross_section_mm, self.section_relaxation)[0]
        if 2.0 * widest >= self.spacing_mm:
            raise WeaveParameterError("section_relaxation", self.section_relaxation,
                                      f"a relaxed width 2·{widest:.4g} mm below spacing_mm = {self.spacing_mm:g} mm "
                                      "(a yarn taller than wide widens between crossings): neighbouring parallel "
                                      "yarns would intersect")

    def _check_crimp(self):
        value = self.crimp_amplitude_mm
        if value is not None:
            single = isinstance(value, Real) and not isinstance(value, bool)
            pair = (value,) if single else value
            shaped = single or (not isinstance(value, str) and hasattr(value, "__len__") and len(value) == 2)
            if not shaped or not all(isinstance(h, Real) and not isinstance(h, bool) and math.isfinite(h) and h >= 0
                                     for h in pair):
                raise WeaveParameterError("crimp_amplitude_mm", value,
                                          "None, a length ≥ 0 or (warp, weft) lengths ≥ 0 (mm)")
        thickness = self.cross_section_mm[1]
        least = 2.0 * thickness * (1.0 + CROSSING_CLEARANCE)
        if sum(self.crimp_amplitudes_mm) < least - 1e-12:
            raise WeaveParameterError("crimp_amplitude_mm", value,
                                      f"warp + weft amplitudes ≥ {least:.4g} mm (the two yarns' thickness "
                                      f"and {CROSSING_CLEARANCE:.0%}): crossing yarns would intersect")

    def _fold(self, semi_axes, curvature: float, shortest_mm: float, relaxation: float) -> str | None:
        """Why a tube of this section, its centreline bent at most to ``curvature`` (1/mm) between
        crossings at least ``shortest_mm`` apart, would fold onto itself (:mod:`.clearance`:
        largest b·κ plus the largest |db/ds| reach 1), or None."""
        thickness = largest_semi_axes(semi_axes, relaxation)[1]
        slope = thickness_slope(semi_axes, relaxation, shortest_mm)
        if thickness * curvature + slope < 1.0:
            return None
        relaxing = (f", growing by up to {slope:.3g} mm/mm between crossings (section_relaxation = "
                    f"{relaxation:g})" if relaxation > 0.0 else "")
        return (f"to a radius of {1 / curvature:.4g} mm, below the half-thickness {thickness:.4g} mm{relaxing}: "
                "the tube would fold onto itself")

    def _problem(self, semi_axes, amplitudes, segments, relaxation) -> tuple[str, str] | None:
        """Why yarns of this cross-section, crimp and relaxation would intersect — ("fold" | "tubes" |
        "mesh", explanation) — or None if they clear, as exact tubes and as meshes of ``segments``."""
        curvature = max_curvature(max(amplitudes), self.spacing_mm)
        fold = self._fold(semi_axes, curvature, self.spacing_mm, relaxation)
        if fold is not None:
            return "fold", (f"a crimp of {max(amplitudes):.4g} mm over spacing_mm = {self.spacing_mm:g} mm bends "
                            f"the centreline {fold}")
        for kind, tessellation, what in (("tubes", None, "the yarns"), ("mesh", segments, "their triangle meshes")):
            gap = float(crossing_gaps(self.interlacing, self.spacing_mm, semi_axes, amplitudes, tessellation,
                                      relaxation=relaxation).min())
            if gap <= 0.0:
                return kind, (f"{what} would cut into the yarns they cross (vertical gap {gap:.3g} mm "
                              f"at spacing_mm = {self.spacing_mm:g} mm)")
        return None

    def _check_clearance(self):
        axes, amplitudes, relaxation = self.cross_section_mm, self.crimp_amplitudes_mm, self.section_relaxation
        problem = self._problem(axes, amplitudes, self.segments_per_crossing, relaxation)
        if problem is None:
            return
        kind, explanation = problem
        if relaxation > 0.0 and self._problem(axes, amplitudes, self.segments_per_crossing, 0.0) is None:
            self._refuse_relaxation(
                lambda r: self._problem(axes, amplitudes, self.segments_per_crossing, r) is None, explanation)
        derived = axes[1] * (1.0 + CROSSING_CLEARANCE)
        if self.crimp_amplitude_mm is not None and \
                self._problem(axes, (derived, derived), self.segments_per_crossing, relaxation) is None:
            raise WeaveParameterError("crimp_amplitude_mm", self.crimp_amplitude_mm,
                                      f"a flatter crimp, e.g. the derived {derived:.4g} mm: {explanation}")
        if kind == "mesh":
            finer = self._finest_needed(axes, amplitudes)
            if finer is not None:
                raise WeaveParameterError("segments_per_crossing", self.segments_per_crossing,
                                          f"≥ {finer} for this weave: {explanation}")
        # printed rounded down, so that the size offered does fit
        scale = float(f"{self._largest_clear_scale() * (1 - 5e-4):.3g}")
        largest = (f"{axes[0] * scale:.4g} mm" if self.semi_axes_mm is None
                   else f"({axes[0] * scale:.4g}, {axes[1] * scale:.4g}) mm or another shape that clears")
        raise WeaveParameterError(self._cross_section_name, self._cross_section_value,
                                  f"at most {largest} with the derived crimp: {explanation}")

    def _refuse_relaxation(self, clears, explanation: str):
        """Refuse ``section_relaxation``, naming the largest that ``clears`` (a test of a relaxation;
        0 clears), found by bisection and printed rounded down, so that it does clear."""
        low, high = 0.0, self.section_relaxation
        for _ in range(12):
            middle = 0.5 * (low + high)
            low, high = (middle, high) if clears(middle) else (low, middle)
        largest = math.floor(low * 1000.0) / 1000.0
        raise WeaveParameterError("section_relaxation", self.section_relaxation,
                                  f"at most {largest:g} for this weave: {explanation}")

    def _irregular_problem(self, jitter_scale: float, relaxation: float) -> str | None:
        """Why this sample's yarns, moved by ``jitter_scale`` × its spacing and height jitters and
        their section relaxed by ``relaxation``, would intersect, or None if they clear, as exact
        tubes and as meshes."""
        layout = sample_layout(self, jitter_scale)
        width = largest_semi_axes(self.cross_section_mm, relaxation)[0]
        closest = min(np.abs(np.diff(positions)).min(initial=np.inf) for positions in (layout.warp_y, layout.weft_x))
        if closest <= 2.0 * width:
            return (f"neighbouring parallel yarns {closest:.4g} mm apart, closer than their width "
                    f"2·{width:g} mm")
        fold = self._fold(self.cross_section_mm, sample_curvature(layout), closest, relaxation)
        if fold is not None:
            return f"a centreline bent {fold}"
        for tessellation, what in ((None, "the yarns"), (self.segments_per_crossing, "their triangle meshes")):
            gap = float(sample_gaps(layout, self.cross_section_mm, self.spacing_mm, tessellation,
                                    relaxation=relaxation).min())
            if gap <= 0.0:
                return f"{what} would cut into the yarns they cross (vertical gap {gap:.3g} mm)"
        return None

    def _check_irregular_clearance(self):
        """Every crossing of an irregular sample clears; else a refusal naming the section's
        relaxation, where the rigid section clears, or the spacing and height jitters with the
        largest of the same proportion that clears for this weave and seed (found by bisection)."""
        if not self.is_irregular:
            return
        relaxation = self.section_relaxation
        problem = self._irregular_problem(1.0, relaxation)
        if problem is None:
            return
        if relaxation > 0.0 and self._irregular_problem(1.0, 0.0) is None:
            self._refuse_relaxation(lambda r: self._irregular_problem(1.0, r) is None, problem)
        low, high = 0.0, 1.0
        for _ in range(10):
            scale = 0.5 * (low + high)
            low, high = (scale, high) if self._irregular_problem(scale, relaxation) is None else (low, scale)
        raise WeaveParameterError(
            "spacing_jitter, height_jitter", (self.spacing_jitter, self.height_jitter),
            f"at most ({self.spacing_jitter * low:.3g}, {self.height_jitter * low:.3g}) for this weave "
            f"and seed {self.seed}: {problem}")

    def _finest_needed(self, semi_axes, amplitudes, most: int = 128) -> int | None:
        """Fewest segments per spacing (up to ``most``) whose mesh clears, by bisection (chords
        shorten, and stand less proud, as the count grows)."""
        if self._problem(semi_axes, amplitudes, most, self.section_relaxation) is not None:
            return None
        low, high = self.segments_per_crossing, most
        while high - low > 1:
            middle = (low + high) // 2
            low, high = ((low, middle) if self._problem(semi_axes, amplitudes, middle, self.section_relaxation) is None
                         else (middle, high))
        return high

    def _largest_clear_scale(self) -> float:
        """Largest factor on the cross-section (derived crimp) for which yarns clear, by bisection."""
        width, thickness = self.cross_section_mm
        low, high = 0.0, 1.0
        for _ in range(24):
            scale = 0.5 * (low + high)
            h = thickness * scale * (1.0 + CROSSING_CLEARANCE)
            fits = self._problem((width * scale, thickness * scale), (h, h), self.segments_per_crossing,
                                 self.section_relaxation) is None
            low, high = (scale, high) if fits else (low, scale)
        return low
