"""One medium on every sample weave (``[sample]``, precompute/optics/measured_sample.py) against a
measured fabric: which weave the medium fits best before any refit.

For each weave the fit's forward model renders its cloth response (once, then cached) and profiles
the preset's sheen and fuzz on it, as a fit does for every candidate medium
(``precompute.fit.optimise.fit_profiled_specular``), with the preset's own medium at
``--relative-error``.  Printed per weave: relative RMS per channel (their mean, then R, G, B) on the
plane of incidence and held out, the profiled sheen and fuzz, and the backscatter model / measured in
the fabric's main channel at θi 60°, θv −60° and −40° and θi 45°, θv −60°; and the shape of the
medium's own cloth BRDF (without the sheen and the fuzz) in that channel, over its value at normal
light and view, at :data:`SHAPE_VIEWS`, the measured fabric's beside it.

    python scripts/compare_sample_weaves.py --measured ../shared/data/real_fabrics/neural/white-fabric.csv \\
        --preset white_cotton
"""

from __future__ import annotations

import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

#: The backscatter views (θi, signed θv), degrees, as the fabric figures give them.
BACKSCATTER_VIEWS = ((60.0, -60.0), (60.0, -40.0), (45.0, -60.0))
#: Where the shape is given (θi, signed θv), degrees: normal light seen at grazing, grazing light
#: seen along the normal and from the light's side; all over normal light and view.
SHAPE_VIEWS = ((0.0, 80.0), (75.0, 0.0), (75.0, -80.0))


def main() -> int:
    import numpy as np

    from clothlight.fit.forward import build_forward_model
    from precompute.fit.objective import Objective, load_measurement, split_views
    from precompute.fit.optimise import cloth_from_parts, fit_profiled_specular
    from precompute.fit.parameters import PARAMETERS
    from precompute.optics.measured_sample import SAMPLE_TABLE, SAMPLE_WEAVE_KEY, SAMPLE_WEAVES
    from precompute.optics.cook_torrance import specular_from_config
    from precompute.optics.medium import load_preset_config

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--measured", type=pathlib.Path, required=True, help="a measured-data CSV")
    parser.add_argument("--preset", required=True, help="a shipped preset name or a preset TOML")
    parser.add_argument("--relative-error", type=float, default=0.03, help="the forward model's (default 0.03)")
    args = parser.parse_args()

    measurement = load_measurement(args.measured)
    views = split_views(measurement)
    objective = Objective(measurement, views)
    count = len(views.forward_views)
    config, base_dir = load_preset_config(args.preset)
    profiled = [PARAMETERS[name] for name in ("specular_weight", "specular_slope", "fuzz_albedo")]
    angles, signed = np.asarray(views.angles_deg, float), np.asarray(views.signed_view_deg, float)
    in_plane = np.isclose((angles[:, 3] - angles[:, 1]) % 180.0, 0.0)

    def row(theta_i, theta_v):
        return np.flatnonzero(in_plane & (angles[:, 0] == theta_i) & (signed == theta_v))[0]

    for weave in SAMPLE_WEAVES:
        model = build_forward_model(views.forward_views, {**config, SAMPLE_TABLE: {SAMPLE_WEAVE_KEY: weave}},
                                    base_dir, seed=0)
        medium, specular = model.parts(config, relative_error=args.relative_error, seed=1)
        depth = {"fuzz_depth": specular_from_config(config)["fuzz_depth"]}  # the preset's, not profiled
        values = fit_profiled_specular(lambda rgb: objective(rgb[:count]), medium, specular, profiled, depth)
        rgb = cloth_from_parts(medium, specular, {**depth, **{p.path: values[p.name] for p in profiled}})[:count]
        fit, held = objective.channel_errors(rgb), objective.channel_errors(rgb, "held_out")
        backscatter = []
        for theta_i, theta_v in BACKSCATTER_VIEWS:
            r = row(theta_i, theta_v)
            channel = int(np.argmax(objective.measured[r]))
            backscatter.append(rgb[r, channel] / objective.measured[r, channel])
        normal = row(0.0, 0.0)
        channel = int(np.argmax(objective.measured[normal]))
        shape = [f"{medium[row(*v), channel] / medium[normal, channel]:.2f} "
                 f"({objective.measured[row(*v), channel] / objective.measured[normal, channel]:.2f})"
                 for v in SHAPE_VIEWS]
        print(f"{weave:9s} plane {fit.mean():.3f} {np.round(fit, 3).tolist()}, held out {held.mean():.3f} "
              f"{np.round(held, 3).tolist()}; sheen w {values['specular_weight']:.3g}, "
              f"m {values['specular_slope']:.3g}, fuzz {values['fuzz_albedo']:.3g}; "
              f"backscatter {np.round(backscatter, 2).tolist()}; the medium's shape (measured) "
              f"{', '.join(shape)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
