"""``python -m precompute plot TABLE.exr --out DIR``: PNG plots of a baked yarn (see precompute/tables/plots.py).

``TABLE`` is a bake's ``brdf.exr`` or its folder.  The in-plane and polar
plots need the table alone; the albedo spectra and the front/back swatches
need the bake's ``spectral.npz`` beside it (skipped, with a note on stderr,
when it is absent).
"""

from __future__ import annotations

import json
import pathlib
import shutil
import sys
import tempfile

from precompute.tables import plots
from precompute.bake import SPECTRAL_FILE, TABLE_FILES, load_spectral
from precompute.errors import ParameterError
from precompute.outputs import check_writable_folder, existing_place
from precompute.tables.folder import check_yarn_table_folder
from precompute.tables.exr import TableError, read_table


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("plot", help="PNG plots of a baked yarn's tables",
                                   description=__doc__.split("\n\n")[1])
    parser.add_argument("table", type=pathlib.Path, metavar="TABLE", help="a bake's brdf.exr, or the bake folder")
    parser.add_argument("--out", type=pathlib.Path, required=True, help="folder for the PNG files")
    parser.set_defaults(func=run)


def run(args) -> int:
    check_writable_folder(args.out, "--out", what="a folder for the PNG files")  # before any work
    path = args.table / TABLE_FILES["brdf"] if args.table.is_dir() else args.table
    try:
        if args.table.is_dir():  # a bake folder: checked as a whole
            tables = check_yarn_table_folder(args.table).tables
            atlas, metadata = tables[TABLE_FILES["brdf"]]
            stderr = tables[TABLE_FILES["brdf_stderr"]].pixels if TABLE_FILES["brdf_stderr"] in tables else None
        else:
            atlas, metadata = read_table(path, kind="brdf")
            stderr_path = path.with_name(TABLE_FILES["brdf_stderr"])
            stderr = read_table(stderr_path, kind="brdf_stderr").pixels if stderr_path.is_file() else None
    except TableError as exc:
        raise ParameterError("TABLE", str(args.table), f"a ClothLight brdf table or bake folder: {exc}") from None
    n_i = int(metadata["layout"]["incidence_resolution"])
    # Drawn beside --out and moved in at the end: an interrupted run writes nothing there.
    with tempfile.TemporaryDirectory(prefix=".clothlight-plot-", dir=existing_place(args.out.parent)) as folder:
        drawn = _draw(pathlib.Path(folder), atlas, n_i, stderr, args.table, metadata)
        args.out.mkdir(parents=True, exist_ok=True)
        written = []
        for png in drawn:
            shutil.move(png, args.out / png.name)  # a rename on one file system
            written.append(args.out / png.name)
    print(json.dumps([str(p) for p in written]))
    return 0


def _draw(staging: pathlib.Path, atlas, n_i: int, stderr, table: pathlib.Path, metadata: dict) -> list[pathlib.Path]:
    """The PNG files of the yarn table ``table`` (a brdf.exr or its bake folder) drawn into ``staging``."""
    path = table / TABLE_FILES["brdf"] if table.is_dir() else table
    written = [
        plots.plot_in_plane(atlas, n_i, staging / "rho_in_plane.png", stderr),
        plots.plot_polar(atlas, n_i, staging / "rho_polar.png"),
    ]
    spectral_path = path.with_name(SPECTRAL_FILE)
    if spectral_path.is_file():
        spectral, spectral_metadata = load_spectral(spectral_path)
        if spectral_metadata.get("key") != metadata["spectral_key"]:
            raise ParameterError(
                "TABLE", str(table), f"a table whose {SPECTRAL_FILE} is its own (their spectral keys differ)"
            )
        colour = metadata["colour"]
        written += [
            plots.plot_albedo_spectra(spectral, n_i, staging / "albedo_spectra.png"),
            plots.plot_swatches(spectral, n_i, staging / "swatches_front_back.png",
                                colour["illuminant"], colour["observer"]),
        ]
    else:
        print(f"note: no {SPECTRAL_FILE} beside {path}: albedo spectra and swatches skipped", file=sys.stderr)
    return written
