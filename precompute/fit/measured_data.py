"""Measured cloth BRDFs: a documented CSV format, a validating importer, and comparison metrics.

Format
------
UTF-8 text, one record per line, fields separated by commas (no quoting: every field is a number).
Blank lines and lines whose first non-blank character is ``#`` are comments.  The first other line
is the header, exactly one of

    theta_i,phi_i,theta_o,phi_o,R,G,B                  BRDF per linear Rec.709 RGB channel, 1/sr
    theta_i,phi_i,theta_o,phi_o,wavelength_nm,value    spectral BRDF, 1/sr, one line per wavelength

followed by at least one data line.  Angles are degrees: zeniths ``theta_i`` (toward the light)
and ``theta_o`` (toward the detector) in [0, 90], azimuths ``phi_i``, ``phi_o`` in [0, 360).  A BRDF
is finite, ≥ 0 and at most :data:`MAX_BRDF_PER_SR`.  Wavelengths are in nm within [360, 830] (the
CIE 1931 observer's range); in a spectral file every direction pair lists the same wavelengths,
covering at least 400–700 nm, and is converted to RGB with the bake's convention
(``precompute.tables.color``: D65, CIE 1931 2°, linear Rec.709, negative channels clipped), so a
measurement and a baked model meet in the same space.
No direction pair (and wavelength) may appear twice.

Rows are numbered like the file's lines, comments and blank lines included, so an editor's line
number finds the row an error names.

In-plane curves: the sweep's signed view angle is −θo when the detector is on the light's side
(φo = φi) and +θo on the mirror side (φo = φi + 180°), as in the paper's graphs; at θi = 0 the
measurement's φi still names the plane.

Metrics (for model and baseline against a measurement): RMS error and relative RMS error (RMS
error over the measurement's RMS), and a shape correlation (Pearson's r: 1 when two curves differ
only by scale and offset).
"""

from __future__ import annotations

import math
import pathlib
from dataclasses import dataclass

import numpy as np

from precompute.errors import InputError, ParameterError

RGB_HEADER = ("theta_i", "phi_i", "theta_o", "phi_o", "R", "G", "B")
SPECTRAL_HEADER = ("theta_i", "phi_i", "theta_o", "phi_o", "wavelength_nm", "value")
#: Wavelength range accepted in spectral files (the CIE 1931 colour-matching functions), nm.
WAVELENGTH_RANGE_NM = (360.0, 830.0)
#: Spectral files must cover at least this band to be converted to RGB, nm.
REQUIRED_BAND_NM = (400.0, 700.0)
#: The largest BRDF a measurement may hold, 1/sr: a gonioreflectometer's detector of 0.5° half-angle
#: (2.4·10⁻⁴ sr) sees at most about 4·10³ sr⁻¹ from a perfect mirror at normal view, and cloth far less;
#: a larger value is a unit or format error, which would otherwise outweigh every other view of a fit.
MAX_BRDF_PER_SR = 1.0e4
#: Angles closer than this are the same direction when matching a measurement to a sweep, degrees.
ANGLE_TOLERANCE_DEG = 0.5


class MeasurementFormatError(InputError):
    """A measurement file breaks the format.  ``row`` is the offending line (1-based, as an editor
    counts); ``path`` the file, when the text came from one (:func:`read_measurement`).  Bad input:
    the command lines exit with code 2 on it."""

    def __init__(self, row: int, reason: str, path: str | pathlib.Path | None = None):
        self.row = row
        self.reason = reason
        self.path = None if path is None else str(path)
        super().__init__(f"{'' if path is None else f'{path}, '}row {row}: {reason}")


