"""The woven samples of :mod:`precompute.optics.measured_sample`'s names: what the fit's cloth response
renders for a preset's ``[sample]`` weave.

Both are about :data:`SAMPLE_SIDE_MM` wide, which frames two weave repeats at the raw-data curves'
views to 80° and light to 75°.  ``"open"`` is the validation's own sample (round yarns of
:data:`.params.DEFAULT_YARN_RADIUS_MM` at 0.5 mm), which the response frames as its views need;
``"sheeting"`` is the close-up's cotton sheeting (:func:`.closeup.sheeting_shape`) of the preset's
yarn, regular and of one ply, so that its response serves every medium of that yarn radius alike.
"""

from __future__ import annotations

from precompute.errors import ParameterError
from precompute.optics.measured_sample import SAMPLE_TABLE, SAMPLE_WEAVE_KEY, SAMPLE_WEAVES

from .closeup import sheeting_shape
from .params import WeaveParameters

#: The side of a sample, mm (module docstring).
SAMPLE_SIDE_MM = 10.0


def sample_weave(name: str, yarn_radius_mm: float) -> WeaveParameters | None:
    """The woven sample ``name`` of yarns of radius ``yarn_radius_mm`` (mm), or None for the open
    weave: the validation's own sample (``clothlight.fit.forward.cloth_response``)."""
    if name == "open":
        return None
    if name == "sheeting":
        shape = sheeting_shape(yarn_radius_mm)
        count = round(SAMPLE_SIDE_MM / shape["spacing_mm"])
        return WeaveParameters(**shape, warp_count=count, weft_count=count, segments_per_crossing=8)
    raise ParameterError(f"{SAMPLE_TABLE}.{SAMPLE_WEAVE_KEY}", name, f"one of {', '.join(SAMPLE_WEAVES)}")
