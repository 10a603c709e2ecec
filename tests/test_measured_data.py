"""Measured-data import and comparison metrics: the CSV format, errors that name the bad row, the
spectral → RGB conversion, and RMS / relative RMS / shape correlation on known vectors."""

import importlib.util
import math
import pathlib
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from precompute.fit.measured_data import (
    MAX_BRDF_PER_SR,
    RGB_HEADER,
    MeasurementFormatError,
    parse_measurement,
    read_measurement,
    relative_rms_error,
    rms_error,
    shape_correlation,
)
from precompute.errors import InputError, ParameterError

REPO = pathlib.Path(__file__).resolve().parents[1]
HEADER = ",".join(RGB_HEADER)
GOOD = f"""# a comment that says what this is
{HEADER}

0,0,0,0,0.2,0.02,0.01
30,180,20,0,0.3,0.03,0.02
30,180,20,180,0.1,0.01,0.01
30,180,0,0,0.15,0.015,0.012
30,180,20,90,9,9,9
"""


def test_rgb_file_rows_and_comments():
    m = parse_measurement(GOOD)
    assert m.rgb.shape == (5, 3) and m.wavelengths_nm is None
    np.testing.assert_array_equal(m.rows, [4, 5, 6, 7, 8])  # line numbers, comments and blanks counted
    assert m.comments == ("a comment that says what this is",)


def test_in_plane_curve_signs_views_by_side_and_drops_other_planes():
    signed, rgb = parse_measurement(GOOD).in_plane(30.0)
    # φo = φi: the light's side (negative); φo = φi + 180°: the mirror side; φo = φi + 90°: dropped
    np.testing.assert_array_equal(signed, [-20.0, 0.0, 20.0])
    np.testing.assert_allclose(rgb[:, 0], [0.1, 0.15, 0.3])
    m = parse_measurement(GOOD)
    np.testing.assert_allclose(m.at(30.0, 20.0), [0.3, 0.03, 0.02])
    assert m.at(30.0, 40.0) is None and m.at(45.0, 0.0) is None


def spectral_text(spectrum, wavelengths, pairs=((0, 0, 0, 0),)):
    lines = ["theta_i,phi_i,theta_o,phi_o,wavelength_nm,value"]
    for pair in pairs:
        lines += [",".join(map(str, pair)) + f",{w},{v}" for w, v in zip(wavelengths, spectrum)]
    return "\n".join(lines) + "\n"


def test_a_flat_spectrum_is_white_and_a_red_one_is_red():
    wavelengths = np.arange(380, 731, 10)
    flat = parse_measurement(spectral_text(np.full(len(wavelengths), 0.2), wavelengths))
    np.testing.assert_allclose(flat.rgb[0], [0.2, 0.2, 0.2], rtol=1e-9)  # the bake's white balance
    red = parse_measurement(spectral_text(np.where(wavelengths >= 600, 0.3, 0.0), wavelengths))
    r, g, b = red.rgb[0]
    assert r > 0.1 and g < 0.1 * r and b < 0.1 * r
    # the spectrum of a long-wavelength red lies outside Rec.709: a channel is clipped and reported
    assert red.gamut_clipping > 0.0


@pytest.mark.parametrize(
    "text, row, words",
    [
        ("", 1, "no header"),
        ("# only a comment\n\n", 1, "no header"),
        ("theta,phi\n0,0\n", 1, "header"),
        (f"# c\n{HEADER}\n", 2, "no data"),
        (f"{HEADER}\n0,0,95,0,1,1,1\n", 2, "theta_o"),
        (f"{HEADER}\n0,0,0,0,1,1,1\n0,0,10,360,1,1,1\n", 3, "phi_o"),
        (f"{HEADER}\n0,-1,0,0,1,1,1\n", 2, "phi_i"),
        (f"{HEADER}\n0,0,0,0,1,-0.5,1\n", 2, "negative"),
        (f"{HEADER}\n0,0,0,0,1e300,1,1\n", 2, "R = 1e\\+300 1/sr: .* at most 10000 1/sr"),
        ("theta_i,phi_i,theta_o,phi_o,wavelength_nm,value\n0,0,0,0,500,2e4\n", 2, "value = 20000 1/sr"),
        (f"{HEADER}\n0,0,0,0,1,1\n", 2, "6 fields"),
        (f"{HEADER}\n0,x,0,0,1,1,1\n", 2, "phi_i"),
        (f"{HEADER}\n0,0,0,0,1,nan,1\n", 2, "finite"),
        (f"{HEADER}\n\n# gap\n0,0,0,0,1,1,1\n0,0,0,0,2,2,2\n", 5, "row 4"),
        ("theta_i,phi_i,theta_o,phi_o,wavelength_nm,value\n0,0,0,0,900,0.1\n", 2, "wavelength_nm"),
    ],
)
def test_malformed_files_name_the_bad_row(text, row, words):
    with pytest.raises(MeasurementFormatError, match=f"^row {row}: .*{words}") as error:
        parse_measurement(text)
    assert error.value.row == row


