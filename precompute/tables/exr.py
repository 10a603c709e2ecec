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
import io
import json
import numbers
import os
import pathlib
import secrets
from typing import NamedTuple

import numpy as np
import OpenEXR

from precompute.errors import InputError

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
    # Attenuation of the unscattered light along a path of length l / R (precompute/optics/ballistic.py).
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
#: The most pixels a table may have: far above any bake's (an N_i·N_o ≈ 400 pixel square atlas), far
#: below what would exhaust memory.  A header that claims more is refused before its pixels are read.
MAX_TABLE_PIXELS = 1 << 24


class TableError(InputError):
    """A file is not a valid ClothLight table; the message names the file and the reason.

    An :class:`~precompute.errors.InputError`: the command lines exit with code 2 on it."""


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
    if not isinstance(layout, dict):
        raise ValueError(f"layout metadata {layout!r} is not a JSON object")
    try:
        sizes = {key: layout[key] for key in LAYOUT_KEYS[kind]}
    except KeyError as exc:
        raise ValueError(f"layout metadata {layout!r} lacks {' / '.join(LAYOUT_KEYS[kind])} ({exc})") from None
    not_integers = {key: value for key, value in sizes.items()
                    if isinstance(value, bool) or not isinstance(value, numbers.Integral)}
    if not_integers:
        raise ValueError(f"layout entries {not_integers} of a {kind} table are not integers")
    sizes = {key: int(value) for key, value in sizes.items()}
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
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise TableError(f"{path}: unreadable ({exc.strerror or exc})") from None
    return table_from_bytes(data, path, kind)


def table_from_bytes(data: bytes, path: str | pathlib.Path, kind: str | None = None) -> Table:
    """:func:`read_table` of a file's content ``data`` (``path`` names it in errors).

    The header is read and checked first, the pixels only once it describes a table of the size
    its layout gives: a damaged header never makes the reader allocate what it claims.
    """
    if data[:4] != EXR_MAGIC:
        raise TableError(f"{path}: not an OpenEXR file")
    header = exr_header(data, path)
    schema = header.get(SCHEMA_KEY)
    if schema is None:
        raise TableError(f"{path}: an OpenEXR file but not a ClothLight table (no {SCHEMA_KEY!r} header attribute)")
    if not isinstance(schema, str):
        raise TableError(f"{path}: corrupt {SCHEMA_KEY!r} header attribute (not a string)")
    if schema != SCHEMA:
        raise TableError(f"{path}: table schema {schema!r}, this version reads {SCHEMA!r}: bake it again")
    try:
        metadata = json.loads(header[METADATA_KEY])
        if not isinstance(metadata, dict):
            raise ValueError("not a JSON object")
        shape = expected_shape(metadata)
    except (KeyError, TypeError, ValueError) as exc:
        raise TableError(f"{path}: unreadable {METADATA_KEY!r} header attribute ({exc})") from None
    if kind is not None and metadata["table"] != kind:
        raise TableError(f"{path}: a {metadata['table']!r} table, not the {kind!r} table asked for")
    if shape[0] * shape[1] > MAX_TABLE_PIXELS:
        raise TableError(f"{path}: its layout {metadata.get('layout')} says {shape}, more than the "
                         f"{MAX_TABLE_PIXELS} pixels a table may have")
    window = data_window_shape(header)
    if window is None:
        raise TableError(f"{path}: corrupt 'dataWindow' header attribute")
    if window != shape[:2]:
        raise TableError(f"{path}: {(*window, 3)} pixels, its layout {metadata.get('layout')} says {shape}")
    try:
        declared = {channel.name: (channel.xSampling, channel.ySampling) for channel in header["channels"]}
    except (KeyError, TypeError, AttributeError, UnicodeDecodeError):
        raise TableError(f"{path}: corrupt 'channels' header attribute") from None
    if sorted(declared) != ["B", "G", "R"]:
        raise TableError(f"{path}: channels {sorted(declared)}, a table has exactly R, G, B")
    if set(declared.values()) != {(1, 1)}:
        raise TableError(f"{path}: subsampled channels, a table has one value per pixel")
    try:
        with OpenEXR.File(io.BytesIO(data), separate_channels=True) as exr:
            channels = {name: (channel.type(), np.array(channel.pixels)) for name, channel in exr.channels().items()}
    except Exception as exc:  # noqa: BLE001 - OpenEXR raises plain exceptions for truncated or corrupt files
        raise TableError(f"{path}: truncated or corrupt OpenEXR file ({exc})") from None
    if sorted(channels) != ["B", "G", "R"]:
        raise TableError(f"{path}: channels {sorted(channels)}, a table has exactly R, G, B")
    if any(pixel_type != OpenEXR.FLOAT for pixel_type, _ in channels.values()):
        raise TableError(f"{path}: channel types {[str(t) for t, _ in channels.values()]}, a table is float32")
    if any(values.shape != shape[:2] for _, values in channels.values()):
        raise TableError(f"{path}: channels of {[values.shape for _, values in channels.values()]} pixels, "
                         f"its layout {metadata.get('layout')} says {shape}")
    pixels = np.stack([channels[name][1] for name in "RGB"], axis=-1).astype(np.float32)
    if header.get(HASH_KEY) != content_hash(pixels):
        raise TableError(f"{path}: pixels do not match the header's content hash: truncated or corrupted, or edited")
    if not np.all(np.isfinite(pixels)) or np.any(pixels < 0):
        raise TableError(f"{path}: holds values that are not finite and ≥ 0")
    return Table(pixels, metadata)


def exr_header(data: bytes, path) -> dict:
    """The header of an OpenEXR file's content, without its pixels; :class:`TableError` if unreadable."""
    try:
        with OpenEXR.File(io.BytesIO(data), header_only=True) as exr:
            return dict(exr.header())  # the File clears its own dicts on close
    except Exception as exc:  # noqa: BLE001 - OpenEXR raises plain exceptions for truncated or corrupt files
        raise TableError(f"{path}: truncated or corrupt OpenEXR file ({exc})") from None


def data_window_shape(header: dict) -> tuple[int, int] | None:
    """(rows, columns) of the header's data window, or None when it is not a window."""
    try:
        (x_min, y_min), (x_max, y_max) = (tuple(int(v) for v in corner) for corner in header["dataWindow"])
    except (KeyError, TypeError, ValueError):
        return None
    return y_max - y_min + 1, x_max - x_min + 1
