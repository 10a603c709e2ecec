"""Measured BRDF data: a documented CSV format, a validating importer, and comparison metrics.

Format (comma-separated, ``#`` starts a comment line, first non-comment line is the header):

    theta_i,phi_i,theta_o,phi_o,R,G,B                 BRDF in 1/sr per RGB channel, or
    theta_i,phi_i,theta_o,phi_o,wavelength_nm,value   spectral BRDF in 1/sr

Angles in degrees: zenith θ in [0, 90], azimuth φ in [0, 360).  In the plane of incidence a view
on the light's side (φo = φi) has a negative signed view angle, the mirror side (φo = φi + 180°)
a positive one, as in the paper's graphs.
"""

from __future__ import annotations

import csv
import io
import math
import pathlib
from dataclasses import dataclass

import numpy as np

RGB_COLUMNS = ("theta_i", "phi_i", "theta_o", "phi_o", "R", "G", "B")
SPECTRAL_COLUMNS = ("theta_i", "phi_i", "theta_o", "phi_o", "wavelength_nm", "value")


class MeasurementFormatError(ValueError):
    """A measurement file breaks the format; the message names the row (1-based, header = row 1)."""


@dataclass(frozen=True)
class Measurement:
    """Rows of a measurement: angles (N, 4) in degrees and values (N, C) in 1/sr."""

    angles: np.ndarray
    values: np.ndarray
    spectral: bool
    wavelengths_nm: np.ndarray | None = None

    def in_plane(self, theta_i: float, tolerance_deg: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
        """Signed view angles and values of the in-plane rows at incidence ``theta_i``."""
        a = self.angles
        same_incidence = np.abs(a[:, 0] - theta_i) <= tolerance_deg
        delta = np.abs(((a[:, 3] - a[:, 1]) + 180.0) % 360.0 - 180.0)
        mirror = np.abs(delta - 180.0) <= tolerance_deg
        light_side = delta <= tolerance_deg
        normal_view = a[:, 2] <= tolerance_deg
        keep = same_incidence & (mirror | light_side | normal_view)
        signed = np.where(light_side[keep] & ~normal_view[keep], -a[keep, 2], a[keep, 2])
        order = np.argsort(signed)
        return signed[order], self.values[keep][order]


def read_measurement(path: str | pathlib.Path) -> Measurement:
    """Read and validate a measurement file (see the module docstring)."""
    return parse_measurement(pathlib.Path(path).read_text())


def parse_measurement(text: str) -> Measurement:
    """Validate measurement CSV text; :class:`MeasurementFormatError` names the first bad row."""
    rows = []
    reader = csv.reader(io.StringIO(text, newline=""))
    while True:
        try:
            row = next(reader)
        except StopIteration:
            break
        except csv.Error as exc:
            raise MeasurementFormatError(f"row {reader.line_num}: unreadable CSV ({exc})") from None
        if row and not row[0].lstrip().startswith("#"):
            rows.append((reader.line_num, row))
    if not rows:
        raise MeasurementFormatError("empty measurement: no header row")
    header_number, header = rows[0]
    header = tuple(h.strip() for h in header)
    if header not in (RGB_COLUMNS, SPECTRAL_COLUMNS):
        raise MeasurementFormatError(f"row {header_number}: header {','.join(header)!r}; expected "
                                     f"{','.join(RGB_COLUMNS)!r} or {','.join(SPECTRAL_COLUMNS)!r}")
    spectral = header == SPECTRAL_COLUMNS
    angles, values = [], []
    for number, row in rows[1:]:
        if len(row) != len(header):
            raise MeasurementFormatError(f"row {number}: {len(row)} fields, expected {len(header)}")
        try:
            numbers = [float(field) for field in row]
        except ValueError:
            raise MeasurementFormatError(f"row {number}: non-numeric field in {row!r}") from None
        if not all(math.isfinite(x) for x in numbers):
            raise MeasurementFormatError(f"row {number}: non-finite value in {row!r}")
        theta_i, phi_i, theta_o, phi_o = numbers[:4]
        for name, value in (("theta_i", theta_i), ("theta_o", theta_o)):
            if not 0.0 <= value <= 90.0:
                raise MeasurementFormatError(f"row {number}: {name} = {value} outside [0, 90] degrees")
        for name, value in (("phi_i", phi_i), ("phi_o", phi_o)):
            if not 0.0 <= value < 360.0:
                raise MeasurementFormatError(f"row {number}: {name} = {value} outside [0, 360) degrees")
        data = numbers[4:]
        brdf = data[1:] if spectral else data
        if spectral and data[0] <= 0:
            raise MeasurementFormatError(f"row {number}: wavelength_nm = {data[0]} must be > 0")
        if any(v < 0 for v in brdf):
            raise MeasurementFormatError(f"row {number}: negative BRDF {brdf}")
        angles.append(numbers[:4])
        values.append(data)
    if not angles:
        raise MeasurementFormatError(f"row {header_number}: a header but no data rows")
    values = np.array(values)
    if spectral:
        return Measurement(np.array(angles), values[:, 1:], True, values[:, 0])
    return Measurement(np.array(angles), values, False)


def rms_error(model, measured) -> float:
    return float(np.sqrt(np.mean((np.asarray(model, float) - np.asarray(measured, float)) ** 2)))


def relative_rms_error(model, measured) -> float:
    """RMS error divided by the RMS of the measurement."""
    scale = float(np.sqrt(np.mean(np.asarray(measured, float) ** 2)))
    return rms_error(model, measured) / scale if scale > 0 else float("inf")


def shape_correlation(model, measured) -> float:
    """Pearson correlation of two curves: 1 when they have the same shape whatever their scale."""
    a, b = np.asarray(model, float).ravel(), np.asarray(measured, float).ravel()
    if a.std() == 0 or b.std() == 0:
        return float("nan")
    return float(np.corrcoef(a, b)[0, 1])
