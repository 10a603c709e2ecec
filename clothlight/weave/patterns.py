"""Weave patterns as interlacing matrices, the way weaving drafts describe them (paper §3.1, §7).

``matrix[i, j]`` is True where warp end ``j`` passes OVER weft pick ``i`` (the drawdown).  The
matrix repeats over the cloth.  Orientation: seen from the face (+z) with the warp running
upwards, ends are numbered from left to right and picks from the bottom up — the drawdown as
drawn with pick 1 at the bottom — so a twill whose floats move one end to the right per pick
shows the Z diagonal (rising to the right).  :mod:`.geometry` lays the cloth out that way.
"""

from __future__ import annotations

import inspect
import math
from functools import partial
from numbers import Integral

import numpy as np

from .errors import WeaveParameterError


def _is_integer(value) -> bool:
    return isinstance(value, Integral) and not isinstance(value, bool)


def plain() -> np.ndarray:
    """Plain (tabby) weave: every warp alternates over and under every weft (paper Figure 1)."""
    return np.array([[True, False], [False, True]])


def basket(size: int = 2) -> np.ndarray:
    """Basket weave: groups of ``size`` warps and ``size`` wefts interlace as one (2 × 2 by default)."""
    if not _is_integer(size) or size < 2:
        raise WeaveParameterError("basket size", size, "an integer ≥ 2")
    return np.kron(plain(), np.ones((size, size), dtype=bool)).astype(bool)


def twill(over: int = 2, under: int = 1, direction: str = "Z") -> np.ndarray:
    """Twill ``over``/``under``: each warp floats over ``over`` picks and under ``under``, and the
    floats move one end per pick: to the right for a Z twill, to the left for an S twill."""
    for name, value in (("twill over", over), ("twill under", under)):
        if not _is_integer(value) or value < 1:
            raise WeaveParameterError(name, value, "an integer ≥ 1")
    if over + under < 3:
        raise WeaveParameterError("twill over/under", (over, under), "a repeat over + under ≥ 3 (1/1 is plain)")
    if direction not in ("Z", "S"):
        raise WeaveParameterError("twill direction", direction, "'Z' or 'S'")
    repeat = over + under
    step = 1 if direction == "Z" else -1
    picks, ends = np.indices((repeat, repeat))
    return ((ends - step * picks) % repeat) < over


def satin_moves(harness: int) -> tuple[int, ...]:
    """Valid move numbers of a ``harness``-end satin: 1 < m < harness − 1 and coprime with it, so
    every end and pick interlaces exactly once per repeat and no two interlacings touch."""
    return tuple(m for m in range(2, harness - 1) if math.gcd(m, harness) == 1)


def satin(harness: int = 5, move: int | None = None, warp_faced: bool = True) -> np.ndarray:
    """Regular satin on ``harness`` ends (5 and 8 are the usual ones; 6 has no regular satin):
    one interlacing per end and pick, stepping ``move`` ends per pick (default: the smallest
    valid move).  Warp-faced: the warp floats on the face; otherwise the weft (a sateen)."""
    if not _is_integer(harness) or harness < 5 or not satin_moves(harness):
        raise WeaveParameterError("satin harness", harness, "an integer ≥ 5 with a regular satin (not 6)")
    moves = satin_moves(harness)
    move = moves[0] if move is None else move
    if move not in moves:
        raise WeaveParameterError("satin move", move, f"one of {moves} for {harness} ends")
    if not isinstance(warp_faced, (bool, np.bool_)):
        raise WeaveParameterError("satin warp_faced", warp_faced, "True or False")
    matrix = np.full((harness, harness), bool(warp_faced))
    picks = np.arange(harness)
    matrix[picks, (picks * move) % harness] = not warp_faced
    return matrix


def validate_interlacing(matrix) -> np.ndarray:
    """A checked boolean copy of an interlacing matrix (rows: picks, columns: ends).

    Refused: anything but a non-empty 2-D matrix of 0/1 (or booleans), and a matrix in which
    a pick or an end never changes sides — such a yarn is not woven into the cloth.
    """
    try:
        array = np.array(matrix)
    except (TypeError, ValueError):
        raise WeaveParameterError("interlacing", matrix, "a non-empty 2-D matrix of 0/1") from None
    if array.ndim != 2 or array.size == 0:
        raise WeaveParameterError("interlacing", f"shape {array.shape}", "a non-empty 2-D matrix of 0/1")
    if array.dtype != bool and (array.dtype.kind not in "iuf" or not np.isin(array, (0, 1)).all()):
        raise WeaveParameterError("interlacing", array.tolist() if array.size <= 64 else f"{array.dtype} entries",
                                  "only 0/1 (or False/True) entries")
    array = array.astype(bool)
    for axis, kind in ((1, "pick (row)"), (0, "end (column)")):
        interlaces = array.any(axis=axis) & (~array).any(axis=axis)
        if not interlaces.all():
            index = int(np.flatnonzero(~interlaces)[0])
            raise WeaveParameterError(f"interlacing {kind} {index}",
                                      array.take(index, axis=1 - axis).astype(int).tolist(),
                                      "both over (1) and under (0) crossings: "
                                      "a yarn that never interlaces is not woven")
    return array


#: Built-in patterns by name; keyword options (``direction``, ``move``, ``warp_faced``, ``size``)
#: pass through ``weave_pattern``.
BUILT_IN = {
    "plain": plain,
    "basket": basket,
    "twill_2_1": partial(twill, 2, 1),
    "twill_2_2": partial(twill, 2, 2),
    "twill_3_1": partial(twill, 3, 1),
    "satin_5": partial(satin, 5),
    "satin_8": partial(satin, 8),
}


def weave_pattern(name: str, **options) -> np.ndarray:
    """A built-in pattern by name, e.g. ``weave_pattern("twill_2_2", direction="S")`` or
    ``weave_pattern("satin_8", move=5, warp_faced=False)``."""
    if name not in BUILT_IN:
        raise WeaveParameterError("pattern", name, f"one of {sorted(BUILT_IN)} or a matrix")
    builder = BUILT_IN[name]
    accepted = list(inspect.signature(builder).parameters)
    unknown = sorted(set(options) - set(accepted))
    if unknown:
        raise WeaveParameterError(f"{name} option", unknown[0], f"one of {accepted}" if accepted else "no options")
    return builder(**options)