def test_spectral_pairs_must_share_wavelengths_and_cover_the_visible():
    wavelengths = np.arange(380, 731, 10)
    text = spectral_text(np.full(len(wavelengths), 0.1), wavelengths, pairs=((0, 0, 0, 0), (0, 0, 20, 0)))
    lines = text.splitlines()
    del lines[1 + len(wavelengths) + 3]  # the second pair loses one wavelength
    with pytest.raises(MeasurementFormatError, match=f"^row {2 + len(wavelengths)}: .*same") as error:
        parse_measurement("\n".join(lines))
    assert error.value.row == 2 + len(wavelengths)
    narrow = np.arange(450, 651, 10)
    with pytest.raises(MeasurementFormatError, match="^row 2: .*cover 400"):
        parse_measurement(spectral_text(np.full(len(narrow), 0.1), narrow))


def test_a_file_that_is_not_utf8_names_the_row(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_bytes(f"{HEADER}\n0,0,0,0,1,1,1\n0,0,1\xff,0,1,1,1\n".encode("latin-1"))
    with pytest.raises(MeasurementFormatError, match=f"^{re.escape(str(path))}, row 3: not UTF-8") as error:
        read_measurement(path)
    assert error.value.path == str(path) and error.value.row == 3


def test_a_missing_file_or_a_folder_is_bad_input_naming_it(tmp_path):
    for path, reason in ((tmp_path / "missing.csv", "No such file"), (tmp_path, "Is a directory")):
        with pytest.raises(ParameterError, match=f"measurement file = '{re.escape(str(path))}'.*{reason}"):
            read_measurement(path)


def test_a_file_with_a_bad_row_names_the_file_and_the_row(tmp_path):
    path = tmp_path / "measured.csv"
    path.write_text(f"{HEADER}\n0,0,0,0,1,1,1\n0,x,0,0,1,1,1\n")
    with pytest.raises(MeasurementFormatError, match=f"^{re.escape(str(path))}, row 3: .*phi_i") as error:
        read_measurement(path)
    assert isinstance(error.value, InputError) and error.value.row == 3


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.text(max_size=300))
@example("\x00")
@example(f"{HEADER}\n0,0,0,0,1,1,1\x00\n")
@example(f"\ufeff{HEADER}\r\n0\r,0,0,0,1,1,1\r\n")
@example(f"{HEADER}\n\"0\",0,0,0,1,1,1\n")
@example(f"{HEADER}\n0,0,0,0,1,1,1e400\n")
def test_arbitrary_text_never_crashes_the_importer(text):
    try:
        parse_measurement(text)
    except MeasurementFormatError as error:
        lines = text.removeprefix("\ufeff").replace("\r\n", "\n").split("\n")
        assert 1 <= error.row <= len(lines)
        assert str(error).startswith(f"row {error.row}: ")


angles = st.integers(0, 90)
azimuths = st.integers(0, 359)
brdf = st.floats(0.0, 10.0, allow_nan=False)
not_a_number = st.text(min_size=1, max_size=6).filter(lambda s: not _is_float(s) and not set(s) & set(",#\n\r"))


def _is_float(s):
    try:
        float(s)
        return True
    except ValueError:
        return False


@st.composite
def valid_rows(draw):
    pairs = draw(st.lists(st.tuples(angles, azimuths, angles, azimuths), min_size=1, max_size=8,
                          unique_by=lambda p: p))
    return [f"{ti},{pi},{to},{po},{draw(brdf)},{draw(brdf)},{draw(brdf)}" for ti, pi, to, po in pairs]


