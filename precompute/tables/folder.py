"""A folder of tables — a yarn bake, a cloth bake — checked as a whole before anything reads it, and
written as a whole.

Every reader of a bake folder goes through :func:`check_files` (the yarn's :func:`check_yarn_table_folder`;
the cloth's ``clothlight.garment.tables.check_cloth_table_folder``): the add-on's Apply Material and
Apply Garment Material, validation, the garment bake, ``python -m precompute plot``.  A folder is
refused, with a :class:`~precompute.tables.exr.TableError` naming the file and the reason, unless

* ``summary.json`` is a JSON object of this schema (an older one: "bake it again"), naming the
  bake's cache key (its id) and the resolutions the readers use;
* every table the readers need is there, and every table present (needed or not) passes
  :func:`~precompute.tables.exr.read_table`: OpenEXR, a ClothLight table of this schema and of the kind its
  name says, the shape its own layout gives, its pixels those its content hash says, finite and ≥ 0;
* each table's layout is the summary's resolutions, and what its header says that a reader takes from
  the summary (the host index, the lobe shape, the specular term) is what the summary says;
* each table is of the same bake: its cache key is the summary's;
* each file's bytes are those the summary lists under ``file_sha256`` (bakes write the list; a file
  present but not listed is refused), so a file edited, damaged or copied from another bake of the
  same inputs is found even where its own header is consistent.

:func:`replace_folder` writes an output folder (``bake --out DIR``) as a whole: into a staging folder
beside it, then swapped in, so that a reader — or a process killed at any moment — finds either the
complete previous folder or the complete new one.  Imports neither numba nor bpy.
"""

from __future__ import annotations

import contextlib
import ctypes
import dataclasses
import errno
import hashlib
import io
import json
import math
import os
import pathlib
import secrets
import shutil
import sys
import time
from collections.abc import Callable, Iterable, Iterator, Mapping

import numpy as np

from precompute.errors import ParameterError
from precompute.optics import measured_sample
from precompute.optics.measured_sample import DEFAULT_SAMPLE_WEAVE, SAMPLE_WEAVES
from precompute.outputs import can_create_in, existing_place
from precompute.tables.exr import SCHEMA, Table, TableError, table_from_bytes

SUMMARY_FILE = "summary.json"
#: The spectral stage's file, as precompute/bake.py names it (that file is the stage's code, digested into its key).
SPECTRAL_FILE = "spectral.npz"
#: The summary's list of the folder's files: {file name: SHA-256 of its bytes}.
FILE_HASHES_KEY = "file_sha256"
#: The table files of a yarn bake by kind, written in this order (summary.json last).
YARN_TABLE_FILES = {
    "brdf": "brdf.exr",
    "brdf_stderr": "brdf_stderr.exr",
    "albedo": "albedo.exr",
    "closure_lobes": "lobes.exr",
    "unscattered": "unscattered.exr",
}
#: The tables the yarn material reads; the others are checked when present (pre-baked folders ship without
#: them, and without spectral.npz).
YARN_REQUIRED_KINDS = ("brdf", "closure_lobes", "unscattered")
#: Every file of a yarn bake folder (``bake --out``).
YARN_FOLDER_FILES = (*YARN_TABLE_FILES.values(), SPECTRAL_FILE, SUMMARY_FILE)
#: The key of a yarn bake's summary (and every table header) recording the yarn shader's specular term
#: (§5.2, ``osl/cloth_yarn.osl``): ``{"weight": SpecularWeight, "slope": Slope (Beckmann rms slope m),
#: "index": SpecularIOR (its Fresnel factor's), "source": where they come from}``; a folder baked before
#: bakes recorded it has the defaults, one baked before they recorded ``index`` the host index.
SPECULAR_KEY = "specular"
#: ``source`` of a specular term taken from a preset's ``[fit]`` table (``python -m clothlight.fit``).
SPECULAR_FROM_PRESET = "preset [fit]"
#: The key of a yarn bake's summary naming the sample weave its preset was fitted on
#: (:mod:`precompute.optics.measured_sample`), where the preset names one.
SAMPLE_WEAVE_KEY = "sample_weave"
#: The key of a yarn bake's summary naming the sample azimuths its preset was fitted at, where the
#: preset names them (``[sample] azimuths_deg``, :mod:`precompute.optics.measured_sample`).
SAMPLE_AZIMUTHS_RECORD_KEY = "sample_azimuths_deg"
#: Staging folders of :func:`replace_folder` whose process has died, or older than this (written by
#: another machine, which this one cannot ask), are left by a run that was killed; a later one removes them.
STALE_STAGING_SECONDS = 24 * 3600
_STAGING_SUFFIX = ".partial"


