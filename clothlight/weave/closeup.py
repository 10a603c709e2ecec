"""The close-up sample of a medium preset: its plies and twist, its ``[closeup]`` table, and the
default dense weave.

The plies and their twist are the medium's (``[yarn]`` ``ply_count``, ``twist_angle_deg``: one
twist parameter per preset, which the medium's fibre orientation uses too).  What only the
close-up geometry needs is the preset's ``[closeup]`` table, every key optional:

``spacing_jitter``, ``height_jitter``, ``ply_radius_jitter``
    the seeded irregularity (:mod:`.irregularity`), fractions;
``flyaway_density_per_mm``, ``flyaway_length_mm``, ``flyaway_curl_per_mm``
    the flyaway fibres (:mod:`.flyaways`): fibres leaving 1 mm of yarn, their mean length, the
    rms curvature of their path in rad/mm (their radius and colour are the medium's fibres',
    :mod:`.fibre_optics`);
``seed``
    the seed of both.

Defaults, for a carded ring-spun cotton:

- Hairiness.  Uster's hairiness H, the total length (cm) of the fibres protruding from 1 cm of
  yarn, is about 4–7 for carded ring-spun cotton yarns of Ne 20 (USTER STATISTICS); the number of
  protruding fibres falls off exponentially with their length below 3 mm (A. Barella and A. M.
  Manich, "The hair-length distribution of yarns, measured by means of the Zweigle G 565
  hairiness meter", J. Textile Inst. 84(3), 326–335, 1993).  H = 5 with a mean length of 0.5 mm
  is 10 fibres per mm of yarn.  The curl is an appearance setting, not a published figure: an rms
  curvature of 5 rad/mm (a radius of 0.2 mm) kinks a 0.5 mm fibre by about a radian in all.
- Evenness.  A ring-spun cotton yarn's mass per length varies by a CV of 12–18 % (USTER
  STATISTICS): plies thinner by up to 15 %; the yarns by up to 3 % of the spacing from their
  places, the crossings by up to 15 % of the yarn's half-thickness from their heights.

The default weave (:func:`sheeting_weave`) has the cover of real cotton sheeting.  Peirce's cover
factor K = n/√Ne (n threads per inch, Ne the cotton count) is the fraction of the cloth that one
system's round yarns of Peirce's diameter d = 1/(28·√Ne) inch cover, times 28 (F. T. Peirce, "The
geometry of cloth structure", J. Textile Inst. 28, T45, 1937).  Sheeting grades sit at K ≈ 14 in
both directions: muslin of 128 threads per square inch (64 × 64) in Ne 20 is K = 14.3, percale of
180 and more (90 × 90) in Ne 40 is K = 14.2.  For the presets' Ne 20 yarn (d = 0.20 mm) K = 14 is
a spacing of 28·d/K = 0.40 mm (63.5 threads per inch), a fractional cover of 0.5 per system and
1 − (1 − 0.5)² = 0.75 for the cloth; the validation's sample (0.5 mm) covers 0.64.  In cloth the
yarns flatten where they cross (A. Kemp, "An extension of Peirce's cloth geometry to the treatment
of non-circular threads", J. Textile Inst. 49, T44, 1958): here 1.6 : 1 with 90 % of the round
yarn's section, the most that leaves the rigid tubes room to change sides at that spacing, which
covers 0.84 of the cloth at the crossings' width (:attr:`.params.WeaveParameters.cover_factor`).

Between crossings nothing presses a yarn, and it relaxes towards its round section
(:mod:`.section`).  Fully relaxed (``section_relaxation`` 1) a yarn of the sheeting's section,
rounder and so thicker midway, no longer clears the yarns it crosses at the sheeting's spacing and
crimp (the regular repeat allows at most 0.81); with the presets' jitters (``voided_red_cotton`` and
``indigo_cotton``, seed 0) 0.75 and 0.5 fail too, and the largest that clears depends on the
sample's size, since a larger sample draws more jitters: 0.448 in the plain weave and 3/1 twill and
0.39 in the 2/2 twill at 16 × 16, 0.368 at 12 × 12, 0.36 at 24 × 24.  The default is 0.25, which
clears plain, 2/2 and 3/1 twill of both presets at every size from 3 × 3 to 48 × 48
(``tests/test_closeup_weave.py`` checks some): midway between crossings the yarn is 1.42 : 1
(0.113 × 0.080 mm), and the cloth seen from above is covered less than the crossings' 0.84.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

from precompute.bounds import Bound
from precompute.errors import ParameterError
from precompute.optics.medium import DEFAULT_PRESET, load_preset, load_preset_config

from .params import IRREGULARITY_BOUNDS, WeaveParameters

#: Peirce's cover factor of cotton sheeting, per system (module docstring).
SHEETING_COVER_FACTOR = 14.0
#: The yarns' flattening where they cross, width over thickness, and the share of the round
#: yarn's section they keep (module docstring).
SHEETING_FLATTENING = 1.6
SHEETING_SECTION_SHARE = 0.9
#: How far the section relaxes towards round between crossings (module docstring; :mod:`.section`).
SHEETING_SECTION_RELAXATION = 0.25

#: The flyaway settings' ranges; the irregularity's are the weave's own.
FLYAWAY_BOUNDS = {
    "flyaway_density_per_mm": Bound("closeup.flyaway_density_per_mm", 0.0, 200.0, unit="1/mm"),
    "flyaway_length_mm": Bound("closeup.flyaway_length_mm", 0.0, 10.0, low_open=True, unit="mm"),
    "flyaway_curl_per_mm": Bound("closeup.flyaway_curl_per_mm", 0.0, 50.0, unit="rad/mm"),
}


@dataclass(frozen=True)
class CloseupSettings:
    """A preset's ``[closeup]`` table, checked (module docstring: meaning, units, defaults)."""

    spacing_jitter: float = 0.03
    height_jitter: float = 0.15
    ply_radius_jitter: float = 0.15
    flyaway_density_per_mm: float = 10.0
    flyaway_length_mm: float = 0.5
    flyaway_curl_per_mm: float = 5.0
    seed: int = 0

    def __post_init__(self):
        for name, bound in (IRREGULARITY_BOUNDS | FLYAWAY_BOUNDS).items():
            bound.check(getattr(self, name), f"closeup.{name}")


