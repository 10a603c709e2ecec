"""Self-describing OpenEXR tables of the yarn BRDF (layout: docs/table-spec.md).

Every table is a float32 RGB OpenEXR image whose header carries, as string
attributes, the schema version, the full JSON description of how it was made
(medium and grid parameters with units, seed, path counts, code version) and a
content hash of its pixels.  :func:`read_table` refuses a wrong schema, a
truncated or corrupted file, and foreign EXR files, with a clear error.
"""

from __future__ import annotations

import hashlib
import json
import pathlib

import numpy as np
import OpenEXR

#: Bump when the layout or the meaning of any header field changes.
SCHEMA = "clothlight-table/1"
SCHEMA_KEY = "clothlight_schema"
METADATA_KEY = "clothlight_metadata"
HASH_KEY = "clothlight_content_sha256"


class TableError(ValueError):
    """A file is not a valid ClothLight table."""


def content_hash(pixels: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(pixels, dtype=np.float32).tobytes()).hexdigest()


def write_table(path: str | pathlib.Path, pixels: np.ndarray, metadata: dict) -> None:
    """Write ``pixels`` (H, W, 3) as a float32 RGB OpenEXR table with a self-describing header."""
    pixels = np.ascontiguousarray(pixels, dtype=np.float32)
    if pixels.ndim != 3 or pixels.shape[2] != 3:
        raise ValueError(f"a table is an (H, W, 3) image, not {pixels.shape}")
    if not np.all(np.isfinite(pixels)):
        raise ValueError("a table must hold finite values only")
    header = {
        "compression": OpenEXR.ZIP_COMPRESSION,
        "type": OpenEXR.scanlineimage,
        SCHEMA_KEY: SCHEMA,
        METADATA_KEY: json.dumps(metadata, sort_keys=True),
        HASH_KEY: content_hash(pixels),
    }
    with OpenEXR.File(header, {"RGB": pixels}) as exr:
        exr.write(str(path))


def read_table(path: str | pathlib.Path) -> tuple[np.ndarray, dict]:
    """Pixels (H, W, 3) float32 and metadata of a ClothLight table; :class:`TableError` if it is not one."""
    path = pathlib.Path(path)
    if not path.is_file():
        raise TableError(f"{path}: no such table file")
    try:
        with OpenEXR.File(str(path)) as exr:
            header = dict(exr.header())  # the File clears its own dict on close
            channels = exr.channels()
            if "RGB" in channels:
                pixels = np.asarray(channels["RGB"].pixels, dtype=np.float32)
            else:
                pixels = np.stack([np.asarray(channels[c].pixels) for c in "RGB"], axis=-1).astype(np.float32)
    except TableError:
        raise
    except Exception as exc:  # OpenEXR raises plain exceptions for truncated or corrupt files
        raise TableError(f"{path}: not a readable OpenEXR file ({exc})") from None
    schema = header.get(SCHEMA_KEY)
    if schema is None:
        raise TableError(f"{path}: an OpenEXR file but not a ClothLight table (no {SCHEMA_KEY!r} header)")
    if schema != SCHEMA:
        raise TableError(f"{path}: table schema {schema!r}; this version reads {SCHEMA!r}: bake it again")
    if header.get(HASH_KEY) != content_hash(pixels):
        raise TableError(f"{path}: pixel content does not match its header hash (corrupted or edited)")
    try:
        metadata = json.loads(header[METADATA_KEY])
    except (KeyError, json.JSONDecodeError) as exc:
        raise TableError(f"{path}: unreadable {METADATA_KEY!r} header ({exc})") from None
    return pixels, metadata
