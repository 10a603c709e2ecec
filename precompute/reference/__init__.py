"""An independent brute-force reference for the yarn tables: Mitsuba 3 renders the yarn the bake simulates.

The same circular cylinder (radius R, mm, axis x), smooth dielectric boundary of the host index
(exterior 1), homogeneous interior medium (μs, μa in 1/mm) and tabulated phase function at one
wavelength, rendered by software this project did not write, and what the tables predict for it::

    from precompute.reference import (CapLight, ReferenceMedium, light_direction, predict_bins,
                                      render_reference)
    medium = ReferenceMedium(radius_mm=0.1, index=1.5, mu_s=45.0, mu_a=5.0, phase=table)
    light = light_direction(45.0)                     # toward the cap centre, 45° from the view
    ref = render_reference(medium, light, bins=16)    # ρ = L_o / E⊥ per width bin, 1/sr, ± stderr
    pred = predict_bins(rho, light, bins=16)          # the same bins from ρ(wi, wo) (1/sr)

Modules: :mod:`.geometry` (scene frame, bins, yarn frames, exact unscattered paths and glint),
:mod:`.cap` (the environment-map cap light and its exact E⊥), :mod:`.render` (the Mitsuba scene,
the glint-free dielectric, the renders), :mod:`.prediction` (the table side; a bake's data).
Mitsuba is imported only by the render functions.  Method: docs/transport.md, "Independent
reference: Mitsuba 3".
"""

from precompute.reference.cap import CapLight, cap_frame
from precompute.reference.geometry import bin_edges, glint_paths, light_direction, unscattered_paths, yarn_frames
from precompute.reference.prediction import (
    BakeWavelength,
    BinPrediction,
    bake_wavelength,
    default_ballistic,
    find_spectral,
    medium_from_record,
    TransportPrediction,
    predict_bins,
    table_rho,
    transport_prediction,
    transport_rho,
)
from precompute.reference.render import (
    DEFAULT_EDGE,
    ReferenceMedium,
    ReferenceResult,
    check_cap_map,
    mitsuba,
    render_reference,
    scene_dict,
)

__all__ = [
    "DEFAULT_EDGE",
    "BakeWavelength",
    "BinPrediction",
    "CapLight",
    "ReferenceMedium",
    "ReferenceResult",
    "bake_wavelength",
    "bin_edges",
    "cap_frame",
    "check_cap_map",
    "default_ballistic",
    "find_spectral",
    "glint_paths",
    "light_direction",
    "medium_from_record",
    "mitsuba",
    "predict_bins",
    "render_reference",
    "scene_dict",
    "table_rho",
    "TransportPrediction",
    "transport_prediction",
    "transport_rho",
    "unscattered_paths",
    "yarn_frames",
]
