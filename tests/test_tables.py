"""Table files: float32 round trip, a self-describing header, and a reader that refuses what is not a table."""

import json
import os

import numpy as np
import OpenEXR
import pytest

from precompute.tables import exr as tables
from precompute.tables.exr import (
    CACHE_KEY_KEY,
    HASH_KEY,
    KIND_KEY,
    METADATA_KEY,
    SCHEMA,
    SCHEMA_KEY,
    VERSION_KEY,
    TableError,
    content_hash,
    read_table,
    write_table,
)

N_I, N_O = 3, 4


def metadata(kind="brdf", **layout):
    return {
        "table": kind,
        "layout": {"incidence_resolution": N_I, "exit_resolution": N_O, **layout},
        "code_version": "0.1.0",
        "cache_key": "ab" * 32,
        "medium": {"yarn": {"radius_mm": 0.1}, "particles": [{"diameter_nm": 150.0}]},
        "transport": {"seed": 7, "paths_per_cell": 100},
        "paths": {"per_incidence_cell": [100] * N_I**2},
        "colour": {"illuminant": "D65"},
        "units": {"rho": "1/sr"},
    }


def pixels(shape=(N_I * N_O, N_I * N_O, 3), seed=1):
    # Values over five decades, as in a real yarn table, where half floats would round visibly.
    return (10.0 ** np.random.default_rng(seed).uniform(-5, 0, shape)).astype(np.float32)


def raw_exr(path, header, channels):
    with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, **header}, channels) as exr:
        exr.write(str(path))


def test_round_trip_is_exact_and_the_header_describes_the_table(tmp_path):
    image = pixels()
    write_table(tmp_path / "t.exr", image, metadata())
    table = read_table(tmp_path / "t.exr", kind="brdf")
    assert table.pixels.dtype == np.float32
    np.testing.assert_array_equal(table.pixels, image)
    assert table.metadata == {**metadata(), "schema": SCHEMA}
    with OpenEXR.File(str(tmp_path / "t.exr"), separate_channels=True) as exr:  # what any EXR tool sees
        header = dict(exr.header())
        assert {name: c.type() for name, c in exr.channels().items()} == dict.fromkeys("RGB", OpenEXR.FLOAT)
    assert header[SCHEMA_KEY] == SCHEMA and header[KIND_KEY] == "brdf"
    assert header[VERSION_KEY] == "0.1.0" and header[CACHE_KEY_KEY] == "ab" * 32
    assert header[HASH_KEY] == content_hash(image)
    assert json.loads(header[METADATA_KEY])["transport"]["seed"] == 7


@pytest.mark.parametrize(
    "kind, layout, shape",
    [("albedo", {}, (N_I, N_I, 3)), ("closure_lobes", {"lobe_count": 5}, (N_O, 5 * N_O, 3)),
     ("brdf_stderr", {}, (N_I * N_O, N_I * N_O, 3))],
)
def test_every_kind_has_its_layout_shape(tmp_path, kind, layout, shape):
    write_table(tmp_path / "t.exr", pixels(shape), metadata(kind, **layout))
    assert read_table(tmp_path / "t.exr", kind=kind).pixels.shape == shape
    with pytest.raises(TableError, match="not the 'brdf' table"):
        read_table(tmp_path / "t.exr", kind="brdf")


@pytest.mark.parametrize(
    "edit, image, message",
    [
        (lambda m: m.pop("medium"), None, "must say how it was made"),
        (lambda m: m.pop("paths"), None, "must say how it was made"),
        (lambda m: m.update(table="rgb"), None, "not one of"),
        (lambda m: None, np.ones((4, 4, 3)), "not"),
        (lambda m: None, np.full((12, 12, 3), -1.0), "finite values ≥ 0"),
        (lambda m: None, np.full((12, 12, 3), np.nan), "finite values ≥ 0"),
    ],
)
def test_writer_refuses_incomplete_or_invalid_tables(tmp_path, edit, image, message):
    meta = metadata()
    edit(meta)
    with pytest.raises(ValueError, match=message):
        write_table(tmp_path / "t.exr", pixels() if image is None else image, meta)
    assert list(tmp_path.iterdir()) == []


