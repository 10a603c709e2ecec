"""Results kept by the content that made them: inputs and the code.

:mod:`.entries` is the content-addressed cache itself, written atomically; :mod:`.sources` finds
the source files a computation is made from by reading their imports, so that a cache key digests
exactly that code; :mod:`.kernel_sources` names the files the compiled transport kernels and the
native slab library are built from.  Imports neither numba nor NumPy.
"""