@dataclasses.dataclass(frozen=True)
class TableRule:
    """What one table file of a folder must be: its ``kind``, the ``layout`` entries the summary gives
    it, whether the folder must have it, and header ``metadata`` that must equal these values (None:
    must be absent)."""

    kind: str
    layout: Mapping[str, int]
    required: bool = True
    metadata: Mapping[str, object] = dataclasses.field(default_factory=dict)


@dataclasses.dataclass(frozen=True)
class CheckedFolder:
    """A folder that passed the check: its absolute path, its summary and its tables by file name
    (those present; every required one is)."""

    folder: pathlib.Path
    summary: dict
    tables: dict[str, Table]


# ---- the check ----------------------------------------------------------------------------------


def file_sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def file_hashes(folder: str | pathlib.Path, names: Iterable[str]) -> dict[str, str]:
    """{name: SHA-256 of the file's bytes} of those of ``names`` that ``folder`` holds: the summary's
    :data:`FILE_HASHES_KEY`."""
    folder = pathlib.Path(folder)
    return {name: file_sha256((folder / name).read_bytes()) for name in names if (folder / name).is_file()}


def load_summary(folder: str | pathlib.Path, schema: str, again: str = "bake it again") -> dict:
    """The summary of a bake folder of ``schema``; :class:`TableError` naming it if it is missing,
    unreadable, not a summary of this kind or of another version (then ``again``)."""
    folder = pathlib.Path(folder)
    path = folder / SUMMARY_FILE
    if not folder.is_dir():
        raise TableError(f"{folder}: no such folder")
    if not path.is_file():
        raise TableError(f"{folder}: not a ClothLight bake folder: no {SUMMARY_FILE}")
    try:
        summary = json.loads(path.read_bytes())
    except (OSError, ValueError, RecursionError) as exc:
        raise TableError(f"{path}: unreadable ({type(exc).__name__}: {exc})") from None
    if not isinstance(summary, dict):
        raise TableError(f"{path}: not a bake summary (a JSON {type(summary).__name__}, not an object)")
    found = summary.get("schema")
    family = schema.rpartition("/")[0] + "/"
    if not isinstance(found, str) or not found.startswith(family):
        raise TableError(f"{path}: not a ClothLight bake summary of {family}* (schema {found!r})")
    if found != schema:
        raise TableError(f"{path}: tables of schema {found!r}, this ClothLight reads {schema!r}: {again}")
    return summary


def summary_integer(summary: dict, key: str, folder: str | pathlib.Path) -> int:
    """``summary[key]``, an integer ≥ 1; :class:`TableError` naming the summary otherwise."""
    value = summary.get(key)
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise TableError(f"{pathlib.Path(folder) / SUMMARY_FILE}: {key} {value!r} is not an integer ≥ 1")
    return value


def summary_number(summary: dict, key: str, folder: str | pathlib.Path) -> float:
    """``summary[key]``, a finite number > 0; :class:`TableError` naming the summary otherwise."""
    value = summary.get(key)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not (math.isfinite(value) and value > 0):
        raise TableError(f"{pathlib.Path(folder) / SUMMARY_FILE}: {key} {value!r} is not a finite number > 0")
    return float(value)


def summary_numbers(summary: dict, key: str, folder: str | pathlib.Path) -> dict[str, float]:
    """``summary[key]``, an object of finite numbers ≥ 0 (a lobe shape); :class:`TableError` otherwise."""
    value = summary.get(key)
    if not isinstance(value, dict) or not value or not all(
            not isinstance(v, bool) and isinstance(v, (int, float)) and math.isfinite(v) and v >= 0
            for v in value.values()):
        raise TableError(f"{pathlib.Path(folder) / SUMMARY_FILE}: {key} {value!r} is not an object of "
                         "finite numbers ≥ 0")
    return {name: float(v) for name, v in value.items()}


