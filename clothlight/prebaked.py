"""The pre-baked tables shipped inside the extension, and the copies of them materials read.

``scripts/build_extension.py`` ships the tables of each shipped preset in ``prebaked/<preset>/``
with the request they were baked from, and the preset's cloth tables (the garment's BSDF measured
on the default woven sample, ``python -m clothlight.garment bake``) in ``prebaked_cloth/<preset>/``.
A material never points into those folders: Blender replaces the extension's folder on every
update and removes it with the extension, and a saved .blend would then render magenta.  Apply
Material and Apply Garment Material copy the folder, once and whole, into the bake cache
(:func:`user_copy`), named by a digest of its content: an update that ships other tables makes
another copy and leaves the one saved files use in place.

No Blender here; ``precompute.tables.folder`` (and OpenEXR with it) is imported only when a copy is
made.
"""

from __future__ import annotations

import hashlib
import json
import pathlib
import shutil

from .jobs import PACKAGE_ROOT
from .medium_settings import BakeRequest

#: Tables baked when the extension was built, one folder per shipped preset (scripts/build_extension.py).
PREBAKED_DIR = PACKAGE_ROOT / "prebaked"
#: Cloth tables baked when the extension was built from each pre-baked preset's tables.
PREBAKED_CLOTH_DIR = PACKAGE_ROOT / "prebaked_cloth"
#: File of a pre-baked folder holding the BakeRequest it was baked from.
REQUEST_FILE = "request.json"
#: Folders of the bake cache holding the copies of yarn and of cloth tables.
COPIES_FOLDER = "prebaked"
CLOTH_COPIES_FOLDER = "prebaked_cloth"


def prebaked_tables(request: BakeRequest, shipped_dir: pathlib.Path | None = None) -> pathlib.Path | None:
    """The shipped tables baked from exactly ``request`` (in ``shipped_dir``, default
    :data:`PREBAKED_DIR`), or None."""
    folder = (shipped_dir or PREBAKED_DIR) / request.preset
    try:
        if BakeRequest.from_json((folder / REQUEST_FILE).read_text()) == request:
            return folder
    except (OSError, ValueError, TypeError):
        pass
    return None


def _file_hashes(folder: pathlib.Path) -> dict[str, str]:
    """{name: SHA-256} of every file of ``folder`` (a pre-baked folder has no sub-folders)."""
    return {path.name: hashlib.sha256(path.read_bytes()).hexdigest()
            for path in sorted(folder.iterdir()) if path.is_file()}


def content_key(hashes: dict[str, str]) -> str:
    """A digest of a folder's file names and contents (:func:`_file_hashes`)."""
    return hashlib.sha256(json.dumps(hashes, sort_keys=True).encode()).hexdigest()


def prebaked_cloth_tables(request: BakeRequest) -> pathlib.Path | None:
    """The shipped cloth tables measured with the shipped yarn tables of exactly ``request``, or None."""
    return prebaked_tables(request, PREBAKED_CLOTH_DIR)


def user_copy(folder: str | pathlib.Path, cache_dir: str | pathlib.Path, *, cloth: bool = False) -> pathlib.Path:
    """The copy of the pre-baked ``folder`` (cloth tables if ``cloth``) in ``cache_dir``, made if it
    is missing or differs.

    The copy is ``<cache_dir>/prebaked/<folder name>-<content digest>`` (``prebaked_cloth/`` for
    cloth tables): the same shipped tables always map to the same copy, other tables (another version
    of the extension) to another.  An existing copy is reused when its files are byte for byte the
    shipped ones; otherwise the shipped folder is checked as a whole
    (``precompute.tables.folder.check_yarn_table_folder``, or
    ``clothlight.garment.tables.check_cloth_table_folder``: a ``TableError`` naming the shipped
    file) and written in one step (``replace_folder``: a reader, or a second Blender
    copying at the same time, finds the complete folder or none).
    """
    folder = pathlib.Path(folder)
    hashes = _file_hashes(folder)
    copies = CLOTH_COPIES_FOLDER if cloth else COPIES_FOLDER
    copy = pathlib.Path(cache_dir) / copies / f"{folder.name}-{content_key(hashes)[:16]}"
    if copy.is_dir() and _file_hashes(copy) == hashes:
        return copy
    from precompute.tables import folder as table_folder
    if cloth:
        from .garment.tables import check_cloth_table_folder
        check_cloth_table_folder(folder)
    else:
        table_folder.check_yarn_table_folder(folder)

    def write(staging: pathlib.Path) -> None:
        for name in hashes:
            shutil.copyfile(folder / name, staging / name)

    return table_folder.replace_folder(copy, write, hashes, option="the bake cache folder")


def tables_for_request(request: BakeRequest, *, tables_dir: str | pathlib.Path | None, tables_request: str,
                       cache_dir: str | pathlib.Path,
                       bake_unavailable: str | None = None) -> tuple[pathlib.Path, str | None]:
    """The table folder a material made from the panel's ``request`` reads, and a warning (or None).

    ``tables_dir`` (absolute), set by Bake Tables or by hand, wins; ``tables_request`` is the JSON
    of the request it was baked from ("" for a folder chosen by hand): another request than the
    panel's gets a warning.  Otherwise the pre-baked tables of an unchanged shipped preset, through
    their copy in ``cache_dir`` (:func:`user_copy`), never the extension's own folder, which an
    update replaces.  Without either, LookupError saying what to do (``bake_unavailable``: why
    the bake cannot run here, when it cannot).
    """
    if tables_dir:
        warning = None
        if tables_request and tables_request != request.to_json():
            warning = "The tables were baked from other settings than the panel's: bake again to use them"
        return pathlib.Path(tables_dir), warning
    shipped = prebaked_tables(request)
    if shipped is not None:
        return user_copy(shipped, cache_dir), None
    raise LookupError("No tables for these settings yet: " + (bake_unavailable or "press Bake Tables"))

