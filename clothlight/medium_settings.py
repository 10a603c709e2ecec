"""A medium's settings three ways, mapped in one place: a preset's keys, a bake request, the panel.

A shipped preset is TOML (``precompute/presets/<name>.toml``) whose values are named by dotted keys
(``dye.weight_percent``, ``particles.0.diameter_nm``); a bake is asked for by a
:class:`BakeRequest`, a preset plus overrides of such keys, the seed, the budget and the grids; the
Yarn Medium panel shows a few of those values as properties (``dye_weight_percent``) and keeps the
rest of a fit's values as overrides.  The panel's medium may also start from a preset TOML file of the
user's (:data:`CUSTOM_BASE`, :func:`medium_config`: a colour's shade recipe, which numeric overrides
cannot express), named in the request by its path.  This module holds the mapping between the three, without
Blender: the panel (:mod:`clothlight.blender.properties`), the bake's child
(:mod:`clothlight.bake_worker`), the fit (:func:`fitted_overrides`) and the extension's build
(``scripts/build_extension.py``, the pre-baked requests) all go through it.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import pathlib
from collections.abc import Iterable, Mapping

from precompute.bounds import GRID_SETTINGS
from precompute.bounds import TRANSPORT_DEFAULTS as _TRANSPORT_DEFAULTS
from precompute.optics.medium import DEFAULT_PRESET, RANDOM_ORIENTATION, load_preset_config


def typed_number(value: float) -> float:
    """A float as typed: Blender stores float properties in single precision (0.14 → 0.14000000059604645),
    and a bake's cache key hashes its inputs, so the digits beyond single precision are dropped."""
    return float(f"{float(value):.6g}")


@dataclasses.dataclass(frozen=True)
class BakeRequest:
    """Everything a bake is made from: a shipped preset, overrides of its medium, seed, budget, grids.

    Two equal requests bake the same tables (the bake's cache key hashes the same inputs), which is
    how the add-on recognises tables it shipped or baked before.

    Attributes
    ----------
    preset
        Name of a shipped medium preset (``precompute/presets/<name>.toml``), or the absolute path of a
        preset TOML file (the panel's Base Medium "Custom File", e.g. a colour's recipe: :data:`CUSTOM_BASE`).
    overrides
        ``(dotted key, value)`` pairs applied to the preset's TOML, e.g. ``("dye.weight_percent", 2.0)``.
    seed
        Seed of the transport's random streams.
    paths_per_cell, target_rel_stderr
        The path budget: paths per incidence cell, or the relative standard error of every cell's
        albedo to reach.  Exactly one is set.
    n_around, n_along, angular_resolution, incidence_resolution
        Transport and table grids (``[transport]`` of a preset, see :mod:`precompute.bake`); the
        defaults are the bake's.  ``incidence_resolution`` is an odd integer or ``AUTO_RESOLUTION``
        (the bake chooses it by its accuracy checks).
    dye_series
        A dye range (low, high), % of fibre weight: the bake simulates once for the range and reads
        any dye amount in it in seconds (``precompute.bake.bake(dye_series=...)``); None: one
        simulation per medium.
    """

    preset: str = DEFAULT_PRESET
    overrides: tuple[tuple[str, float], ...] = ()
    seed: int = _TRANSPORT_DEFAULTS["seed"]
    paths_per_cell: int | None = _TRANSPORT_DEFAULTS["paths_per_cell"]
    target_rel_stderr: float | None = _TRANSPORT_DEFAULTS["target_rel_stderr"]
    n_around: int = _TRANSPORT_DEFAULTS["n_around"]
    n_along: int = _TRANSPORT_DEFAULTS["n_along"]
    angular_resolution: int = _TRANSPORT_DEFAULTS["angular_resolution"]
    incidence_resolution: int | str = _TRANSPORT_DEFAULTS["incidence_resolution"]
    dye_series: tuple[float, float] | None = None

    def __post_init__(self):
        object.__setattr__(self, "overrides", tuple(sorted((str(k), typed_number(v)) for k, v in self.overrides)))
        if self.dye_series is not None:
            object.__setattr__(self, "dye_series", tuple(typed_number(v) for v in self.dye_series))
        if self.target_rel_stderr is not None:
            object.__setattr__(self, "target_rel_stderr", typed_number(self.target_rel_stderr))

    def to_json(self) -> str:
        """Canonical JSON: equal requests give equal text."""
        return json.dumps(dataclasses.asdict(self), sort_keys=True, separators=(",", ":"))

    @classmethod
    def from_json(cls, text: str) -> "BakeRequest":
        fields = json.loads(text)
        fields["overrides"] = tuple(tuple(pair) for pair in fields.get("overrides", ()))
        if fields.get("dye_series") is not None:
            fields["dye_series"] = tuple(fields["dye_series"])
        return cls(**fields)

    def same_but_dye(self, other: "BakeRequest") -> bool:
        """Whether ``other`` asks for the same bake but another dye amount."""

        def without_dye(request):
            return dataclasses.replace(request, overrides=tuple(pair for pair in request.overrides
                                                                if pair[0] != "dye.weight_percent"))

        return without_dye(self) == without_dye(other)

    def bake_arguments(self) -> dict:
        """Keyword arguments of :func:`precompute.bake.bake`."""
        grids = {f"transport.{name}": getattr(self, name) for name in GRID_SETTINGS}
        return {
            "preset_or_params": self.preset,
            "overrides": {**dict(self.overrides), **grids},
            "seed": self.seed,
            "paths_per_cell": self.paths_per_cell,
            "target_rel_stderr": None if self.paths_per_cell is not None else self.target_rel_stderr,
            "dye_series": self.dye_series,
        }