def default_specular() -> dict:
    """The specular record of the shader's defaults, the paper's (§6): weight and slope of
    :mod:`precompute.optics.cook_torrance`, their ``source`` saying so."""
    from precompute.optics.cook_torrance import DEFAULT_SLOPE, DEFAULT_WEIGHT  # (SciPy) only where a default is needed

    return {"weight": float(DEFAULT_WEIGHT), "slope": float(DEFAULT_SLOPE), "fuzz_albedo": 0.0,
            "source": f"default (paper §6: m = {DEFAULT_SLOPE:g})"}


def summary_sample_weave(summary: dict, folder: str | pathlib.Path) -> str:
    """The sample weave a yarn bake's summary names (:data:`SAMPLE_WEAVE_KEY`), the default where it
    names none; :class:`TableError` naming the summary when it is not a known weave."""
    name = summary.get(SAMPLE_WEAVE_KEY, DEFAULT_SAMPLE_WEAVE)
    if name not in SAMPLE_WEAVES:
        raise TableError(f"{pathlib.Path(folder) / SUMMARY_FILE}: {SAMPLE_WEAVE_KEY} {name!r} is not one of "
                         f"{', '.join(SAMPLE_WEAVES)}")
    return name


def summary_sample_table(summary: dict, folder: str | pathlib.Path) -> dict:
    """The ``[sample]`` table (:mod:`precompute.optics.measured_sample`) of the preset a yarn bake's
    summary records: its weave (:func:`summary_sample_weave`) and, where the preset named them, its
    azimuths (:data:`SAMPLE_AZIMUTHS_RECORD_KEY`); :class:`TableError` naming the summary when they
    are not valid."""
    table = {measured_sample.SAMPLE_WEAVE_KEY: summary_sample_weave(summary, folder)}
    if SAMPLE_AZIMUTHS_RECORD_KEY in summary:
        table[measured_sample.SAMPLE_AZIMUTHS_KEY] = summary[SAMPLE_AZIMUTHS_RECORD_KEY]
        try:
            measured_sample.sample_azimuths_deg({measured_sample.SAMPLE_TABLE: table})
        except ParameterError as error:
            raise TableError(f"{pathlib.Path(folder) / SUMMARY_FILE}: {SAMPLE_AZIMUTHS_RECORD_KEY}: {error}") from None
    return table


def summary_specular(summary: dict, folder: str | pathlib.Path) -> dict:
    """The specular record of a yarn bake's summary (:data:`SPECULAR_KEY`): ``weight`` (a finite number
    ≥ 0), ``slope`` (finite, > 0), ``index`` (finite, ≥ 1), ``fuzz_albedo`` (in [0, 1]), ``source``
    and, where the fuzz has a depth, ``fuzz_depth`` (finite, > 0; none: 0, the fuzz a veneer), where it
    scatters forward or back ``fuzz_asymmetry`` (in (−1, 1); none: 0), where it is coloured
    ``fuzz_tint_red`` and ``fuzz_tint_blue`` (≥ 0; none: 1) and where its fibres lie flat
    ``fuzz_flatness`` (in [0, 1]; none: 0);
    :func:`default_specular` where the summary has none (a folder baked before bakes recorded it), the
    summary's ``host_index`` where it has no ``index`` and no fuzz (0) where it has no ``fuzz_albedo``
    (baked before bakes recorded those).  :class:`TableError` naming the
    summary otherwise."""
    value = summary.get(SPECULAR_KEY)
    if value is None:
        record = default_specular()
    else:
        def number(key: str, low: float, inclusive: bool) -> bool:
            v = value.get(key)
            return (not isinstance(v, bool) and isinstance(v, (int, float)) and math.isfinite(v)
                    and (v >= low if inclusive else v > low))

        if not (isinstance(value, dict) and number("weight", 0.0, True) and number("slope", 0.0, False)
                and ("index" not in value or number("index", 1.0, True))
                and ("fuzz_albedo" not in value or (number("fuzz_albedo", 0.0, True) and value["fuzz_albedo"] <= 1.0))
                and ("fuzz_depth" not in value or number("fuzz_depth", 0.0, False))
                and ("fuzz_asymmetry" not in value or (number("fuzz_asymmetry", -1.0, False)
                                                       and value["fuzz_asymmetry"] < 1.0))
                and all(key not in value or number(key, 0.0, True) for key in ("fuzz_tint_red", "fuzz_tint_blue"))
                and ("fuzz_flatness" not in value or (number("fuzz_flatness", 0.0, True)
                                                      and value["fuzz_flatness"] <= 1.0))
                and isinstance(value.get("source"), str)):
            raise TableError(f"{pathlib.Path(folder) / SUMMARY_FILE}: {SPECULAR_KEY} {value!r} is not an object of "
                             "weight (≥ 0), slope (> 0), index (≥ 1), fuzz_albedo (in [0, 1]), source and "
                             "perhaps fuzz_depth (> 0), fuzz_asymmetry (in (−1, 1)), fuzz_tint_red and "
                             "fuzz_tint_blue (≥ 0) and fuzz_flatness (in [0, 1])")
        record = {key: float(value[key]) for key in ("weight", "slope", "index", "fuzz_albedo", "fuzz_depth",
                                                     "fuzz_asymmetry", "fuzz_tint_red", "fuzz_tint_blue",
                                                     "fuzz_flatness")
                  if key in value}
        record.setdefault("fuzz_albedo", 0.0)
        record["source"] = value["source"]
    if "index" not in record and "host_index" in summary:
        record["index"] = float(summary["host_index"])
    return record


