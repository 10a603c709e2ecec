"""numba keys a cached kernel by its own file only; precompute.transport.kernel_cache flushes every
transport kernel's cache when any transport source (or the direction grids they inline) changes."""

import pathlib

from precompute.tables import grids
from precompute.cache import kernel_sources
from precompute.transport import _kernels, _paths, kernel_cache


def test_the_digest_covers_the_sources_that_kernels_inline_from_other_files():
    assert {"transport/_paths.py", "transport/_interactions.py", "transport/_rng.py", "transport/_kernels.py",
            "tables/grids.py", "slab/layout.py", "slab/native.py"} <= set(kernel_sources.kernel_sources())


def test_a_changed_source_flushes_every_kernel_cache_beside_it():
    modules = (grids, _kernels, _paths)
    kernels = kernel_cache.cached_kernels(modules)
    assert _kernels.yarn_kernel in kernels and _paths.trace in kernels and grids.hemisphere_cell in kernels
    current = kernel_sources.sources_digest()
    kernel_cache.flush_stale_kernel_caches(modules, current)
    assert not kernel_cache.flush_stale_kernel_caches(modules, current)  # up to date: nothing flushed
    flushed = []
    markers = set()
    for kernel in kernels:
        kernel._cache.flush = lambda kernel=kernel: flushed.append(kernel)  # record, keep the real cache
    try:
        assert kernel_cache.flush_stale_kernel_caches(modules, "a digest of other sources")
        markers = {pathlib.Path(kernel._cache.cache_path) / kernel_cache.DIGEST_FILE for kernel in kernels}
        assert all(marker.read_text() == "a digest of other sources" for marker in markers)
    finally:
        for kernel in kernels:
            del kernel._cache.flush
        for marker in markers:  # the caches were not flushed: they still match the current sources
            marker.write_text(current)
    assert set(flushed) == set(kernels)
