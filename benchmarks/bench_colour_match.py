"""Target colour → shade recipe (issue 44: ΔE2000 ≤ 2 in ≤ 30 s): the colours of real fabrics, matched.

The targets are the colours of the raw-data MERL fabrics (../shared/data/real_fabrics/neural): each
one's reflectance factor π f at normal light and views 15–30° off the normal (the mirror's glint
left out, as the match leaves it out), linear RGB → sRGB.  Each is matched on ``--preset``'s yarn
(default voided_red_cotton) with the shipped red, blue and yellow dyes (clothlight/fit/colour_match.py).
Printed per fabric: the recipe, CIEDE2000 of the cloth to the target, evaluations and wall seconds
of the solve; and once, the time to get the model ready (the response and the series from the cache,
or made: minutes the first time).

    python benchmarks/bench_colour_match.py [--preset voided_red_cotton] [--fabrics red-fabric2,blue-fabric] \
        [--plot PNG]

``--plot`` draws each fabric's colour beside its recipe's (sRGB patches, ΔE2000 under them).
``--check-grid`` also evaluates a dense grid of recipes (:data:`CHECK_LEVELS_PERCENT` per dye ×
:data:`CHECK_FIBRE_PER_MM`) and prints its nearest ΔE2000 per fabric: a solve that missed a nearer
recipe would show there.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
from subject_medium import SUBJECT_PRESET

import numpy as np

FABRICS = pathlib.Path(__file__).resolve().parents[2] / "shared" / "data" / "real_fabrics" / "neural"
#: ``--check-grid``: dye amounts (% o.w.f., none then 0.003–2 % geometric) and fibre absorptions (1/mm).
CHECK_LEVELS_PERCENT = (1e-4, *np.geomspace(0.003, 2.0, 11))
CHECK_FIBRE_PER_MM = (0.0, 0.2, 0.8, 2.0)
#: Views of the fabric's colour: normal light, views this far off the normal, degrees.
COLOUR_VIEWS_DEG = (15.0, 30.0)


def fabric_srgb(path: pathlib.Path) -> np.ndarray:
    """sRGB (3,) of a raw-data curves CSV: π f at θi = 0 and 15° ≤ |θo| ≤ 30°, averaged, encoded."""
    from precompute.fit.measured_data import read_measurement
    from precompute.tables.color import linear_to_srgb

    measurement = read_measurement(path)
    theta_i, theta_o = measurement.angles_deg[:, 0], np.abs(measurement.angles_deg[:, 2])
    select = (theta_i == 0.0) & (theta_o >= COLOUR_VIEWS_DEG[0]) & (theta_o <= COLOUR_VIEWS_DEG[1])
    return linear_to_srgb(np.pi * measurement.rgb[select].mean(axis=0))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--preset", default=SUBJECT_PRESET)
    parser.add_argument("--fabrics", help="comma-separated fabric names (default: every CSV in the folder)")
    parser.add_argument("--plot", type=pathlib.Path, help="PNG of each target beside its recipe's colour")
    parser.add_argument("--check-grid", action="store_true", help="also the nearest recipe of a dense grid")
    args = parser.parse_args()

    from clothlight.fit.colour_match import MATCH_DELTA_E, ShadeModel, match_colour
    from precompute.optics.medium import load_preset_config

    start = time.perf_counter()
    base, base_dir = load_preset_config(args.preset)
    model = ShadeModel(base, base_dir, progress=lambda text: print(f"  … {text}", flush=True))
    print(f"{args.preset}: model ready in {time.perf_counter() - start:.1f} s "
          f"(clear cloth: linear RGB {np.round(model([1e-4] * len(model.dyes) + [0.0]), 3).tolist()})")
    names = args.fabrics.split(",") if args.fabrics else sorted(p.stem for p in FABRICS.glob("*.csv"))
    grid_labs = None
    if args.check_grid:
        import itertools

        from precompute.tables.color import linear_rgb_to_lab

        grid = [(*dyes, fibre) for fibre in CHECK_FIBRE_PER_MM
                for dyes in itertools.product(CHECK_LEVELS_PERCENT, repeat=len(model.dyes))]
        grid_labs = linear_rgb_to_lab(np.array([model(recipe) for recipe in grid]))
    print(f"{'fabric':22s} {'target':8s} {'recipe: ' + ', '.join(d.removesuffix('.csv') for d in model.dyes):42s} "
          f"{'fibre/mm':>8s} {'ΔE2000':>7s} {'evals':>5s} {'s':>5s}" + ("  grid ΔE2000" if args.check_grid else ""))
    reached, rows = 0, []
    for name in names:
        target = fabric_srgb(FABRICS / f"{name}.csv")
        result = match_colour(target, model)
        reached += result.reached
        hex_target = "#" + "".join(f"{round(255 * v):02x}" for v in target)
        recipe = ", ".join(f"{p:.3g} %" for p in result.recipe[:-1])
        nearest = ""
        if grid_labs is not None:
            from precompute.tables.color import delta_e_2000, linear_rgb_to_lab, srgb_to_linear_rgb

            nearest = f"  {float(delta_e_2000(grid_labs, linear_rgb_to_lab(srgb_to_linear_rgb(target))).min()):11.2f}"
        print(f"{name:22s} {hex_target:8s} {recipe:42s} {result.recipe[-1]:8.3g} {result.delta_e:7.2f} "
              f"{result.evaluations:5d} {result.seconds:5.1f}{nearest}", flush=True)
        rows.append((name, target, result))
    print(f"reached (ΔE2000 ≤ {MATCH_DELTA_E:g}): {reached} of {len(names)}")
    if args.plot:
        plot_matches(rows, args.plot, args.preset)
        print(f"plot: {args.plot}")


def plot_matches(rows, path: pathlib.Path, preset: str) -> None:
    """Each fabric's colour (top) over its recipe's (bottom), ΔE2000 beneath: a reached match in black."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from clothlight.fit.colour_match import MATCH_DELTA_E
    from precompute.tables.color import linear_to_srgb

    figure, axis = plt.subplots(figsize=(1.1 * len(rows) + 1.0, 3.2))
    for column, (name, target, result) in enumerate(rows):
        axis.add_patch(plt.Rectangle((column, 1.0), 0.9, 0.9, color=np.clip(target, 0, 1)))
        axis.add_patch(plt.Rectangle((column, 0.0), 0.9, 0.9, color=linear_to_srgb(result.cloth_rgb)))
        axis.text(column + 0.45, -0.15, f"ΔE {result.delta_e:.1f}", ha="center", va="top", fontsize=8,
                  color="black" if result.delta_e <= MATCH_DELTA_E else "firebrick")
        axis.text(column + 0.45, 2.0, name.replace("-fabric", "").replace("-", " "), ha="center", va="bottom",
                  fontsize=8, rotation=30)
    axis.text(-0.1, 1.45, "fabric", ha="right", va="center", fontsize=9)
    axis.text(-0.1, 0.45, "recipe", ha="right", va="center", fontsize=9)
    axis.set_xlim(-1.0, len(rows))
    axis.set_ylim(-0.6, 2.7)
    axis.set_aspect("equal")
    axis.axis("off")
    axis.set_title(f"Raw-data fabrics' colours and the shade recipes on {preset}'s yarn "
                   f"(specular excluded; ΔE2000 ≤ {MATCH_DELTA_E:g} reached)", fontsize=9)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=150, bbox_inches="tight")
    plt.close(figure)


if __name__ == "__main__":
    main()