@dataclass(frozen=True)
class Measurement:
    """A validated measurement.

    Attributes
    ----------
    angles_deg
        (M, 4) direction pairs θi, φi, θo, φo, degrees.
    rgb
        (M, 3) BRDF per linear Rec.709 channel, 1/sr (converted when the file is spectral).
    rows
        (M,) the file row of each direction pair (its first row in a spectral file).
    wavelengths_nm, spectral
        For a spectral file: wavelengths (L,), nm, and the BRDF (M, L), 1/sr; otherwise None.
    gamut_clipping
        Largest negative channel set to 0 in the spectral → RGB conversion, relative to the
        largest channel (0 for an RGB file).
    comments
        The comment lines before the header, without their ``#`` (where a file says what it is).
    """

    angles_deg: np.ndarray
    rgb: np.ndarray
    rows: np.ndarray
    wavelengths_nm: np.ndarray | None = None
    spectral: np.ndarray | None = None
    gamut_clipping: float = 0.0
    comments: tuple[str, ...] = ()

    def in_plane(self, theta_i_deg: float, tolerance_deg: float = ANGLE_TOLERANCE_DEG):
        """Signed view angles (K,), degrees, ascending, and RGB BRDF (K, 3), 1/sr, of the direction
        pairs at incidence θi in its plane of incidence (module docstring)."""
        a = self.angles_deg
        same_incidence = np.abs(a[:, 0] - theta_i_deg) <= tolerance_deg
        azimuth = np.abs((a[:, 3] - a[:, 1] + 180.0) % 360.0 - 180.0)
        light_side = azimuth <= tolerance_deg
        mirror_side = np.abs(azimuth - 180.0) <= tolerance_deg
        normal_view = a[:, 2] <= tolerance_deg
        keep = same_incidence & (light_side | mirror_side | normal_view)
        signed = np.where(light_side & ~normal_view, -a[:, 2], a[:, 2])[keep]
        order = np.argsort(signed, kind="stable")
        return signed[order], self.rgb[keep][order]

    def at(self, theta_i_deg: float, theta_v_deg: float, tolerance_deg: float = ANGLE_TOLERANCE_DEG):
        """RGB BRDF (3,), 1/sr, at incidence θi and signed in-plane view θv, or None if not measured."""
        signed, rgb = self.in_plane(theta_i_deg, tolerance_deg)
        if not len(signed):
            return None
        k = int(np.argmin(np.abs(signed - theta_v_deg)))
        return rgb[k] if abs(signed[k] - theta_v_deg) <= tolerance_deg else None


def read_measurement(path: str | pathlib.Path) -> Measurement:
    """Read and validate a measurement file (module docstring).

    Raises MeasurementFormatError naming the file and the bad row; ParameterError naming ``path`` for
    a file that is missing, a folder or unreadable (both bad input).
    """
    try:
        data = pathlib.Path(path).read_bytes()
    except OSError as error:
        raise ParameterError("measurement file", str(path),
                             f"a measured-data CSV file this user can read ({error.strerror})") from None
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise MeasurementFormatError(data[: error.start].count(b"\n") + 1, "not UTF-8 text", path) from None
    try:
        return parse_measurement(text)
    except MeasurementFormatError as error:  # the file named with its row
        raise MeasurementFormatError(error.row, error.reason, path) from None


def parse_measurement(text: str) -> Measurement:
    """Validate measurement CSV text (module docstring); MeasurementFormatError names the first bad row."""
    lines = text.removeprefix("\ufeff").replace("\r\n", "\n").split("\n")
    records = [(number, line) for number, line in enumerate(lines, start=1)
               if line.strip() and not line.lstrip().startswith("#")]
    if not records:
        raise MeasurementFormatError(
            1, f"no header: expected {','.join(RGB_HEADER)!r} or {','.join(SPECTRAL_HEADER)!r}")
    header_row, header_line = records[0]
    header = tuple(name.strip() for name in header_line.split(","))
    if header not in (RGB_HEADER, SPECTRAL_HEADER):
        raise MeasurementFormatError(header_row, f"header {header_line.strip()!r}; expected "
                                                 f"{','.join(RGB_HEADER)!r} or {','.join(SPECTRAL_HEADER)!r}")
    if len(records) == 1:
        raise MeasurementFormatError(header_row, "a header but no data rows after it")
    is_spectral = header == SPECTRAL_HEADER
    numbers, rows, seen = [], [], {}
    for row, line in records[1:]:
        values = _parse_row(row, line, len(header), is_spectral)
        key = tuple(values[:5] if is_spectral else values[:4])
        if key in seen:
            what = "direction pair and wavelength" if is_spectral else "direction pair"
            raise MeasurementFormatError(row, f"repeats the {what} of row {seen[key]}")
        seen[key] = row
        numbers.append(values)
        rows.append(row)
    numbers = np.array(numbers, dtype=float)
    rows = np.array(rows)
    comments = tuple(line.strip().removeprefix("#").strip() for line in lines[: header_row - 1]
                     if line.lstrip().startswith("#"))
    if not is_spectral:
        return Measurement(numbers[:, :4], numbers[:, 4:7], rows, comments=comments)
    return _spectral_measurement(numbers, rows, comments)


