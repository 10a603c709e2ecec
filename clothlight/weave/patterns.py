"""Weave patterns as interlacing matrices, the way weaving drafts describe them.

``matrix[i, j]`` is True where warp yarn ``j`` passes OVER weft yarn ``i``;
rows are weft picks, columns warp ends, and the matrix repeats over the cloth.
"""

from __future__ import annotations

import numpy as np

from .errors import WeaveParameterError

#: Valid satin move numbers (coprime with the harness count, not ±1).
SATIN_MOVES = {5: (2, 3), 8: (3, 5)}


def plain() -> np.ndarray:
    """Plain (tabby) weave: every warp alternates over and under every weft (the paper's Figure 1)."""
    return np.array([[True, False], [False, True]])


def basket(size: int = 2) -> np.ndarray:
    """Basket weave: groups of ``size`` warps and wefts interlace as one."""
    if size < 2:
        raise WeaveParameterError("basket size", size, "an integer ≥ 2")
    return np.kron(plain(), np.ones((size, size), dtype=bool)).astype(bool)


def twill(over: int = 2, under: int = 1, direction: str = "Z") -> np.ndarray:
    """Twill ``over/under``: each warp floats over ``over`` wefts, under ``under``, stepping by one
    end per pick; ``direction`` "Z" (right-hand diagonal) or "S" (left-hand)."""
    if over < 1 or under < 1:
        raise WeaveParameterError("twill over/under", (over, under), "integers ≥ 1")
    if direction not in ("Z", "S"):
        raise WeaveParameterError("twill direction", direction, "'Z' or 'S'")
    repeat = over + under
    step = 1 if direction == "Z" else -1
    rows, cols = np.indices((repeat, repeat))
    return ((cols - step * rows) % repeat) < over


def satin(harness: int = 5, move: int | None = None, warp_faced: bool = True) -> np.ndarray:
    """Satin on ``harness`` (5 or 8) shafts: one interlacing per warp and weft per repeat, placed by
    the ``move`` number so no two are adjacent."""
    if harness not in SATIN_MOVES:
        raise WeaveParameterError("satin harness", harness, f"one of {sorted(SATIN_MOVES)}")
    move = SATIN_MOVES[harness][0] if move is None else move
    if move not in SATIN_MOVES[harness]:
        raise WeaveParameterError("satin move", move, f"one of {SATIN_MOVES[harness]} for {harness} shafts")
    matrix = np.full((harness, harness), warp_faced)
    for row in range(harness):
        matrix[row, (row * move) % harness] = not warp_faced
    return matrix


def validate_interlacing(matrix) -> np.ndarray:
    """A checked boolean copy of a user interlacing matrix (rows: wefts, columns: warps)."""
    array = np.asarray(matrix)
    if array.ndim != 2 or array.size == 0:
        raise WeaveParameterError("interlacing", getattr(array, "shape", array), "a non-empty 2-D matrix")
    if not np.isin(array, (0, 1, True, False)).all():
        raise WeaveParameterError("interlacing", "non-binary entries", "only 0/1 (or False/True)")
    array = array.astype(bool)
    for axis, kind in ((1, "weft row"), (0, "warp column")):
        over = array.any(axis=axis)
        under = (~array).any(axis=axis)
        never = np.flatnonzero(~(over & under))
        if never.size:
            raise WeaveParameterError(f"interlacing {kind} {int(never[0])}", array.take(int(never[0]), axis=1 - axis).astype(int).tolist(),
                                      "both over (1) and under (0) crossings: a yarn that never interlaces is not woven")
    return array


BUILT_IN = {
    "plain": plain,
    "basket": basket,
    "twill_2_1": lambda: twill(2, 1),
    "twill_2_2": lambda: twill(2, 2),
    "twill_3_1": lambda: twill(3, 1),
    "satin_5": lambda: satin(5),
    "satin_8": lambda: satin(8),
}


def weave_pattern(name: str) -> np.ndarray:
    """A built-in pattern by name: plain, basket, twill_2_1, twill_2_2, twill_3_1, satin_5, satin_8."""
    if name not in BUILT_IN:
        raise WeaveParameterError("pattern", name, f"one of {sorted(BUILT_IN)} or a matrix")
    return BUILT_IN[name]()
