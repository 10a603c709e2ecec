"""A hint to the processor to fetch an array element's cache line ahead of a write to it.

A yarn path's exit adds its L weights to rows of tallies far larger than the caches (the BSSRDF table:
464 MB at the default grids), so each exit's writes wait on main memory.  The kernel asks for those
lines when the path exits and makes the writes one exit later (:func:`._kernels._trace_cell`).
"""

from __future__ import annotations

from llvmlite import ir
from numba.core import cgutils, types
from numba.extending import intrinsic


@intrinsic
def prefetch_for_write(typingctx, array, index):
    """Ask for the cache line of ``array[index]`` (``index`` a tuple of integers), to be written soon;
    no effect on the program's results, and no fault for any index."""
    if not isinstance(array, types.Array) or not isinstance(index, types.BaseTuple) or len(index) != array.ndim:
        return None

    def codegen(context, builder, signature, args):
        array_type, index_type = signature.args
        target = context.make_array(array_type)(context, builder, value=args[0])
        indices = [context.cast(builder, value, kind, types.intp)
                   for value, kind in zip(cgutils.unpack_tuple(builder, args[1], len(index_type)), index_type)]
        pointer = cgutils.get_item_pointer(context, builder, array_type, target, indices)
        byte_pointer = ir.IntType(8).as_pointer()
        prefetch = cgutils.get_or_insert_function(
            builder.module, ir.FunctionType(ir.VoidType(), [byte_pointer] + [ir.IntType(32)] * 3), "llvm.prefetch.p0")
        # read/write 1 (write), locality 3 (keep in all cache levels), cache type 1 (data)
        builder.call(prefetch, [builder.bitcast(pointer, byte_pointer)] + [ir.Constant(ir.IntType(32), v)
                                                                           for v in (1, 3, 1)])
        return context.get_dummy_value()

    return types.none(array, index), codegen
