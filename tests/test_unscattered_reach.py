"""How the yarn material reads the unscattered light's table (clothlight/yarn_tables.py): the general
mode's reach, the path length beyond which a path weighs less than the shader's floor, and whether
any path is that short (else the general mode is plain Cycles nodes)."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from clothlight.yarn_tables import (
    GENERAL_MODE_MIN_WEIGHT,
    attenuation_reach,
    has_unscattered_light,
    renders_in_nodes,
    shortest_unscattered_path,
)
from precompute.optics import ballistic
from precompute.tables.layout import interpolate_attenuation


def test_the_reach_is_where_the_attenuation_falls_below_the_general_modes_floor_for_good():
    floor = GENERAL_MODE_MIN_WEIGHT
    table = np.exp(-np.outer(ballistic.attenuation_lengths(), [3.0, 1.5, 1.0]))[None]
    reach = attenuation_reach(table)
    step = ballistic.MAX_LENGTH_OVER_RADIUS / (ballistic.ATTENUATION_SAMPLES - 1)
    assert interpolate_attenuation(table, reach - step).max() >= floor
    beyond = np.linspace(reach, 2.0 * ballistic.MAX_LENGTH_OVER_RADIUS, 500)
    assert interpolate_attenuation(table, beyond).max() < floor
    assert reach == pytest.approx(math.log(1.0 / floor), abs=step)  # the slowest channel, e^{-ℓ}
    assert attenuation_reach(np.full((1, ballistic.ATTENUATION_SAMPLES, 3), 0.5 * floor)) == 0.0
    clear = np.exp(-np.outer(ballistic.attenuation_lengths(), [0.1, 0.1, 0.1]))[None]
    assert attenuation_reach(clear) == math.inf


@pytest.mark.parametrize("index", [1.33, 1.557, 2.0])
def test_the_shortest_unscattered_path_is_the_least_chord_over_every_view(index):
    # Views over the hemisphere, denser toward the horizon where the least chord lies.
    rng = np.random.default_rng(5)
    z = rng.uniform(0.0, 1.0, 200_000) ** 3
    phi = rng.uniform(0.0, 2.0 * math.pi, z.size)
    planar = np.sqrt(1.0 - z**2)
    wo = np.stack([planar * np.cos(phi), planar * np.sin(phi), z], axis=-1)
    wo = np.concatenate([wo, [[0.0, 1.0, 0.0], [0.0, -1.0, 0.0]]])
    _, _, length = ballistic.unscattered_paths(wo, index)
    shortest = shortest_unscattered_path(index)
    assert length.min() >= shortest * (1.0 - 1e-9)
    assert length.min() == pytest.approx(shortest, rel=1e-9)  # reached at the horizon across the axis
    assert length[..., 1:].min() > shortest  # a path reflected inside is longer still


def test_a_medium_renders_in_plain_nodes_only_where_no_unscattered_path_reaches_the_floor():
    reach = {"scattering": 0.78, "clear": math.inf, "at the shortest chord": shortest_unscattered_path(1.557)}
    tables = {name: SimpleNamespace(unscattered_reach=value, host_index=1.557) for name, value in reach.items()}
    assert renders_in_nodes(tables["scattering"])
    assert not renders_in_nodes(tables["clear"])
    assert not renders_in_nodes(tables["at the shortest chord"])  # that path would still be rendered


def test_a_yarn_of_fibres_in_air_renders_its_unscattered_light_in_plain_nodes():
    # Its host is air: light passes straight between the fibres at the yarn's edges, a path plain
    # nodes render.  A denser host with the same reach refracts it, and only the OSL shader can.
    air = SimpleNamespace(unscattered_reach=0.43, host_index=1.0)
    assert has_unscattered_light(air) and renders_in_nodes(air)
    glass_rod = SimpleNamespace(unscattered_reach=math.inf, host_index=1.557)
    assert has_unscattered_light(glass_rod) and not renders_in_nodes(glass_rod)
    scattering = SimpleNamespace(unscattered_reach=0.43, host_index=1.557)  # shorter than any chord
    assert not has_unscattered_light(scattering) and renders_in_nodes(scattering)
    opaque = SimpleNamespace(unscattered_reach=0.0, host_index=1.0)
    assert not has_unscattered_light(opaque)


def test_in_air_the_one_unscattered_path_runs_straight_along_the_views_chord():
    # What the plain-node material assumes (yarn_nodes._straight_unscattered_light): at η = 1 the
    # closed form's first path carries everything, leaves along the view's own line, and is
    # 2 ω_z / (1 − ω_x²) radii long.
    rng = np.random.default_rng(11)
    z = rng.uniform(0.01, 1.0, 2000)
    phi = rng.uniform(0.0, 2.0 * math.pi, z.size)
    planar = np.sqrt(1.0 - z**2)
    wo = np.stack([planar * np.cos(phi), planar * np.sin(phi), z], axis=-1)
    toward_light, factor, length = ballistic.unscattered_paths(wo, 1.0)
    np.testing.assert_allclose(toward_light[:, 0], -wo, atol=1e-12)
    np.testing.assert_allclose(factor[:, 0], 1.0)
    np.testing.assert_allclose(factor[:, 1:], 0.0, atol=1e-12)
    np.testing.assert_allclose(length[:, 0], 2.0 * wo[:, 2] / (1.0 - wo[:, 0] ** 2), rtol=1e-9)
