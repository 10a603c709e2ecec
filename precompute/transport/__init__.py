"""Monte-Carlo light transport in a yarn → BSSRDF → yarn BRDF (paper §3.3, §5.3); slab mode for checks.

Quantities, units and the spectral estimator: docs/transport.md.
"""

from .brdf import YarnBRDF, yarn_brdf
from .cylinder import TransportGrids, YarnGeometry, YarnTransport, simulate_yarn
from .media import TransportMedium, henyey_greenstein_medium, medium_from_optics
from .slab import SlabResult, simulate_hg_slab, simulate_slab

__all__ = [
    "SlabResult",
    "TransportGrids",
    "TransportMedium",
    "YarnBRDF",
    "YarnGeometry",
    "YarnTransport",
    "henyey_greenstein_medium",
    "medium_from_optics",
    "simulate_hg_slab",
    "simulate_slab",
    "simulate_yarn",
    "yarn_brdf",
]
