"""The validation sweep on the close-up geometry against the plain-tube validation sample (issue 46).

Runs the virtual gonioreflectometer (:func:`clothlight.blender.validation.run.run_validation`, the
code path of ``python -m clothlight.validate``) with the same yarn material (the preset's bake, sun
mode), the same sun and the same angles, resolution, samples and seed on:

- ``plain``: the rig's own sample, :data:`clothlight.blender.validation.rig.VALIDATION_WEAVE` (12 × 12
  round single tubes at 0.5 mm), what ``python -m clothlight.validate`` builds by itself;
- ``closeup``: the default close-up, ``sheeting_weave(preset)`` (cotton sheeting at 0.4 mm, yarns
  flattened 1.6 : 1, the preset's plies at its twist angle, seeded irregularity), without its
  flyaway fibres: the rig measures one mesh object, and the fibres are a curves object of their own;

and, to say where a difference comes from, the steps between the two, one change at a time
(``--no-steps`` skips them): the plain sample with the close-up's plies and twist; round tubes at the
sheeting's spacing; the sheeting's flattened single tubes; those with plies and twist; the plain
sample again with another Cycles seed (the render noise); and the plain sample and the close-up
with the yarn material's sheen off (SpecularWeight 0), the one against the other.  Each sweep is
compared with the plain sample (``Sample.reference``) over the diffuse views (at least
``--mirror-margin`` degrees from the mirror direction θv = θi, docs/validation.md's convention) and
over all views, and with the raw-data fabric red-fabric2
(``--measured``; MERL's raw measurement through a neural fit, the same file as
``../shared/data/real_fabrics/neural/red-fabric2.csv``).

    python scripts/compare_closeup_sweep.py            # the rig's default angles, 128 px, 16 samples: ~8 min
    python scripts/compare_closeup_sweep.py --quick    # 2 incidences, 5 views, 32 px, 4 samples: ~1 min

The yarn tables are the preset's bake (``python -m precompute bake --preset PRESET``, as ``make demo``
bakes them; cached) unless ``--tables`` names a bake folder.  Figures and their meaning:
docs/closeups.md, "The validation sweep on the close-up geometry".

Outputs under ``--out`` (default ``out/closeup_sweep``): one validation folder per sample (its
``results.json``, ``report.md``, ``sweeps.png``) and ``comparison.json`` with every figure printed.
``--reuse`` reads a sample's earlier ``results.json`` when its settings are the same instead of
rendering it again.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import subprocess
import sys
import time
from dataclasses import dataclass

import numpy as np

REPO_ROOT = pathlib.Path(__file__).resolve().parent.parent
if str(REPO_ROOT) not in sys.path:
    sys.path.insert(0, str(REPO_ROOT))

from precompute.fit.measured_data import read_measurement, relative_rms_error  # noqa: E402

MEASURED_FABRIC = REPO_ROOT / "clothlight" / "validation" / "data" / "merl_red_fabric2.csv"
CHANNELS = {"R": [0], "G": [1], "B": [2], "RGB": [0, 1, 2]}


@dataclass(frozen=True)
class Sample:
    """A sample to sweep: what it is, its weave (None: the rig's own), the Cycles seed's offset, the
    yarn material's SpecularWeight (None: the bake's), and the sample it is compared with."""

    description: str
    weave: object
    seed: int = 0
    specular_weight: float | None = None
    reference: str = "plain"


QUICK = {"incidences": (0.0, 45.0), "views": (-60.0, -30.0, 0.0, 30.0, 60.0), "resolution": 32, "samples": 4}


def samples(preset: str, steps: bool) -> dict:
    """The samples to sweep, {name: Sample}; ``plain`` and ``closeup`` first, then the steps between them."""
    import dataclasses

    from clothlight.blender.validation.rig import VALIDATION_WEAVE
    from clothlight.weave import WeaveParameters
    from clothlight.weave.closeup import sheeting_weave

    closeup = sheeting_weave(preset)
    regular = {"spacing_jitter": 0.0, "height_jitter": 0.0, "ply_radius_jitter": 0.0}
    chosen = {
        "plain": Sample("plain tubes, the rig's validation sample (12 × 12, 0.5 mm, round, 0.2 mm across, 1 ply)",
                        None),
        "closeup": Sample("the close-up, sheeting_weave(): 0.4 mm, flattened, plies and twist, irregular; no fibres",
                          closeup),
    }
    if steps:
        chosen |= {
            "plain_plies": Sample("plain tubes with the close-up's plies and twist (grooves only)",
                                  dataclasses.replace(VALIDATION_WEAVE, ply_count=closeup.ply_count,
                                                      twist_angle_deg=closeup.twist_angle_deg)),
            "round_dense": Sample("round single tubes at the sheeting's 0.4 mm (density only)",
                                  WeaveParameters(warp_count=closeup.warp_count, weft_count=closeup.weft_count,
                                                  spacing_mm=closeup.spacing_mm, segments_per_crossing=48)),
            "sheeting_single": Sample("the sheeting's flattened single tubes, regular (density and flattening)",
                                      sheeting_weave(preset, ply_count=1, twist_angle_deg=0.0, **regular)),
            "sheeting_plies": Sample("the sheeting with plies and twist, regular (the close-up without jitters)",
                                     sheeting_weave(preset, **regular)),
            "plain_seed1": Sample("plain tubes again, Cycles seed + 1 (the render noise)", None, seed=1),
            "plain_nosheen": Sample("plain tubes, the yarn material without its sheen (SpecularWeight 0)", None,
                                    specular_weight=0.0, reference="plain_nosheen"),
            "closeup_nosheen": Sample("the close-up without the sheen, against plain_nosheen", closeup,
                                      specular_weight=0.0, reference="plain_nosheen"),
        }
    return chosen


def bake_tables(preset: str, out: pathlib.Path) -> pathlib.Path:
    """The preset's yarn tables, as ``make demo`` bakes them (cached in ~/.cache/clothlight)."""
    folder = out / "bake"
    subprocess.run([sys.executable, "-m", "precompute", "bake", "--preset", preset, "--out", str(folder), "--json"],
                   check=True, stdout=subprocess.DEVNULL, cwd=REPO_ROOT)
    return folder