@st.composite
def corrupted_row(draw, good_rows):
    fields = draw(st.sampled_from(good_rows)).split(",")
    kind = draw(st.sampled_from(["token", "zenith", "azimuth", "negative", "huge", "count", "nonfinite", "duplicate"]))
    if kind == "duplicate":
        return ",".join(fields)
    if kind == "token":
        fields[draw(st.integers(0, 6))] = draw(not_a_number)
    elif kind == "zenith":
        fields[draw(st.sampled_from([0, 2]))] = repr(draw(st.one_of(st.floats(90.001, 1e6), st.floats(-1e6, -0.001))))
    elif kind == "azimuth":
        fields[draw(st.sampled_from([1, 3]))] = repr(draw(st.one_of(st.floats(360.0, 1e6), st.floats(-1e6, -0.001))))
    elif kind == "negative":
        fields[draw(st.integers(4, 6))] = repr(draw(st.floats(-1e6, -1e-9)))
    elif kind == "huge":
        fields[draw(st.integers(4, 6))] = repr(draw(st.floats(MAX_BRDF_PER_SR * (1 + 1e-9), 1e308)))
    elif kind == "count":
        fields = fields[: draw(st.integers(1, 6))] if draw(st.booleans()) else fields + ["1"] * draw(st.integers(1, 3))
    else:
        fields[draw(st.integers(0, 6))] = draw(st.sampled_from(["nan", "inf", "-inf", "1e999"]))
    return ",".join(fields)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_one_bad_row_among_good_ones_is_the_row_named(data):
    rows = data.draw(valid_rows())
    bad = data.draw(corrupted_row(rows))
    # a duplicate must come after its original; anything else may go anywhere
    position = data.draw(st.integers(len(rows) if bad in rows else 0, len(rows)))
    comments = data.draw(st.lists(st.sampled_from(["", "# note", "   ", "  # indented"]), max_size=3))
    lines = ["# header comment", *comments, HEADER, *rows[:position], bad, *rows[position:]]
    with pytest.raises(MeasurementFormatError) as error:
        parse_measurement("\n".join(lines) + "\n")
    assert error.value.row == 2 + len(comments) + 1 + position
    assert str(error.value).startswith(f"row {error.value.row}: ")


def test_metrics_on_known_vectors():
    measured = np.array([1.0, 2.0, 3.0, 4.0])
    assert rms_error(measured, measured) == 0.0
    assert rms_error(measured + 0.5, measured) == pytest.approx(0.5)
    assert rms_error([0.0, 0.0], [3.0, 4.0]) == pytest.approx(math.sqrt(12.5))
    # relative RMS: the error's RMS over the measurement's RMS = sqrt(30/4)
    assert relative_rms_error(1.1 * measured, measured) == pytest.approx(0.1)
    assert relative_rms_error(measured + 1.0, measured) == pytest.approx(1.0 / math.sqrt(7.5))
    assert relative_rms_error([1.0], [0.0]) == math.inf
    # shape: invariant to scale and offset, sign-sensitive, and r = 0.5 for (1, 2, 3) vs (1, 3, 2)
    assert shape_correlation(3.0 * measured + 7.0, measured) == pytest.approx(1.0)
    assert shape_correlation(-measured, measured) == pytest.approx(-1.0)
    assert shape_correlation([1.0, 2.0, 3.0], [1.0, 3.0, 2.0]) == pytest.approx(0.5)
    assert math.isnan(shape_correlation([2.0, 2.0, 2.0], [1.0, 2.0, 3.0]))
    with pytest.raises(ParameterError):
        rms_error([1.0, 2.0], [1.0, 2.0, 3.0])
    with pytest.raises(ParameterError):
        shape_correlation([], [])


def test_the_shipped_example_is_labelled_synthetic_and_follows_its_documented_model():
    path = REPO / "clothlight" / "validation" / "data" / "synthetic_red_cotton.csv"
    m = read_measurement(path)
    assert "SYNTHETIC" in m.comments[0]
    spec = importlib.util.spec_from_file_location("make_synthetic", REPO / "scripts" / "make_synthetic_measurement.py")
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    for theta_i in (0.0, 30.0, 45.0, 60.0):
        signed, rgb = m.in_plane(theta_i)
        np.testing.assert_array_equal(signed, np.arange(-60.0, 71.0, 10.0))
        expected = [script.synthetic_brdf(theta_i, v) for v in signed]
        np.testing.assert_allclose(rgb, expected, rtol=1e-5)
    # by construction the paper's Table 1 colour of real red cotton at normal incidence and view
    r, g, b = m.at(0.0, 0.0)
    assert b / r == pytest.approx(0.08, rel=1e-4) and g / r == pytest.approx(0.011, rel=1e-4)
