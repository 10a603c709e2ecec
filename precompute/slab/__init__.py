"""The slab: the transport core on a plane-parallel slab, checked against exact solutions.

:mod:`.layout` says how a slab run is laid out (its random streams and the rows of its tallies and
result), for the numba kernel (:mod:`precompute.transport.slab`) and the native library alike;
:mod:`.native` runs the slab through the library compiled ahead of time (``make setup``) without
numba or NumPy, which is what ``python -m precompute slab`` uses when the library is built.  The
kernel itself stays with the other transport kernels, whose package imports numba: this package
must not, so that the slab command starts in a tenth of a second (docs/transport.md).
"""
