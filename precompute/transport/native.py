"""The slab kernel compiled ahead of time into a native library, for a slab run without numba (issue 24).

A whole ``python -m precompute slab`` process spends most of its time before any path: importing numba
and NumPy and loading the cached kernels take ~0.5 s, where 10⁶ paths take ~0.1 s.  This module
compiles the slab's task (:func:`._kernels._slab_task`, the kernel's own code) and its result
(:func:`._kernels.slab_results`) with numba's ahead-of-time code generator, as ``numba.pycc`` does,
but without pycc's Python module, whose import needs NumPy: two functions in a shared library,
linked by the C compiler, which :mod:`precompute.slab.native` calls through ``ctypes``.

Nothing in the library allocates: every array is a view (``numba.carray``) of memory its caller
holds, so the library needs none of numba's runtime but the reference count's destructor, which no
borrowed view ever reaches (declared weak, so that the library loads without numba).  A function
follows numba's calling convention: ``status = f(&return_value, &exception, arguments…)``, status 0
when it returned.  It is compiled for a generic CPU of the machine's architecture, so a library kept
in a shared cache folder runs on any machine that reads it; the slab's single-wavelength paths gain
nothing from wider vectors (10.2 against 10.5 M paths/s with the host's).

``python -m precompute.transport.compile`` (``make setup``) builds it beside the numba cache,
named by the digest of the transport's sources (:func:`precompute.slab.native.library_path`).
"""

from __future__ import annotations

import os
import pathlib
import shutil
import subprocess
import tempfile

from llvmlite.binding import Linkage
from numba import carray, types
from numba.core.compiler import Flags, compile_extra
from numba.core.compiler_lock import global_compiler_lock
from numba.core.registry import cpu_target
from numba.core.runtime import nrtdynmod

from precompute.slab import native as native_slab
from precompute.slab.layout import SLAB_RESULTS, SLAB_TALLY_ROWS, SLAB_TASKS
from precompute.transport._interactions import PHASE_HG, fresnel_reflectance, hg_phase_max
from precompute.transport._kernels import _slab_task, slab_results
from precompute.transport._paths import (
    PHASE_WIDTH,
    ROULETTE_INTERVAL_ABSORBING,
    ROULETTE_INTERVAL_SCATTERING,
    KernelMedium,
    PathArrays,
    albedo_power_table,
    roulette_interval,
)
from precompute.transport._rng import seed_stream

_F8P, _I8P = types.CPointer(types.float64), types.CPointer(types.int64)
_U8P, _I4P = types.CPointer(types.uint64), types.CPointer(types.int32)

# Where each of a task's arrays lies in the caller's work area (native_slab.WORK_DOUBLES doubles),
# one wavelength: the medium's arrays, the path's, two rows of two for the medium's unused phase and
# alias tables (a Henyey–Greenstein medium samples without them), then its albedo's powers.
_DIMS, _HERO_P, _HERO_CDF, _IMPORTANCE, _MU_T, _LOG_MU_T, _ALBEDO, _HG_G = range(8)
_POS, _D, _WEIGHTS, _BANKED, _ALBEDO_N, _ALBEDO_MARK, _RATIOS, _PRODUCT = 8, 11, 14, 15, 16, 17, 18, 20
_TABLE_ROW, _THRESHOLD_ROW = 12, 13
_POWERS = 2 * (_THRESHOLD_ROW + 1)
assert _PRODUCT + PHASE_WIDTH <= 2 * _TABLE_ROW
assert _POWERS + max(ROULETTE_INTERVAL_SCATTERING, ROULETTE_INTERVAL_ABSORBING) + 1 <= native_slab.WORK_DOUBLES


