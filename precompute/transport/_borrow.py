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

from numba.core import types
from numba.extending import intrinsic
from numba.np.arrayobj import make_array, populate_array


def _view(context, builder, array_type, value):
    source = make_array(array_type)(context, builder, value=value)
    view = make_array(array_type)(context, builder)
    populate_array(view, data=source.data, shape=source.shape, strides=source.strides, itemsize=source.itemsize,
                   meminfo=None)
    return view._getvalue()


@intrinsic
def borrowed(typingctx, value):
    """A view of the array ``value`` (same data, shape and strides, same type) without a reference count;
    of a tuple (a :data:`._paths.KernelMedium`, :data:`._paths.PathArrays`), the same tuple with each of its
    arrays such a view."""
    if isinstance(value, types.Array):
        def codegen(context, builder, signature, args):
            return _view(context, builder, value, args[0])
    elif isinstance(value, types.BaseTuple):
        def codegen(context, builder, signature, args):
            out = args[0]
            for i, member in enumerate(value.types):
                if isinstance(member, types.Array):
                    out = builder.insert_value(out, _view(context, builder, member, builder.extract_value(out, i)), i)
            return out
    else:
        return None
    return value(value), codegen