def sweep(name: str, sample: Sample, args, tables: pathlib.Path) -> dict:
    """One validation sweep of ``sample`` into ``out/name``; its results."""
    from clothlight.blender import scene_files
    from clothlight.blender.validation.rig import RigSettings
    from clothlight.blender.validation.run import run_validation
    from clothlight.validate import stdout_to_stderr

    settings = RigSettings(incidences_deg=args.incidences, views_deg=args.views, resolution=args.resolution,
                           samples=args.samples, seed=args.seed + sample.seed)
    folder = args.out / name
    previous = folder / "results.json"
    if args.reuse and previous.is_file():
        results = json.loads(previous.read_text(encoding="utf-8"))
        wanted = {"incidences_deg": list(settings.incidences_deg), "views_deg": list(settings.views_deg),
                  "resolution": settings.resolution, "samples": settings.samples, "seed": settings.seed,
                  "tables_dir": str(tables), "measured_csv": str(args.measured)}
        specular = results["settings"].get("yarn_specular") or {}
        if (all(results["settings"].get(key) == value for key, value in wanted.items())
                and (sample.specular_weight is None) == ("set to" not in specular.get("source", ""))):
            print(f"{name}: reusing {previous}", file=sys.stderr)
            return results
    with stdout_to_stderr():
        scene_files.open_empty_file()
        start = time.perf_counter()
        results = run_validation(sample.weave, folder, scheduler=None, materials=("yarn",), tables_dir=tables,
                                 measured_csv=args.measured, settings=settings, swatches=False,
                                 specular_weight=sample.specular_weight)
    print(f"{name}: swept in {time.perf_counter() - start:.0f} s (patch {results['settings']['patch_mm']:g} mm)",
          file=sys.stderr)
    return results


def curve(results: dict) -> tuple[list[tuple[float, float]], np.ndarray, np.ndarray]:
    """The views (θi, θv), the calibrated BRDF (n, 3) and the cloth coverage (n,) of a sweep."""
    views = results["materials"]["yarn"]["views"]
    return ([(v["theta_i_deg"], v["theta_v_deg"]) for v in views], np.array([v["brdf_rgb"] for v in views]),
            np.array([v["coverage"] for v in views]))


def is_diffuse(theta_i: float, theta_v: float, margin: float) -> bool:
    """A view at least ``margin`` degrees from the mirror direction θv = θi (docs/validation.md)."""
    return abs(theta_v - theta_i) >= margin