def check_files(
    folder: str | pathlib.Path,
    summary: dict,
    rules: Mapping[str, TableRule],
    other: Mapping[str, tuple[bool, Callable[[pathlib.Path, bytes], None]]] | None = None,
) -> CheckedFolder:
    """Check the files of a bake folder whose summary (:func:`load_summary`) is ``summary``: each table
    of ``rules`` ({file name: rule}) and each file of ``other`` ({file name: (required, check(path,
    bytes))}, the check raising :class:`TableError`), as the module docstring says."""
    folder = pathlib.Path(folder).absolute()
    summary_path = folder / SUMMARY_FILE
    key = summary.get("cache_key")
    if not isinstance(key, str) or not key:
        raise TableError(f"{summary_path}: no cache key (the bake's id) in the summary")
    hashes = summary.get(FILE_HASHES_KEY)
    if hashes is not None and not (isinstance(hashes, dict) and all(
            isinstance(name, str) and isinstance(digest, str) for name, digest in hashes.items())):
        raise TableError(f"{summary_path}: corrupt {FILE_HASHES_KEY!r} (not an object of file names and hashes)")
    tables = {}
    for name, rule in rules.items():
        path = folder / name
        data = _read(path, rule.required)
        if data is None:
            continue
        table = table_from_bytes(data, path, rule.kind)
        layout = table.metadata["layout"]
        for key, value in rule.layout.items():
            if layout.get(key) != value:
                raise TableError(f"{path}: {key} {layout.get(key)!r}, where the folder's {SUMMARY_FILE} says "
                                 f"{value!r}")
        found = table.metadata.get("cache_key")
        if found != summary["cache_key"]:
            raise TableError(f"{path}: a table of another bake (cache key {str(found)[:16]}…, the folder's "
                             f"{SUMMARY_FILE} {summary['cache_key'][:16]}…): bake the folder again")
        for key, value in rule.metadata.items():
            if table.metadata.get(key) != value:
                raise TableError(f"{path}: header {key} {table.metadata.get(key)!r}, where the folder's "
                                 f"{SUMMARY_FILE} says {value!r}")
        _match_listed_hash(path, data, hashes)
        tables[name] = table
    for name, (required, check) in (other or {}).items():
        path = folder / name
        data = _read(path, required)
        if data is None:
            continue
        check(path, data)
        _match_listed_hash(path, data, hashes)
    return CheckedFolder(folder, summary, tables)


def _read(path: pathlib.Path, required: bool) -> bytes | None:
    if not path.is_file():
        if required:
            raise TableError(f"{path}: missing: the folder is not a complete bake")
        return None
    try:
        return path.read_bytes()
    except OSError as exc:
        raise TableError(f"{path}: unreadable ({exc.strerror or exc})") from None


