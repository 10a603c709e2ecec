"""Array views that numba does not reference-count, for the arrays a path reads at every collision.

numba counts references to an array atomically: binding an array to a variable, reading it from a
tuple or handing it to an inlined helper takes and drops a reference, and on x86 each is a locked
instruction that also drains the store buffer.  Where such pairs sit on every collision (the random
stream's state handed to every draw, the medium's tables to the phase sampler and the phase-product
update) they cost more than the arithmetic around them: a tenth of the yarn kernel's time
(docs/transport.md, "Reference counts, and a collision without a division").  A view made here has no
memory-info block, so taking and dropping a reference to it is a test of a null pointer.  It must not
outlive the array it views: a kernel borrows its own arguments, which its caller holds for the whole
call.
"""

from __future__ import annotations

import numba
from numba.core import types
from numba.extending import intrinsic
from numba.np.arrayobj import make_array, populate_array

from ._paths import KernelMedium, PathArrays


@intrinsic
def borrowed(typingctx, array):
    """A view of ``array`` (same data, shape and strides, same type) without a reference count."""
    if not isinstance(array, types.Array):
        return None

    def codegen(context, builder, signature, args):
        source = make_array(array)(context, builder, value=args[0])
        view = make_array(array)(context, builder)
        populate_array(view, data=source.data, shape=source.shape, strides=source.strides,
                       itemsize=source.itemsize, meminfo=None)
        return view._getvalue()

    return array(array), codegen


@numba.njit(cache=True, error_model="numpy", inline="always")
def borrowed_medium(medium):
    """:data:`._paths.KernelMedium` ``medium`` with every array a :func:`borrowed` view."""
    return KernelMedium(borrowed(medium.mu_t), borrowed(medium.log_mu_t), borrowed(medium.albedo), medium.brightest,
                        medium.roulette_interval, medium.phase_kind, borrowed(medium.hg_g),
                        borrowed(medium.phase_by_mu), medium.phase_max, borrowed(medium.alias_threshold),
                        borrowed(medium.alias), medium.grey)


@numba.njit(cache=True, error_model="numpy", inline="always")
def borrowed_path_arrays(arrays):
    """:data:`._paths.PathArrays` ``arrays`` with every array a :func:`borrowed` view."""
    return PathArrays(borrowed(arrays.state), borrowed(arrays.pos), borrowed(arrays.d), borrowed(arrays.weights),
                      borrowed(arrays.phase_product), borrowed(arrays.banked), borrowed(arrays.albedo_n),
                      borrowed(arrays.albedo_mark), borrowed(arrays.ratios))
