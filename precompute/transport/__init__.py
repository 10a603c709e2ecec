"""Monte-Carlo light transport in a yarn → BSSRDF → yarn BRDF (paper §3.3, §5.3); slab mode for checks.

What is simulated, tallied and tabulated, with units, and the proof of the
spectral estimator: docs/transport.md.
"""

from precompute.transport.beam import ParallelBeamRadiance, simulate_parallel_beam
from precompute.transport.brdf import YarnBRDF, source_weights, yarn_brdf, yarn_brdf_at
from precompute.transport.cylinder import TransportGrids, YarnGeometry, YarnTransport, simulate_yarn
from precompute.transport.media import TransportMedium, henyey_greenstein_medium, medium_from_optics
from precompute.transport.slab import SlabResult, simulate_hg_slab, simulate_slab


def _flush_stale_kernels() -> None:
    from precompute.tables import grids
    from precompute.transport import _interactions, _kernels, _paths, _rng, kernel_cache

    kernel_cache.flush_stale_kernel_caches((grids, _interactions, _kernels, _paths, _rng))


_flush_stale_kernels()

__all__ = [
    "ParallelBeamRadiance",
    "SlabResult",
    "TransportGrids",
    "TransportMedium",
    "YarnBRDF",
    "YarnGeometry",
    "YarnTransport",
    "henyey_greenstein_medium",
    "medium_from_optics",
    "simulate_hg_slab",
    "simulate_parallel_beam",
    "simulate_slab",
    "simulate_yarn",
    "source_weights",
    "yarn_brdf",
    "yarn_brdf_at",
]
