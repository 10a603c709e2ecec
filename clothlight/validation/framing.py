"""Where the gonioreflectometer's sun and cameras go and which patch of cloth they see (paper §4).

Pure geometry, no Blender (and which turns of the sample a sweep averages, from a bake's summary).
Conventions: the cloth lies in the x-y plane with its macroscopic normal +z; the plane of incidence
is x-z.  The sun sits on the −x side at zenith θi, a camera at signed zenith θv, negative on the
light's side (the paper's §6 graphs), so θv = +θi is the mirror direction.  Angles are in degrees,
lengths in millimetres (the woven sample's unit).

Framing.  Every view frames the same square patch of side P centred on the sample.  An
orthographic camera at θv sees that patch foreshortened to P cos θv across the plane of incidence
and P along it, so the frame is P cos θv × P.  The rig keeps the image N × N pixels and makes
the pixels non-square (pixel aspect 1 : 1/cos θv, ortho scale P on the vertical axis): each pixel
then covers the same (P/N)² of cloth at every view, and its cross-section perpendicular to the
view is (P/N)² cos θv.

No edges.  A view ray through the patch crosses the cloth's slab (half-thickness h about its
mid-plane) within h tan θv of where it meets the mid-plane, and a shadow ray toward the sun from a
visible point travels at most 2h tan θi sideways before leaving the slab; Cycles' pixel filter
reaches about one pixel outside the frame.  So the sample must extend, across the plane of
incidence, P/2 + h tan|θv|max + 2h tan θi,max + P/N + edge band from the patch centre (the edge
band, one yarn spacing for a woven sample, keeps the incomplete outermost yarns out of view), and
P/2 + P/N + edge band along it.

Turned samples.  A sweep may average the sample over azimuths α about its normal (the warp's angle
from the plane of incidence), turning the sun and the cameras together by α about the normal through
the patch centre, as the fit's forward model does (:mod:`precompute.optics.measured_sample`).  What
must lie on the sample is then the rectangle above (half-extents P/2 + P/N + h tan|θv|max +
2h tan θi,max across the plane of incidence, P/2 + P/N along it) turned by α: its reach along the
sample's x is the first half-extent × |cos α| + the second × |sin α|, along y the same with cos and
sin swapped, each plus the edge band.  At 45° a square patch reaches √2 times as far, so a sweep
with a diagonal azimuth may frame fewer weave repeats than one at 0° and 90°.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


from precompute.errors import ParameterError
from precompute.optics.measured_sample import SAMPLE_AZIMUTHS_KEY, SAMPLE_TABLE, sample_azimuths_deg

#: The paper's incidences (§6, graphs 1–6), degrees.
DEFAULT_INCIDENCES_DEG = (0.0, 30.0, 45.0, 60.0)
#: The paper's views: −60 … 70° in 10° steps, negative on the light's side (§6), degrees.
DEFAULT_VIEWS_DEG = tuple(float(v) for v in range(-60, 71, 10))
#: Views beyond this zenith are refused: the frame shrinks as cos θv and the pixel aspect
#: 1/cos θv would exceed what Blender accepts long before 90°.
MAX_VIEW_DEG = 85.0
#: Incidences beyond this zenith are refused: the sun's irradiance on the cloth, E cos θi, vanishes.
MAX_INCIDENCE_DEG = 85.0

#: Materials a sweep can measure, in the order they are swept and plotted (:mod:`.run`; here, without
#: Blender, so that the command line checks its arguments before importing bpy).
MATERIALS = ("yarn", "yarn_general", "yarn_scene", "baseline", "garment", "garment_general")
#: What a sweep measures when no materials are named and tables are given.
DEFAULT_MATERIALS = ("yarn", "baseline")
#: Materials that read the yarn tables.
YARN_MATERIALS = ("yarn", "yarn_general", "yarn_scene")
#: Materials rendered with full path tracing (light bounces between yarns); every other one is
#: rendered with direct light only (:meth:`clothlight.blender.validation.rig.Rig.use_path_tracing`).
PATH_TRACED_MATERIALS = ("yarn_scene",)
#: Materials that read a cloth bake, swept on a flat patch in place of the sample.
GARMENT_MATERIALS = ("garment", "garment_general")
#: The turns of the sample a sweep measures where none are named: one, its warp in the plane of
#: incidence (the fit's forward model averages ``[sample] azimuths_deg``, 0° and 90° by default:
#: a sweep takes them from ``--sample-azimuths`` or the bake's summary, ``clothlight.validate``).
DEFAULT_RIG_AZIMUTHS_DEG = (0.0,)


def toward_sun(theta_i_deg: float) -> np.ndarray:
    """Unit vector toward a sun at incidence θi (degrees), on the −x side of the plane of incidence."""
    t = math.radians(theta_i_deg)
    return np.array([-math.sin(t), 0.0, math.cos(t)])


def toward_camera(theta_v_deg: float) -> np.ndarray:
    """Unit vector toward a camera at signed view zenith θv (degrees); negative: the light's side."""
    t = math.radians(theta_v_deg)
    return np.array([math.sin(t), 0.0, math.cos(t)])


