"""The weave of the measured sample a preset was fitted on, by name: its ``[sample]`` table.

A cloth BRDF depends on the weave as much as on the yarn: which faces of its yarns a view sees lit,
at which local angles, and how much of the cloth is gap (docs/fitting.md, "The sample's weave",
measures both weaves below against the raw-data fabrics).  MERL measured its fabrics
wrapped round a cylinder, so their weave is unknown (``../shared/data/real_fabrics/README.md``); a
preset names the weave its medium was fitted on, and the fit, the tables baked from it and the
figures that compare it with a fabric use that weave::

    [sample]
    weave = "sheeting"

``"open"`` (the default, also where a preset has no ``[sample]`` table)
    the validation weave: plain, round yarns at 0.5 mm covering 0.64 of the cloth;
``"sheeting"``
    cotton sheeting: plain, the yarns pressed 1.6 : 1 where they cross and relaxing between, at
    Peirce's cover factor 14, covering 0.84;
``"pressed"``
    plain, the yarns pressed 5 : 1 all along, side by side with no gap between them, covering 0.99.

The geometry of each is the add-on's (``clothlight.weave.sample_weaves``); this module only reads
and checks the name, so that the bake can record it without the add-on.
"""

from __future__ import annotations

from collections.abc import Mapping

from precompute.errors import ParameterError

SAMPLE_TABLE = "sample"
SAMPLE_WEAVE_KEY = "weave"
SAMPLE_WEAVES = ("open", "sheeting", "pressed")
DEFAULT_SAMPLE_WEAVE = "open"


def sample_weave_name(config: Mapping) -> str:
    """The sample weave a preset's TOML content ``config`` names (:data:`DEFAULT_SAMPLE_WEAVE` when it
    has no ``[sample]`` table); an unknown key or weave is refused naming ``sample.<key>``."""
    table = config.get(SAMPLE_TABLE, {})
    if not isinstance(table, Mapping):
        raise ParameterError(SAMPLE_TABLE, table, f"a table with the key {SAMPLE_WEAVE_KEY!r}")
    for key in table:
        if key != SAMPLE_WEAVE_KEY:
            raise ParameterError(f"{SAMPLE_TABLE}.{key}", table[key], f"the key {SAMPLE_WEAVE_KEY!r}")
    name = table.get(SAMPLE_WEAVE_KEY, DEFAULT_SAMPLE_WEAVE)
    if name not in SAMPLE_WEAVES:
        raise ParameterError(f"{SAMPLE_TABLE}.{SAMPLE_WEAVE_KEY}", name, f"one of {', '.join(SAMPLE_WEAVES)}")
    return name


__all__ = ["DEFAULT_SAMPLE_WEAVE", "SAMPLE_TABLE", "SAMPLE_WEAVES", "SAMPLE_WEAVE_KEY", "sample_weave_name"]
