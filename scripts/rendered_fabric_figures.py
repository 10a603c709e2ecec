"""Issue 43's band figures of a rendered validation sweep: each material of a ``python -m
clothlight.validate`` report against the measurement it was run with, from its ``results.json``.

Per material: the report's relative RMS per channel and pooled over RGB and its shape correlation in
red (the 56 in-plane views of the paper's sweep the fabric has), the backscatter in red at the views of
:data:`precompute.fit.figures.BACKSCATTER_VIEWS` and the off-specular B/R and G/R medians, model over
measured, at the views :func:`precompute.fit.figures.off_specular` picks (θi ≤ 45°, |θv| ≥ 20°,
20° from the mirror), the figures ``scripts/fabric_figures.py`` gives of the fit's forward model.

    python -m clothlight.validate --tables BAKE --material yarn \\
        --measured ../shared/data/real_fabrics/neural/red-fabric2.csv --out DIR
    python scripts/rendered_fabric_figures.py DIR/results.json

It first names the azimuths the report's sample was averaged at (``sample_azimuths_deg``; the fit's
forward model averages its preset's ``[sample] azimuths_deg``, which ``--tables`` brings by default).
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from precompute.fit.figures import BACKSCATTER_VIEWS, off_specular


def rendered_figures(results: dict) -> dict[str, dict]:
    """The figures (module docstring) of every material in a validation report's ``results``."""
    measured = {(float(theta_i), row[0]): np.array(row[1:4]) for theta_i, rows in
                results["measurement"]["in_plane"].items() for row in rows}
    figures = {}
    for name, material in results["materials"].items():
        model = {(v["theta_i_deg"], v["theta_v_deg"]): np.array(v["brdf_rgb"]) for v in material["views"]}
        shared = [key for key in model if key in measured]
        off = [(ti, tv) for ti, tv in shared if off_specular(ti, tv)]

        def median_ratio(channel: int) -> float:
            return float(np.median([model[k][channel] / model[k][0] for k in off])
                         / np.median([measured[k][channel] / measured[k][0] for k in off]))

        metrics = material["metrics"]["brdf_rgb"]
        figures[name] = {
            "relative_rms": {channel: metrics[channel]["relative_rms"] for channel in ("R", "G", "B", "RGB")},
            "shape_correlation_red": metrics["R"]["shape_correlation"],
            "backscatter_red": {f"{ti:g}/{tv:g}": float(model[(ti, tv)][0] / measured[(ti, tv)][0])
                                for ti, tv in BACKSCATTER_VIEWS if (ti, tv) in model and (ti, tv) in measured},
            "off_specular_views": len(off),
            "off_specular_B/R": median_ratio(2),
            "off_specular_G/R": median_ratio(1),
        }
    return figures


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("results", type=pathlib.Path, help="a validation report's results.json")
    args = parser.parse_args()
    results = json.loads(args.results.read_text())
    azimuths = results.get("sample_azimuths_deg")  # absent from reports written before sweeps recorded them
    if azimuths:
        print(("sample averaged over the warp at " if len(azimuths) > 1 else "sample at one turn, the warp at ")
              + ", ".join(f"{a:g}°" for a in azimuths) + " from the plane of incidence")
    for name, f in rendered_figures(results).items():
        rms = f["relative_rms"]
        back = ", ".join(f"{view} {ratio:.2f}" for view, ratio in f["backscatter_red"].items())
        print(f"{name}: relative RMS R {rms['R']:.3f}, G {rms['G']:.3f}, B {rms['B']:.3f}, pooled {rms['RGB']:.3f}; "
              f"shape correlation in R {f['shape_correlation_red']:.3f}; backscatter R (θi/θv) {back}; "
              f"off-specular ({f['off_specular_views']} views) B/R {f['off_specular_B/R']:.2f}, "
              f"G/R {f['off_specular_G/R']:.2f} of the fabric's")
    return 0


if __name__ == "__main__":
    sys.exit(main())
