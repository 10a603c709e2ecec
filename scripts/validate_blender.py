"""Run the validation sweep inside a real Blender:

    blender -b -P scripts/validate_blender.py -- --out out/validation --tables out/bake

Same arguments and the same code path as ``python -m clothlight.validate``.  This development
script puts the repository root on sys.path; the installed extension never does.
"""

import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from clothlight.validate import main  # noqa: E402

argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
sys.exit(main(argv))