def preset_request(name: str) -> BakeRequest:
    """The request of the shipped preset ``name`` untouched: its own [transport] table over the defaults."""
    config = load_preset_config(name)[0]
    given = config.get("transport", {})
    defaults = BakeRequest(preset=name)
    fields = {key: given.get(key, getattr(defaults, key)) for key in ("seed", *GRID_SETTINGS)}
    if given.get("paths_per_cell") is not None and "target_rel_stderr" not in given:
        fields.update(paths_per_cell=int(given["paths_per_cell"]), target_rel_stderr=None)
    else:
        fields.update(target_rel_stderr=float(given.get("target_rel_stderr", defaults.target_rel_stderr)))
    return BakeRequest(preset=name, **fields)


@functools.lru_cache(maxsize=None)
def preset_config(name: str) -> dict:
    """The TOML content of the shipped preset ``name`` (ParameterError for an unknown name)."""
    return load_preset_config(name)[0]


#: The panel's Base Medium that is a preset TOML file of the user's (a colour's recipe, a fit's preset),
#: not a shipped preset: its request names the file by its absolute path.
CUSTOM_BASE = "CUSTOM"

#: The number a .blend stores for each Base Medium: Blender keeps an enum property as its item's number,
#: not its name, so a shipped preset's number never changes and a new preset is appended with the next
#: one.  The first ten are the presets' sorted positions that files saved before 2026-12-07 hold.
BASE_MEDIUM_NUMBERS = {name: number for number, name in enumerate((
    "beige_cotton", "blue_cotton", "dark_dyed_cotton", "delustred_polyester", "paper_2008", "paper_red_cotton",
    "pink_felt", "red_cotton", "undyed_cotton", "white_cotton",
    "voided_red_cotton", "ecru_cotton", "indigo_cotton",
))} | {CUSTOM_BASE: 999}


def is_preset_file(name_or_path: str) -> bool:
    """Whether a request's ``preset`` is a preset TOML file rather than a shipped preset's name."""
    return str(name_or_path).endswith(".toml") or pathlib.Path(str(name_or_path)).is_absolute()


def medium_config(name_or_path: str) -> dict:
    """The TOML content of a shipped preset (by name, as :func:`preset_config`) or of a preset TOML
    file (by path, read again whenever the file changes: a colour solved again rewrites it);
    ParameterError for an unknown name or a missing or unreadable file."""
    if not is_preset_file(name_or_path):
        return preset_config(name_or_path)
    path = pathlib.Path(name_or_path)
    try:
        stat = path.stat()
    except OSError:
        stat = None
    if stat is None or not path.is_file():
        from precompute.errors import ParameterError

        raise ParameterError("preset", str(name_or_path), "an existing preset TOML file")
    return _file_config(str(path.resolve()), stat.st_mtime_ns, stat.st_size)


@functools.lru_cache(maxsize=16)
def _file_config(path: str, _mtime_ns: int, _size: int) -> dict:
    return load_preset_config(path)[0]


def particle_size_key(config: dict) -> str | None:
    """The dotted key of the first particle species' size (its diameter, or a size distribution's
    median), or None when the preset has no particles."""
    particles = config.get("particles") or [{}]
    for key in ("diameter_nm", "median_diameter_nm"):
        if key in particles[0]:
            return f"particles.0.{key}"
    return None


