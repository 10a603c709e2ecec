"""The allowed ranges of the add-on's render settings: the validation sweep (``python -m
clothlight.validate``, the Validation panel, :class:`clothlight.blender.validation.rig.RigSettings`) and the
cloth gonioreflectometer (``python -m clothlight.garment bake``,
:class:`clothlight.blender.garment.measure.GoniometerSettings`), as :class:`precompute.bounds.Bound` data
(the yarn bake's are in ``precompute/bounds.py``).  The command lines parse with
:meth:`~precompute.bounds.Bound.argument`, the settings check with :meth:`~precompute.bounds.Bound.check`.

A render's memory is estimated from its pixels before it starts (:func:`check_render_memory`) and
refused above half of this machine's memory, with the estimate and the settings that make it.

No Blender, no numpy: the command lines check their arguments with this before importing bpy.
"""

from __future__ import annotations


from precompute import bounds as _bounds
Bound = _bounds.Bound

#: Cycles' seed is a 32-bit integer.
RENDER_SEED = Bound("seed", 0, 2**31 - 1, integer=True)
#: Cycles samples per pixel (Cycles takes up to 2^24; the measurements need a few dozen).
RENDER_SAMPLES = Bound("samples", 1, 4096, integer=True)
#: Bytes a rendered pixel costs in all, planned generously: Cycles' film and its passes, the render
#: result, the EXR written and read back as float32, and the NumPy copies of the measurement.
RENDER_BYTES_PER_PIXEL = 96

# ---- the validation sweep ----

#: Pixels along the patch side, and samples per pixel, of a sweep by default (benchmarks/bench_validation.py).
DEFAULT_VALIDATION_RESOLUTION = 128
DEFAULT_VALIDATION_SAMPLES = 16
#: Pixels along the patch side of every view (the image is resolution × resolution).
VALIDATION_RESOLUTION = Bound("resolution", 4, 4096, integer=True)
VALIDATION_SAMPLES = RENDER_SAMPLES
#: Side of the framed patch (the sample must be larger: checked against it when the rig is built).
VALIDATION_PATCH_MM = Bound("patch_mm", 0.0, 1000.0, low_open=True, unit="mm")
VALIDATION_SEED = RENDER_SEED

# ---- the cloth gonioreflectometer (garment bake) ----

#: Defaults of GoniometerSettings and the command line.  Red cotton: the flat patch within 3.9 % of
#: the yarn sample on the validation sweep, 40–65 min on 2 cores; N_i = 9, N_o = 8, 16 pixels (a
#: 7-min draft) 9.3 % on the schema-3 tables (docs/garment.md).
DEFAULT_GONIO_INCIDENCE_RESOLUTION = 11
DEFAULT_GONIO_EXIT_RESOLUTION = 12
DEFAULT_GONIO_PIXELS_PER_PATCH = 12
DEFAULT_GONIO_SAMPLES = 4

#: N_i of the cloth tables' incidence sphere grid: odd; all N_i² incidences share each render.
GONIO_INCIDENCE_RESOLUTION = Bound("incidence_resolution", 3, 31, integer=True, odd=True)
#: N_o per side: 2 N_o² renders (24: 1152 renders, a day on a workstation).
GONIO_EXIT_RESOLUTION = Bound("exit_resolution", 2, 24, integer=True)
GONIO_PIXELS_PER_PATCH = Bound("pixels_per_patch", 4, 64, integer=True)
GONIO_SAMPLES = RENDER_SAMPLES
GONIO_PATCH_REPEATS = Bound("patch_repeats", 1, 16, integer=True)
GONIO_SEED = RENDER_SEED


def render_memory_bytes(pixels: int) -> int:
    return int(pixels) * RENDER_BYTES_PER_PIXEL


def check_render_memory(pixels: int, name: str, value: object) -> None:
    """ParameterError naming ``name`` (the settings that make the image this large) when a render of
    ``pixels`` pixels would need more than half of this machine's memory."""
    _bounds.check_memory(render_memory_bytes(pixels), name, value)


__all__ = ["DEFAULT_GONIO_EXIT_RESOLUTION", "DEFAULT_GONIO_INCIDENCE_RESOLUTION", "DEFAULT_GONIO_PIXELS_PER_PATCH",
           "DEFAULT_GONIO_SAMPLES", "DEFAULT_VALIDATION_RESOLUTION", "DEFAULT_VALIDATION_SAMPLES",
           "GONIO_EXIT_RESOLUTION", "GONIO_INCIDENCE_RESOLUTION", "GONIO_PATCH_REPEATS", "GONIO_PIXELS_PER_PATCH",
           "GONIO_SAMPLES", "GONIO_SEED", "RENDER_BYTES_PER_PIXEL", "RENDER_SAMPLES", "RENDER_SEED",
           "VALIDATION_PATCH_MM", "VALIDATION_RESOLUTION", "VALIDATION_SAMPLES", "VALIDATION_SEED",
           "check_render_memory", "render_memory_bytes"]