def _match_listed_hash(path: pathlib.Path, data: bytes, hashes: dict | None) -> None:
    if hashes is None:
        return  # a folder written before bakes listed their files: the other checks only
    if path.name not in hashes:
        raise TableError(f"{path}: not among the files its {SUMMARY_FILE} lists: not of this bake")
    if file_sha256(data) != hashes[path.name]:
        raise TableError(f"{path}: its bytes are not those its {SUMMARY_FILE} lists (SHA-256): changed since "
                         "the bake, damaged, or copied from another bake")


def check_yarn_table_folder(folder: str | pathlib.Path) -> CheckedFolder:
    """Check a yarn bake folder (``python -m precompute bake --out DIR``, a cache entry, pre-baked
    tables) as the module docstring says; :class:`TableError` naming the file and the reason."""
    folder = pathlib.Path(folder).absolute()
    summary = load_summary(folder, SCHEMA, "bake them again")
    grid = {"incidence_resolution": summary_integer(summary, "incidence_resolution", folder),
            "exit_resolution": summary_integer(summary, "exit_resolution", folder)}
    summary_specular(summary, folder)  # checked; absent in folders baked before bakes recorded it
    agree = {"host_index": summary_number(summary, "host_index", folder), SPECULAR_KEY: summary.get(SPECULAR_KEY)}
    lobes = {**grid, "lobe_count": summary_integer(summary, "lobe_count", folder)}
    lobe_shape = summary_numbers(summary, "lobe_shape", folder)
    attenuation = {"attenuation_samples": summary_integer(summary, "unscattered_samples", folder)}
    layouts = {"brdf": grid, "brdf_stderr": grid, "albedo": grid, "closure_lobes": lobes, "unscattered": attenuation}
    rules = {
        name: TableRule(kind, layouts[kind], kind in YARN_REQUIRED_KINDS,
                        {**agree, "lobe_shape": lobe_shape} if kind == "closure_lobes" else agree)
        for kind, name in YARN_TABLE_FILES.items()
    }

    def spectral(path: pathlib.Path, data: bytes) -> None:
        try:
            with np.load(io.BytesIO(data), allow_pickle=False) as arrays:
                key = json.loads(str(arrays["metadata"])).get("key")
        except Exception as exc:  # noqa: BLE001 - NumPy and zipfile raise many kinds for a damaged archive
            raise TableError(f"{path}: truncated or corrupt ({type(exc).__name__}: {exc})") from None
        if key != summary.get("spectral_key"):
            raise TableError(f"{path}: the simulation of another bake (spectral key {str(key)[:16]}…, the "
                             f"folder's {SUMMARY_FILE} {str(summary.get('spectral_key'))[:16]}…)")

    return check_files(folder, summary, rules, {SPECTRAL_FILE: (False, spectral)})


# ---- writing a folder as a whole ----------------------------------------------------------------


def check_output_folder(out: str | pathlib.Path, names: Iterable[str], option: str = "--out", *,
                        job: str = "bake") -> pathlib.Path:
    """``out`` (its real path) if :func:`replace_folder` may write it: absent, or a folder holding only
    entries of ``names`` (an earlier ``job``'s, which it replaces; a name ending in ``/`` is a folder,
    any other a file), in a writable folder.  Otherwise :class:`~precompute.errors.ParameterError`
    naming ``option``: called before any work starts."""
    out = pathlib.Path(os.path.realpath(out))
    names = set(names)
    if out.exists():
        if not out.is_dir():
            raise ParameterError(option, str(out), f"a folder to write the {job} into (this is a file)")

        def earlier(entry: os.DirEntry) -> bool:
            return (entry.name in names and entry.is_file(follow_symlinks=False)) or (
                f"{entry.name}/" in names and entry.is_dir(follow_symlinks=False))

        with os.scandir(out) as entries:
            foreign = sorted(entry.name for entry in entries if not earlier(entry) and not _is_staging(entry.name))
        if foreign:
            shown = ", ".join(foreign[:5]) + (", …" if len(foreign) > 5 else "")
            raise ParameterError(option, str(out), f"a new or empty folder, or one that holds an earlier {job} "
                                                   f"only (this one also holds {shown}, which a new {job} would "
                                                   "remove)")
    place = existing_place(out.parent)
    if not place.is_dir():
        raise ParameterError(option, str(out), f"a folder to write the {job} into (its parent {place} is a file, "
                                               "not a folder)")
    if not can_create_in(place):
        raise ParameterError(option, str(out), f"a folder in a writable place ({place} is not writable)")
    return out


