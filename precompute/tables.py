"""Self-describing OpenEXR tables of a baked yarn (layout: docs/table-spec.md).

Every table is a single-part scanline OpenEXR image with three float32
channels R, G, B.  Its header carries, as string attributes, the schema
version, the table kind, the code version, the cache key, a SHA-256 of the
pixels and a JSON object with everything needed to reproduce and check it:
every medium and grid parameter with units, the seed, the path counts, the
colour convention and the layout.  :func:`read_table` refuses files that are
missing, not OpenEXR, truncated or corrupt, foreign (no ClothLight schema), of
another schema version or table kind, of the wrong shape or channel types, or
whose pixels do not match their hash, each with a :class:`TableError` that
names the file and the reason.

Files are written to a temporary name in the same folder and renamed into
place, so a reader never sees a half-written table.  Only float32 is written:
ρ spans five decades within one table and half floats' 11-bit mantissa would
add a 0.05 % quantisation on top of nothing gained but disk space.
"""

from __future__ import annotations

import hashlib
import json
import os
import pathlib
import secrets
from typing import NamedTuple

import numpy as np
import OpenEXR

#: Bump when the layout or the meaning of any header field changes (docs/table-spec.md).
SCHEMA = "clothlight-table/4"
SCHEMA_KEY = "clothlight_schema"
KIND_KEY = "clothlight_table"
VERSION_KEY = "clothlight_code_version"
CACHE_KEY_KEY = "clothlight_cache_key"
HASH_KEY = "clothlight_content_sha256"
METADATA_KEY = "clothlight_metadata"

#: Table kinds and the image shape (rows, columns) each has, from its ``layout`` metadata.
KINDS = {
    "brdf": lambda layout: (layout["incidence_resolution"] * layout["exit_resolution"],) * 2,
    "brdf_stderr": lambda layout: (layout["incidence_resolution"] * layout["exit_resolution"],) * 2,
    "albedo": lambda layout: (layout["incidence_resolution"],) * 2,
    "closure_lobes": lambda layout: (layout["exit_resolution"], layout["lobe_count"] * layout["exit_resolution"]),
    # Garment closure weights, front and back side stacked (docs/table-spec.md, "Cloth tables").
    "cloth_lobes": lambda layout: (2 * layout["exit_resolution"], layout["lobe_count"] * layout["exit_resolution"]),
    # Attenuation of the unscattered light along a path of length l / R (precompute/ballistic.py).
    "unscattered": lambda layout: (1, layout["attenuation_samples"]),
}
#: The integer ``layout`` entries each kind needs.
LAYOUT_KEYS = {
    "brdf": ("incidence_resolution", "exit_resolution"),
    "brdf_stderr": ("incidence_resolution", "exit_resolution"),
    "albedo": ("incidence_resolution", "exit_resolution"),
    "closure_lobes": ("incidence_resolution", "exit_resolution", "lobe_count"),
    "cloth_lobes": ("incidence_resolution", "exit_resolution", "lobe_count"),
    "unscattered": ("attenuation_samples",),
}
#: Metadata every table must carry (besides ``table`` and ``layout``) to be reproducible.
REQUIRED_METADATA = ("code_version", "cache_key", "medium", "transport", "paths", "colour", "units")
EXR_MAGIC = b"\x76\x2f\x31\x01"


class TableError(ValueError):
    """A file is not a valid ClothLight table; the message names the file and the reason."""


class Table(NamedTuple):
    """A table read back: ``pixels`` (H, W, 3) float32, top row first, and its ``metadata``."""

    pixels: np.ndarray
    metadata: dict


def content_hash(pixels: np.ndarray) -> str:
    """SHA-256 (hex) of a table's shape and float32 pixels, row-major, top row first."""
    pixels = np.ascontiguousarray(pixels, dtype=np.float32)
    digest = hashlib.sha256("x".join(map(str, pixels.shape)).encode())
    digest.update(pixels.tobytes())
    return digest.hexdigest()


def expected_shape(metadata: dict) -> tuple[int, int, int]:
    """(H, W, 3) of a table of ``metadata["table"]`` with ``metadata["layout"]`` resolutions."""
    kind = metadata.get("table")
    if kind not in KINDS:
        raise ValueError(f"table kind {kind!r} is not one of {sorted(KINDS)}")
    layout = metadata.get("layout", {})
    try:
        sizes = {key: int(layout[key]) for key in LAYOUT_KEYS[kind]}
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"layout metadata {layout!r} lacks {' / '.join(LAYOUT_KEYS[kind])} ({exc})") from None
    too_small = {key: value for key, value in sizes.items() if value < 1}
    if too_small:
        raise ValueError(f"a {kind} table needs layout entries ≥ 1, not {too_small}")
    return (*KINDS[kind](sizes), 3)


