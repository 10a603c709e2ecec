"""Weaving drafts in WIF, the Weaving Information File (version 1.1, 1997): read and write.

A WIF is an INI file.  The drawdown follows from the loom set-up: [THREADING] puts every warp
end on shafts (``end=shaft[,shaft…]``), [TIEUP] ties every treadle to shafts
(``treadle=shaft,…``), [TREADLING] says which treadles each pick presses (``pick=treadle,…``) —
or [LIFTPLAN] says directly which shafts each pick lifts (``pick=shaft,…``, a dobby or table
loom; it takes precedence).  With a rising shed ([WEAVING] ``Rising Shed``, default true) the
lifted shafts raise their ends over the pick; with a sinking shed they lower them and the others
rise.  Shaft or treadle 0 and empty entries mean none.  [WARP] and [WEFT] give the ``Threads``
count and optionally ``Spacing`` in ``Units`` (centimeters, inches or decipoints = 1/720 inch).

End 1 becomes column 0 and pick 1 row 0 of the interlacing matrix (see :mod:`.patterns` for
how that shows on the cloth).  Colours, thickness and per-thread spacing tables are not read.
"""

from __future__ import annotations

import configparser
import pathlib
from dataclasses import dataclass

import numpy as np

from .errors import WeaveParameterError
from .patterns import validate_interlacing

#: Millimetres per WIF length unit.
UNITS_MM = {"centimeters": 10.0, "inches": 25.4, "decipoints": 25.4 / 720.0}
_TRUE = {"true", "yes", "on", "1"}
_FALSE = {"false", "no", "off", "0"}


@dataclass(frozen=True, eq=False)
class WeavingDraft:
    """What a WIF says about the weave: its interlacing matrix (picks × ends, True where the end
    is raised over the pick), the title, and the warp and weft spacing in mm where given."""

    interlacing: np.ndarray
    title: str | None = None
    warp_spacing_mm: float | None = None
    weft_spacing_mm: float | None = None


def _sections(text: str) -> dict[str, dict[str, str]]:
    parser = configparser.RawConfigParser(strict=False, interpolation=None, delimiters=("=",),
                                          comment_prefixes=(";",), inline_comment_prefixes=None)
    try:
        parser.read_string(text)
    except configparser.Error as error:
        raise WeaveParameterError("wif", str(error).splitlines()[0], "an INI-style WIF text") from None
    return {name.strip().upper(): dict(parser.items(name)) for name in parser.sections()}


def _numbers(section: str, key: str, value: str) -> list[int]:
    try:
        numbers = [int(item) for item in value.split(",") if item.strip()]
    except ValueError:
        raise WeaveParameterError(f"wif [{section}] {key}", value, "comma-separated integers ≥ 0") from None
    if any(n < 0 for n in numbers):
        raise WeaveParameterError(f"wif [{section}] {key}", value, "comma-separated integers ≥ 0")
    return [n for n in numbers if n > 0]


def _table(sections, name: str) -> dict[int, list[int]]:
    """A WIF index table (``n=a,b,…``) with 1-based keys; empty entries dropped."""
    table = {}
    for key, value in sections[name].items():
        try:
            index = int(key)
        except ValueError:
            raise WeaveParameterError(f"wif [{name}]", key, "integer keys ≥ 1") from None
        if index < 1:
            raise WeaveParameterError(f"wif [{name}]", key, "integer keys ≥ 1")
        table[index] = _numbers(name, key, value)
    return table


def _threads(sections, name: str, fallback: int) -> int:
    value = sections.get(name, {}).get("threads")
    if value is None:
        return fallback
    try:
        threads = int(value)
    except ValueError:
        threads = 0
    if threads < 1:
        raise WeaveParameterError(f"wif [{name}] Threads", value, "an integer ≥ 1")
    return threads


def _spacing_mm(sections, name: str) -> float | None:
    entries = sections.get(name, {})
    if "spacing" not in entries or "units" not in entries:
        return None
    units = entries["units"].strip().lower()
    if units not in UNITS_MM:
        raise WeaveParameterError(f"wif [{name}] Units", entries["units"], f"one of {sorted(UNITS_MM)}")
    try:
        spacing = float(entries["spacing"])
    except ValueError:
        spacing = float("nan")
    if not spacing > 0:
        raise WeaveParameterError(f"wif [{name}] Spacing", entries["spacing"], "a number > 0")
    return spacing * UNITS_MM[units]


