"""How a slab run is laid out: its random streams, the rows of their tallies and of its result.

Shared by the numba kernel (:mod:`precompute.transport.slab`) and the slab compiled ahead of time into
a native library (:mod:`precompute.slab.native`), which must split the paths and name the rows as the
kernel does to give the same answer bit for bit; so this module imports neither numba nor NumPy.
"""

from __future__ import annotations

#: Independent random streams of a slab run (fixed, so results do not depend on the thread count).
SLAB_TASKS = 64

#: Rows of a task's tallies (8, L), per unit incident flux summed over its paths; the last two are the
#: per-path squares of the reflected and transmitted flux.
SLAB_R_DIFFUSE, SLAB_R_UNSCATTERED, SLAB_T_DIFFUSE, SLAB_T_UNSCATTERED, SLAB_ABSORBED, SLAB_LOST = range(6)
SLAB_R_SQUARES, SLAB_T_SQUARES = 6, 7
SLAB_TALLY_ROWS = 8

#: Rows of a slab's result (:class:`precompute.transport.SlabResult`'s per-wavelength fields), in order.
SLAB_RESULTS = ("R_total", "T_total", "R_total_stderr", "T_total_stderr", "R_specular", "R_unscattered",
                "R_diffuse", "T_unscattered", "T_diffuse", "absorbed", "lost")


def task_paths(paths: int) -> list[int]:
    """The paths of each of the :data:`SLAB_TASKS` streams: ``paths`` split as evenly as it goes."""
    share, extra = divmod(paths, SLAB_TASKS)
    return [share + (task < extra) for task in range(SLAB_TASKS)]
