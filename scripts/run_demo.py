"""The main job (`make demo`): everything ClothLight does, end to end, on the default medium.

1. Medium optics of the default red cotton (fibres in air): a table, JSON and a plot.
2. The Monte-Carlo bake of its yarn BRDF tables (cached: a second run is instant).
3. Plots of the baked tables (in-plane curves, exit maps, albedo spectra, colour swatches).
4. The virtual gonioreflectometer in Blender: the woven sample under the paper's sweep (θi = 0, 30,
   45, 60°; θv = −60 … 70°), the yarn material against the paper's baseline and a real fabric,
   MERL's red-fabric2 (the raw measurement through its neural fit, shipped with its licence:
   clothlight/validation/data/README.md), with plots, JSON and a Markdown report.

Each step runs the same public command a user would type; the script stops at the first failure
and finally prints where every output is.

    python scripts/run_demo.py --out out
"""

from __future__ import annotations

import argparse
import json
import pathlib
import subprocess
import sys
import time

REPO_ROOT = pathlib.Path(__file__).resolve().parents[1]
#: The real fabric the default is fitted to (clothlight/validation/data/README.md).
MEASURED_FABRIC = REPO_ROOT / "clothlight" / "validation" / "data" / "merl_red_fabric2.csv"


def step(title: str, command: list[str]) -> str:
    print(f"\n== {title} ==\n$ {' '.join(command)}", flush=True)
    start = time.perf_counter()
    result = subprocess.run(command, cwd=REPO_ROOT, stdout=subprocess.PIPE, text=True)
    sys.stdout.write(result.stdout[-4000:])
    if result.returncode != 0:
        raise SystemExit(f"step failed ({title}): exit code {result.returncode}")
    print(f"({time.perf_counter() - start:.1f} s)", flush=True)
    return result.stdout


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=pathlib.Path, default=REPO_ROOT / "out")
    parser.add_argument("--preset", help="a shipped preset or TOML file (default: the commands' own default)")
    args = parser.parse_args()
    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    python = sys.executable

    preset = ["--preset", args.preset] if args.preset else []
    step("1. medium optics", [python, "-m", "precompute", "optics", *preset, "--plot", str(out / "optics.png")])
    bake = json.loads(step("2. bake", [python, "-m", "precompute", "bake", *preset, "--out", str(out / "bake"),
                                       "--json"]))
    step("3. table plots", [python, "-m", "precompute", "plot", bake["brdf_table"], "--out", str(out / "plots")])
    step("4. validation sweep", [python, "-m", "clothlight.validate", "--tables", str(out / "bake"),
                                 "--measured", str(MEASURED_FABRIC), "--out", str(out / "validation")])

    print("\n== outputs ==")
    for path in sorted(p for p in out.rglob("*") if p.is_file() and "renders" not in p.parts):
        print(path)
    print(f"\nreport: {out / 'validation' / 'report.md'}")


if __name__ == "__main__":
    main()
