"""The Yarn Medium panel's Match Colour in a separate process, so Blender's interface never waits on it (issue 44).

An artist picks a colour; the solve of ``python -m clothlight.fit.match_colour`` (the same shade
model, solve and preset: :mod:`clothlight.fit.colour_match`) finds the recipe of red, blue and
yellow dye and the fibre's own absorption that give the panel's yarn that colour, and writes it as a
preset TOML that the panel then bakes (its Base Medium "Custom File").  It runs in the child
:mod:`clothlight.fit.colour_match_worker`, driven as the bake and the fit are
(:class:`clothlight.jobs.ChildJob`: JSON-line progress, ``cancel`` on stdin, exit codes 0/2/130/1).
The shade model renders the swatches' response with bpy the first time (then cached), so inside
Blender the child is Blender itself in background mode.

A colour the dyes cannot reach writes nothing: the job's outcome still carries the nearest recipe
and its preset's text, which :func:`write_preset` writes when the user applies it anyway.  A
cancelled job writes nothing either (the preset is written whole at the end, the shade model's
cache entries are staged).

No Blender here: the operators use it, and the tests drive it from a plain Python.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import pathlib
import re

from .jobs import ChildJob, JobCancelled, JobFailed
from .medium_settings import BakeRequest, config_value, preset_request

COLOUR_WORKER_MODULE = "clothlight.fit.colour_match_worker"
#: Keys of the medium the recipe replaces: the panel's values of these are not the yarn's to keep.
RECIPE_KEYS = ("dye.", "host.absorption_per_mm", "fibres.absorption_per_mm")


def srgb_hex(srgb) -> str:
    """``#rrggbb`` of an sRGB colour (3 values in [0, 1])."""
    return "#" + "".join(f"{round(255 * min(max(float(v), 0.0), 1.0)):02x}" for v in srgb)


def dye_label(name: str) -> str:
    """A recipe's dye as the panel names it: ``congo_red.csv`` → ``Congo red``."""
    stem = pathlib.Path(str(name)).name.removesuffix(".csv").replace("_", " ")
    return stem[:1].upper() + stem[1:]


def recipe_file_name(medium: BakeRequest, srgb) -> str:
    """The preset file a colour's recipe is written to: the yarn's name (a shipped preset's, or a
    custom file's without an earlier colour's suffix), the colour, and a short hash of the panel's
    changes to the yarn when there are any (``red_cotton_6a2717.toml``)."""
    import hashlib

    yarn = pathlib.Path(medium.preset).stem if medium.preset.endswith(".toml") else medium.preset
    yarn = re.sub(r"(_[0-9a-f]{6})+$", "", yarn) or "yarn"
    name = f"{yarn}_{srgb_hex(srgb)[1:]}"
    kept = [pair for pair in medium.overrides if not pair[0].startswith(RECIPE_KEYS)]
    if kept:
        name += "_" + hashlib.sha256(json.dumps(kept).encode()).hexdigest()[:6]
    return name + ".toml"


def write_preset(text: str, out: str | os.PathLike) -> pathlib.Path:
    """Write a recipe's preset ``text`` to ``out`` whole (a partial file, then renamed): a reader never
    sees half a preset."""
    out = pathlib.Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    partial = out.with_name(f".{out.name}.partial")
    partial.write_text(text, encoding="utf-8")
    partial.replace(out)
    return out


