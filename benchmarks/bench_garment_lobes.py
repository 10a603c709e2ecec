"""The garment's general-lighting closure mixture against the cloth BSDF it stands for, in NumPy.

At the validation sweep's configurations (``clothlight.validation.framing``: sun and camera in the
plane of incidence, here along the warp and along the weft), ρ of a cloth bake's front side as the
sun mode evaluates it — the tables' ρ plus w_s f_CT cos θ_i V — against the mixture of each lobe set,
its coloured lobes fitted at the sweep's own views as the bake fits them
(``clothlight.garment.tables.FIT_WEIGHTING``) and the specular term carried as the bake carries it
(``tables.gloss_weights`` and the Metallic lobe) or, as before, by a plain Beckmann lobe fitted to the
term tabulated at the cells' centres.  Prints the RMS over the configurations of (mixture − ρ) / ρ
per channel and pooled, and per incidence the mixture / ρ in red.  No Blender; seconds.

    python -m precompute bake --preset voided_red_cotton --out out/voided_red_cotton
    python -m clothlight.garment bake --tables out/voided_red_cotton --out out/red_cotton_cloth
    python benchmarks/bench_garment_lobes.py --cloth-tables out/red_cotton_cloth
"""

import argparse
import dataclasses
import json
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

import numpy as np

from clothlight.garment.tables import (
    FIT_WEIGHTING,
    GARMENT_LOBES,
    SPECULAR_LOBE,
    SPECULAR_VISIBILITY_FILES,
    BRDF_FILES,
    SUMMARY_FILE,
    gloss_weights,
)
from clothlight.validation.framing import DEFAULT_INCIDENCES_DEG, DEFAULT_VIEWS_DEG
from precompute.optics.cook_torrance import cook_torrance, direction
from precompute.tables import closure_fit, cycles_closures
from precompute.tables.exr import read_table
from precompute.tables.grids import AngularGrid
from precompute.tables.layout import brdf_atlas, interpolate_rho, rho_from_brdf_atlas

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--cloth-tables", type=pathlib.Path, required=True, help="a cloth bake folder")
args = parser.parse_args()
summary = json.loads((args.cloth_tables / SUMMARY_FILE).read_text())
n_i, specular = summary["incidence_resolution"], summary["specular"]
shape = closure_fit.LobeShape(**summary["lobe_shape"])
rho_atlas = read_table(args.cloth_tables / BRDF_FILES["front"]).pixels[..., :3].astype(float)
visibility_atlas = read_table(args.cloth_tables / SPECULAR_VISIBILITY_FILES["front"]).pixels[..., :1].astype(float)

# The sweep: negative views on the light's side.
sweep = [(theta_i, theta_v, plane) for plane in (0.0, 90.0) for theta_i in DEFAULT_INCIDENCES_DEG
         for theta_v in DEFAULT_VIEWS_DEG]
light = np.array([direction(theta_i, 180.0 + plane) for theta_i, _, plane in sweep])
view = np.array([direction(abs(theta_v), plane if theta_v >= 0 else 180.0 + plane) for _, theta_v, plane in sweep])
views, view_of = np.unique(view.round(12), axis=0, return_inverse=True)
view_of = view_of.ravel()
normal = closure_fit.YARN_NORMAL


def specular_term(toward_sun, toward_camera, visibility):
    return (specular["weight"] * cook_torrance(toward_sun, toward_camera, specular["slope"], specular["ior"])
            * np.maximum(toward_sun[..., 2], 0.0) * visibility)


exact = interpolate_rho(rho_atlas, n_i, light, view) + specular_term(
    light, view, interpolate_rho(visibility_atlas, n_i, light, view)[:, 0])[:, None]

# The specular lobe as the bake weighs it, and as it did before: a plain Beckmann lobe fitted to the
# term at the cells' centres (the response's tabulation).
shipped_gloss = gloss_weights(rho_from_brdf_atlas(visibility_atlas, n_i)[..., 0], specular, n_i, views)
cell_light = AngularGrid("sphere", n_i).cell_centers()[:, None, :]
cell_view = AngularGrid("hemisphere", summary["exit_resolution"]).cell_centers()[None, :, :]
tabulated = specular_term(cell_light, cell_view, rho_from_brdf_atlas(visibility_atlas, n_i)[..., 0])
fitted_gloss, _ = closure_fit.fit_closure_weights(brdf_atlas(np.repeat(tabulated[..., None], 3, axis=-1)), n_i, shape,
                                                  lobes=(SPECULAR_LOBE,), views=views, weighting=FIT_WEIGHTING)


def mixture(lobes, lobe_shape=shape, gloss="shipped"):
    """The mixture of the coloured ``lobes`` and the specular lobe at every sweep configuration (n, 3)."""
    weights, _ = closure_fit.fit_closure_weights(rho_atlas, n_i, lobe_shape, lobes=lobes, views=views,
                                                 weighting=FIT_WEIGHTING)
    result = np.zeros_like(exact)
    for k, toward_camera in enumerate(views):
        here = view_of == k
        result[here] = closure_fit.lobe_responses(toward_camera, light[here], lobe_shape, lobes) @ weights[k]
        if gloss == "shipped":
            result[here] += (shipped_gloss[k] * cycles_closures.beckmann_conductor_eval(
                normal, toward_camera, light[here], specular["slope"], specular["ior"]))[:, None]
        else:
            result[here] += (fitted_gloss[k, 0, 0] * cycles_closures.beckmann_reflection_eval(
                normal, toward_camera, light[here], specular["slope"]))[:, None]
    return result


def report(label, predicted):
    error = (predicted - exact) / exact
    rms = np.sqrt(np.mean(error**2, axis=0))
    print(f"{label:62s} RGB {np.sqrt(np.mean(error**2)):6.1%}   R {rms[0]:6.1%}  G {rms[1]:6.1%}  B {rms[2]:6.1%}")
    return predicted / exact


coloured = tuple(k for k in GARMENT_LOBES if k != SPECULAR_LOBE)
before = ("diffuse", "translucent", "fibre_transmission")
print(f"{args.cloth_tables}: {len(sweep)} configurations, the mixture's relative RMS against the cloth BSDF")
ratios = {"before": report("before: diffuse, translucent, fibre transmission; gloss fitted to the table",
                           mixture(before, gloss="fitted"))}
report("the same, the specular lobe as shipped", mixture(before))
report("  + uniform", mixture(before + ("uniform",)))
report("  + retro-reflection", mixture(before + ("retroreflection",)))
ratios["shipped"] = report(f"shipped: {', '.join(coloured)}", mixture(coloured))
report("shipped, the specular lobe fitted to the table", mixture(coloured, gloss="fitted"))
for alpha in (0.3, 0.5):
    report(f"shipped, retro-reflection α {alpha}",
           mixture(coloured, dataclasses.replace(shape, retroreflection_alpha=alpha)))
report("shipped without diffuse", mixture(tuple(k for k in coloured if k != "diffuse")))
report("shipped + fibre reflection", mixture(coloured + ("fibre_reflection",)))
for name, ratio in ratios.items():
    print(f"{name}: mixture / ρ in red, along the warp; columns θv {', '.join(f'{v:g}' for v in DEFAULT_VIEWS_DEG)}")
    for a, theta_i in enumerate(DEFAULT_INCIDENCES_DEG):
        row = ratio[a * len(DEFAULT_VIEWS_DEG):(a + 1) * len(DEFAULT_VIEWS_DEG), 0]
        print(f"  θi {theta_i:4g}: " + " ".join(f"{x:5.2f}" for x in row))