def _parse_row(row: int, line: str, width: int, is_spectral: bool) -> list[float]:
    fields = line.split(",")
    if len(fields) != width:
        raise MeasurementFormatError(row, f"{len(fields)} fields, expected {width}")
    values = []
    for name, field in zip(SPECTRAL_HEADER if is_spectral else RGB_HEADER, fields):
        try:
            value = float(field)
        except ValueError:
            raise MeasurementFormatError(row, f"{name} = {field.strip()!r} is not a number") from None
        if not math.isfinite(value):
            raise MeasurementFormatError(row, f"{name} = {field.strip()!r} is not finite")
        values.append(value)
    for name, value in zip(("theta_i", "phi_i", "theta_o", "phi_o"), values):
        if name.startswith("theta") and not 0.0 <= value <= 90.0:
            raise MeasurementFormatError(row, f"{name} = {value:g} outside [0, 90] degrees")
        if name.startswith("phi") and not 0.0 <= value < 360.0:
            raise MeasurementFormatError(row, f"{name} = {value:g} outside [0, 360) degrees")
    if is_spectral:
        low, high = WAVELENGTH_RANGE_NM
        if not low <= values[4] <= high:
            raise MeasurementFormatError(row, f"wavelength_nm = {values[4]:g} outside [{low:g}, {high:g}] nm")
    for name, value in zip(("value",) if is_spectral else ("R", "G", "B"), values[5:] if is_spectral else values[4:]):
        if value < 0.0:
            raise MeasurementFormatError(row, f"{name} = {value:g}: a BRDF cannot be negative")
        if value > MAX_BRDF_PER_SR:
            raise MeasurementFormatError(row, f"{name} = {value:g} 1/sr: a measured BRDF is at most "
                                              f"{MAX_BRDF_PER_SR:g} 1/sr (a perfect mirror seen by a 0.5° detector "
                                              "gives about 4000)")
    return values


def _spectral_measurement(numbers: np.ndarray, rows: np.ndarray, comments: tuple[str, ...]) -> Measurement:
    pairs: dict[tuple, list[int]] = {}
    for k, values in enumerate(numbers):
        pairs.setdefault(tuple(values[:4]), []).append(k)
    first = next(iter(pairs.values()))
    wavelengths = np.sort(numbers[first, 4])
    for members in pairs.values():
        if not np.array_equal(np.sort(numbers[members, 4]), wavelengths):
            raise MeasurementFormatError(int(rows[members[0]]), f"this direction pair lists wavelengths "
                                         f"{np.sort(numbers[members, 4]).tolist()}, row {int(rows[first[0]])}'s lists "
                                         f"{wavelengths.tolist()}: every pair needs the same")
    low, high = REQUIRED_BAND_NM
    if wavelengths[0] > low or wavelengths[-1] < high:
        raise MeasurementFormatError(int(rows[first[0]]), f"wavelengths {wavelengths[0]:g}–{wavelengths[-1]:g} nm "
                                     f"do not cover {low:g}–{high:g} nm, needed for the conversion to RGB")
    angles = np.array(list(pairs))
    spectral = np.array([numbers[members][np.argsort(numbers[members, 4]), 5] for members in pairs.values()])
    from precompute.tables import color

    rgb, clipping = color.clip_to_gamut(color.spectral_to_rgb(spectral, wavelengths))
    return Measurement(angles, rgb, rows[[members[0] for members in pairs.values()]], wavelengths, spectral, clipping,
                       comments)


def _paired(model, measured) -> tuple[np.ndarray, np.ndarray]:
    model, measured = np.asarray(model, float), np.asarray(measured, float)
    if model.shape != measured.shape or model.size == 0:
        raise ParameterError("model", model.shape, f"the non-empty shape of the measurement, {measured.shape}")
    return model, measured


def rms_error(model, measured) -> float:
    """Root-mean-square difference of two equally shaped arrays, in their unit (1/sr for BRDFs)."""
    model, measured = _paired(model, measured)
    return float(np.sqrt(np.mean((model - measured) ** 2)))


def relative_rms_error(model, measured) -> float:
    """RMS error over the RMS of the measurement (dimensionless; inf for an all-zero measurement)."""
    model, measured = _paired(model, measured)
    scale = float(np.sqrt(np.mean(measured**2)))
    return rms_error(model, measured) / scale if scale > 0.0 else math.inf


def shape_correlation(model, measured) -> float:
    """Pearson's r of two curves: 1 when they differ only by a positive scale and offset, −1 when
    one is the other upside down; NaN when either is constant (a shape needs variation)."""
    model, measured = _paired(model, measured)
    a, b = model.ravel() - model.mean(), measured.ravel() - measured.mean()
    norm = math.sqrt(float(a @ a) * float(b @ b))
    return float(a @ b) / norm if norm > 0.0 else math.nan