def compare(model: np.ndarray, reference: np.ndarray) -> dict:
    """``model`` (n, 3) against ``reference``: the relative RMS (RMS difference over the reference's
    RMS, as the validation report gives it) per channel and pooled over R, G, B; the mean and the
    range of model / reference per channel; and, after the one scale k that fits ``model`` best to
    ``reference`` (least squares, all channels: the colour kept), k and the relative RMS left."""
    ratio = model / reference
    figures = {name: relative_rms_error(model[:, cols], reference[:, cols]) for name, cols in CHANNELS.items()}
    figures["mean_ratio"] = [float(r) for r in ratio.mean(axis=0)]
    figures["min_ratio"] = [float(r) for r in ratio.min(axis=0)]
    figures["max_ratio"] = [float(r) for r in ratio.max(axis=0)]
    k = float((model * reference).sum() / (model * model).sum())
    figures["best_scale"] = k
    figures["RGB_after_best_scale"] = relative_rms_error(k * model, reference)
    return figures


def analyse(all_results: dict, references: dict, measured_csv: pathlib.Path, margin: float) -> dict:
    """Every figure of the comparison (module docstring), by sample; ``references``: {sample: the
    sample it is compared with}."""
    measurement = read_measurement(measured_csv)
    views = curve(all_results["plain"])[0]
    diffuse = np.array([is_diffuse(i, v, margin) for i, v in views])
    fabric = [measurement.at(i, v) for i, v in views]
    with_fabric = np.array([f is not None for f in fabric])
    fabric_rgb = np.array([f if f is not None else [np.nan] * 3 for f in fabric], dtype=float)
    out = {"views": len(views), "diffuse_views": int(diffuse.sum()), "mirror_margin_deg": margin, "samples": {}}
    for name, results in all_results.items():
        these, brdf, cover = curve(results)
        _, ref, ref_cover = curve(all_results[references[name]])
        if these != views:
            raise ValueError(f"{name} was swept on other views than the plain sample")
        if not np.all(np.isfinite(brdf)) or not np.all(brdf > 0):
            raise ValueError(f"{name}: a BRDF that is not finite and positive in every view")
        entry = {"reference": references[name], "patch_mm": results["settings"]["patch_mm"],
                 "seed": results["settings"]["seed"], "yarn_specular": results["settings"].get("yarn_specular"),
                 "coverage_diffuse_mean": float(cover[diffuse].mean()),
                 "coverage_ratio_diffuse_mean": float((cover / ref_cover)[diffuse].mean()),
                 "vs_reference_diffuse": compare(brdf[diffuse], ref[diffuse]),
                 "vs_reference_all": compare(brdf, ref),
                 # the BRDF per unit of cloth seen: what is left of the difference once the coverage is taken out
                 "per_coverage_vs_reference_diffuse": compare((brdf / cover[:, None])[diffuse],
                                                              (ref / ref_cover[:, None])[diffuse])}
        for label, mask in (("diffuse", diffuse & with_fabric), ("all", with_fabric)):
            entry[f"vs_fabric_{label}"] = compare(brdf[mask], fabric_rgb[mask])
            entry[f"vs_fabric_{label}"]["views"] = int(mask.sum())
        entry["vs_fabric_rig_metrics_rgb"] = results["materials"]["yarn"]["metrics"]["brdf_rgb"]["RGB"]["relative_rms"]
        out["samples"][name] = entry
    return out