def medium_keys(config: dict) -> dict[str, str]:
    """The dotted TOML keys of the values the panel exposes that the preset ``config`` has: property
    name → key."""
    keys = {"yarn_radius_mm": "yarn.radius_mm"}
    if isinstance(config.get("dye"), dict):
        keys["dye_weight_percent"] = "dye.weight_percent"
    size = particle_size_key(config)
    if size is not None:
        keys["particle_diameter_nm"] = size
        keys["particle_volume_fraction"] = "particles.0.volume_fraction"
    return keys


def takes_dye_series(config: dict) -> bool:
    """Whether the preset ``config`` can bake a dye series (the panel's Dye Range): a dyed medium whose
    dye only absorbs (``MediumParameters.dye_only_absorbs``): not in randomly oriented fibres, whose
    scattering it changes (``precompute.bake.check_dye_series`` refuses those)."""
    fibres = config.get("fibres")
    return "dye_weight_percent" in medium_keys(config) and (
        fibres is None or fibres.get("orientation", RANDOM_ORIENTATION) != RANDOM_ORIENTATION)


def config_value(config: dict, key: str):
    """The value of the dotted ``key`` in ``config`` (a list's items by index: ``particles.0.volume_fraction``);
    KeyError or IndexError when it has none."""
    node = config
    for part in key.split("."):
        node = node[int(part)] if isinstance(node, list) else node[part]
    return node


def shown_key(key: str, config: dict) -> str:
    """A dotted override key as the panel shows it: a particle species by its name."""
    parts = key.split(".")
    if parts[0] == "particles" and len(parts) == 3 and parts[1].isdigit():
        particles = config.get("particles") or []
        index = int(parts[1])
        if index < len(particles) and isinstance(particles[index], dict) and particles[index].get("name"):
            return f"{particles[index]['name']}.{parts[2]}"
    return key


def exposed_values(config: dict, overrides: Iterable[tuple[str, float]]) -> tuple[dict[str, float], dict[str, float]]:
    """The panel's values of the medium ``config`` with ``overrides`` ((dotted key, value) pairs, as a
    :class:`BakeRequest` holds them): the exposed ones by property name, from the overrides or the
    preset, and the overrides left over (key → value), which the panel keeps as fitted values."""
    given = {str(key): float(value) for key, value in overrides}
    values = {}
    for prop, key in medium_keys(config).items():
        value = given.pop(key, None)
        values[prop] = float(config_value(config, key)) if value is None else value
    return values, given


def request_overrides(config: dict, values: Mapping[str, float],
                      fitted: Iterable[tuple[str, float]] = ()) -> tuple[tuple[str, float], ...]:
    """The overrides a bake of the medium ``config`` needs for the panel's exposed ``values`` (by
    property name) and its ``fitted`` values ((key, value) pairs it does not expose): a value only
    where it differs from the preset's, as typed (:func:`typed_number`)."""
    exposed = medium_keys(config)
    overrides = [(key, typed_number(values[prop])) for prop, key in exposed.items()
                 if typed_number(values[prop]) != typed_number(config_value(config, key))]
    for key, value in fitted:
        try:
            preset_value = typed_number(config_value(config, key))
        except (KeyError, IndexError, TypeError, ValueError):
            preset_value = None
        if key not in exposed.values() and typed_number(value) != preset_value:
            overrides.append((key, typed_number(value)))
    return tuple(overrides)


def fitted_overrides(result) -> tuple[tuple[str, float], ...]:
    """The fitted values of a fit's free parameters (:class:`precompute.fit.optimise.FitResult`) as the
    bake's overrides (:attr:`BakeRequest.overrides`: dotted keys of the preset's TOML, a particle
    species by its index; the sheen in the ``[fit]`` table, which the bake's tables carry), so that
    the panel can show and bake the fitted medium."""
    overrides = []
    for parameter in result.free:
        if parameter.is_specular:
            overrides.append((f"fit.{parameter.path}", float(result.specular[parameter.path])))
            continue
        section, _, key = parameter.path.rpartition(".")
        table = result.config
        if section.startswith("particles["):
            species = section[len("particles["):-1]
            index = next(i for i, t in enumerate(result.config["particles"]) if t.get("name") == species)
            section, table = f"particles.{index}", result.config["particles"][index]
        else:
            table = result.config[section]
        overrides.append((f"{section}.{key}", float(table[key])))
    return tuple(overrides)


def fitted_values_json(fitted: Mapping[str, float]) -> str:
    """The panel's store of fitted values it does not expose: JSON (key, value) pairs, "" for none."""
    return json.dumps(sorted([key, value] for key, value in fitted.items())) if fitted else ""
