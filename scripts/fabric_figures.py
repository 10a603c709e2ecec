"""Issue 43's figures of a cloth against a measured fabric: a bake folder's tables, a preset, or a fit.

The cloth BRDF at every measured view comes from the fit's forward model (the cloth response,
rendered once per view set and cached, docs/fitting.md): for ``--tables`` the bake's own atlas,
unscattered table and specular term, on the sample weave it records; for ``--preset`` a candidate's tables simulated at
``--relative-error`` with the preset's ``[fit]`` sheen; for ``--fit`` the views a fit's
``fit.json`` holds (its final evaluation, python -m clothlight.fit --out), no render.  Beside it, the paper's Lambert +
Cook–Torrance baseline fitted to the plane of incidence.  Printed (and with ``--json`` written):
relative RMS pooled and per channel on the plane of incidence and on the held-out azimuths,
backscatter model / measured at θi 60°, θv −60° and −40° (and θi 45°, θv −60°), off-specular B/R and
G/R against the measurement (``precompute/fit/figures.py``), and lit from behind / from the front.

    python scripts/fabric_figures.py --measured ../shared/data/real_fabrics/neural/red-fabric2.csv --tables bake
    python scripts/fabric_figures.py --measured ../shared/data/real_fabrics/neural/red-fabric2.csv \
        --preset voided_red_cotton
    python scripts/fabric_figures.py --measured ../shared/data/real_fabrics/neural/red-fabric2.csv --fit out/fit
"""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))


def bake_folder_brdf(model, folder: pathlib.Path):
    """The cloth BRDF (n_views + 2, 3) of a bake folder's tables through ``model``'s response, with
    the specular term and the fuzz (albedo, depth, asymmetry, tint, flatness) its summary records."""
    from clothlight.validation.response import TableLayout
    from precompute.optics import ballistic
    from precompute.optics.cook_torrance import fuzz_tint
    from precompute.tables import folder as table_folder

    checked = table_folder.check_yarn_table_folder(folder.resolve())
    files, summary = table_folder.YARN_TABLE_FILES, checked.summary
    specular = table_folder.summary_specular(summary, checked.folder)
    layout = TableLayout(summary["incidence_resolution"], summary["exit_resolution"], summary["unscattered_samples"],
                         float(summary["host_index"]), ballistic.SUN_MODE_SPREAD_RAD)
    atlas = checked.tables[files["brdf"]].pixels[..., :3]
    attenuation = checked.tables[files["unscattered"]].pixels[..., :3]
    return model.cloth_brdf(atlas, attenuation, layout, specular_weight=float(specular["weight"]),
                            specular_slope=float(specular["slope"]), specular_index=float(specular["index"]),
                            fuzz_albedo=float(specular["fuzz_albedo"]),
                            fuzz_depth=float(specular.get("fuzz_depth", 0.0)),
                            fuzz_asymmetry=float(specular.get("fuzz_asymmetry", 0.0)),
                            fuzz_tint=fuzz_tint(specular),
                            fuzz_flatness=float(specular.get("fuzz_flatness", 0.0)))


def bake_folder_sample(config: dict, folder: pathlib.Path) -> dict:
    """``config`` with the yarn radius and the sample (``[sample]``: its weave and azimuths) of a bake
    folder's summary, which decide the weave its response renders and the azimuths it averages."""
    from precompute.optics.measured_sample import SAMPLE_TABLE
    from precompute.tables import folder as table_folder

    summary = table_folder.check_yarn_table_folder(folder.resolve()).summary
    yarn = {**config["yarn"], "radius_mm": summary["medium"]["yarn"]["radius_mm"]}
    return {**config, "yarn": yarn, SAMPLE_TABLE: table_folder.summary_sample_table(summary, folder)}


