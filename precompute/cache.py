"""Content-addressed cache of baked tables, written atomically.

A bake's folder is named by a hash of everything that determines its content
(all medium and grid parameters, seed, path budget, table schema, code
version).  It is assembled in a private temporary folder and renamed into
place in one step, so an interrupted bake never leaves a half-written folder
that a later run or a shader could pick up, and of two concurrent bakes of
the same inputs one wins and the other's identical result is discarded.
"""

from __future__ import annotations

import hashlib
import json
import os
import pathlib
import shutil
import tempfile
from collections.abc import Callable

import platformdirs

#: A finished cache entry always holds this file; it is written last.
COMPLETE_MARKER = "summary.json"


def default_cache_dir() -> pathlib.Path:
    """The user cache folder (platformdirs), e.g. ~/.cache/clothlight/tables on Linux."""
    return pathlib.Path(platformdirs.user_cache_dir("clothlight")) / "tables"


def cache_key(inputs: dict) -> str:
    """SHA-256 of the canonical JSON of ``inputs``."""
    text = json.dumps(inputs, sort_keys=True, separators=(",", ":"), default=_jsonable)
    return hashlib.sha256(text.encode()).hexdigest()


def _jsonable(value):
    try:
        import numpy as np

        if isinstance(value, np.ndarray):
            return value.tolist()
        if isinstance(value, np.generic):
            return value.item()
    except ImportError:  # pragma: no cover - numpy is a dependency
        pass
    raise TypeError(f"not JSON-serialisable: {type(value).__name__}")


def entry_path(cache_dir: pathlib.Path, key: str) -> pathlib.Path:
    return pathlib.Path(cache_dir) / key[:24]


def lookup(cache_dir: pathlib.Path, key: str) -> pathlib.Path | None:
    """The folder of a complete entry for ``key``, or None."""
    folder = entry_path(cache_dir, key)
    return folder if (folder / COMPLETE_MARKER).is_file() else None


def store(cache_dir: pathlib.Path, key: str, write: Callable[[pathlib.Path], None]) -> pathlib.Path:
    """Create the entry for ``key`` by calling ``write(folder)`` on a private temporary folder,
    then renaming it into place atomically.  ``write`` must create COMPLETE_MARKER last."""
    cache_dir = pathlib.Path(cache_dir)
    cache_dir.mkdir(parents=True, exist_ok=True)
    final = entry_path(cache_dir, key)
    staging = pathlib.Path(tempfile.mkdtemp(prefix=f".{final.name}.", suffix=".partial", dir=cache_dir))
    try:
        write(staging)
        if not (staging / COMPLETE_MARKER).is_file():
            raise RuntimeError(f"cache writer did not produce {COMPLETE_MARKER}")
        try:
            os.rename(staging, final)
        except OSError:
            # Another bake of the same inputs finished first: keep its entry, drop ours.
            if lookup(cache_dir, key) is None:
                raise
    finally:
        if staging.exists():
            shutil.rmtree(staging, ignore_errors=True)
    return final