def hg_slab_tasks(first_task, tasks, counts_p, seed, thickness, eta, albedo, g, sums_p, events_p, work_p, state_p,
                  alias_p):
    """Tasks ``first_task`` … ``first_task + tasks − 1`` of a Henyey–Greenstein slab at one wavelength
    (μt = 1/mm, so ``thickness`` is τ; index ratio ``eta``), as :func:`._kernels.slab_kernel` runs each:
    task c traces ``counts[c]`` paths from stream (seed, c, 0) into ``sums[c]`` (8, 1), zeroed by the
    caller, and counts its collisions in ``events[c]``.  ``counts``, ``sums`` and ``events`` hold all
    :data:`SLAB_TASKS` tasks; ``work``, ``state`` (2 words) and ``alias`` (1) are the caller's scratch."""
    counts = carray(counts_p, (SLAB_TASKS,))
    sums = carray(sums_p, (SLAB_TASKS, SLAB_TALLY_ROWS, 1))
    events = carray(events_p, (SLAB_TASKS,))
    work = carray(work_p, (native_slab.WORK_DOUBLES,))
    rows = carray(work_p, (native_slab.WORK_DOUBLES // 2, 2))
    column = carray(work_p, (native_slab.WORK_DOUBLES, 1))
    for slot, value in ((_DIMS, thickness), (_HERO_P, 1.0), (_HERO_CDF, 1.0), (_IMPORTANCE, 1.0), (_MU_T, 1.0),
                        (_LOG_MU_T, 0.0), (_ALBEDO, albedo), (_HG_G, g)):
        work[slot] = value
    for k in range(PHASE_WIDTH):
        work[_PRODUCT + k] = 0.0  # the phase products' padding, which trace() leaves at 0
    albedos, hg_g = work[_ALBEDO:_ALBEDO + 1], work[_HG_G:_HG_G + 1]
    interval = roulette_interval(albedos)
    powers = column[_POWERS:_POWERS + interval + 1]
    albedo_power_table(albedos, powers)
    # one wavelength: grey, its own brightest (as TransportMedium.kernel() makes them)
    medium = KernelMedium(work[_MU_T:_MU_T + 1], work[_LOG_MU_T:_LOG_MU_T + 1], albedos, 0, interval, powers,
                          PHASE_HG, hg_g, rows[_TABLE_ROW:_TABLE_ROW + 1], hg_phase_max(hg_g),
                          rows[_THRESHOLD_ROW:_THRESHOLD_ROW + 1], carray(alias_p, (1, 1)), True,
                          hg_g, hg_g, hg_g)  # (no fibres: never read)
    arrays = PathArrays(carray(state_p, (2,)), work[_POS:_POS + 3], work[_D:_D + 3], work[_WEIGHTS:_WEIGHTS + 1],
                        work[_PRODUCT:_PRODUCT + PHASE_WIDTH], work[_BANKED:_BANKED + 1],
                        work[_ALBEDO_N:_ALBEDO_N + 1], work[_ALBEDO_MARK:_ALBEDO_MARK + 1],
                        work[_RATIOS:_RATIOS + 1])
    specular = fresnel_reflectance(1.0, 1.0 / eta)
    for c in range(first_task, first_task + tasks):
        seed_stream(arrays.state, seed, c, 0)
        events[c] = _slab_task(counts[c], work[_DIMS:_DIMS + 1], eta, medium, specular, work[_HERO_P:_HERO_P + 1],
                               work[_HERO_CDF:_HERO_CDF + 1], work[_IMPORTANCE:_IMPORTANCE + 1], arrays, sums[c])


def one_wavelength_results(sums_p, paths, eta, out_p):
    """:func:`._kernels.slab_results` of the tallies of :func:`hg_slab_tasks` into ``out``
    (len(SLAB_RESULTS),)."""
    slab_results(carray(sums_p, (SLAB_TASKS, SLAB_TALLY_ROWS, 1)), paths, eta, carray(out_p, (len(SLAB_RESULTS), 1)))


#: The library's functions: name → (Python function, numba signature).
_EXPORTS = {
    native_slab.TASKS_FUNCTION: (hg_slab_tasks, types.void(
        types.int64, types.int64, _I8P, types.uint64, types.float64, types.float64, types.float64, types.float64,
        _F8P, _I8P, _F8P, _U8P, _I4P)),
    native_slab.RESULTS_FUNCTION: (one_wavelength_results, types.void(_F8P, types.int64, types.float64, _F8P)),
}


def _native_object() -> bytes:
    """The exported functions and everything they call, as one relocatable object (ELF on Linux)."""
    context = cpu_target.target_context.with_aot_codegen("clothlight_slab", cpu_name="")
    library = context.codegen().create_library("clothlight_slab")
    library.add_ir_module(nrtdynmod.create_nrt_module(context)[0])  # the reference counts' inline helpers
    flags = Flags()
    flags.no_compile = True
    flags.no_cpython_wrapper = flags.no_cfunc_wrapper = True
    flags.nrt = True  # numba.carray is typed through its runtime, though a view allocates nothing
    flags.error_model = "numpy"
    with global_compiler_lock:
        for name, (function, signature) in _EXPORTS.items():
            result = compile_extra(cpu_target.typing_context, context, function, signature.args,
                                   signature.return_type, flags, locals={}, library=library)
            library.get_function(result.fndesc.llvm_func_name).name = name
        library.finalize()
        for function in library.get_defined_functions():
            if function.name not in _EXPORTS:
                private = function.linkage in {Linkage.private, Linkage.internal}
                function.visibility = "default" if private else "hidden"
        for function in library._final_module.functions:
            if function.is_declaration and function.name.startswith("NRT_"):
                function.linkage = Linkage.external_weak
        return library.emit_native_object()


def build_native_slab(path: str | os.PathLike | None = None) -> pathlib.Path:
    """Compile and link the native slab library at ``path`` (default
    :func:`precompute.slab.native.library_path`, whose folder's libraries of other sources are removed);
    the path.  Raises ``RuntimeError`` where there is no C compiler to link it."""
    compiler = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")
    if compiler is None:
        raise RuntimeError("no C compiler (cc or gcc) to link the native slab library")
    target = pathlib.Path(path) if path is not None else native_slab.library_path()
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=target.parent) as work:
        obj = pathlib.Path(work, "slab.o")
        obj.write_bytes(_native_object())
        linked = pathlib.Path(work, target.name)
        subprocess.run([compiler, "-shared", "-o", str(linked), str(obj), "-lm"], check=True, capture_output=True)
        os.replace(linked, target)  # in one step: a concurrent run loads the old library or the new
    if path is None:
        for stale in target.parent.glob(native_slab.LIBRARY_PATTERN):
            if stale != target:
                stale.unlink(missing_ok=True)
    return target

