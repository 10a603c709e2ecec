"""``python -m clothlight.fit.colour_match_worker``: one colour match in a child process of Blender
(the Yarn Medium panel's Match Colour; :class:`clothlight.colour_match_job.ColourMatchJob`).

The solve of ``python -m clothlight.fit.match_colour`` (the same shade model, solve and preset text:
:mod:`.colour_match`, :func:`.match_colour.preset_text`) for a
:class:`~clothlight.colour_match_job.ColourMatchRequest`.  Writes JSON lines on stdout —
``{"event": "progress", "fraction": f, "stage": "…"}`` (the swatches' response renders and the clear
yarn's absorption series, the first time for a yarn; then the solve), then one of ``done`` (the
recipe, its CIEDE2000, whether it reaches the colour, the preset file and its text, and whether it
was written), ``error`` or ``cancelled`` — and stops when its stdin says ``cancel`` or closes
(:mod:`clothlight.worker_io`).  Exit status as every ClothLight command: 0 done (a colour out of reach
too: the outcome says so and nothing is written unless the request asks for the nearest), 2 bad
input, 130 cancelled (nothing written: the cache stages its entries, the preset is written at the
end), 1 any other failure.

A cancel that comes while Blender renders the response is held until the render ends (Blender
swallows an exception raised inside one).
"""

from __future__ import annotations

import argparse
import pathlib
import sys

from ..colour_match_job import ColourMatchRequest, write_preset
from ..worker_io import ProgressEvents, run_worker

#: Shares of the progress bar: the swatches' response renders, the clear yarn's absorption series
#: (each only the first time for a yarn, then read from the cache), the solve.
RESPONSE_AT, SERIES_AT, SOLVE_AT = 0.0, 0.4, 0.85


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m clothlight.fit.colour_match_worker", description=__doc__)
    parser.add_argument("--request", required=True, help="a ColourMatchRequest as JSON")
    parser.add_argument("--cache-dir", required=True, help="cache folder of the shade model")
    parser.add_argument("--threads", type=int)
    return run_worker(lambda: parser.parse_args(argv), _match)


def _match(args, _cancelled) -> dict:
    import numpy as np

    from precompute.exit_codes import DeferredInterrupt
    from precompute.tables.color import linear_to_srgb
    from .colour_match import ShadeModel, match_colour
    from .match_colour import preset_text

    request = ColourMatchRequest.from_json(args.request).check()
    base, base_dir = request.base_config()
    progress = ProgressEvents()
    held = DeferredInterrupt(note="")
    progress(0.0, stage="starting")

    def say(text: str) -> None:
        at = SERIES_AT if text.startswith("absorption series") else RESPONSE_AT
        progress(at, stage=text.split(" (")[0])

    def building(done: int, total: int) -> None:
        held.check()  # a cancel during the renders, held until one ended
        progress(RESPONSE_AT + (SERIES_AT - RESPONSE_AT) * done / max(total, 1),
                 stage=f"cloth response: {done}/{total} renders")

    model = ShadeModel(base, base_dir, cache_dir=args.cache_dir, seed=request.seed, threads=args.threads,
                       progress=say, building=building, while_building=lambda: held)
    progress(SOLVE_AT, stage="solving the recipe")
    result = match_colour(np.array(request.target), model)
    out = request.out
    text = preset_text(result, request.target, base, base_dir, pathlib.Path(out).stem,
                       "solved by ClothLight's Match Colour in Blender")
    written = result.reached or request.nearest
    if written:
        write_preset(text, out)
    return {"target_srgb": list(request.target), "dyes": list(result.dyes),
            "dye_percent": result.recipe[:-1].tolist(), "fibre_absorption_per_mm": float(result.recipe[-1]),
            "delta_e_2000": float(result.delta_e), "reached": bool(result.reached),
            "cloth_srgb": np.clip(linear_to_srgb(result.cloth_rgb), 0.0, 1.0).tolist(),
            "preset": out, "written": bool(written), "text": text, "evaluations": int(result.evaluations),
            "seconds": float(result.seconds)}


if __name__ == "__main__":
    sys.exit(main())
