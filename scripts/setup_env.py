"""Make OSL's ``oslquery`` module importable in the development environment.

The bpy wheel ships ``oslquery`` (and OpenImageIO's bindings) in
``bpy/5.0/python/lib/python3.11/site-packages``, a folder that is not on the
import path of the venv.  Cycles imports ``oslquery`` when it compiles a script
node, so without it every OSL node fails with "No module named 'oslquery'".

This is the one place that fixes it: a ``.pth`` file in the venv's
site-packages adds that folder to ``sys.path`` at interpreter start-up.  The
extension itself never touches ``sys.path``: inside a real Blender the folder
is already importable.
"""

import importlib.util
import pathlib
import sys
import sysconfig

PTH_NAME = "clothlight-bpy-oslquery.pth"


def bpy_bundled_site_packages() -> pathlib.Path:
    spec = importlib.util.find_spec("bpy")
    if spec is None or spec.origin is None:
        raise SystemExit("bpy is not installed in this environment")
    bpy_dir = pathlib.Path(spec.origin).parent
    matches = sorted(bpy_dir.glob("*/python/lib/python3*/site-packages"))
    for candidate in matches:
        if (candidate / "oslquery").exists() or list(candidate.glob("oslquery*")):
            return candidate
    raise SystemExit(f"no oslquery module found under {bpy_dir}")


def main() -> None:
    target = bpy_bundled_site_packages()
    site_packages = pathlib.Path(sysconfig.get_paths()["purelib"])
    pth = site_packages / PTH_NAME
    pth.write_text(f"{target}\n")
    print(f"wrote {pth} -> {target}", file=sys.stderr)


if __name__ == "__main__":
    main()
