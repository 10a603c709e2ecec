"""e^x for x ≤ 0 in arithmetic alone, so that a loop of them compiles to vector instructions.

A path's MIS weights need one exponential per wavelength at every exit (:func:`._paths.mis_ratios`):
35 calls of libm's ``exp`` per path, which LLVM can only issue one after another.  The same
function written as arithmetic (Cody–Waite reduction by ln 2, a polynomial, the power of two
assembled in the exponent bits) lets LLVM vectorise the loop.  Within 2 ulp of libm down to
x = −708 (tests/test_transport_bookkeeping.py); below that it returns 0 (e^{−708} ≈ 3·10⁻³⁰⁸: a
weight that small beside the path's largest, which is 1, changes no sum).
"""

from __future__ import annotations

import math

import numba
from llvmlite import ir
from numba.core import types
from numba.extending import intrinsic

#: Below this e^x is returned as 0 (2^k must stay a normal number: k ≥ −1022).
SMALLEST_EXPONENT = -708.0
_LOG2_E = 1.0 / math.log(2.0)
#: ln 2 in two parts, the first with trailing zero bits so that k·LN2_HIGH is exact for |k| < 2^11.
_LN2_HIGH = 6.93147180369123816490e-01
_LN2_LOW = 1.90821492927058770002e-10


@intrinsic
def _float_from_bits(typingctx, bits):
    """The float64 whose IEEE-754 bits are the int64 ``bits``."""
    if not isinstance(bits, types.Integer):
        return None

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.DoubleType())

    return types.float64(types.int64), codegen


@numba.njit(cache=True, error_model="numpy", inline="always")
def exp_nonpositive(x):
    """e^x for x ≤ 0 (0 below SMALLEST_EXPONENT; not a number stays not a number)."""
    clipped = max(x, SMALLEST_EXPONENT)
    k = math.floor(clipped * _LOG2_E + 0.5)
    r = (clipped - k * _LN2_HIGH) - k * _LN2_LOW  # |r| ≤ ln 2 / 2
    # e^r to degree 13 (the remainder r^14/14! < 10⁻¹⁷ relative), Horner's scheme
    p = 1.0 / 6227020800.0
    p = p * r + 1.0 / 479001600.0
    p = p * r + 1.0 / 39916800.0
    p = p * r + 1.0 / 3628800.0
    p = p * r + 1.0 / 362880.0
    p = p * r + 1.0 / 40320.0
    p = p * r + 1.0 / 5040.0
    p = p * r + 1.0 / 720.0
    p = p * r + 1.0 / 120.0
    p = p * r + 1.0 / 24.0
    p = p * r + 1.0 / 6.0
    p = p * r + 0.5
    value = 1.0 + (r + r * r * p)
    scale = _float_from_bits((numba.int64(k) + 1023) << 52)  # 2^k, k ≥ −1022
    return value * scale if x >= SMALLEST_EXPONENT else (0.0 if x < SMALLEST_EXPONENT else x)
