"""Build the ClothLight extension zip with Blender's own extension tool, then validate it.

Runs ``blender_ext.py build`` and ``validate`` from the installed bpy wheel
(the same code as ``blender --command extension build``).  Prints the zip path.

    python scripts/build_extension.py --output-dir dist
"""

from __future__ import annotations

import argparse
import importlib.util
import pathlib
import subprocess
import sys

REPO_ROOT = pathlib.Path(__file__).resolve().parents[1]


def blender_extension_tool() -> pathlib.Path:
    spec = importlib.util.find_spec("bpy")
    if spec is None or spec.origin is None:
        raise SystemExit("bpy is not installed: run `make setup`")
    tools = sorted(pathlib.Path(spec.origin).parent.glob("*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))
    if not tools:
        raise SystemExit("Blender's extension tool (blender_ext.py) is missing from the bpy wheel")
    return tools[-1]


def build_extension(output_dir: pathlib.Path) -> pathlib.Path:
    output_dir.mkdir(parents=True, exist_ok=True)
    tool = blender_extension_tool()
    before = set(output_dir.glob("*.zip"))
    subprocess.run(
        [sys.executable, str(tool), "build", "--source-dir", str(REPO_ROOT), "--output-dir", str(output_dir)],
        check=True,
    )
    built = sorted(set(output_dir.glob("*.zip")) - before) or sorted(output_dir.glob("clothlight-*.zip"))
    zip_path = max(built, key=lambda p: p.stat().st_mtime)
    subprocess.run([sys.executable, str(tool), "validate", str(zip_path)], check=True)
    return zip_path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--output-dir", type=pathlib.Path, default=REPO_ROOT / "dist")
    args = parser.parse_args()
    print(build_extension(args.output_dir.resolve()))


if __name__ == "__main__":
    main()
