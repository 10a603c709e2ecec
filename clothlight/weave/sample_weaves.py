"""The woven samples of :mod:`precompute.optics.measured_sample`'s names: what the fit's cloth response
renders for a preset's ``[sample]`` weave.

Both are about :data:`SAMPLE_SIDE_MM` wide, which frames two weave repeats at the raw-data curves'
views to 80° and light to 75°.  ``"open"`` is the validation's own sample (round yarns of
:data:`.params.DEFAULT_YARN_RADIUS_MM` at 0.5 mm), which the response frames as its views need;
``"sheeting"`` is the close-up's cotton sheeting (:func:`.closeup.sheeting_shape`) of the preset's
yarn, regular and of one ply, so that its response serves every medium of that yarn radius alike;
``"pressed"`` the same yarn pressed flat (:func:`pressed_shape`), regular and of one ply too.
"""

from __future__ import annotations

import math

from precompute.errors import ParameterError
from precompute.optics.measured_sample import SAMPLE_TABLE, SAMPLE_WEAVE_KEY, SAMPLE_WEAVES

from .closeup import SHEETING_SECTION_SHARE, sheeting_shape
from .params import WeaveParameters

#: The side of a sample, mm (module docstring).
SAMPLE_SIDE_MM = 10.0
#: The pressed weave's yarn: width over thickness, kept all along (no relaxation between crossings);
#: the spacing in yarn radii (covering 0.99 of the cloth); the crimp in half-thicknesses, enough to
#: clear the crossing yarns at that spacing (1.5 is not).
PRESSED_FLATTENING = 5.0
PRESSED_SPACING_RADII = 4.6
PRESSED_CRIMP_HALF_THICKNESSES = 2.0


def pressed_shape(yarn_radius_mm: float) -> dict:
    """A plain weave of yarns of radius ``yarn_radius_mm`` (mm) pressed flat, as :class:`.params.WeaveParameters`
    keywords: the section :data:`PRESSED_FLATTENING` : 1 of the sheeting's area (Kemp's flattened yarns of a
    calendered or tightly woven cloth, whose surface faces the light almost flat), at
    :data:`PRESSED_SPACING_RADII` radii with no gap between the yarns."""
    scale = math.sqrt(SHEETING_SECTION_SHARE)
    semi_axes = (yarn_radius_mm * scale * math.sqrt(PRESSED_FLATTENING),
                 yarn_radius_mm * scale / math.sqrt(PRESSED_FLATTENING))
    return dict(interlacing="plain", spacing_mm=PRESSED_SPACING_RADII * yarn_radius_mm, semi_axes_mm=semi_axes,
                crimp_amplitude_mm=PRESSED_CRIMP_HALF_THICKNESSES * semi_axes[1], segments_around=12,
                section_relaxation=0.0)


#: The shape of each named sample weave but the open one, from its yarn's radius (mm).
SAMPLE_SHAPES = {"sheeting": sheeting_shape, "pressed": pressed_shape}


def sample_weave(name: str, yarn_radius_mm: float) -> WeaveParameters | None:
    """The woven sample ``name`` of yarns of radius ``yarn_radius_mm`` (mm), or None for the open
    weave: the validation's own sample (``clothlight.fit.forward.cloth_response``)."""
    if name == "open":
        return None
    if name not in SAMPLE_SHAPES:
        raise ParameterError(f"{SAMPLE_TABLE}.{SAMPLE_WEAVE_KEY}", name, f"one of {', '.join(SAMPLE_WEAVES)}")
    shape = SAMPLE_SHAPES[name](yarn_radius_mm)
    count = round(SAMPLE_SIDE_MM / shape["spacing_mm"])
    return WeaveParameters(**shape, warp_count=count, weft_count=count, segments_per_crossing=8)
