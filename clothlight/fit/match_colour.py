"""``python -m clothlight.fit.match_colour``: a dyed preset whose cloth has the colour asked for.

Example (a picker's sRGB, written as ``#rrggbb`` or ``R,G,B`` in [0, 1])::

    python -m clothlight.fit.match_colour --target '#8c1c24' --out my_red.toml
    python -m precompute bake --config my_red.toml --out out/my_red      # its yarn tables
    python -m clothlight.garment bake --tables out/my_red --out out/my_red_cloth

The recipe is a mixture of the shipped red, blue and yellow dyes in the preset's yarn
(:mod:`clothlight.fit.colour_match`); the cloth's colour is the §6.1 swatch, lit and seen along the
normal.  The first run for a medium renders the swatches' response and simulates the undyed yarn
once (minutes, then cached); every colour after that takes seconds.  A colour the dyes cannot give
is refused (exit 2, with the nearest they give) unless ``--nearest`` asks for that one.

Exit codes (``precompute/exit_codes.py``): 0 done, 2 bad input, 130 interrupted (nothing written),
1 an internal error.
"""

from __future__ import annotations

try:  # a Ctrl-C before the handler in main() is in place still exits with 130, without a traceback
    import argparse
    import json
    import pathlib
    import shlex
    import sys

except KeyboardInterrupt:
    if __name__ != "__main__":
        raise
    print("interrupted", file=__import__("sys").stderr)
    raise SystemExit(130) from None


def build_parser() -> argparse.ArgumentParser:
    from precompute import bounds
    from precompute.optics.medium import DEFAULT_PRESET, preset_names

    parser = argparse.ArgumentParser(
        prog="python -m clothlight.fit.match_colour",
        description="Solve the dye recipe (red, blue, yellow: % of fibre weight) that gives the cloth, lit and seen "
        "along its normal, the sRGB colour asked for, within CIEDE2000 2; write it as a preset TOML.")
    parser.add_argument("--target", required=True, metavar="#RRGGBB|R,G,B",
                        help="the colour: #rrggbb, or three sRGB values in [0, 1]")
    source = parser.add_mutually_exclusive_group()
    source.add_argument("--preset", default=DEFAULT_PRESET,
                        help=f"the yarn to dye: a shipped preset, {', '.join(preset_names())} "
                        f"(default {DEFAULT_PRESET}); its own dye is replaced")
    source.add_argument("--config", type=pathlib.Path, help="the yarn to dye as a preset TOML file")
    parser.add_argument("--out", type=pathlib.Path, required=True, help="the preset TOML file to write")
    parser.add_argument("--nearest", action="store_true",
                        help="write the nearest recipe when the dyes cannot reach the colour (default: refuse)")
    parser.add_argument("--seed", type=bounds.SEED.argument("--seed"), default=0,
                        help="seed of the series' transport and the response's renders (default 0)")
    parser.add_argument("--cache-dir", type=pathlib.Path, help="cache folder (default: ClothLight's)")
    parser.add_argument("--json", action="store_true", help="print the recipe as JSON on stdout")
    return parser


def main(argv=None) -> int:
    from precompute import exit_codes

    return exit_codes.run_cli(lambda: _main(sys.argv[1:] if argv is None else argv))


def _main(argv) -> int:
    from precompute import exit_codes, outputs
    from precompute.cli.arguments import parse_arguments, preset_argument
    from precompute.errors import ParameterError
    from precompute.optics.medium import load_preset_config

    args = parse_arguments(build_parser(), argv)
    from .colour_match import MATCH_DELTA_E, parse_srgb

    target = parse_srgb(args.target, "--target")
    out = outputs.check_writable_file(args.out, "--out", what="a preset TOML file")
    if args.cache_dir is not None:
        outputs.check_writable_folder(args.cache_dir, "--cache-dir", what="a cache folder")
    base, base_dir = load_preset_config(preset_argument(args))

    from .colour_match import ShadeModel, match_colour

    # Blender prints and drops an exception raised in a render: a Ctrl-C while the swatch response
    # renders (and while bpy is imported) is held and raised between renders instead.
    held = exit_codes.DeferredInterrupt("interrupting after the current render…")
    model = ShadeModel(base, base_dir, cache_dir=args.cache_dir, seed=args.seed,
                       progress=lambda text: print(text, file=sys.stderr, flush=True),
                       building=lambda done, total: held.check(), while_building=lambda: held)
    result = match_colour(target, model)
    recipe = recipe_line(result)
    if not result.reached and not args.nearest:
        raise ParameterError("--target", args.target,
                             f"a colour the dyes reach on this yarn within ΔE2000 {MATCH_DELTA_E:g} (the nearest, "
                             f"{recipe}, is ΔE2000 {result.delta_e:.2f} away; --nearest writes it)")
    command = "python -m clothlight.fit.match_colour " + shlex.join(argv)
    text = preset_text(result, target, base, base_dir, out.stem, f"solved by `{command}`")
    out.parent.mkdir(parents=True, exist_ok=True)
    partial = out.with_name(f".{out.name}.partial")
    partial.write_text(text, encoding="utf-8")
    partial.replace(out)
    summary = {"target_srgb": target.tolist(), "dyes": list(result.dyes),
               "dye_percent": result.recipe[:-1].tolist(), "fibre_absorption_per_mm": float(result.recipe[-1]),
               "cloth_rgb_linear": result.cloth_rgb.tolist(),
               "delta_e_2000": result.delta_e, "reached": result.reached, "evaluations": result.evaluations,
               "seconds": result.seconds, "preset": str(out)}
    if args.json:
        print(json.dumps(summary, indent=1))
    else:
        print(f"{out}: {recipe}; ΔE2000 {result.delta_e:.2f} ({result.evaluations} evaluations, "
              f"{result.seconds:.1f} s)")
    return 0


def recipe_line(result) -> str:
    """A recipe (:class:`.colour_match.ShadeMatch`) in one line: each dye used, % of fibre weight, and the
    fibre's own absorption."""
    recipe = ", ".join(f"{name.removesuffix('.csv')} {percent:.3g} %"
                       for name, percent in zip(result.dyes, result.recipe) if percent > 0)
    return recipe + f" of fibre weight, fibre absorption {result.recipe[-1]:.3g} /mm"


def preset_text(result, target, base: dict, base_dir, name: str, solved_by: str) -> str:
    """The preset TOML of a recipe (:class:`.colour_match.ShadeMatch`) for the sRGB ``target`` on the yarn
    ``base`` (a preset's TOML content, its files resolving in ``base_dir``), named ``name``: a header
    saying how it was solved (``solved_by``) and how near it comes, then the preset, its data files by
    absolute path where they are not shipped ones."""
    from precompute.fit.report import absolute_data_files, to_toml

    recipe = recipe_line(result)
    hex_target = "#" + "".join(f"{round(255 * v):02x}" for v in target)
    header = [f"# Shade recipe for sRGB {hex_target}, {solved_by}:",
              f"# {recipe}; the cloth lit and seen along its normal (specular excluded) is CIEDE2000 "
              f"{result.delta_e:.2f} from the colour asked for (clothlight/fit/colour_match.py)."]
    config = dict(result.config)
    absolute_data_files(config, base_dir)
    config["name"] = name
    config["description"] = f"{base.get('description', 'a yarn')}; dyed to sRGB {hex_target} ({recipe})"
    return "\n".join(header) + "\n\n" + to_toml(config)


if __name__ == "__main__":
    raise SystemExit(main())