@dataclasses.dataclass(frozen=True)
class ColourMatchRequest:
    """A colour to match on a yarn (``python -m clothlight.fit.match_colour``).

    Attributes
    ----------
    target
        The colour, sRGB (gamma-encoded, as a colour picker gives it), three values in [0, 1].
    medium
        The yarn to dye as the panel bakes it (:class:`clothlight.medium_settings.BakeRequest`: a shipped
        preset or a preset TOML file, and overrides of its values); its dye and fibre absorption are
        replaced by the recipe, its other values and changed grids kept (:meth:`base_config`).
    out
        The preset TOML file to write.
    nearest
        Write the nearest recipe when the dyes cannot reach the colour (``--nearest``); otherwise
        nothing is written then.
    seed
        Seed of the shade model's transport and renders (``--seed``).
    """

    target: tuple[float, float, float] = (0.5, 0.5, 0.5)
    medium: BakeRequest = BakeRequest()
    out: str = ""
    nearest: bool = False
    seed: int = 0

    def __post_init__(self):
        object.__setattr__(self, "target", tuple(float(f"{float(v):.6g}") for v in self.target))
        object.__setattr__(self, "out", str(self.out))

    @property
    def hex(self) -> str:
        return srgb_hex(self.target)

    def to_json(self) -> str:
        """Canonical JSON: equal requests give equal text."""
        fields = dataclasses.asdict(self)
        fields["medium"] = json.loads(self.medium.to_json())
        return json.dumps(fields, sort_keys=True, separators=(",", ":"))

    @classmethod
    def from_json(cls, text: str) -> "ColourMatchRequest":
        fields = json.loads(text)
        if not isinstance(fields, dict):
            raise ValueError("a ColourMatchRequest is a JSON object")
        if "medium" in fields:
            fields["medium"] = BakeRequest.from_json(json.dumps(fields["medium"]))
        fields["target"] = tuple(fields.get("target", ()))
        return cls(**fields)

    def check(self) -> "ColourMatchRequest":
        """This request, if a solve can start from it; ParameterError naming the first bad field:
        the colour, the yarn (a shipped preset or a readable preset file), the output file."""
        from precompute import bounds, outputs
        from precompute.errors import ParameterError
        from precompute.optics.medium import load_preset_config

        if len(self.target) != 3 or not all(math.isfinite(v) and 0.0 <= v <= 1.0 for v in self.target):
            raise ParameterError("target colour", list(self.target), "an sRGB colour: three values in [0, 1]")
        load_preset_config(self.medium.preset)
        bounds.SEED.check(self.seed, "seed")
        outputs.check_writable_file(self.out, "out", what="a preset TOML file")
        return self

    def base_config(self) -> tuple[dict, pathlib.Path]:
        """The yarn to dye as a preset's TOML content and the folder its files resolve in: the
        medium's preset with the panel's overrides but the dye's and the fibre absorption's (the
        recipe's), and the grids where the panel changed them (an untouched preset is its file's
        content, as ``--preset`` reads it, and shares its cached shade model)."""
        from precompute.bake import apply_overrides
        from precompute.bounds import GRID_SETTINGS
        from precompute.optics.medium import load_preset_config

        config, base_dir = load_preset_config(self.medium.preset)
        own = preset_request(self.medium.preset)
        overrides = {key: value for key, value in self.medium.overrides if not key.startswith(RECIPE_KEYS)}
        for name in GRID_SETTINGS:
            value = getattr(self.medium, name)
            if value != getattr(own, name):
                overrides[f"transport.{name}"] = value
        overrides = {key: value for key, value in overrides.items() if not _same(config, key, value)}
        return (apply_overrides(config, overrides) if overrides else config), base_dir


def _same(config: dict, key: str, value) -> bool:
    try:
        return config_value(config, key) == value
    except (KeyError, IndexError, TypeError, ValueError):
        return False


class ColourMatchFailed(JobFailed):
    """The child solve stopped with an error; ``message`` is meant for the user, ``log`` for the console."""


class ColourMatchCancelled(JobCancelled):
    """The solve was cancelled before it finished: nothing was written."""