def closeup_settings(config: dict) -> CloseupSettings:
    """The ``[closeup]`` table of a preset's TOML content ``config``, checked; defaults where it
    has none.  An unknown key or a value out of range is refused naming ``closeup.<key>``."""
    table = config.get("closeup", {})
    if not isinstance(table, dict):
        raise ParameterError("closeup", table, "a table of close-up settings")
    known = [field.name for field in fields(CloseupSettings)]
    for key in table:
        if key not in known:
            raise ParameterError(f"closeup.{key}", table[key], f"one of {', '.join(known)}")
    return CloseupSettings(**table)


def sheeting_weave(preset: str = DEFAULT_PRESET, **overrides) -> WeaveParameters:
    """The default close-up: a plain weave of the preset's yarn at the cover of cotton sheeting
    (module docstring), flattened where its yarns cross and relaxing between, made of the preset's
    plies at its twist angle, irregular as its ``[closeup]`` table says; ``overrides`` replace any of
    these parameters."""
    medium = load_preset(preset)
    settings = closeup_settings(load_preset_config(preset)[0])
    values = dict(
        sheeting_shape(medium.yarn.radius_mm), warp_count=16, weft_count=16, segments_per_crossing=16,
        ply_count=medium.yarn.ply_count, twist_angle_deg=medium.yarn.twist_angle_deg,
        spacing_jitter=settings.spacing_jitter, height_jitter=settings.height_jitter,
        ply_radius_jitter=settings.ply_radius_jitter, seed=settings.seed)
    return WeaveParameters(**(values | overrides))


def sheeting_shape(yarn_radius_mm: float) -> dict:
    """The shape of cotton sheeting woven of round yarns of radius ``yarn_radius_mm`` (mm), as
    :class:`.params.WeaveParameters` keywords (module docstring): plain weave, spacing, pressed
    section, crimp and relaxation; the sample's size, tessellation, plies and irregularity are the
    caller's."""
    spacing = 28.0 * 2.0 * yarn_radius_mm / SHEETING_COVER_FACTOR
    scale = math.sqrt(SHEETING_SECTION_SHARE)
    semi_axes = (yarn_radius_mm * scale * math.sqrt(SHEETING_FLATTENING),
                 yarn_radius_mm * scale / math.sqrt(SHEETING_FLATTENING))
    # the crimp above the least that clears (1.02 × the half-thickness), so that the crossings can jitter
    return dict(interlacing="plain", spacing_mm=spacing, semi_axes_mm=semi_axes, crimp_amplitude_mm=1.13 * semi_axes[1],
                segments_around=12, section_relaxation=SHEETING_SECTION_RELAXATION)