def write_table(path: str | pathlib.Path, pixels: np.ndarray, metadata: dict) -> pathlib.Path:
    """Write ``pixels`` (H, W, 3) as a float32 RGB OpenEXR table, atomically; returns the path.

    ``metadata`` needs ``table`` (one of :data:`KINDS`), ``layout`` and every key of
    :data:`REQUIRED_METADATA`; the schema version is added here.  Values must be
    finite and ≥ 0 (every table holds a non-negative quantity).
    """
    path = pathlib.Path(path)
    pixels = np.ascontiguousarray(pixels, dtype=np.float32)
    missing = [key for key in REQUIRED_METADATA if key not in metadata]
    if missing:
        raise ValueError(f"table metadata lacks {missing}: a table must say how it was made")
    shape = expected_shape(metadata)
    if pixels.shape != shape:
        raise ValueError(
            f"a {metadata['table']!r} table with layout {metadata['layout']} is {shape}, not {pixels.shape}"
        )
    if not np.all(np.isfinite(pixels)) or np.any(pixels < 0):
        raise ValueError("a table holds finite values ≥ 0 only")
    metadata = {**metadata, "schema": SCHEMA}
    header = {
        "compression": OpenEXR.ZIP_COMPRESSION,
        "type": OpenEXR.scanlineimage,
        SCHEMA_KEY: SCHEMA,
        KIND_KEY: str(metadata["table"]),
        VERSION_KEY: str(metadata["code_version"]),
        CACHE_KEY_KEY: str(metadata["cache_key"]),
        HASH_KEY: content_hash(pixels),
        METADATA_KEY: json.dumps(metadata, sort_keys=True, allow_nan=False),
    }
    temporary = path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.partial")
    try:
        with OpenEXR.File(header, {"RGB": pixels}) as exr:
            exr.write(str(temporary))
        os.replace(temporary, path)
    finally:
        temporary.unlink(missing_ok=True)
    return path


def read_table(path: str | pathlib.Path, kind: str | None = None) -> Table:
    """Read and validate a ClothLight table (of ``kind`` if given); :class:`TableError` if it is not one."""
    path = pathlib.Path(path)
    if not path.is_file():
        raise TableError(f"{path}: no such table file")
    with open(path, "rb") as handle:
        if handle.read(4) != EXR_MAGIC:
            raise TableError(f"{path}: not an OpenEXR file")
    try:
        with OpenEXR.File(str(path), separate_channels=True) as exr:
            header = dict(exr.header())  # the File clears its own dicts on close
            channels = {name: (channel.type(), np.array(channel.pixels)) for name, channel in exr.channels().items()}
    except Exception as exc:  # noqa: BLE001 - OpenEXR raises plain exceptions for truncated or corrupt files
        raise TableError(f"{path}: truncated or corrupt OpenEXR file ({exc})") from None
    schema = header.get(SCHEMA_KEY)
    if schema is None:
        raise TableError(f"{path}: an OpenEXR file but not a ClothLight table (no {SCHEMA_KEY!r} header attribute)")
    if schema != SCHEMA:
        raise TableError(f"{path}: table schema {schema!r}, this version reads {SCHEMA!r}: bake it again")
    try:
        metadata = json.loads(header[METADATA_KEY])
        shape = expected_shape(metadata)
    except (KeyError, TypeError, ValueError) as exc:
        raise TableError(f"{path}: unreadable {METADATA_KEY!r} header attribute ({exc})") from None
    if kind is not None and metadata["table"] != kind:
        raise TableError(f"{path}: a {metadata['table']!r} table, not the {kind!r} table asked for")
    if sorted(channels) != ["B", "G", "R"]:
        raise TableError(f"{path}: channels {sorted(channels)}, a table has exactly R, G, B")
    if any(pixel_type != OpenEXR.FLOAT for pixel_type, _ in channels.values()):
        raise TableError(f"{path}: channel types {[str(t) for t, _ in channels.values()]}, a table is float32")
    pixels = np.stack([channels[name][1] for name in "RGB"], axis=-1).astype(np.float32)
    if pixels.shape != shape:
        raise TableError(f"{path}: {pixels.shape} pixels, its layout {metadata.get('layout')} says {shape}")
    if header.get(HASH_KEY) != content_hash(pixels):
        raise TableError(f"{path}: pixels do not match the header's content hash (corrupted or edited)")
    if not np.all(np.isfinite(pixels)) or np.any(pixels < 0):
        raise TableError(f"{path}: holds values that are not finite and ≥ 0")
    return Table(pixels, metadata)
