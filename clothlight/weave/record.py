"""What a woven sample was built from, as JSON-ready values, and back: the record a sample object
keeps (``clothlight.blender.sample_object``) and the key of the measurements made on it (the
garment's, the fit's cloth response).  No Blender here."""

from __future__ import annotations

import numpy as np

from .params import WeaveParameters


def weave_record(params: WeaveParameters) -> dict:
    """What a sample was built from, as JSON-ready values.  The section's relaxation, the plies, twist
    and irregularity are recorded only where they change the geometry, so that a plain regular sample records what it
    always did (the garment's measurement cache is keyed by this record)."""
    record = {
        "units": "mm",
        "spacing_mm": params.spacing_mm,
        "semi_axes_mm": list(params.cross_section_mm),
        "crimp_amplitude_mm": list(params.crimp_amplitudes_mm),
        "warp_count": params.warp_count,
        "weft_count": params.weft_count,
        "interlacing": params.interlacing.astype(int).tolist(),
        "segments_per_crossing": params.segments_per_crossing,
        "segments_around": params.segments_around,
    }
    if params.ply_count > 1 or params.is_irregular or params.ply_radius_jitter > 0:
        record.update(ply_count=params.ply_count, twist_angle_deg=params.twist_angle_deg,
                      spacing_jitter=params.spacing_jitter, height_jitter=params.height_jitter,
                      ply_radius_jitter=params.ply_radius_jitter, seed=params.seed)
    if params.section_relaxation > 0:
        record.update(section_relaxation=params.section_relaxation)
    return record


def weave_from_record(record) -> WeaveParameters:
    """The parameters a sample was built from, read back from its :func:`weave_record` (a dict or
    the object's ID property)."""
    record = record.to_dict() if hasattr(record, "to_dict") else dict(record)
    closeup = {key: record[key] for key in ("ply_count", "twist_angle_deg", "spacing_jitter", "height_jitter",
                                            "ply_radius_jitter", "seed", "section_relaxation") if key in record}
    return WeaveParameters(
        interlacing=np.array(record["interlacing"], dtype=bool), warp_count=record["warp_count"],
        weft_count=record["weft_count"], spacing_mm=record["spacing_mm"],
        semi_axes_mm=tuple(record["semi_axes_mm"]), crimp_amplitude_mm=tuple(record["crimp_amplitude_mm"]),
        segments_per_crossing=record["segments_per_crossing"], segments_around=record["segments_around"], **closeup)
