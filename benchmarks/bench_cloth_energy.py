"""Where a cloth sends the light of a sun along its normal, path-traced and from its cloth tables
(issue 44: "reflected + transmitted + open weave at normal incidence within 5 % of the path-traced
yarn sample's").

    python benchmarks/bench_cloth_energy.py [--yarn PRESET_OR_BAKE ...] [--exit-resolution 8]
        [--samples 16] [--pixels-per-patch 12] [--threads-per-cm 20] [--cache-dir DIR]

For each yarn (a preset's name, baked with ``python -m precompute bake``'s defaults and cached, or a
yarn bake folder; default ``voided_red_cotton`` and ``ecru_cotton``), on the validation weave at
``--threads-per-cm`` (default 20, the validation weave itself):

1. **The path-traced sample** (``clothlight.blender.garment.path_traced``): the cloth
   gonioreflectometer's woven sample in the yarn's general-lighting material under one sun along
   the normal, seen from every exit cell of both sides, twice: with Cycles following the light from
   yarn to yarn (the validation rig's ``yarn_scene``) and stopping at the first yarn (its direct
   light).  Reflected and transmitted energy are ρ cos θ_o summed over the exit cells' solid
   angles, the open weave 1 − the coverage along the normal.  G = with / without, per channel: what
   the light between yarns adds.
2. **The cloth tables** (``python -m clothlight.garment bake``'s defaults: read off the weave's
   cloth response, traced once per weave and cached, then seconds):
   the summary's energy at normal incidence, with the light between yarns
   (``clothlight.garment.between_yarns``) and without it.
3. **The model's share q** of yarn-scattered light that meets another yarn, as this run measures
   it: q = (G − 1) / (G a), a the yarn's albedo under broad light from its tables, per channel
   where a is large enough to say (the red of a red yarn); and the q the tables used.

No figure is asserted (tests/test_between_yarns.py holds the model to closed forms).
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
from subject_medium import SUBJECT_PRESET

DEFAULT_YARNS = (SUBJECT_PRESET, "ecru_cotton")
#: Below this broad-light albedo a channel's gain is too small to measure q from.
LEAST_ALBEDO_FOR_Q = 0.2


def _yarn_folder(yarn: str, cache_dir) -> pathlib.Path:
    if pathlib.Path(yarn).is_dir():
        return pathlib.Path(yarn)
    from precompute.bake import bake

    return bake(yarn, cache_dir=cache_dir).folder


def _energy(measured: dict, exit_resolution: int):
    """(reflected, transmitted, open) of a path-traced measurement under a sun along the front normal."""
    import numpy as np

    from clothlight.garment.tables import coverage_along
    from precompute.tables.grids import AngularGrid

    exits = AngularGrid("hemisphere", exit_resolution)
    weight = exits.cell_centers()[:, 2] * exits.cell_solid_angle
    open_weave = 1.0 - float(coverage_along(measured["coverage"]["front"], np.array([0.0, 0.0, 1.0])))
    return weight @ measured["rho"]["front"], weight @ measured["rho"]["back"], open_weave


def _rgb(values) -> str:
    return " ".join(f"{v:.4f}" for v in values)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--yarn", nargs="+", default=list(DEFAULT_YARNS),
                        help="preset names or yarn bake folders (default: %(default)s)")
    parser.add_argument("--exit-resolution", type=int, default=8,
                        help="N_o of the path-traced views per side (default 8: the tables' 12 takes 1/cos θ_o as "
                             "many pixels at 81° and five times as long)")
    parser.add_argument("--samples", type=int, default=16, help="Cycles samples per pixel (default 16)")
    parser.add_argument("--pixels-per-patch", type=int, default=12)
    parser.add_argument("--threads-per-cm", type=int, default=None,
                        help="warp and weft threads per cm of the validation weave (default: its own, 20)")
    parser.add_argument("--cache-dir", type=pathlib.Path, default=None, help="default: the user cache")
    args = parser.parse_args()

    import json

    import bpy  # noqa: F401  (Blender as a module)
    import numpy as np

    from clothlight.blender.garment.bake import bake_cloth
    from clothlight.blender.garment.density import weave_at_thread_count
    from clothlight.blender.garment.measure import GoniometerSettings
    from clothlight.blender.garment.path_traced import measure_path_traced
    from clothlight.blender.scene_files import open_empty_file
    from clothlight.garment import between_yarns
    from clothlight.garment.tables import lost_to_yarns
    from clothlight.garment.response_measurement import yarn_lookup
    from clothlight.yarn_tables import yarn_tables_from_bake
    from precompute.cache.entries import default_cache_dir
    from precompute.tables.grids import AngularGrid

    cache_dir = args.cache_dir or default_cache_dir()
    # The path-traced sample on the cloth gonioreflectometer's weave and framing (3 × 3 regions: every
    # patch sees the same sun, and a view's ρ is their mean).
    weave = weave_at_thread_count(args.threads_per_cm)
    traced = GoniometerSettings(incidence_resolution=3, exit_resolution=args.exit_resolution,
                                pixels_per_patch=args.pixels_per_patch, samples=args.samples, weave=weave)
    print(f"path-traced: N_o {traced.exit_resolution} a side, {traced.pixels_per_patch} px a patch, "
          f"{traced.samples} spp; sun along the front normal, 1 W/m²; weave "
          f"{traced.to_dict()['weave']['spacing_mm']} mm spacing")
    for yarn in args.yarn:
        folder = _yarn_folder(yarn, cache_dir)
        tables = yarn_tables_from_bake(folder)
        open_empty_file()
        energies = {}
        for bounces in (False, True):
            start = time.perf_counter()
            with tempfile.TemporaryDirectory(prefix="clothlight-bench-energy-") as renders:
                measured = measure_path_traced(tables, (0.0, 0.0, 1.0), traced, bounces=bounces, render_dir=renders)
            energies[bounces] = _energy(measured, traced.exit_resolution)
            reflected, transmitted, open_weave = energies[bounces]
            total = reflected + transmitted + open_weave
            print(f"{yarn}, path-traced {'with light between yarns' if bounces else 'first yarn only'} "
                  f"({time.perf_counter() - start:.0f} s): reflected {_rgb(reflected)}, transmitted "
                  f"{_rgb(transmitted)}, open weave {open_weave:.4f}, total {_rgb(total)}")
        scattered = {bounces: energies[bounces][0] + energies[bounces][1] for bounces in energies}
        gain = scattered[True] / scattered[False]
        albedo = between_yarns.broad_light_albedo(yarn_lookup(tables))
        lost, _ = lost_to_yarns(weave)
        predicted = 1.0 + between_yarns.between_yarns_gain(albedo, lost)
        q = (gain - 1.0) / (gain * albedo)
        print(f"{yarn}: G (with / without light between yarns) {_rgb(gain)}; the model's 1 + g "
              f"{_rgb(predicted)} (a {_rgb(albedo)}, q {lost:.4f}); q this run implies "
              + ", ".join(f"{c} {v:.3f}" for c, v, a in zip("RGB", q, albedo) if a >= LEAST_ALBEDO_FOR_Q))

        cloth, _ = bake_cloth(folder, GoniometerSettings(weave=weave), cache_dir=cache_dir)
        summary = json.loads((cloth / "summary.json").read_text())
        print(f"{yarn}, cloth tables: q {summary['light_between_yarns']['lost_to_yarns']:.3f}")
        normal = int(np.argmax(AngularGrid("sphere", summary["incidence_resolution"]).cell_centers()[:, 2]))
        with_between = np.array(summary["energy"]["per_incidence_total_rgb"][normal])
        between = np.array(summary["light_between_yarns"]["normal_incidence_energy_rgb"])
        traced_total = scattered[True] + energies[True][2]
        for label, total in (("without light between yarns", with_between - between),
                             ("with light between yarns", with_between)):
            print(f"{yarn}, cloth tables {label}: total {_rgb(total)}, vs path-traced "
                  + " ".join(f"{100 * (t / p - 1):+.1f} %" for t, p in zip(total, traced_total)))


if __name__ == "__main__":
    main()
