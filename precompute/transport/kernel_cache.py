"""Cached kernels that follow every source they are compiled from.

numba keys a cached kernel by the source file of the function it caches only (its modification time
and size): a kernel of ``_kernels.py`` that inlines ``trace`` from ``_paths.py``, or the direction maps
of ``precompute/tables/grids.py``, would go on loading the machine code of the old ``trace`` after
``_paths.py`` changed, silently.  The digest of every transport source, kept beside the cache, flushes
the cache of every kernel when any of them changes, so the next call compiles afresh.
"""

from __future__ import annotations

import pathlib

from numba.core.registry import CPUDispatcher

from precompute.cache.kernel_sources import sources_digest

#: Where the digest of the sources is kept, in each folder of cached kernels.
DIGEST_FILE = "clothlight-kernel-sources.sha256"


def cached_kernels(modules) -> list:
    """The numba dispatchers with an on-disk cache among the attributes of ``modules``, each once
    (a module holds the kernels it imports as well as its own)."""
    kernels = {id(value): value for module in modules for value in vars(module).values()
               if isinstance(value, CPUDispatcher) and hasattr(value._cache, "cache_path")}
    return list(kernels.values())


def flush_stale_kernel_caches(modules, digest: str | None = None) -> bool:
    """Flush the caches of the kernels of ``modules`` wherever the digest kept beside them is not
    ``digest`` (by default :func:`precompute.cache.kernel_sources.sources_digest`), and keep that digest there;
    returns whether any cache was flushed.  A folder that cannot be written is left as it is."""
    digest = digest or sources_digest()
    by_folder: dict[pathlib.Path, list] = {}
    for kernel in cached_kernels(modules):
        by_folder.setdefault(pathlib.Path(kernel._cache.cache_path), []).append(kernel)
    flushed = False
    for folder, kernels in by_folder.items():
        marker = folder / DIGEST_FILE
        try:
            if marker.is_file() and marker.read_text() == digest:
                continue
            for kernel in kernels:
                kernel._cache.flush()
            folder.mkdir(parents=True, exist_ok=True)
            marker.write_text(digest)
        except OSError:
            continue
        flushed = True
    return flushed
