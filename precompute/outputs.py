"""Output and cache folders checked before any work starts: a command refuses, naming the option,
a folder it could not write into, instead of failing after minutes of work (issue 22).

Standard library only.  Bake folders written as a whole have their own, stricter check
(:func:`precompute.tables.folder.check_output_folder`).  :func:`json_ready` makes results standard JSON.
"""

from __future__ import annotations

import math
import numbers
import os
import pathlib
import tempfile

from precompute.errors import ParameterError


def existing_place(path: pathlib.Path) -> pathlib.Path:
    """``path`` or its nearest ancestor that exists."""
    place = path
    while not place.exists() and place != place.parent:
        place = place.parent
    return place


def can_create_in(folder: pathlib.Path) -> bool:
    """Whether this process can create an entry in the existing folder ``folder``: tried with a
    temporary folder, removed at once, not read off the permission bits, which say yes to root
    everywhere and know nothing of a read-only or virtual file system (``/sys``)."""
    try:
        with tempfile.TemporaryDirectory(prefix=".clothlight-write-check-", dir=folder):
            return True
    except OSError:
        return False


def check_writable_folder(path: str | os.PathLike, option: str, *, what: str = "an output folder") -> pathlib.Path:
    """``path`` (absolute) if a command can write files into it: an existing, writable folder, or a
    new one in a writable place (not created here).  ParameterError naming ``option`` otherwise."""
    if isinstance(path, str) and not path.strip():
        raise ParameterError(option, path, f"{what}: a folder path")
    path = pathlib.Path(os.path.abspath(path))
    if path.exists():
        if not path.is_dir():
            raise ParameterError(option, str(path), f"{what} (this is a file, not a folder)")
        if not can_create_in(path):
            raise ParameterError(option, str(path), f"{what} this user can write into (this one is not writable)")
        return path
    place = existing_place(path.parent)
    if not place.is_dir():
        raise ParameterError(option, str(path), f"{what} (its parent {place} is a file, not a folder)")
    if not can_create_in(place):
        raise ParameterError(option, str(path), f"{what} in a writable place ({place} is not writable)")
    return path


def check_writable_file(path: str | os.PathLike, option: str, *, what: str = "an output file") -> pathlib.Path:
    """``path`` (absolute) if a command can write it: not a folder, and its folder writable or creatable."""
    if isinstance(path, str) and not path.strip():
        raise ParameterError(option, path, f"{what}: a file path")
    path = pathlib.Path(os.path.abspath(path))
    if path.is_dir():
        raise ParameterError(option, str(path), f"{what} (this is a folder)")
    if path.exists() and not os.access(path, os.W_OK):
        raise ParameterError(option, str(path), f"{what} this user can write (this one is read-only)")
    check_writable_folder(path.parent, option, what=f"{what} in a writable folder")
    return path


def json_ready(value):
    """``value`` with NumPy numbers as Python ones and NaN and infinities as None, through dicts,
    lists and tuples, so that the JSON written of it is standard."""
    if isinstance(value, dict):
        return {key: json_ready(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(item) for item in value]
    if isinstance(value, bool):
        return value
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, numbers.Real):
        number = float(value)
        return number if math.isfinite(number) else None
    return value