@dataclasses.dataclass
class ColourMatchOutcome:
    """A finished solve: the recipe, how near its cloth comes to the colour, and its preset.

    ``dye_percent`` % of fibre weight per dye of ``dyes``; ``fibre_absorption_per_mm`` the fibre's own
    absorption, 1/mm; ``delta_e`` CIEDE2000 between the cloth (lit and seen along its normal,
    specular excluded) and the colour; ``reached`` whether that is within the match's 2;
    ``cloth_srgb`` the cloth's colour, sRGB; ``preset`` the file the recipe is (``written``) or would
    be written to; ``text`` the preset's TOML (:func:`write_preset` writes it)."""

    target_srgb: tuple[float, ...]
    dyes: tuple[str, ...]
    dye_percent: tuple[float, ...]
    fibre_absorption_per_mm: float
    delta_e: float
    reached: bool
    cloth_srgb: tuple[float, ...]
    preset: pathlib.Path
    written: bool
    text: str
    evaluations: int = 0
    seconds: float = 0.0

    def recipe_text(self) -> str:
        """The recipe in one line: each dye used, % of fibre weight, then the fibre's absorption."""
        dyes = ", ".join(f"{dye_label(name)} {percent:.3g} %" for name, percent in zip(self.dyes, self.dye_percent)
                         if percent > 0)
        return f"{dyes or 'no dye'}; fibre absorption {self.fibre_absorption_per_mm:.3g} /mm"

    def to_json(self) -> str:
        fields = dataclasses.asdict(self)
        fields["preset"] = str(self.preset)
        return json.dumps(fields)

    @classmethod
    def from_json(cls, text: str) -> "ColourMatchOutcome":
        fields = json.loads(text)
        for name in ("target_srgb", "dyes", "dye_percent", "cloth_srgb"):
            fields[name] = tuple(fields[name])
        fields["preset"] = pathlib.Path(fields["preset"])
        return cls(**fields)


class ColourMatchJob(ChildJob):
    """One colour match in a child process.  ``start()``, then ``poll()`` until ``done``; or ``wait()``.

    Parameters
    ----------
    request
        What to match (checked by :meth:`ColourMatchRequest.check` first, by the caller).
    cache_dir
        The cache folder of the shade model (the swatches' response and the clear yarn's absorption
        series: the bake cache's).
    threads
        CPU threads of the transport; None: all.
    blender
        ``bpy.app.binary_path``: inside Blender, the child is Blender (:func:`clothlight.jobs.child_command`).
    numba_cache_dir, bytecode_cache_dir
        As :class:`clothlight.jobs.ChildJob`.
    """

    module = COLOUR_WORKER_MODULE
    what = "colour match"
    imports_bpy = True
    failure = ColourMatchFailed
    cancellation = ColourMatchCancelled
    cancelled_note = "nothing was written"
    killed_note = "a later match removes its temporary cache folder"

    def __init__(self, request: ColourMatchRequest, *, cache_dir, threads: int | None = None,
                 blender: str | None = None, numba_cache_dir=None, bytecode_cache_dir=None):
        super().__init__(numba_cache_dir=numba_cache_dir, bytecode_cache_dir=bytecode_cache_dir, blender=blender)
        self.request = request
        self.cache_dir = pathlib.Path(cache_dir)
        self.threads = threads
        self.outcome: ColourMatchOutcome | None = None

    def arguments(self) -> list[str]:
        arguments = ["--request", self.request.to_json(), "--cache-dir", str(self.cache_dir)]
        if self.threads:
            arguments += ["--threads", str(int(self.threads))]
        return arguments

    def outcome_from(self, event: dict) -> ColourMatchOutcome:
        return ColourMatchOutcome(
            target_srgb=tuple(float(v) for v in event["target_srgb"]), dyes=tuple(event["dyes"]),
            dye_percent=tuple(float(v) for v in event["dye_percent"]),
            fibre_absorption_per_mm=float(event["fibre_absorption_per_mm"]), delta_e=float(event["delta_e_2000"]),
            reached=bool(event["reached"]), cloth_srgb=tuple(float(v) for v in event["cloth_srgb"]),
            preset=pathlib.Path(event["preset"]), written=bool(event["written"]), text=str(event["text"]),
            evaluations=int(event.get("evaluations", 0)), seconds=float(event.get("seconds", 0.0)))


__all__ = ["COLOUR_WORKER_MODULE", "ColourMatchCancelled", "ColourMatchFailed", "ColourMatchJob",
           "ColourMatchOutcome", "ColourMatchRequest", "dye_label", "recipe_file_name", "srgb_hex", "write_preset"]
