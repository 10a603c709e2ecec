"""How much closer a preset would come to a measured fabric with a white Lommel–Seeliger term: the
headroom of a hairy layer's first reflections, measured before it is built (issue 43).

A cloth's surface fibres reflect a few percent of the light undyed before any of it meets a dye.
The single scattering of a semi-infinite layer of isotropic scatterers is the Lommel–Seeliger law
(Hapke, "Bidirectional reflectance spectroscopy 1. Theory", JGR 86 (B4), 1981, eq. 14 without the
opposition term):

    f_LS(l, v) = A / (4π (μi + μo))                                                    [1/sr]

with μi, μo the cosines of the light and the view with the cloth normal and A the layer's albedo
times its phase function (white: the same in R, G and B).  It rises toward grazing light and view
in every azimuth, where the fibre media fitted so far are too dark in their weak channels.

For the preset's medium (its tables simulated through the fit's forward model, the cloth response
``python -m clothlight.fit`` renders and caches for ``--measured``) this prints the relative RMS
(per channel, as the fit's objective) on the plane of incidence and on the held-out azimuths with
the Cook–Torrance sheen re-profiled (``precompute.fit.optimise.fit_profiled_specular``) and with the
sheen and A profiled together; the medium itself is not refitted.

    python scripts/white_term_headroom.py --measured ../shared/data/real_fabrics/neural/blue-fabric.csv \\
        --preset precompute/presets/experimental/fibre_blue_cotton.toml
"""

from __future__ import annotations

import argparse
import math
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

#: The white term's albedos A scanned (their best is polished by the sheen's profile at each).
ALBEDO_GRID = tuple(0.4 * k / 24 for k in range(25))


def lommel_seeliger(theta_i_deg, theta_o_deg):
    """f_LS / A (…), 1/sr: 1 / (4π (μi + μo)) at zenith angles in degrees (module docstring)."""
    import numpy as np

    mu_i, mu_o = np.cos(np.radians(theta_i_deg)), np.cos(np.radians(theta_o_deg))
    return 1.0 / (4.0 * math.pi * (mu_i + mu_o))


def main() -> int:
    import numpy as np

    from clothlight.fit.forward import build_forward_model
    from precompute.fit.objective import Objective, combined, load_measurement, split_views
    from precompute.fit.optimise import fit_profiled_specular
    from precompute.fit.parameters import PARAMETERS
    from precompute.optics.medium import load_preset_config

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--measured", type=pathlib.Path, required=True, help="a measured-data CSV")
    parser.add_argument("--preset", required=True, help="a shipped preset name or a preset TOML")
    parser.add_argument("--relative-error", type=float, default=0.03, help="the forward model's (0.03)")
    parser.add_argument("--seed", type=int, default=1, help="the transport's seed (1)")
    args = parser.parse_args()

    measurement = load_measurement(args.measured)
    views = split_views(measurement)
    objective = Objective(measurement, views)
    count = len(views.forward_views)
    config, base_dir = load_preset_config(args.preset)
    model = build_forward_model(views.forward_views, config, base_dir, seed=0)
    medium, specular = model.parts(config, relative_error=args.relative_error, seed=args.seed)
    medium = medium[:count]
    angles = np.asarray(views.angles_deg, float)
    white = lommel_seeliger(angles[:, 0], angles[:, 2])[:, None]
    profiled = (PARAMETERS["specular_weight"], PARAMETERS["specular_slope"])

    def profile(albedo: float):
        base = medium + albedo * white
        sheen = fit_profiled_specular(objective, base, lambda w, m: specular(w, m)[:count], profiled, {})
        rgb = base + specular(sheen["specular_weight"], sheen["specular_slope"])[:count, None]
        return objective(rgb), sheen, rgb

    def line(label, sheen, rgb, albedo=None):
        fit, held = objective.channel_errors(rgb, "fit"), objective.channel_errors(rgb, "held_out")
        extra = "" if albedo is None else f", A {albedo:.3f}"
        return (f"{label}: sheen {sheen['specular_weight']:.3f}, m {sheen['specular_slope']:.3f}{extra}; relative "
                f"RMS per channel, plane of incidence {combined(fit):.3f} (R {fit[0]:.3f}, G {fit[1]:.3f}, "
                f"B {fit[2]:.3f}), held out {combined(held):.3f} (R {held[0]:.3f}, G {held[1]:.3f}, B {held[2]:.3f})")

    _, sheen, rgb = profile(0.0)
    print(f"{args.preset} against {args.measured.name} (the medium at relative error {args.relative_error:g})")
    print(line("  the sheen re-profiled", sheen, rgb))
    scores = [profile(a)[0] for a in ALBEDO_GRID]
    best = ALBEDO_GRID[int(np.argmin(scores))]
    step = ALBEDO_GRID[1] - ALBEDO_GRID[0]
    fine = np.linspace(max(best - step, 0.0), best + step, 21)
    albedo = float(fine[int(np.argmin([profile(a)[0] for a in fine]))])
    _, sheen, rgb = profile(albedo)
    print(line("  with a white Lommel–Seeliger term", sheen, rgb, albedo))
    return 0


if __name__ == "__main__":
    sys.exit(main())
