"""The §6.1 swatches of bake folders split into the light the yarn scattered and the light it let
through unscattered: what makes a yarn brighter lit from behind than from the front.

The fit's swatches (``clothlight.fit.forward.SWATCH_VIEWS``: the sun straight in front and straight
behind, normal view) through its cloth response, without the specular term: luminance (Rec.709)
of the cloth BRDF lit from the front and the BTDF lit from behind, with and without the unscattered
light (``unscattered.exr``), and their ratios.  The response is the one ``python -m clothlight.fit``
renders for ``--measured`` (cached).

    python scripts/swatch_parts.py --measured ../shared/data/real_fabrics/neural/red-fabric2.csv \\
        fibre_bake red_cotton_bake
"""

from __future__ import annotations

import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

#: Rec.709 luminance of linear RGB.
LUMINANCE = (0.2126, 0.7152, 0.0722)


def main() -> int:
    import numpy as np

    from clothlight.fit.forward import build_forward_model
    from clothlight.validation.response import TableLayout
    from precompute.fit.objective import load_measurement, split_views
    from precompute.optics import ballistic
    from precompute.optics.medium import load_preset_config
    from precompute.tables import folder as table_folder

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--measured", type=pathlib.Path, required=True, help="a measured-data CSV (its views)")
    parser.add_argument("folders", nargs="+", type=pathlib.Path, help="yarn bake folders")
    args = parser.parse_args()

    views = split_views(load_measurement(args.measured))
    config, base_dir = load_preset_config("voided_red_cotton")  # the response depends on no medium
    model = build_forward_model(views.forward_views, config, base_dir, seed=0)
    luminance = np.array(LUMINANCE)
    for folder in args.folders:
        checked = table_folder.check_yarn_table_folder(folder.resolve())
        summary, files = checked.summary, table_folder.YARN_TABLE_FILES
        layout = TableLayout(summary["incidence_resolution"], summary["exit_resolution"],
                             summary["unscattered_samples"], float(summary["host_index"]),
                             ballistic.SUN_MODE_SPREAD_RAD)
        atlas = checked.tables[files["brdf"]].pixels[..., :3]
        attenuation = checked.tables[files["unscattered"]].pixels[..., :3]
        swatches = {name: model.cloth_brdf(atlas, table, layout, specular_weight=0.0,
                                           specular_slope=1.0)[-model.swatch_count:] @ luminance
                    for name, table in (("all", attenuation), ("scattered", None))}
        (front, back), (_, back_scattered) = swatches["all"], swatches["scattered"]
        print(f"{folder}: front {front:.4g} 1/sr; behind {back:.4g} 1/sr, {back_scattered:.4g} without the "
              f"unscattered light; behind / front {back / front:.3g}, {back_scattered / front:.3g} without it")
    return 0


if __name__ == "__main__":
    sys.exit(main())