def parse_wif(text: str) -> WeavingDraft:
    """The weaving draft in WIF ``text`` (see the module docstring); its interlacing is checked
    like any other (:func:`.validate_interlacing`: an unthreaded end is refused)."""
    sections = _sections(text)
    if "THREADING" not in sections:
        raise WeaveParameterError("wif [THREADING]", None, "a threading section")
    threading = _table(sections, "THREADING")
    if "LIFTPLAN" in sections:
        lifts = _table(sections, "LIFTPLAN")
    elif "TREADLING" in sections and "TIEUP" in sections:
        tieup = _table(sections, "TIEUP")
        lifts = {pick: sorted({shaft for treadle in treadles for shaft in tieup.get(treadle, [])})
                 for pick, treadles in _table(sections, "TREADLING").items()}
    else:
        raise WeaveParameterError("wif [LIFTPLAN]", None, "a liftplan, or a tie-up and a treadling")
    ends = _threads(sections, "WARP", max(threading, default=0))
    picks = _threads(sections, "WEFT", max(lifts, default=0))
    if ends < 1 or picks < 1:
        raise WeaveParameterError("wif", f"{ends} ends × {picks} picks", "at least one end and one pick")
    shed = sections.get("WEAVING", {}).get("rising shed", "true").strip().lower()
    if shed not in _TRUE | _FALSE:
        raise WeaveParameterError("wif [WEAVING] Rising Shed", shed, "true or false")
    shafts = 1 + max([0] + [s for row in (*threading.values(), *lifts.values()) for s in row])
    threaded = np.zeros((ends, shafts), dtype=bool)
    for end, on in threading.items():
        if end <= ends:
            threaded[end - 1, on] = True
    lifted = np.zeros((picks, shafts), dtype=bool)
    for pick, on in lifts.items():
        if pick <= picks:
            lifted[pick - 1, on] = True
    moved = (lifted.astype(np.int64) @ threaded.T.astype(np.int64)) > 0
    raised = moved if shed in _TRUE else ~moved
    return WeavingDraft(
        interlacing=validate_interlacing(raised),
        title=sections.get("TEXT", {}).get("title"),
        warp_spacing_mm=_spacing_mm(sections, "WARP"),
        weft_spacing_mm=_spacing_mm(sections, "WEFT"),
    )


def read_wif(path) -> WeavingDraft:
    """The weaving draft in the WIF file at ``path``."""
    path = pathlib.Path(path)
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as error:
        raise WeaveParameterError("path", str(path), f"a readable WIF file ({error.strerror})") from None
    return parse_wif(text)


def format_wif(interlacing, spacing_mm: float | None = None, title: str = "ClothLight weave") -> str:
    """A WIF 1.1 text for ``interlacing``: one shaft per distinct end, one treadle per distinct
    pick (the smallest straight set-up), rising shed; ``spacing_mm`` for warp and weft alike."""
    matrix = validate_interlacing(interlacing)
    end_kinds, shaft_of_end = np.unique(matrix.T, axis=0, return_inverse=True)
    pick_kinds, treadle_of_pick = np.unique(matrix, axis=0, return_inverse=True)
    picks, ends = matrix.shape
    lines = ["[WIF]", "Version=1.1", "Date=April 20, 1997", "Developers=wif@mhsoft.com",
             "Source Program=ClothLight", "", "[CONTENTS]"]
    lines += [f"{name}=true" for name in ("TEXT", "WEAVING", "WARP", "WEFT", "THREADING", "TIEUP", "TREADLING")]
    lines += ["", "[TEXT]", f"Title={title}", "", "[WEAVING]", f"Shafts={len(end_kinds)}",
              f"Treadles={len(pick_kinds)}", "Rising Shed=true"]
    for name, threads in (("WARP", ends), ("WEFT", picks)):
        lines += ["", f"[{name}]", f"Threads={threads}"]
        if spacing_mm is not None:
            lines += [f"Spacing={spacing_mm / UNITS_MM['centimeters']:.10g}", "Units=centimeters"]
    lines += ["", "[THREADING]"] + [f"{end + 1}={shaft + 1}" for end, shaft in enumerate(shaft_of_end)]
    # treadle t lifts the shafts whose ends are raised in (any) pick of kind t
    first_pick = [np.flatnonzero(treadle_of_pick == t)[0] for t in range(len(pick_kinds))]
    tieup = end_kinds[:, first_pick].T
    lines += ["", "[TIEUP]"] + [f"{t + 1}=" + ",".join(str(s + 1) for s in np.flatnonzero(row))
                                for t, row in enumerate(tieup)]
    lines += ["", "[TREADLING]"] + [f"{pick + 1}={treadle + 1}" for pick, treadle in enumerate(treadle_of_pick)]
    return "\n".join(lines) + "\n"


def write_wif(interlacing, path, spacing_mm: float | None = None, title: str = "ClothLight weave") -> pathlib.Path:
    """Write :func:`format_wif` of ``interlacing`` to ``path``; returns the path."""
    path = pathlib.Path(path)
    path.write_text(format_wif(interlacing, spacing_mm, title), encoding="utf-8")
    return path