def test_reader_refuses_missing_and_non_exr_files(tmp_path):
    with pytest.raises(TableError, match="no such table file"):
        read_table(tmp_path / "absent.exr")
    (tmp_path / "image.exr").write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(100))
    with pytest.raises(TableError, match="not an OpenEXR file"):
        read_table(tmp_path / "image.exr")


def test_reader_refuses_a_foreign_exr(tmp_path):
    image = pixels()
    raw_exr(tmp_path / "render.exr", {}, {"RGB": image})
    with pytest.raises(TableError, match="not a ClothLight table"):
        read_table(tmp_path / "render.exr")


@pytest.mark.parametrize("keep", [0.999, 0.9, 0.5, 0.1, 0.01])
def test_reader_refuses_truncated_files(tmp_path, keep):
    write_table(tmp_path / "t.exr", pixels(), metadata())
    data = (tmp_path / "t.exr").read_bytes()
    (tmp_path / "cut.exr").write_bytes(data[: int(len(data) * keep)])
    with pytest.raises(TableError, match="truncated or corrupt|not an OpenEXR"):
        read_table(tmp_path / "cut.exr")


def test_reader_refuses_corrupted_or_edited_pixels(tmp_path):
    write_table(tmp_path / "t.exr", pixels(), metadata())
    data = bytearray((tmp_path / "t.exr").read_bytes())
    data[-200] ^= 0x5A  # inside the compressed pixel data
    (tmp_path / "t.exr").write_bytes(bytes(data))
    with pytest.raises(TableError, match="content hash|truncated or corrupt"):
        read_table(tmp_path / "t.exr")


def clothlight_header(meta, image, schema=SCHEMA):
    return {SCHEMA_KEY: schema, METADATA_KEY: json.dumps(meta), HASH_KEY: content_hash(image)}


def test_reader_refuses_another_schema_version(tmp_path):
    image = pixels()
    raw_exr(tmp_path / "old.exr", clothlight_header(metadata(), image, "clothlight-table/1"), {"RGB": image})
    with pytest.raises(TableError, match="schema 'clothlight-table/1'.*bake it again"):
        read_table(tmp_path / "old.exr")


def test_reader_refuses_half_floats_extra_channels_and_wrong_shapes(tmp_path):
    image = pixels()
    raw_exr(tmp_path / "half.exr", clothlight_header(metadata(), image), {"RGB": image.astype(np.float16)})
    with pytest.raises(TableError, match="float32"):
        read_table(tmp_path / "half.exr")
    alpha = {"R": image[..., 0], "G": image[..., 1], "B": image[..., 2], "A": image[..., 0]}
    raw_exr(tmp_path / "rgba.exr", clothlight_header(metadata(), image), alpha)
    with pytest.raises(TableError, match="exactly R, G, B"):
        read_table(tmp_path / "rgba.exr")
    small = pixels((N_I * N_O, N_I * N_O - 1, 3))
    raw_exr(tmp_path / "shape.exr", clothlight_header(metadata(), small), {"RGB": small})
    with pytest.raises(TableError, match="its layout"):
        read_table(tmp_path / "shape.exr")
    raw_exr(tmp_path / "meta.exr", {SCHEMA_KEY: SCHEMA, METADATA_KEY: "{not json", HASH_KEY: "0"}, {"RGB": image})
    with pytest.raises(TableError, match="unreadable"):
        read_table(tmp_path / "meta.exr")


def test_a_failed_write_leaves_the_previous_table_intact(tmp_path, monkeypatch):
    write_table(tmp_path / "t.exr", pixels(seed=1), metadata())
    before = (tmp_path / "t.exr").read_bytes()

    class DiskFull:
        def __init__(self, header, channels):
            pass

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def write(self, path):
            with open(path, "wb") as handle:
                handle.write(before[: len(before) // 3])  # a half-written file ...
            raise OSError("No space left on device")  # ... then the failure

    monkeypatch.setattr(tables.OpenEXR, "File", DiskFull)
    with pytest.raises(OSError, match="No space"):
        write_table(tmp_path / "t.exr", pixels(seed=2), metadata())
    assert os.listdir(tmp_path) == ["t.exr"]
    assert (tmp_path / "t.exr").read_bytes() == before