def fit_folder_brdf(folder: pathlib.Path, measured):
    """The model BRDF (n_views + 2, 3) a fit's ``fit.json`` holds at its final evaluation, then its
    swatches, and a label; ValueError when its views are not ``measured``'s."""
    import numpy as np

    fit = json.loads((folder / "fit.json").read_text())
    if not np.allclose([v["measured"] for v in fit["views"]], measured):
        raise ValueError(f"{folder / 'fit.json'} was fitted to another measurement")
    swatches = fit.get("swatches") or {}
    rows = [v["model"] for v in fit["views"]] + [swatches.get("front_rgb", [np.nan] * 3),
                                                  swatches.get("back_rgb", [np.nan] * 3)]
    return np.array(rows, float), f"fit {folder} (its final evaluation)"


def main() -> int:
    from clothlight.fit.forward import build_forward_model
    from precompute.fit.baseline import baseline_brdf, fit_baseline
    from precompute.fit.figures import diffuse_shortfall, fabric_figures, figures_text
    from precompute.fit.objective import Objective, load_measurement, split_views
    from precompute.optics.cook_torrance import specular_from_config
    from precompute.optics.medium import DEFAULT_PRESET, load_preset_config

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--measured", type=pathlib.Path, required=True, help="a measured-data CSV")
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--tables", type=pathlib.Path, help="a bake folder (python -m precompute bake --out)")
    source.add_argument("--preset", help="a shipped preset name or a preset TOML, simulated at --relative-error")
    source.add_argument("--fit", type=pathlib.Path, help="a fit's folder (its fit.json) against the same measurement")
    parser.add_argument("--relative-error", type=float, default=0.03, help="a --preset's forward model's (0.03)")
    parser.add_argument("--seed", type=int, default=1, help="a --preset's transport seed (1)")
    parser.add_argument("--json", type=pathlib.Path, help="also write the figures here")
    parser.add_argument("--diffuse-shortfall", action="store_true",
                        help="also the figures of the cloth plus the constant BRDF per channel that brings it "
                             "closest on the plane of incidence (precompute.fit.figures.diffuse_shortfall)")
    args = parser.parse_args()

    measurement = load_measurement(args.measured)
    views = split_views(measurement)
    objective = Objective(measurement, views)
    count = len(views.forward_views)
    if args.fit is not None:
        cloth, label = fit_folder_brdf(args.fit, objective.measured)
    else:
        config, base_dir = load_preset_config(args.preset or DEFAULT_PRESET)
        if args.tables is not None:
            config = bake_folder_sample(config, args.tables)
        model = build_forward_model(views.forward_views, config, base_dir, seed=0)
        if args.tables is not None:
            cloth = bake_folder_brdf(model, args.tables)
            label = f"tables {args.tables}"
        else:
            sheen = specular_from_config(config)
            cloth = model(config, **sheen, relative_error=args.relative_error, seed=args.seed)
            label = f"preset {args.preset} at relative error {args.relative_error:g}"
    baseline = fit_baseline(objective)
    fitted = baseline_brdf(views.angles_deg, baseline.albedo, baseline.weight, baseline.slope)
    results = {"measured": str(args.measured),
               "model": fabric_figures(cloth[:count], objective.measured, views, swatches=cloth[count:]),
               "baseline": fabric_figures(fitted, objective.measured, views)}
    print("\n".join(figures_text(results["model"], label)))
    if args.diffuse_shortfall:
        shortfall = diffuse_shortfall(cloth[:count], objective.measured, views)
        results["diffuse_shortfall"] = {"brdf_per_sr": shortfall.tolist(), "albedo": (math.pi * shortfall).tolist(),
                                        "figures": fabric_figures(cloth[:count] + shortfall, objective.measured, views)}
        rgb = ", ".join(f"{c:.4f}" for c in shortfall)
        print("\n".join(figures_text(results["diffuse_shortfall"]["figures"],
                                      f"the same plus a Lambertian term of {rgb} /sr in R, G, B "
                                      f"(albedo {', '.join(f'{a:.3f}' for a in math.pi * shortfall)})")))
    print("\n".join(figures_text(results["baseline"], "the paper's Lambert + Cook–Torrance fitted to the plane "
                                                      "of incidence")))
    if args.json is not None:
        args.json.write_text(json.dumps({**results, "source": label}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