def frame_size_mm(patch_mm: float, theta_v_deg: float) -> tuple[float, float]:
    """Width (image x, in the plane of incidence) and height (image y, along the world's y) of the
    frame that shows exactly the square patch of side ``patch_mm`` from θv: (P cos θv, P), mm."""
    return patch_mm * math.cos(math.radians(theta_v_deg)), patch_mm


def pixel_aspect(theta_v_deg: float) -> tuple[float, float]:
    """Blender's (pixel_aspect_x, pixel_aspect_y) that make an N × N image span P cos θv × P."""
    return 1.0, 1.0 / math.cos(math.radians(theta_v_deg))


def pixel_cross_section_mm2(patch_mm: float, resolution: int, theta_v_deg: float) -> float:
    """Area of one pixel's beam perpendicular to the view, (P/N)² cos θv, mm²."""
    return (patch_mm / resolution) ** 2 * math.cos(math.radians(theta_v_deg))


@dataclass(frozen=True)
class SampleBounds:
    """The sample's extent in its own frame (cloth normal +z), mm.

    ``center``: centre of its bounding box; ``half_size``: half extents along x and y;
    ``half_thickness``: half its extent along z; ``edge_band``: width along the border that must stay
    out of view (one yarn spacing for a woven sample, 0 for a plain surface); ``period``: the
    weave's repeat along x and y, or None for a surface without one.
    """

    center: tuple[float, float, float]
    half_size: tuple[float, float]
    half_thickness: float
    edge_band: float = 0.0
    period: tuple[float, float] | None = None


def _turn(azimuth_deg: float) -> tuple[float, float]:
    """|cos α|, |sin α| of a sample azimuth (degrees), exactly 1 and 0 at α = 0."""
    if azimuth_deg == 0.0:
        return 1.0, 0.0
    a = math.radians(azimuth_deg)
    return abs(math.cos(a)), abs(math.sin(a))


def required_half_extent_mm(patch_mm: float, bounds: SampleBounds, resolution: int,
                            max_view_deg: float, max_incidence_deg: float,
                            azimuths_deg=(0.0,)) -> tuple[float, float]:
    """How far the sample must reach from the patch centre along x and y to keep its edges out
    of every view (module docstring), at every sample azimuth of ``azimuths_deg``, mm."""
    h = bounds.half_thickness
    filter_reach = patch_mm / resolution
    along = patch_mm / 2.0 + filter_reach
    across = along + h * math.tan(math.radians(abs(max_view_deg))) + 2.0 * h * math.tan(math.radians(max_incidence_deg))
    need_x = need_y = 0.0
    for azimuth in azimuths_deg:
        c, s = _turn(azimuth)
        need_x = max(need_x, across * c + along * s)
        need_y = max(need_y, across * s + along * c)
    return need_x + bounds.edge_band, need_y + bounds.edge_band


