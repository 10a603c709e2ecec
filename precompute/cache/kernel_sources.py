"""The sources that the transport's compiled code is built from, and their digest.

numba's cache keys a kernel by its own file only, though a kernel inlines functions of other files; the
digest of all of them keys the compiled code instead (:mod:`precompute.transport.kernel_cache` for
numba's cache, :mod:`precompute.slab.native` for the native slab library).  Importing this module
imports neither numba nor NumPy.
"""

from __future__ import annotations

import pathlib

from precompute.cache.entries import source_digest

#: The ``precompute`` package, which the sources are named relative to.
PACKAGE_ROOT = pathlib.Path(__file__).resolve().parents[1]


def kernel_sources() -> list[str]:
    """The transport's source files, the direction grids and the slab's layout that they inline, and the
    native slab library's calling side (its functions' names and scratch size), relative to the package."""
    transport = sorted(path.relative_to(PACKAGE_ROOT).as_posix() for path in (PACKAGE_ROOT / "transport").glob("*.py"))
    return transport + ["tables/grids.py", "slab/layout.py", "slab/native.py"]


def sources_digest() -> str:
    """:func:`precompute.cache.entries.source_digest` of :func:`kernel_sources`."""
    return source_digest(PACKAGE_ROOT, kernel_sources())
