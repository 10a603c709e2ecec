"""What a sheen index apart from the boundary index would give a yarn of fibres: a measurement.

A yarn of fibres in air has boundary index 1, so the cloth's Cook–Torrance sheen, whose Fresnel
factor takes the tables' boundary index (in the shader too), is 0.  This fits such a medium as
``python -m clothlight.fit`` does, with the sheen's weight and slope free (profiled), but with the
sheen's Fresnel at ``--sheen-index`` (the fibres' own, 1.557 for cellulose) through the forward
model's ``sheen_index`` (clothlight/fit/forward.py).  The shader cannot render that yet (the bake's
summary carries one index): the result answers whether carrying a sheen index is worth it, it is no
preset to ship.  Writes a fit folder (fit.json, report.md, preset.toml); its figures:
``python scripts/fabric_figures.py --measured CSV --fit OUT``.

    python scripts/fit_fibres_sheen_index.py --measured ../shared/data/real_fabrics/neural/red-fabric2.csv \\
        --config precompute/presets/experimental/fibre_cotton.toml \\
        --free fibre_fraction,fibre_diameter_um,dye_weight_percent,fibre_absorption_per_mm \\
        --budget-evaluations 60 --budget-seconds 1800 --out fit_sheen
"""

from __future__ import annotations

import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))


def main() -> int:
    from clothlight.fit.forward import build_forward_model
    from precompute.fit.objective import load_measurement, split_views
    from precompute.fit.optimise import Budget, fit_medium
    from precompute.fit.report import write_fit_folder
    from precompute.optics.medium import load_preset_config

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--measured", type=pathlib.Path, required=True, help="a measured-data CSV")
    parser.add_argument("--config", required=True, help="the starting medium: a preset name or TOML")
    parser.add_argument("--free", required=True, help="the medium's free parameters (the sheen's two are added)")
    parser.add_argument("--sheen-index", type=float, default=1.557, help="the sheen's Fresnel index (1.557)")
    parser.add_argument("--max-back-front", type=float, default=None, help="as python -m clothlight.fit's")
    parser.add_argument("--target-ratios", default=None, help="as python -m clothlight.fit's, e.g. B/R=0.06,G/R=0.14")
    parser.add_argument("--budget-evaluations", type=int, default=60)
    parser.add_argument("--budget-seconds", type=float, default=None)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=pathlib.Path, required=True)
    args = parser.parse_args()

    measurement = load_measurement(args.measured)
    config, base_dir = load_preset_config(args.config)
    model = build_forward_model(split_views(measurement).forward_views, config, base_dir, seed=args.seed,
                                sheen_index=args.sheen_index)
    free = [*args.free.split(","), "specular_weight", "specular_slope"]
    result = fit_medium(measurement, config, base_dir, free=free, forward_model=model, seed=args.seed,
                        budget=Budget(args.budget_evaluations, args.budget_seconds),
                        max_back_front=args.max_back_front, target_ratios=args.target_ratios,
                        progress=lambda p: print(f"{p.evaluations}/{p.total} best {p.best_objective:.4f}", flush=True))
    write_fit_folder(result, args.out, measured_name=args.measured.name)
    model_metrics = result.metrics["model"]
    print(f"relative RMS {model_metrics['fit_views']['relative_rms']:.3f} on the plane of incidence, "
          f"{model_metrics['held_out_views']['relative_rms']:.3f} held out; {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