def largest_patch_mm(bounds: SampleBounds, resolution: int, max_view_deg: float, max_incidence_deg: float,
                     azimuths_deg=(0.0,)) -> float:
    """The largest patch that keeps the sample's edges out of every view at every sample azimuth
    of ``azimuths_deg`` (module docstring): a whole number of weave repeats when the sample has a
    period (the patch average is then the cloth's average at every view, whatever the phase of the
    weave under the patch, at the azimuths 0° and 90°), mm.

    Raises ParameterError when the sample cannot hold one repeat (or, without a period, any patch).
    """
    hx, hy = bounds.half_size
    h = bounds.half_thickness
    tilt = h * math.tan(math.radians(abs(max_view_deg))) + 2.0 * h * math.tan(math.radians(max_incidence_deg))
    # Solve (P/2 + P/N + tilt)|cos α| + (P/2 + P/N)|sin α| + band <= hx (and swapped for hy) for P.
    shrink = 0.5 + 1.0 / resolution
    turns = [_turn(azimuth) for azimuth in azimuths_deg]
    limit = min(min((hx - bounds.edge_band - tilt * c) / (shrink * (c + s)),
                    (hy - bounds.edge_band - tilt * s) / (shrink * (c + s))) for c, s in turns)
    turned = "" if tuple(azimuths_deg) == (0.0,) else (
        f" with the sample turned to {', '.join(f'{a:g}' for a in azimuths_deg)}° about its normal")
    if bounds.period is None:
        if limit <= 0.0:
            reach = max(bounds.edge_band + tilt * max(c, s) for c, s in turns)
            raise ParameterError("sample", f"{2 * hx:.3g} × {2 * hy:.3g} mm",
                                 f"a sample wider than {2 * reach:.3g} mm across the plane of "
                                 f"incidence{turned}, so that a patch fits inside it with its edges out of view")
        return limit
    repeat = max(bounds.period)
    whole = math.floor(limit / repeat + 1e-9)
    if whole < 1:
        needed = 2.0 * max(repeat * shrink * (c + s) + bounds.edge_band + tilt * max(c, s) for c, s in turns)
        raise ParameterError("sample", f"{2 * hx:.3g} × {2 * hy:.3g} mm",
                             f"at least {needed:.3g} mm across the plane of incidence{turned} (one {repeat:g} mm "
                             f"weave repeat plus margins for views to {max_view_deg:g}° and incidence to "
                             f"{max_incidence_deg:g}°): use more yarns")
    return whole * repeat


def check_patch(patch_mm: float, bounds: SampleBounds, resolution: int, max_view_deg: float,
                max_incidence_deg: float, azimuths_deg=(0.0,)) -> None:
    """Raise ParameterError unless a patch of side ``patch_mm`` keeps the sample's edges out of view
    at every sample azimuth of ``azimuths_deg``."""
    if not (isinstance(patch_mm, (int, float)) and math.isfinite(patch_mm) and patch_mm > 0):
        raise ParameterError("patch_mm", patch_mm, "a length > 0 (mm)")
    need_x, need_y = required_half_extent_mm(patch_mm, bounds, resolution, max_view_deg, max_incidence_deg,
                                             azimuths_deg)
    hx, hy = bounds.half_size
    if need_x > hx + 1e-9 or need_y > hy + 1e-9:
        largest = largest_patch_mm(SampleBounds(bounds.center, bounds.half_size, bounds.half_thickness,
                                                bounds.edge_band, None), resolution, max_view_deg, max_incidence_deg,
                                   azimuths_deg)
        turned = "" if tuple(azimuths_deg) == (0.0,) else (
            f" with the sample turned to {', '.join(f'{a:g}' for a in azimuths_deg)}°")
        raise ParameterError("patch_mm", patch_mm,
                             f"≤ {largest:.4g} mm on this {2 * hx:.3g} × {2 * hy:.3g} mm sample{turned}: a larger "
                             f"patch would bring the sample's edges into view at θv up to {max_view_deg:g}° or into "
                             f"the shadow rays at θi up to {max_incidence_deg:g}°")