def replace_folder(
    out: str | pathlib.Path,
    write: Callable[[pathlib.Path], None],
    names: Iterable[str],
    option: str = "--out",
) -> pathlib.Path:
    """Make ``out`` the folder ``write(folder)`` fills, as a whole; returns its real path
    (:func:`staged_folder`)."""
    with staged_folder(out, names, option) as staging:
        write(staging)
    return pathlib.Path(os.path.realpath(out))


@contextlib.contextmanager
def staged_folder(out: str | pathlib.Path, names: Iterable[str], option: str = "--out", *,
                  job: str = "bake") -> Iterator[pathlib.Path]:
    """A staging folder beside ``out`` to fill in the ``with`` block, which then becomes ``out`` as a whole.

    When the block ends normally the two are swapped in one step (Linux: ``renameat2(RENAME_EXCHANGE)``)
    and the previous folder is removed.  So ``out`` always holds either the complete previous folder or
    the complete new one, whenever the process stops; an exception (a generator closed early included)
    leaves the previous one untouched and removes the staging folder.  Where the file system cannot swap
    folders, the previous one is renamed away first: for the moment between the two renames ``out`` is
    missing (never incomplete).  ``out`` must pass :func:`check_output_folder` (checked again here).
    """
    out = check_output_folder(out, names, option, job=job)
    out.parent.mkdir(parents=True, exist_ok=True)
    _remove_stale_staging(out)
    staging = out.parent / f".{out.name}.{os.getpid()}.{secrets.token_hex(4)}{_STAGING_SUFFIX}"
    staging.mkdir()
    try:
        yield staging
        if not out.exists():
            os.rename(staging, out)
        elif not _exchange(staging, out):
            aside = out.parent / f".{out.name}.{os.getpid()}.{secrets.token_hex(4)}.previous{_STAGING_SUFFIX}"
            os.rename(out, aside)
            try:
                os.rename(staging, out)
            except BaseException:
                os.rename(aside, out)
                raise
            staging = aside
        # staging now holds the previous folder (or nothing)
    finally:
        if staging.exists():
            shutil.rmtree(staging, ignore_errors=True)


def _exchange(first: pathlib.Path, second: pathlib.Path) -> bool:
    """Swap two folders atomically (Linux ``renameat2`` with ``RENAME_EXCHANGE``); False where the
    system or the file system cannot."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        renameat2 = ctypes.CDLL(None, use_errno=True).renameat2
    except (OSError, AttributeError):
        return False
    renameat2.argtypes = (ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint)
    renameat2.restype = ctypes.c_int
    at_fdcwd, rename_exchange = -100, 2
    if renameat2(at_fdcwd, os.fsencode(first), at_fdcwd, os.fsencode(second), rename_exchange) == 0:
        return True
    error = ctypes.get_errno()
    if error in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP, errno.ENOTSUP):
        return False
    raise OSError(error, os.strerror(error), str(first), None, str(second))


def _is_staging(name: str) -> bool:
    return name.startswith(".") and name.endswith(_STAGING_SUFFIX)


def _process_is_gone(pid: int) -> bool:
    """Whether no process ``pid`` runs on this machine."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except (PermissionError, OverflowError, ValueError):
        return False  # another user's process: alive
    return False


def _remove_stale_staging(out: pathlib.Path) -> None:
    """Remove the staging folders beside ``out`` that runs killed before their end left: their process
    is gone (the process id is in the name: ``.<out>.<pid>.<random>[.previous].partial``), or they are
    older than :data:`STALE_STAGING_SECONDS`."""
    now = time.time()
    prefix = f".{out.name}."
    for entry in out.parent.iterdir():
        if not (entry.name.startswith(prefix) and entry.name.endswith(_STAGING_SUFFIX)):
            continue
        pid = entry.name[len(prefix):].partition(".")[0]
        try:
            if (pid.isdigit() and int(pid) != os.getpid() and _process_is_gone(int(pid))) \
                    or now - entry.stat().st_mtime > STALE_STAGING_SECONDS:
                shutil.rmtree(entry, ignore_errors=True)
        except OSError:
            continue  # removed by another process meanwhile