def print_table(analysis: dict) -> None:
    print(f"{analysis['diffuse_views']} diffuse views (≥ {analysis['mirror_margin_deg']:g}° from the mirror "
          f"direction θv = θi) of {analysis['views']}; relative RMS of the calibrated BRDF against the sample named "
          f"under 'vs' (R, G, B, RGB pooled: diffuse views; all: every view; /cover: the BRDF per cloth pixel; "
          f"scaled: after the best common scale k) and against red-fabric2 (fabric: diffuse views, all: every view)")
    print(f"{'sample':<16} {'vs':<13} {'cover':>6} {'R':>6} {'G':>6} {'B':>6} {'RGB':>6} {'all':>6} "
          f"{'ratio R, G, B':>18} {'/cover':>6} {'k':>5} {'scaled':>6} {'fabric':>6} {'all':>6}")
    for name, e in analysis["samples"].items():
        d = e["vs_reference_diffuse"]
        ratios = ", ".join(f"{r:.3f}" for r in d["mean_ratio"])
        print(f"{name:<16} {e['reference']:<13} {e['coverage_diffuse_mean']:6.3f} {d['R']:6.2%} {d['G']:6.2%} "
              f"{d['B']:6.2%} {d['RGB']:6.2%} {e['vs_reference_all']['RGB']:6.2%} {ratios:>18} "
              f"{e['per_coverage_vs_reference_diffuse']['RGB']:6.2%} {d['best_scale']:5.3f} "
              f"{d['RGB_after_best_scale']:6.2%} {e['vs_fabric_diffuse']['RGB']:6.1%} {e['vs_fabric_all']['RGB']:6.1%}")
    print()
    for name, text in analysis["descriptions"].items():
        print(f"{name:<16} {text}")
    print()
    for name in ("plain", "closeup"):
        f = analysis["samples"][name]["vs_fabric_diffuse"]
        print(f"{name} against red-fabric2, diffuse views: R {f['R']:.1%}, G {f['G']:.1%}, B {f['B']:.1%}, "
              f"RGB {f['RGB']:.1%}; model / fabric on average {', '.join(f'{r:.3f}' for r in f['mean_ratio'])}; "
              f"every view (the rig's report): {analysis['samples'][name]['vs_fabric_rig_metrics_rgb']:.1%}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="tiny settings: checks that it runs, in about a minute")
    parser.add_argument("--preset", default="voided_red_cotton")
    parser.add_argument("--tables", type=pathlib.Path, help="bake folder (default: bake the preset under --out)")
    parser.add_argument("--measured", type=pathlib.Path, default=MEASURED_FABRIC)
    parser.add_argument("--out", type=pathlib.Path, default=REPO_ROOT / "out" / "closeup_sweep")
    parser.add_argument("--incidences", type=float, nargs="+")
    parser.add_argument("--views", type=float, nargs="+")
    parser.add_argument("--resolution", type=int)
    parser.add_argument("--samples", type=int)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--mirror-margin", type=float, default=20.0,
                        help="diffuse views: at least this far from θv = θi, degrees (default 20)")
    parser.add_argument("--no-steps", dest="steps", action="store_false",
                        help="only the plain and the close-up sample")
    parser.add_argument("--reuse", action="store_true", help="reuse a sample's results.json of the same settings")
    args = parser.parse_args(argv)
    from clothlight.blender.validation.rig import DEFAULT_RESOLUTION, DEFAULT_SAMPLES
    from clothlight.validation.framing import DEFAULT_INCIDENCES_DEG, DEFAULT_VIEWS_DEG

    defaults = QUICK if args.quick else {"incidences": DEFAULT_INCIDENCES_DEG, "views": DEFAULT_VIEWS_DEG,
                                         "resolution": DEFAULT_RESOLUTION, "samples": DEFAULT_SAMPLES}
    for key, value in defaults.items():
        if getattr(args, key) is None:
            setattr(args, key, value)
    args.incidences, args.views = tuple(map(float, args.incidences)), tuple(map(float, args.views))
    if args.quick and args.out == REPO_ROOT / "out" / "closeup_sweep":
        args.out = REPO_ROOT / "out" / "closeup_sweep_quick"
    args.out.mkdir(parents=True, exist_ok=True)
    tables = (args.tables or bake_tables(args.preset, args.out)).resolve()
    args.measured = args.measured.resolve()
    chosen = samples(args.preset, args.steps)
    all_results = {name: sweep(name, sample, args, tables) for name, sample in chosen.items()}
    analysis = analyse(all_results, {name: sample.reference for name, sample in chosen.items()}, args.measured,
                       args.mirror_margin)
    analysis["settings"] = {"preset": args.preset, "tables": str(tables), "measured": str(args.measured),
                            "incidences_deg": list(args.incidences), "views_deg": list(args.views),
                            "resolution": args.resolution, "samples": args.samples, "seed": args.seed,
                            "material": "yarn (sun mode)", "flyaway_fibres": "not measured (a curves object)"}
    analysis["descriptions"] = {name: sample.description for name, sample in chosen.items()}
    (args.out / "comparison.json").write_text(json.dumps(analysis, indent=1), encoding="utf-8")
    print_table(analysis)
    closeup, plain = analysis["samples"]["closeup"], analysis["samples"]["plain"]
    verdict = "within" if closeup["vs_reference_diffuse"]["RGB"] <= 0.05 else "NOT within"
    closer = "the close-up" if closeup["vs_fabric_diffuse"]["RGB"] < plain["vs_fabric_diffuse"]["RGB"] else "plain"
    print(f"\nclose-up vs plain over the diffuse views: {closeup['vs_reference_diffuse']['RGB']:.1%} RGB, {verdict} "
          f"5 %; closer to red-fabric2 there: {closer}")
    print(f"figures: {args.out / 'comparison.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
