"""The light scattered between yarns (clothlight/garment/between_yarns.py): the yarn's albedo over
its whole lit surface, the gain of the bounces between yarns, and the BSDF term that carries it,
checked on yarns and cloths whose answers are known in closed form.  No Blender."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clothlight.garment import between_yarns
from clothlight.garment.goniometry import SIDES
from clothlight.garment.response_measurement import YarnLookup
from clothlight.garment.tables import energy_balance, with_light_between_yarns
from clothlight.validation.response import TableLayout
from precompute.errors import ParameterError
from precompute.tables import layout as table_layout
from precompute.tables.grids import AngularGrid

N_I, N_O = 11, 8


def lambertian_yarn(albedo, n_i: int = 21, n_o: int = 12) -> YarnLookup:
    """A yarn whose surface is Lambertian of ``albedo`` (RGB) and lets nothing through unscattered:
    ρ = albedo/π cos θ_i where the light reaches the point, 0 on its dark side."""
    cos_i = AngularGrid("sphere", n_i).cell_centers()[:, 2]
    rho = np.maximum(cos_i, 0.0)[:, None, None] * np.asarray(albedo, float)[None, None, :] / math.pi
    atlas = table_layout.brdf_atlas(np.repeat(rho, n_o * n_o, axis=1))
    return YarnLookup(atlas, np.zeros((16, 3)), TableLayout(n_i, n_o, 16, 1.5, 0.05), {})


def test_a_lambertian_yarn_sends_away_its_albedo_under_every_sun():
    """Over a round yarn lit from any angle to its axis, a Lambertian surface of albedo ρ0 sends
    out ρ0 of the intercepted flux: ∫ ρ0 cos⁺ dφ / (2 sin α) = ρ0."""
    yarn = lambertian_yarn([0.8, 0.4, 0.1])
    albedo = between_yarns.cylinder_albedo(yarn, np.array([0.0, 0.5, 0.8]))
    np.testing.assert_allclose(albedo, [[0.8, 0.4, 0.1]] * 3, rtol=0.03)
    # Near the cloth plane one of the two yarns is lit along its axis, where the table's incidence
    # cells interpolate cos⁺ across the terminator: within the grid's 5 %.
    directions = AngularGrid("sphere", 5).cell_centers()
    np.testing.assert_allclose(between_yarns.lit_yarn_albedo(yarn, directions), [[0.8, 0.4, 0.1]] * 25, rtol=0.05)
    np.testing.assert_allclose(between_yarns.broad_light_albedo(yarn), [0.8, 0.4, 0.1], rtol=0.03)


def test_light_crossing_a_clear_yarn_counts_in_its_albedo():
    """A yarn that scatters nothing but lets its light through unattenuated sends away what the two
    Fresnel crossings pass (a little less than 1), and nothing when the crossing is black."""
    dark = lambertian_yarn([0.0, 0.0, 0.0])
    clear = YarnLookup(dark.atlas, np.ones((16, 3)), dark.layout, {})
    sent = between_yarns.cylinder_albedo(clear, np.array([0.0]))[0]
    assert np.all((sent > 0.8) & (sent < 1.0))
    assert np.all(between_yarns.cylinder_albedo(dark, np.array([0.0])) == 0.0)


def test_the_gain_sums_the_bounces_between_yarns():
    """g = a q / (1 − a q): nothing from black yarns or a weave where nothing meets another yarn;
    with white yarns every bounce's light leaves at last: g = q / (1 − q)."""
    np.testing.assert_allclose(between_yarns.between_yarns_gain([0.0, 0.5, 1.0], 0.0), 0.0)
    np.testing.assert_allclose(between_yarns.between_yarns_gain([0.0], 0.3), 0.0)
    np.testing.assert_allclose(between_yarns.between_yarns_gain([1.0], 0.3), 0.3 / 0.7)
    # A bounce at a time: E q/(1 − q) meets yarns, a of it is sent on, 1 − q of that leaves, …
    a, q = 0.6, 0.25
    met, left = q / (1.0 - q), 0.0
    for _ in range(200):
        sent = a * met
        left, met = left + (1.0 - q) * sent, q * sent
    np.testing.assert_allclose(between_yarns.between_yarns_gain([a], q), left, rtol=1e-9)
    with pytest.raises(ParameterError, match="lost_to_yarns"):
        between_yarns.between_yarns_gain([0.5], 1.0)
    with pytest.raises(ParameterError, match="albedo"):
        between_yarns.between_yarns_gain([1.5])


