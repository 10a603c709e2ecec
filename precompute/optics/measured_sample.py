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

**The sample's azimuths.**  MERL measured each fabric as an isotropic BRDF, so the weave's anisotropy
is averaged out of the data (``../shared/data/real_fabrics/README.md``): the fabric's value at a view
is its mean over the weave's azimuth about the normal.  The fit's forward model renders the sample at
a few azimuths α (the warp's angle from the plane of incidence, degrees) and averages them::

    [sample]
    weave = "pressed"
    azimuths_deg = [0, 45, 90, 135]

``[0, 90]`` (the default) sees the warp and the weft alike, each square to the light or across it; a
plain weave's yarns at 45° to the light scatter the fibres' cones out of the plane of incidence,
which only the diagonal azimuths show (docs/fitting.md, "The weave at every azimuth").
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from precompute.errors import ParameterError

SAMPLE_TABLE = "sample"
SAMPLE_WEAVE_KEY = "weave"
SAMPLE_WEAVES = ("open", "sheeting", "pressed")
DEFAULT_SAMPLE_WEAVE = "open"
SAMPLE_AZIMUTHS_KEY = "azimuths_deg"
#: The warp's azimuths from the plane of incidence that a response averages, degrees, where a preset
#: names none: the warp square to the light and across it.
DEFAULT_SAMPLE_AZIMUTHS_DEG = (0.0, 90.0)


def _sample_table(config: Mapping) -> Mapping:
    table = config.get(SAMPLE_TABLE, {})
    keys = f"the keys {SAMPLE_WEAVE_KEY!r} and {SAMPLE_AZIMUTHS_KEY!r}"
    if not isinstance(table, Mapping):
        raise ParameterError(SAMPLE_TABLE, table, f"a table with {keys}")
    for key in table:
        if key not in (SAMPLE_WEAVE_KEY, SAMPLE_AZIMUTHS_KEY):
            raise ParameterError(f"{SAMPLE_TABLE}.{key}", table[key], keys)
    return table


def sample_weave_name(config: Mapping) -> str:
    """The sample weave a preset's TOML content ``config`` names (:data:`DEFAULT_SAMPLE_WEAVE` when it
    has no ``[sample]`` table); an unknown key or weave is refused naming ``sample.<key>``."""
    name = _sample_table(config).get(SAMPLE_WEAVE_KEY, DEFAULT_SAMPLE_WEAVE)
    if name not in SAMPLE_WEAVES:
        raise ParameterError(f"{SAMPLE_TABLE}.{SAMPLE_WEAVE_KEY}", name, f"one of {', '.join(SAMPLE_WEAVES)}")
    return name


def sample_azimuths_deg(config: Mapping) -> tuple[float, ...]:
    """The warp's azimuths from the plane of incidence (degrees, ascending in [0°, 180°), distinct)
    that the forward model averages the sample over, as ``config``'s ``[sample] azimuths_deg`` names
    them (:data:`DEFAULT_SAMPLE_AZIMUTHS_DEG` where it names none); a weave looks the same turned by
    180°, so an angle outside [0°, 180°) is refused, as are repeats and an unsorted list."""
    values = _sample_table(config).get(SAMPLE_AZIMUTHS_KEY, DEFAULT_SAMPLE_AZIMUTHS_DEG)
    path, expected = f"{SAMPLE_TABLE}.{SAMPLE_AZIMUTHS_KEY}", "a list of distinct ascending angles in [0, 180) degrees"
    if (isinstance(values, (str, bytes)) or not isinstance(values, Sequence) or not values
            or any(isinstance(v, bool) or not isinstance(v, (int, float)) or not 0.0 <= v < 180.0 for v in values)
            or any(b <= a for a, b in zip(values, values[1:]))):
        raise ParameterError(path, values, expected)
    return tuple(float(v) for v in values)


__all__ = ["DEFAULT_SAMPLE_AZIMUTHS_DEG", "DEFAULT_SAMPLE_WEAVE", "SAMPLE_AZIMUTHS_KEY", "SAMPLE_TABLE",
           "SAMPLE_WEAVES", "SAMPLE_WEAVE_KEY", "sample_azimuths_deg", "sample_weave_name"]
