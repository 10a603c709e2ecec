"""Run the validation sweep inside a real Blender binary:

    blender -b -P scripts/validate_blender.py -- --out out/validation --tables out/bake
    blender -b my_cloth.blend -P scripts/validate_blender.py -- --object "ClothLight Sample" --out out/validation

Same arguments and the same code path as ``python -m clothlight.validate`` (``--help`` lists
them).  Blender's own Python has no matplotlib: the report then says the plots were skipped, and
``python -m clothlight.validation.report out/validation/results.json`` draws them afterwards.
Spectral measurement files need colour-science for the conversion to RGB.

This development script puts the repository root on sys.path; the installed extension never does.
"""

import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from clothlight.validate import main

# Guarded: a local cluster's workers are spawned processes that import this script again.
if __name__ == "__main__":
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    sys.exit(main(argv))
