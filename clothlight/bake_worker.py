"""``python -m clothlight.bake_worker``: one bake in a child process of Blender (see :mod:`clothlight.jobs`).

Writes JSON lines on stdout — ``{"event": "progress", "fraction": f}``, then one of ``done``,
``error`` or ``cancelled`` — and stops when its stdin says ``cancel`` or closes.  Exit status as
every ClothLight command (``precompute/exit_codes.py``): 0 done, 2 bad input (an InputError, named;
its event says ``bad_input``), 130 cancelled (also a Ctrl-C), 1 any other failure (a one-line message
in the event for the report; the traceback on stderr, the bake's log that the add-on keeps for the
console).  The events, the stdin watch and the exit codes are :mod:`clothlight.worker_io`'s, shared
with the fit's worker.
"""

from __future__ import annotations

import argparse
import sys

from .medium_settings import BakeRequest
from .worker_io import ProgressEvents, run_worker


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m clothlight.bake_worker", description=__doc__)
    parser.add_argument("--request", required=True, help="a BakeRequest as JSON")
    parser.add_argument("--cache-dir", required=True)
    parser.add_argument("--threads", type=int)
    parser.add_argument("--scheduler", help="a dask scheduler's address (default: this process's threads)")
    return run_worker(lambda: parser.parse_args(argv), _bake)


def _bake(args, _cancelled) -> dict:
    from precompute import bake as bake_module
    request = BakeRequest.from_json(args.request)
    result = bake_module.bake(**request.bake_arguments(), threads=args.threads, cache_dir=args.cache_dir,
                              progress=ProgressEvents(), scheduler=args.scheduler)
    return {"folder": str(result.folder), "cache_hit": result.cache_hit,
            "seconds": float(result.summary.get("call_seconds", 0.0)),
            "table1_ratios": result.summary.get("table1_ratios_normal", {})}


if __name__ == "__main__":
    sys.exit(main())
