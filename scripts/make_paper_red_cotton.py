"""Write precompute/presets/paper_red_cotton.toml: the paper's own measured red cotton (issue 43).

The paper gives its real red cotton's colour as channel ratios at normal light and view (Table 1:
B/R 0.08, G/R 0.011) and shows it darker and redder lit from behind (Fig. 9).  One dye does not
make that colour (a dye series of Congo red clips B/R to 0 before G/R reaches 0.011; the band-model
red clips G/R first, docs/garment.md), a shade recipe does: the particle yarn (`voided_red_cotton`, a real
red cotton's fibres and voids, fitted to MERL's red-fabric2) dyed with the paper-style band-model
red, Congo red and Evans blue, the lightest recipe with Table 1's ratios on its §6.1 front swatch
(clothlight.fit.colour_match.recipe_for_ratios; specular excluded).  Prints the swatches, front
and back, with which the header of the preset records them::

    python scripts/make_paper_red_cotton.py
"""

from __future__ import annotations

import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

import numpy as np

#: The paper's Table 1, the real red cotton at normal light and view.
TABLE_1 = {"B/R": 0.08, "G/R": 0.011}
DYES = ("red_dye_band_model.csv", "congo_red.csv", "evans_blue.csv")
OUT = pathlib.Path(__file__).resolve().parents[1] / "precompute" / "presets" / "paper_red_cotton.toml"


def luminance(rgb) -> float:
    return float(np.dot([0.2126, 0.7152, 0.0722], rgb))  # Rec.709 Y


def main() -> None:
    from clothlight.fit.colour_match import ShadeModel, recipe_config, recipe_for_ratios
    from precompute.fit.report import to_toml
    from precompute.optics.medium import load_preset_config

    base, base_dir = load_preset_config("voided_red_cotton")
    model = ShadeModel(base, base_dir, DYES, progress=lambda text: print(f"… {text}", flush=True))
    recipe = recipe_for_ratios(TABLE_1["B/R"], TABLE_1["G/R"], model)
    front, back = model.swatches(recipe, exact=True)
    ratios = {side: (rgb[2] / rgb[0], rgb[1] / rgb[0]) for side, rgb in (("front", front), ("back", back))}
    figures = (f"front swatch B/R {ratios['front'][0]:.4f}, G/R {ratios['front'][1]:.4f} (Table 1: 0.08, 0.011); "
               f"lit from behind B/R {ratios['back'][0]:.4f}, G/R {ratios['back'][1]:.4f}, "
               f"luminance {luminance(back) / luminance(front):.2f} of the front")
    recipe_text = ", ".join(f"{name.removesuffix('.csv')} {percent:.3g} %" for name, percent in zip(DYES, recipe))
    config = recipe_config(base, recipe, DYES)
    config["name"] = "paper_red_cotton"
    config["description"] = ("The paper's red cotton (Table 1, Fig. 9): voided_red_cotton's fibres and voids dyed "
                             "with the band-model red, Congo red and Evans blue to Table 1's B/R and G/R")
    header = ["# The paper's own measured red cotton (§6.1, Table 1: B/R 0.08, G/R 0.011 at normal light and view;",
              "# Fig. 9: darker and redder lit from behind), written by `python scripts/make_paper_red_cotton.py`:",
              "# voided_red_cotton's yarn (fitted to MERL's red-fabric2) with the lightest shade recipe that gives",
              f"# its §6.1 front swatch (specular excluded) Table 1's ratios: {recipe_text}, "
              f"fibre {recipe[-1]:.3g} /mm.",
              f"# {figures}.",
              "# The paper's literal medium is paper_2008."]
    OUT.write_text("\n".join(header) + "\n\n" + to_toml(config), encoding="utf-8")
    print(f"{OUT}\nrecipe: {recipe_text}, fibre absorption {recipe[-1]:.3g} /mm\n{figures}\n"
          f"front {np.round(front, 5).tolist()}, back {np.round(back, 5).tolist()}")


if __name__ == "__main__":
    main()
