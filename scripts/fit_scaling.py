"""How long a fit's search would take on more workers, from the evaluations a fit recorded.

    python scripts/fit_scaling.py FIT_DIR/fit.json [--workers 1,2,4,9,16]

A CMA-ES generation's candidates and the incumbent's re-evaluation are one batch of independent
tasks (precompute/fit/optimise.py), so on W workers a generation takes as long as the busiest
worker when its tasks are dealt out longest first; the generations run one after the other, and
the final, accurate evaluation after them.  The task times are those ``fit.json`` recorded, on the
machine and load of that fit: a model of the search's wall time, to hold against the measured one
at the workers the fit had (printed beside it).
"""

from __future__ import annotations

import argparse
import collections
import heapq
import json
import pathlib


def generation_wall(seconds: list[float], workers: int) -> float:
    """Wall time of one batch of tasks on ``workers``, dealt out longest first to the least busy."""
    loads = [0.0] * workers
    for task in sorted(seconds, reverse=True):
        heapq.heapreplace(loads, loads[0] + task)
    return max(loads)


def predicted_search_seconds(history: list[dict], workers: int) -> float:
    batches = collections.defaultdict(list)
    final = 0.0
    for evaluation in history:
        if evaluation["kind"] == "final":
            final += evaluation["seconds"]
        elif evaluation["seconds"] is not None:
            batches[evaluation["generation"]].append(evaluation["seconds"])
    return sum(generation_wall(batch, workers) for batch in batches.values()) + final


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fit_json", type=pathlib.Path)
    parser.add_argument("--workers", default="1,2,4,9,16", help="comma-separated worker counts")
    args = parser.parse_args(argv)
    fit = json.loads(args.fit_json.read_text())
    history = fit["history"]
    total = sum(e["seconds"] for e in history if e["seconds"] is not None)
    print(f"{args.fit_json}: {len(history)} evaluations in {fit['generations']} generations, {total:.0f} s of "
          f"evaluation in all; the search took {fit['seconds']:.0f} s wall (final evaluation included)")
    for workers in (int(w) for w in args.workers.split(",")):
        print(f"  {workers:3d} worker(s): {predicted_search_seconds(history, workers):7.0f} s predicted")


if __name__ == "__main__":
    main()
