"""``python -m clothlight.cloth_bake_worker``: one cloth bake in a child process of Blender (the Garment
panel's Bake Cloth; :class:`clothlight.jobs.ClothBakeJob`).

The cloth tables of ``python -m clothlight.garment bake`` (:func:`clothlight.blender.garment.bake.bake_cloth`,
cached by content) for a yarn bake folder, written into the cache only: the add-on reads them there.
Events, the stdin watch and the exit codes are :mod:`clothlight.worker_io`'s: JSON lines on stdout
— ``{"event": "progress", "fraction": f, "stage": "views k/N"}`` (the response's views, traced or
rendered), then ``done`` (the folder and whether it made the response or the measurement),
``error`` or ``cancelled`` — 0 done, 2 bad input, 130 cancelled (nothing
written: the cache stores an entry whole), 1 any other failure.  A cancel that comes while Blender
renders is held until the render ends (Blender swallows an exception raised inside one).
"""

from __future__ import annotations

import argparse
import sys

from .worker_io import ProgressEvents, run_worker


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m clothlight.cloth_bake_worker", description=__doc__)
    parser.add_argument("--tables", required=True, help="the yarn bake folder")
    parser.add_argument("--cache-dir", required=True)
    parser.add_argument("--incidence-resolution", type=int, help="N_i of the cloth tables (default: the command's)")
    parser.add_argument("--exit-resolution", type=int, help="N_o of the cloth tables (default: the command's)")
    parser.add_argument("--pixels-per-patch", type=int, help="pixels along a region's patch (default: the command's)")
    parser.add_argument("--samples", type=int, help="Cycles samples per pixel (default: the command's)")
    parser.add_argument("--threads-per-cm", type=int, help="warp and weft threads per cm of the measured weave "
                                                           "(default: the validation weave's)")
    return run_worker(lambda: parser.parse_args(argv), _bake)


def _bake(args, _cancelled) -> dict:
    import dataclasses
    import pathlib

    from precompute.errors import ParameterError
    from precompute.exit_codes import DeferredInterrupt
    from .blender.garment.bake import bake_cloth
    from .blender.garment.density import weave_at_thread_count
    from .blender.garment.measure import GoniometerSettings

    if not pathlib.Path(args.tables).is_dir():
        raise ParameterError("tables", args.tables, "an existing yarn bake folder")
    chosen = {field.name: getattr(args, field.name) for field in dataclasses.fields(GoniometerSettings)
              if getattr(args, field.name, None) is not None}
    settings = GoniometerSettings(**chosen, weave=weave_at_thread_count(args.threads_per_cm))
    events = ProgressEvents()
    held = DeferredInterrupt(note="")

    def progress(done: int, total: int, _what: str) -> None:
        held.check()  # a cancel during a render, held until it ended
        events(done / max(total, 1), stage=f"views {done}/{total}")

    events(0.0, stage="starting")
    with held:
        folder, rendered = bake_cloth(args.tables, settings, cache_dir=args.cache_dir, progress=progress)
    return {"folder": str(folder), "rendered": bool(rendered)}


if __name__ == "__main__":
    sys.exit(main())
