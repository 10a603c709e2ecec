"""Where a preset's cloth misses a measured fabric: model / measured and fitted baseline / measured per view.

The fit's forward model (the cloth response, cached after its first render) at the preset's own
medium and ``[fit]`` sheen, against the measurement; the paper's Lambert + Cook–Torrance baseline
fitted to the same views beside it (docs/fitting.md).  One row per measured view: θi, the signed view
angle (negative on the light's side), the azimuth from the light's plane, the measured RGB (1/sr) and
the two ratios per channel, then the relative RMS errors.

    python scripts/residuals_by_view.py --measured ../shared/data/real_fabrics/red-fabric2.csv \
        [--preset voided_red_cotton]
"""

from __future__ import annotations

import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))


def main() -> int:
    from precompute.fit.baseline import baseline_brdf, fit_baseline
    from clothlight.fit.forward import build_forward_model
    from precompute.fit.objective import Objective, load_measurement, split_views
    from precompute.fit.optimise import cloth_from_parts
    from precompute.optics.cook_torrance import specular_from_config
    from precompute.optics.medium import DEFAULT_PRESET, load_preset_config

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--measured", type=pathlib.Path, required=True, help="a measured-data CSV")
    parser.add_argument("--preset", default=DEFAULT_PRESET, help="a shipped preset name or a preset TOML")
    parser.add_argument("--relative-error", type=float, default=0.03, help="the forward model's (default 0.03)")
    args = parser.parse_args()

    measurement = load_measurement(args.measured)
    views = split_views(measurement)
    objective = Objective(measurement, views)
    config, base_dir = load_preset_config(args.preset)
    model = build_forward_model(views.forward_views, config, base_dir, seed=0)
    medium, specular = model.parts(config, relative_error=args.relative_error, seed=1)
    sheen = specular_from_config(config)
    count = len(views.forward_views)
    cloth = cloth_from_parts(medium, specular, sheen)[:count]
    baseline = fit_baseline(objective)
    fitted = baseline_brdf(views.angles_deg, baseline.albedo, baseline.weight, baseline.slope)
    measured = objective.measured
    print(" θi  view  Δφ |  measured R      G      B  |  model / measured  |  baseline / measured")
    for i, (angles, signed) in enumerate(zip(views.angles_deg, views.signed_view_deg)):
        azimuth = (angles[3] - angles[1]) % 360
        print(f"{angles[0]:3.0f}  {signed:4.0f}  {azimuth:3.0f} | {measured[i, 0]:.4f} {measured[i, 1]:.4f} "
              f"{measured[i, 2]:.4f} | " + " ".join(f"{v:5.2f}" for v in cloth[i] / measured[i]) + " | "
              + " ".join(f"{v:5.2f}" for v in fitted[i] / measured[i]))
    for name, rgb in (("model", cloth), ("fitted baseline", fitted)):
        fit, held = objective.channel_errors(rgb), objective.channel_errors(rgb, "held_out")
        print(f"{name}: relative RMS R, G, B on the fit views {fit.round(3).tolist()}, "
              f"held out {held.round(3).tolist()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