def check_sample_azimuths(values, name: str) -> tuple[float, ...]:
    """``values`` as a tuple of sample azimuths (degrees), checked by the rule of a preset's
    ``[sample] azimuths_deg`` (:func:`precompute.optics.measured_sample.sample_azimuths_deg`:
    ascending, distinct, in [0, 180)); ParameterError naming ``name`` otherwise."""
    values = values.tolist() if isinstance(values, np.ndarray) else values
    try:
        return sample_azimuths_deg({SAMPLE_TABLE: {SAMPLE_AZIMUTHS_KEY: values}})
    except ParameterError as error:
        raise ParameterError(name, values, error.allowed) from None


def tables_sample_azimuths(tables_dir) -> tuple[float, ...] | None:
    """The sample azimuths a yarn bake folder's preset was fitted at, as its summary records them
    (:func:`precompute.tables.folder.summary_sample_table`), or None where it records none (a preset
    that names no ``[sample] azimuths_deg``).  TableError naming the summary when they are not valid."""
    import pathlib

    from precompute.tables import folder as table_folder

    summary = table_folder.check_yarn_table_folder(pathlib.Path(tables_dir).resolve()).summary
    table = table_folder.summary_sample_table(summary, tables_dir)
    return sample_azimuths_deg({SAMPLE_TABLE: table}) if SAMPLE_AZIMUTHS_KEY in table else None


def tables_sample_weave(tables_dir):
    """The woven sample a bake folder's preset was fitted on (its summary's sample weave,
    :mod:`precompute.optics.measured_sample`) as WeaveParameters, or None for the validation's own."""
    import pathlib

    from precompute.optics.measured_sample import DEFAULT_SAMPLE_WEAVE
    from precompute.tables import folder as table_folder

    from ..weave.sample_weaves import sample_weave

    summary = table_folder.check_yarn_table_folder(pathlib.Path(tables_dir).resolve()).summary
    name = table_folder.summary_sample_weave(summary, tables_dir)
    return None if name == DEFAULT_SAMPLE_WEAVE else sample_weave(name, summary["medium"]["yarn"]["radius_mm"])


def sweep_sample_azimuths(azimuths, tables_dir, name: str = "sample_azimuths_deg") -> tuple[float, ...]:
    """The sample azimuths a sweep averages: ``azimuths`` where given (checked, ParameterError naming
    ``name``), else those the bake folder ``tables_dir`` records (:func:`tables_sample_azimuths`),
    else one turn (:data:`DEFAULT_RIG_AZIMUTHS_DEG`)."""
    if azimuths is not None:
        return check_sample_azimuths(list(azimuths), name)
    recorded = tables_sample_azimuths(tables_dir) if tables_dir is not None else None
    return recorded if recorded is not None else DEFAULT_RIG_AZIMUTHS_DEG


def check_angles(incidences_deg, views_deg) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The incidences and views as float tuples, or ParameterError naming the first bad one."""
    checked = []
    for name, values, low, high in (("incidences_deg", incidences_deg, 0.0, MAX_INCIDENCE_DEG),
                                    ("views_deg", views_deg, -MAX_VIEW_DEG, MAX_VIEW_DEG)):
        values = tuple(values)
        if not values:
            raise ParameterError(name, values, "at least one angle")
        for value in values:
            if not (isinstance(value, (int, float)) and math.isfinite(value) and low <= value <= high):
                raise ParameterError(name, value, f"angles in [{low:g}, {high:g}] degrees")
        if len(set(values)) != len(values):
            raise ParameterError(name, values, "distinct angles")
        checked.append(tuple(float(v) for v in values))
    return checked[0], checked[1]
