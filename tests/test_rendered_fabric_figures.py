"""Issue 43's band figures of a rendered sweep (scripts/rendered_fabric_figures.py): the views they read
and the ratios they form, on a synthetic validation report."""

from __future__ import annotations

import importlib.util
import pathlib

import numpy as np
import pytest

_PATH = pathlib.Path(__file__).resolve().parents[1] / "scripts" / "rendered_fabric_figures.py"
_SPEC = importlib.util.spec_from_file_location("rendered_fabric_figures", _PATH)
rendered_fabric_figures = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(rendered_fabric_figures)

INCIDENCES = (0.0, 30.0, 45.0, 60.0)
VIEWS = tuple(float(v) for v in range(-80, 81, 10))


def report(model_of) -> dict:
    """A validation report's results: a measured red cloth in the plane of incidence and one material
    whose BRDF at (θi, θv) is ``model_of(θi, θv, measured)``."""
    def measured(ti, tv):
        return np.array([0.05 + 0.001 * abs(tv), 0.006, 0.003 + 0.0001 * ti])

    return {"measurement": {"in_plane": {f"{ti:g}": [[tv, *measured(ti, tv)] for tv in VIEWS] for ti in INCIDENCES}},
            "materials": {"yarn": {
                "metrics": {"brdf_rgb": {c: {"relative_rms": 0.1, "shape_correlation": 0.9} for c in "RGB"} | {
                    "RGB": {"relative_rms": 0.2, "shape_correlation": 0.95}}},
                "views": [{"theta_i_deg": ti, "theta_v_deg": tv, "brdf_rgb": list(model_of(ti, tv, measured(ti, tv)))}
                          for ti in INCIDENCES for tv in VIEWS]}}}


def test_a_cloth_brighter_seen_from_the_light_and_bluer_off_specular_shows_both():
    def model(ti, tv, measured):
        back = 1.5 if tv < 0 and ti >= 45 else 1.0
        return measured * np.array([back, 1.0, 2.0 * back])  # twice the blue everywhere

    figures = rendered_fabric_figures.rendered_figures(report(model))["yarn"]
    assert figures["backscatter_red"] == {"60/-60": pytest.approx(1.5), "60/-40": pytest.approx(1.5),
                                          "45/-60": pytest.approx(1.5)}
    assert figures["off_specular_B/R"] == pytest.approx(2.0)
    # θi ≤ 45°, |θv| ≥ 20° and at least 20° from the mirror (θv = θi)
    expected = sum(1 for ti in INCIDENCES[:3] for tv in VIEWS if abs(tv) >= 20 and abs(tv - ti) >= 20)
    assert figures["off_specular_views"] == expected
    assert figures["relative_rms"]["RGB"] == 0.2


def test_a_cloth_that_is_the_measurement_is_one_everywhere():
    figures = rendered_fabric_figures.rendered_figures(report(lambda ti, tv, measured: measured))["yarn"]
    assert len(figures["backscatter_red"]) == 3
    assert all(ratio == pytest.approx(1.0) for ratio in figures["backscatter_red"].values())
    assert figures["off_specular_B/R"] == pytest.approx(1.0) and figures["off_specular_G/R"] == pytest.approx(1.0)
