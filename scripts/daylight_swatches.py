"""The §6.1 swatches under daylight: a bake's cloth seen along its normal, lit by a uniform sky over the
front or the back hemisphere (the paper's Fig. 9 was a photograph in daylight).

A sky of radiance L gives the cloth the irradiance E = πL, and the cloth seen along its normal the
radiance L_o = ∫ f(ω_i, n) L cos θi dω_i, so L_o / E = 2 ∫ f̄(μ) μ dμ, f̄ the cloth BRDF (the BTDF
from behind) averaged over the light's azimuth.  The integral is a Gauss–Legendre rule in μ = cos θi
over θi ≤ :data:`MAX_INCIDENCE_DEG` (the rig's framing; the share of the sky beyond, 3 %, is left
out and the weights renormalised), each node a sun-mode view of the fit's cloth response
(``clothlight.fit.forward``; the azimuth average is the response's own, the sample turned by 0° and
90°), on the sample weave the bake records.  Unlike the swatch lit from straight behind, no node
lines the sun up with the camera: the unscattered light's share of a sky (its cone, 0.05 rad) is
left out with the grazing band.

    python scripts/daylight_swatches.py --tables BAKE [BAKE ...]

Printed per bake: L_o / E (1/sr, R G B) lit from the front and from behind, their luminance ratio,
and B/R, G/R of each (the paper: darker and redder from behind).
"""

from __future__ import annotations

import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

#: The largest incidence of the rule, degrees, and its number of nodes.
MAX_INCIDENCE_DEG = 80.0
NODES = 4
LUMINANCE = (0.2126, 0.7152, 0.0722)


def daylight_rule(nodes: int = NODES, max_incidence_deg: float = MAX_INCIDENCE_DEG):
    """Incidences θi (degrees) and weights (summing to 1) of 2 ∫ g(μ) μ dμ over θi ≤ ``max_incidence_deg``."""
    import numpy as np

    x, w = np.polynomial.legendre.leggauss(nodes)
    low = np.cos(np.radians(max_incidence_deg))
    mu = low + (1.0 - low) * 0.5 * (x + 1.0)
    weights = w * mu
    return np.degrees(np.arccos(mu)), weights / weights.sum()


def main() -> int:
    import numpy as np

    from clothlight.fit.forward import build_forward_model
    from fabric_figures import bake_folder_brdf, bake_folder_sample
    from precompute.optics.medium import DEFAULT_PRESET, load_preset_config

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tables", type=pathlib.Path, nargs="+", required=True, help="bake folders")
    args = parser.parse_args()
    theta, weights = daylight_rule()
    # the CSV convention of the fit's views (θi, φi, θo, φo): the light at φi = 180°, behind at θi > 90°
    views = [(float(t), 180.0, 0.0, 0.0) for t in theta] + [(180.0 - float(t), 180.0, 0.0, 0.0) for t in theta]
    luminance = np.array(LUMINANCE)
    for folder in args.tables:
        config, base_dir = load_preset_config(DEFAULT_PRESET)  # its yarn and sample the bake folder's
        model = build_forward_model(views, bake_folder_sample(config, folder), base_dir, seed=0)
        rgb = bake_folder_brdf(model, folder)
        front, back = (weights @ rgb[k * len(theta):(k + 1) * len(theta)] for k in (0, 1))
        ratio = luminance @ back / (luminance @ front)
        print(f"{folder}: L/E lit from the front {np.round(front, 4).tolist()}, "
              f"from behind {np.round(back, 4).tolist()} (1/sr); behind / front (luminance) {ratio:.3f}; "
              f"B/R, G/R front {front[2] / front[0]:.3f}, {front[1] / front[0]:.3f}, "
              f"behind {back[2] / back[0]:.3f}, {back[1] / back[0]:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