def cloth(albedo: float = 0.5, coverage: float = 0.6) -> tuple[dict, dict]:
    """ρ and coverage of a cloth whose yarns scatter diffusely to both sides: ρ = albedo/(2π) cos θ_i
    on each side for light from either side, covering ``coverage`` of the cloth."""
    cos_i = np.abs(AngularGrid("sphere", N_I).cell_centers()[:, 2])
    rho = np.repeat((albedo / (2.0 * math.pi) * cos_i)[:, None, None], N_O * N_O, axis=1)
    rho = np.repeat(rho, 3, axis=2)
    return {side: rho.copy() for side in SIDES}, {side: np.full(N_O * N_O, coverage) for side in SIDES}


def test_the_term_carries_the_gain_times_the_escaped_light_and_keeps_the_open_weave():
    rho, coverage = cloth()
    single = {side: energy_balance(rho, coverage, N_I, side) for side in SIDES}
    escaped = {side: single[side]["reflected"] + single[side]["transmitted"] for side in SIDES}
    gain = np.array([0.3, 0.1, 0.0])
    shape = between_yarns.broad_light_shape(rho)
    added = between_yarns.between_yarns_rho(escaped, gain, shape, N_I)
    steep = np.abs(AngularGrid("sphere", N_I).cell_centers()[:, 2]) > 0.5
    for side in SIDES:
        balance = energy_balance(added, coverage, N_I, side)
        # Half each way, as from light that no longer knows the side it came from; the other side's
        # table read between its incidence cells as the shader interpolates ρ (= f |cos θ_i|) there.
        np.testing.assert_allclose(balance["reflected"][steep], balance["transmitted"][steep], rtol=0.15)
        np.testing.assert_allclose((balance["reflected"] + balance["transmitted"])[steep],
                                   (escaped[side] * gain)[steep], rtol=0.06)
    np.testing.assert_allclose(balance["open"], single["front"]["open"])
    exits = AngularGrid("hemisphere", N_O)
    np.testing.assert_allclose(2.0 * (exits.cell_centers()[:, 2] * exits.cell_solid_angle) @ shape, 1.0)


def test_tables_add_the_term_to_the_measurement_and_record_it():
    from clothlight.garment.goniometry import ClothMeasurement

    rho, coverage = cloth()
    zero = {side: np.zeros(rho[side].shape[:2]) for side in SIDES}
    measurement = ClothMeasurement(rho, zero, zero, {"weight": 0.0, "slope": 0.3, "ior": 1.5}, coverage, 1.0,
                                   (10.0, 10.0), 0.1, 0.0)
    yarn = lambertian_yarn([0.6, 0.3, 0.0])
    added, record = with_light_between_yarns(measurement, yarn)
    gain = between_yarns.between_yarns_gain(between_yarns.broad_light_albedo(yarn))
    np.testing.assert_allclose(gain, between_yarns.between_yarns_gain([0.6, 0.3, 0.0]), rtol=0.05)
    np.testing.assert_allclose(record["gain_rgb"], gain, rtol=1e-6)
    before = energy_balance(measurement.rho, coverage, N_I)
    after = energy_balance(added.rho, coverage, N_I)
    lit = np.abs(AngularGrid("sphere", N_I).cell_centers()[:, 2]) > 0.3
    gained = (after["reflected"] + after["transmitted"]) / (before["reflected"] + before["transmitted"])
    np.testing.assert_allclose(gained[lit], np.broadcast_to(1.0 + gain, gained[lit].shape), rtol=0.03)
    assert record["normal_incidence_and_view_rho_rgb"][0] > record["normal_incidence_and_view_rho_rgb"][1] > 0.0
    assert record["normal_incidence_and_view_rho_rgb"][2] == 0.0
    assert added.specular is measurement.specular and added.coverage is measurement.coverage
