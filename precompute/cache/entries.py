"""A content-addressed cache of bake results, written atomically.

An entry is a folder named by the SHA-256 of everything that determines its
content (:func:`cache_key` of the inputs, which include the schema version and
a digest of the code that computes it), inside a namespace folder
(``spectral``, ``tables``).  An entry is assembled in a private temporary
folder and renamed into place in one step, its ``entry.json`` written last
inside it, so:

* an interrupted bake (an exception, Ctrl-C, a killed process) never leaves a
  half-written entry that a later run or a shader could pick up: only the
  temporary folder remains, under a name no lookup reads, and a later store
  removes it once it is :data:`STALE_PARTIAL_SECONDS` old;
* of two concurrent bakes of the same inputs, the first rename wins and the
  other's identical result is discarded: one valid entry.

The default location is the user cache folder (platformdirs); inside Blender
the add-on passes its extension user folder instead.
"""

from __future__ import annotations

import hashlib
import json
import os
import pathlib
import secrets
import shutil
import time
from collections.abc import Callable, Iterable

import platformdirs

#: Written last into every entry: its full key and the inputs it was made from.
ENTRY_FILE = "entry.json"
#: Temporary folders older than this belong to bakes that died; a later store removes them.
STALE_PARTIAL_SECONDS = 24 * 3600
_PARTIAL_SUFFIX = ".partial"


def default_cache_dir() -> pathlib.Path:
    """The user cache folder, e.g. ``~/.cache/clothlight`` on Linux."""
    return pathlib.Path(platformdirs.user_cache_dir("clothlight", appauthor=False))


def canonical_json(value) -> str:
    """JSON with sorted keys and no whitespace; NumPy arrays and scalars as lists and numbers."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), allow_nan=False, default=_jsonable)


def _jsonable(value):
    if hasattr(value, "tolist"):  # NumPy arrays and scalars
        return value.tolist()
    raise TypeError(f"not JSON-serialisable: {type(value).__name__}")


def cache_key(inputs: dict) -> str:
    """SHA-256 (hex) of the canonical JSON of ``inputs``."""
    return hashlib.sha256(canonical_json(inputs).encode()).hexdigest()


def source_digest(root: pathlib.Path, relative_paths: Iterable[str]) -> str:
    """SHA-256 (hex) of source files (names and contents), so a change of the code is a change of key."""
    digest = hashlib.sha256()
    for relative in sorted(relative_paths):
        digest.update(relative.encode() + b"\0")
        digest.update((pathlib.Path(root) / relative).read_bytes() + b"\0")
    return digest.hexdigest()


def entry_path(cache_dir: str | pathlib.Path, namespace: str, key: str) -> pathlib.Path:
    """The folder an entry of ``key`` has (or would have) in ``namespace``."""
    return pathlib.Path(cache_dir) / namespace / key


def lookup(cache_dir: str | pathlib.Path, namespace: str, key: str) -> pathlib.Path | None:
    """The folder of the complete entry of ``key``, or None."""
    folder = entry_path(cache_dir, namespace, key)
    try:
        return folder if json.loads((folder / ENTRY_FILE).read_text())["key"] == key else None
    except (OSError, ValueError, KeyError, TypeError):
        return None


def store(
    cache_dir: str | pathlib.Path, namespace: str, key: str, inputs: dict, write: Callable[[pathlib.Path], None]
) -> tuple[pathlib.Path, bool]:
    """Create the entry of ``key`` by ``write(folder)`` on a private temporary folder, then rename it into place.

    Returns the entry's folder and whether this call's result is the one kept
    (False when a concurrent store of the same key finished first).
    """
    space = pathlib.Path(cache_dir) / namespace
    space.mkdir(parents=True, exist_ok=True)
    _remove_stale_partials(space)
    final = space / key
    staging = space / f".{key[:16]}.{os.getpid()}.{secrets.token_hex(4)}{_PARTIAL_SUFFIX}"
    staging.mkdir()
    try:
        write(staging)
        entry = {"key": key, "inputs": json.loads(canonical_json(inputs))}
        (staging / ENTRY_FILE).write_text(json.dumps(entry, indent=1))
        try:
            os.rename(staging, final)
            return final, True
        except OSError:
            if lookup(cache_dir, namespace, key) is not None:
                return final, False  # a concurrent bake of the same inputs finished first
            if not final.exists():
                raise
        # ``final`` exists without a valid entry.json: not made by store (which renames complete
        # entries only), e.g. damaged by hand.  Move it aside, then take its place.
        discarded = space / f".{key[:16]}.discarded.{secrets.token_hex(4)}{_PARTIAL_SUFFIX}"
        os.rename(final, discarded)
        shutil.rmtree(discarded, ignore_errors=True)
        os.rename(staging, final)
        return final, True
    finally:
        if staging.exists():
            shutil.rmtree(staging, ignore_errors=True)


def _remove_stale_partials(space: pathlib.Path) -> None:
    now = time.time()
    for partial in space.glob(f".*{_PARTIAL_SUFFIX}"):
        try:
            if now - partial.stat().st_mtime > STALE_PARTIAL_SECONDS:
                shutil.rmtree(partial, ignore_errors=True)
        except OSError:
            continue  # removed by another process meanwhile
