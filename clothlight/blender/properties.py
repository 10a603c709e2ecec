"""Scene settings of the add-on: the woven sample, the yarn medium and its bake and fit, the material.

Registered as ``Scene.clothlight`` (saved with the .blend, undoable, animatable where it makes
sense).  Lengths carry their unit in the name ("mm", "nm") because the weave core and the bake
work in those units whatever the scene's unit system; the sample object is then scaled into the
scene (see :func:`millimetre_scale`).

The medium settings start from a shipped preset (``precompute/presets/*.toml``, chosen by
``base``) and expose the values an artist tunes; only values that differ from the preset go to
the bake as overrides, so an untouched preset bakes exactly what ``python -m precompute bake
--preset <name>`` bakes and hits the same cache entry (and the same pre-baked tables).  Values a
fit found that the panel does not expose (a second particle species, the fibre's absorption, the
sheen) are kept as overrides of their own (``fitted_overrides``) and baked with the rest.  The base may
also be a preset TOML file of the user's (``base`` "Custom File", ``custom_path``): Match Colour writes
the recipe of the ``target_colour`` (an sRGB picker) there and points the base at it
(:mod:`clothlight.colour_match_job`); its last outcome is kept in ``colour_match``.

The fit settings (``Scene.clothlight.fit``) say what ``python -m clothlight.fit`` would be told:
the measurement, the free parameters, the budget, the colour targets, the output folder
(:class:`clothlight.fit_job.FitRequest`).
"""

from __future__ import annotations

import json
import pathlib

import bpy
import numpy as np
from bpy.props import (BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty, IntProperty, PointerProperty,
                       StringProperty)

from ..fit_job import FREE_PARAMETERS, FitRequest
from .garment.density import DEFAULT_THREADS_PER_CM, THREADS_PER_CM
from ..colour_match_job import ColourMatchOutcome
from ..medium_settings import (
    BASE_MEDIUM_NUMBERS,
    CUSTOM_BASE,
    BakeRequest,
    config_value,
    exposed_values,
    fitted_values_json,
    is_preset_file,
    medium_config,
    medium_keys,
    particle_size_key,
    preset_config,
    preset_request,
    request_overrides,
    shown_key,
    takes_dye_series,
    typed_number,
)
from . import running_jobs
from ..weave import BUILT_IN, WeaveParameterError, WeaveParameters
from ..weave.closeup import FLYAWAY_BOUNDS, CloseupSettings, sheeting_weave
from ..weave.params import (COUNT_BOUNDS, CROSSING_CLEARANCE, DEFAULT_YARN_RADIUS_MM, IRREGULARITY_BOUNDS,
                             SECTION_BOUNDS)

from precompute.optics import medium as _medium
#: The allowed ranges, one definition shared with the bake's API and command line (precompute/bounds.py).
from precompute import bounds as _bounds
from precompute.errors import ParameterError

#: What Build Sample makes by default: cotton sheeting at its real density, of the default medium's
#: plies, irregular (clothlight.weave.closeup.sheeting_weave; the validation rig keeps its own sample).
_WEAVE = sheeting_weave()
_CLOSEUP = CloseupSettings()
_REQUEST = preset_request(_medium.DEFAULT_PRESET)

PATTERN_LABELS = {
    "plain": ("Plain", "Plain (tabby) weave: every end over one pick, under the next (the paper's sample, §3.1)"),
    "basket": ("Basket", "Basket weave: pairs of ends and picks interlace as one"),
    "twill_2_1": ("Twill 2/1", "Twill: each end floats over 2 picks and under 1, stepping one end per pick"),
    "twill_2_2": ("Twill 2/2", "Twill: over 2, under 2 (a balanced twill, as in serge)"),
    "twill_3_1": ("Twill 3/1", "Twill: over 3, under 1 (a warp-faced twill, as in denim)"),
    "satin_5": ("Satin 5", "Five-end satin: long warp floats, one interlacing per end and pick"),
    "satin_8": ("Satin 8", "Eight-end satin: longer floats, a smoother and shinier face"),
}


def _pattern_items():
    items = [(name, *PATTERN_LABELS.get(name, (name, f"Built-in pattern {name}"))) for name in BUILT_IN]
    items.append(("CUSTOM", "Custom Draft", "An interlacing matrix typed as rows of 0 and 1"))
    items.append(("WIF", "WIF File", "The drawdown of a weaving draft in a WIF (Weaving Information File)"))
    return [(key, label, description, index) for index, (key, label, description) in enumerate(items)]


def parse_draft(text: str) -> np.ndarray:
    """An interlacing matrix from rows of 0/1 separated by '/' or ';' ("10/01"): 1 where the end
    passes over the pick, rows are picks.  Raises WeaveParameterError naming the draft."""
    rows = [row.strip().replace(" ", "") for row in text.replace(";", "/").split("/") if row.strip()]
    if not rows or any(set(row) - {"0", "1"} for row in rows) or len({len(row) for row in rows}) != 1:
        raise WeaveParameterError("custom draft", text,
                                  "rows of equal length made of 0 and 1, separated by '/', e.g. 110/011/101")
    return np.array([[c == "1" for c in row] for row in rows])


def millimetre_scale(scene) -> float:
    """Object scale that shows a mesh modelled in millimetres at its real size in ``scene``'s units."""
    return 0.001 / scene.unit_settings.scale_length


class ClothLightWeaveSettings(bpy.types.PropertyGroup):
    """The woven sample that Build Sample makes (paper §3.1; other weaves and yarn shapes, §7)."""

    pattern: EnumProperty(
        name="Pattern", items=_pattern_items(), default="plain",
        description="How warp and weft interlace: the weave's drawdown, repeated over the sample")
    custom_draft: StringProperty(
        name="Draft", default="10/01",
        description="Interlacing rows, one per weft pick, separated by '/': 1 where the warp end passes over "
                    "the pick, 0 under it (e.g. 110/011/101 is a 2/1 twill)")
    wif_path: StringProperty(
        name="WIF File", subtype="FILE_PATH", default="",
        description="Weaving Information File whose drawdown (threading, tie-up and treadling, or lift plan) "
                    "gives the interlacing")
    warp_count: IntProperty(
        name="Warp Ends", default=_WEAVE.warp_count, **COUNT_BOUNDS["warp_count"].limits(), soft_max=64,
        description="Number of warp yarns (ends) in the sample; they run along the sample's X axis")
    weft_count: IntProperty(
        name="Weft Picks", default=_WEAVE.weft_count, **COUNT_BOUNDS["weft_count"].limits(), soft_max=64,
        description="Number of weft yarns (picks) in the sample; they run along the sample's Y axis")
    spacing_mm: FloatProperty(
        name="Spacing (mm)", default=_WEAVE.spacing_mm, min=0.001, max=100.0, soft_min=0.05, soft_max=5.0,
        precision=3, step=1,
        description="Centre-to-centre distance of neighbouring yarns, warp and weft alike, in millimetres "
                    "(0.5 mm is 20 threads per centimetre)")
    cross_section: EnumProperty(
        name="Cross-Section", default="ELLIPTICAL" if _WEAVE.semi_axes_mm else "ROUND",
        items=[("ROUND", "Round", "A circular yarn, as the paper's model (§3.2)"),
               ("ELLIPTICAL", "Elliptical", "A yarn flattened in the cloth plane, as in dense cloth (§7)")],
        description="Shape of the yarn's cross-section")
    yarn_radius_mm: FloatProperty(
        name="Yarn Radius (mm)", default=DEFAULT_YARN_RADIUS_MM, min=0.001, max=10.0, soft_min=0.02, soft_max=1.0,
        precision=3, step=1,
        description="Radius of the round yarn, in millimetres. The tables are baked for the medium's yarn "
                    "radius: keep the two equal")
    half_width_mm: FloatProperty(
        name="Half-Width (mm)", default=_WEAVE.cross_section_mm[0], min=0.001, max=10.0, soft_min=0.02,
        soft_max=1.0, precision=3, step=1,
        description="Semi-axis of the elliptical cross-section in the cloth plane, in millimetres")
    half_thickness_mm: FloatProperty(
        name="Half-Thickness (mm)", default=_WEAVE.cross_section_mm[1], min=0.001, max=10.0, soft_min=0.02,
        soft_max=1.0, precision=3, step=1,
        description="Semi-axis of the elliptical cross-section across the cloth, in millimetres")
    section_relaxation: FloatProperty(
        name="Section Relaxation", default=_WEAVE.section_relaxation,
        **SECTION_BOUNDS["section_relaxation"].limits(), precision=3, step=1, subtype="FACTOR",
        description="How far the yarn relaxes towards a round section of the same area midway between "
                    "crossings, where nothing presses it: 0 keeps the cross-section everywhere, 1 is round "
                    "midway; at every crossing the section is the one set above")
    auto_crimp: BoolProperty(
        name="Automatic Crimp", default=_WEAVE.crimp_amplitude_mm is None,
        description=f"Crimp just clearing the crossing yarns: (1 + {CROSSING_CLEARANCE:g}) × the yarn's half-thickness")
    crimp_warp_mm: FloatProperty(
        name="Warp Crimp (mm)", default=_WEAVE.crimp_amplitudes_mm[0], min=0.0, max=10.0,
        soft_max=1.0, precision=3, step=1,
        description="Height of a warp yarn's centreline above (below) the cloth's mid-plane where it passes over "
                    "(under) a pick, in millimetres")
    crimp_weft_mm: FloatProperty(
        name="Weft Crimp (mm)", default=_WEAVE.crimp_amplitudes_mm[1], min=0.0, max=10.0,
        soft_max=1.0, precision=3, step=1,
        description="Height of a weft yarn's centreline above (below) the cloth's mid-plane where it passes over "
                    "(under) an end, in millimetres")
    segments_per_crossing: IntProperty(
        name="Segments Along", default=_WEAVE.segments_per_crossing, soft_max=32,
        **COUNT_BOUNDS["segments_per_crossing"].limits(),
        description="Mesh segments along a yarn per yarn spacing")
    segments_around: IntProperty(
        name="Segments Around", default=_WEAVE.segments_around, **COUNT_BOUNDS["segments_around"].limits(), soft_max=48,
        description="Mesh segments around a yarn's cross-section")
    use_plies: BoolProperty(
        name="Plies and Twist", default=_WEAVE.ply_count > 1,
        description="Yarns made of the Base Medium's plies (its yarn.ply_count) twisted about the yarn axis at its "
                    "twist angle (yarn.twist_angle_deg), the one twist of the preset; off: smooth tubes")
    spacing_jitter: FloatProperty(
        name="Spacing Jitter", default=_WEAVE.spacing_jitter,
        **IRREGULARITY_BOUNDS["spacing_jitter"].limits(), soft_max=0.1,
        precision=3, step=1, subtype="FACTOR",
        description="Seeded irregularity: every yarn moves across the cloth by up to this fraction of the spacing "
                    "(cotton's default)")
    height_jitter: FloatProperty(
        name="Height Jitter", default=_WEAVE.height_jitter,
        **IRREGULARITY_BOUNDS["height_jitter"].limits(), soft_max=0.5,
        precision=3, step=1, subtype="FACTOR",
        description="Seeded irregularity: every crossing moves up or down by up to this fraction of the yarn's "
                    "half-thickness (cotton's default)")
    ply_radius_jitter: FloatProperty(
        name="Ply Radius Jitter", default=_WEAVE.ply_radius_jitter,
        **IRREGULARITY_BOUNDS["ply_radius_jitter"].limits(), soft_max=0.5,
        precision=3, step=1, subtype="FACTOR",
        description="Seeded irregularity: every ply is thinner at each crossing by up to this fraction of its "
                    "radius (cotton's default)")
    irregularity_seed: IntProperty(
        name="Seed", default=_CLOSEUP.seed, min=0, max=2**31 - 1,
        description="Seed of the irregularity and the flyaway fibres: the same seed builds the same sample")
    flyaway_density_per_mm: FloatProperty(
        name="Fibres per mm", default=_CLOSEUP.flyaway_density_per_mm,
        **FLYAWAY_BOUNDS["flyaway_density_per_mm"].limits(), soft_max=30.0, precision=1,
        description="Flyaway fibres leaving each millimetre of yarn (Uster hairiness H = 5 of a carded cotton "
                    "with 0.5 mm fibres is 10)")
    flyaway_length_mm: FloatProperty(
        name="Fibre Length (mm)", default=_CLOSEUP.flyaway_length_mm, min=0.001,
        max=FLYAWAY_BOUNDS["flyaway_length_mm"].high, soft_max=3.0, precision=2, step=1,
        description="Mean length of a flyaway fibre, in millimetres (lengths are exponential, as measured)")
    flyaway_curl_per_mm: FloatProperty(
        name="Fibre Curl (rad/mm)", default=_CLOSEUP.flyaway_curl_per_mm,
        **FLYAWAY_BOUNDS["flyaway_curl_per_mm"].limits(), soft_max=10.0, precision=1,
        description="How much a flyaway fibre bends: the rms curvature of its path, in radians per millimetre")
    real_world_size: BoolProperty(
        name="Real-World Size", default=True,
        description="Scale the sample to its physical size in the scene's units (a 0.5 mm spacing measures "
                    "0.5 mm); off: one Blender unit per millimetre")

    def interlacing(self) -> np.ndarray | str:
        if self.pattern == "CUSTOM":
            return parse_draft(self.custom_draft)
        if self.pattern == "WIF":
            from ..weave import read_wif

            if not self.wif_path:
                raise WeaveParameterError("WIF file", "", "the path of a .wif weaving draft")
            return read_wif(bpy.path.abspath(self.wif_path)).interlacing
        return self.pattern

    def parameters(self) -> WeaveParameters:
        """The weave core's parameters; raises WeaveParameterError naming the bad one."""
        shape = ({"yarn_radius_mm": typed_number(self.yarn_radius_mm)} if self.cross_section == "ROUND"
                 else {"semi_axes_mm": (typed_number(self.half_width_mm), typed_number(self.half_thickness_mm))})
        crimp = None if self.auto_crimp else (typed_number(self.crimp_warp_mm), typed_number(self.crimp_weft_mm))
        plies, twist = self.medium_plies() if self.use_plies else (1, 0.0)
        return WeaveParameters(
            interlacing=self.interlacing(), warp_count=self.warp_count, weft_count=self.weft_count,
            spacing_mm=typed_number(self.spacing_mm), crimp_amplitude_mm=crimp,
            segments_per_crossing=self.segments_per_crossing, segments_around=self.segments_around,
            ply_count=plies, twist_angle_deg=typed_number(twist), spacing_jitter=typed_number(self.spacing_jitter),
            height_jitter=typed_number(self.height_jitter), ply_radius_jitter=typed_number(self.ply_radius_jitter),
            seed=self.irregularity_seed, section_relaxation=typed_number(self.section_relaxation), **shape)

    def medium_plies(self) -> tuple[int, float]:
        """The plies and twist angle (degrees) of the scene's Base Medium preset (``[yarn]``)."""
        medium = self.id_data.clothlight.medium
        try:
            yarn = medium.base_config().get("yarn", {})
        except ParameterError:
            raise WeaveParameterError("Base Medium", medium.custom_path, "a readable preset TOML file") from None
        return int(yarn.get("ply_count", 1)), float(yarn.get("twist_angle_deg", 0.0))

    def closeup_settings(self) -> CloseupSettings:
        """The flyaway fibres' and the irregularity's settings as the close-up core takes them."""
        return CloseupSettings(
            spacing_jitter=typed_number(self.spacing_jitter), height_jitter=typed_number(self.height_jitter),
            ply_radius_jitter=typed_number(self.ply_radius_jitter),
            flyaway_density_per_mm=typed_number(self.flyaway_density_per_mm),
            flyaway_length_mm=typed_number(self.flyaway_length_mm),
            flyaway_curl_per_mm=typed_number(self.flyaway_curl_per_mm), seed=self.irregularity_seed)

    @property
    def yarn_thickness_mm(self) -> float:
        return self.yarn_radius_mm if self.cross_section == "ROUND" else self.half_thickness_mm


# -- the medium ------------------------------------------------------------------------------

_DEFAULT_CONFIG = preset_config(_medium.DEFAULT_PRESET)


def _default(key: str, fallback: float) -> float:
    try:
        return float(config_value(_DEFAULT_CONFIG, key))
    except (KeyError, IndexError):
        return fallback


def _base_items():
    items = []
    for name in _medium.preset_names():
        description = str(preset_config(name).get("description", name))
        items.append((name, bpy.path.display_name(name), description, BASE_MEDIUM_NUMBERS[name]))
    items.append((CUSTOM_BASE, "Custom File", "A preset TOML file of your own (Custom File below): a colour's "
                                              "shade recipe that Match Colour wrote, a fit's preset.toml",
                  BASE_MEDIUM_NUMBERS[CUSTOM_BASE]))
    return items


def _load_base(self, _context) -> None:
    if self.base != CUSTOM_BASE:
        self.load_preset(self.base)
    elif self.custom_problem() is None:
        self.load_preset(self.base_preset())


def _load_custom(self, _context) -> None:
    if self.base == CUSTOM_BASE and self.custom_problem() is None:
        self.load_preset(self.base_preset())


#: Match Colour's colour when nothing was picked yet: MERL red-fabric2's (benchmarks/bench_colour_match.py).
DEFAULT_TARGET_COLOUR = (0x6a / 255, 0x27 / 255, 0x17 / 255)


#: The Dye Range's default, % of fibre weight: the shipped dyed presets' amounts and the paper's 1–5 % (§6.2).
DYE_SERIES_DEFAULT = (0.05, 5.0)


def _recolour(self, context) -> None:
    """A dye change with Dye Range on, after a bake of these settings at another dye: re-bake (seconds)."""
    if not (self.use_dye_series and self.tables_request):
        return
    try:
        baked = BakeRequest.from_json(self.tables_request)
        wanted = self.request()
    except (ValueError, TypeError, KeyError, ParameterError):
        return
    if baked.dye_series is None or wanted == baked or not wanted.same_but_dye(baked):
        return
    low, high = baked.dye_series
    if low <= typed_number(self.dye_weight_percent) <= high:
        running_jobs.schedule_recolour(context.scene.name)





def _forget_request(self, _context) -> None:
    # A folder chosen by hand: what it was baked from is in its summary, not in these settings.
    self.tables_request = ""


class ClothLightMediumSettings(bpy.types.PropertyGroup):
    """The yarn's medium (paper §3.2, §6.2) and the Monte-Carlo bake of its BRDF tables (§5)."""

    base: EnumProperty(
        name="Base Medium", items=_base_items(), default=_medium.DEFAULT_PRESET,
        update=_load_base,
        description="Shipped medium preset the values below start from (host, particles, dye spectrum, yarn), "
                    "or a preset file of your own (Custom File); choosing one loads its values")
    custom_path: StringProperty(
        name="Custom File", subtype="FILE_PATH", default="", update=_load_custom,
        description="Preset TOML file the medium starts from when the Base Medium is Custom File (Match Colour "
                    "writes its recipe here; 'python -m clothlight.fit.match_colour' and a fit's preset.toml "
                    "are such files); choosing one loads its values")
    target_colour: FloatVectorProperty(
        name="Target Colour", subtype="COLOR_GAMMA", size=3, min=0.0, max=1.0, default=DEFAULT_TARGET_COLOUR,
        description="The colour the cloth should have (sRGB), lit and seen along its normal without the sheen, "
                    "as textile colour is measured: Match Colour solves the red, blue and yellow dye and the "
                    "fibre's own absorption that give the Base Medium's yarn this colour")
    bake_after_match: BoolProperty(
        name="Bake After Match", default=True,
        description="Once a colour is matched (or its nearest recipe applied), bake the recipe's tables "
                    "(Bake Tables, in the background)")
    colour_match: StringProperty(
        name="Last Colour Match", default="", options={"HIDDEN"},
        description="The last Match Colour's outcome (JSON: the colour, the recipe, its CIEDE2000, its preset)")
    matched_colour: FloatVectorProperty(
        name="Cloth Colour", subtype="COLOR_GAMMA", size=3, min=0.0, max=1.0, default=(0.0, 0.0, 0.0),
        description="The colour the last matched recipe gives the cloth (sRGB), for comparison with the target")
    dye_weight_percent: FloatProperty(
        name="Dye (% of fibre weight)", default=_default("dye.weight_percent", 0.0), min=0.0, max=100.0,
        soft_max=10.0, precision=2, step=10, update=_recolour,
        description="Dye content as a percentage of the fibre's weight; the paper's range is 1–5 % (§6.2). "
                    "With Dye Range on and its tables baked, a change recolours the yarn materials in seconds")
    use_dye_series: BoolProperty(
        name="Dye Range", default=False,
        description="Bake once for a range of dye amounts (one Monte-Carlo transport, reweighted for absorption); "
                    "then changing the dye within the range re-bakes in seconds and recolours the yarn materials "
                    "that read these tables")
    dye_series_low: FloatProperty(
        name="From (%)", default=DYE_SERIES_DEFAULT[0], min=0.0, max=99.0, soft_max=10.0, precision=2, step=10,
        description="Least dye of the range, % of fibre weight")
    dye_series_high: FloatProperty(
        name="To (%)", default=DYE_SERIES_DEFAULT[1], min=0.01, max=99.9, soft_max=10.0, precision=2, step=10,
        description="Most dye of the range, % of fibre weight (a wider range takes more memory while baking)")
    particle_diameter_nm: FloatProperty(
        name="Particle Diameter (nm)", default=_default(particle_size_key(_DEFAULT_CONFIG) or "", 150.0),
        **_bounds.PARTICLE_DIAMETER_NM.limits(), soft_min=10.0, soft_max=2000.0, precision=1, step=100,
        description="Diameter of the scattering particles in nanometres (the paper's 150 nm, §6.2); for a "
                    "log-normal size distribution, its number median")
    particle_volume_fraction: FloatProperty(
        name="Particle Volume Fraction", default=_default("particles.0.volume_fraction", 0.14),
        min=1e-6, max=_medium.MAX_VOLUME_FRACTION, soft_max=0.4, precision=4, step=1,
        description="Fraction of the yarn's volume the particles fill (the paper's 'concentration 0.14', §6.2); "
                    f"below {_medium.MAX_VOLUME_FRACTION}, the densest packing of spheres")
    yarn_radius_mm: FloatProperty(
        name="Yarn Radius (mm)", default=_default("yarn.radius_mm", DEFAULT_YARN_RADIUS_MM),
        **_bounds.YARN_RADIUS_MM.limits(), soft_min=0.02, soft_max=1.0, precision=3, step=1,
        description="Radius of the circular yarn the light is traced through, in millimetres (§3.2); "
                    "the sample's yarns should match it")
    budget: EnumProperty(
        name="Budget", default="TARGET_ERROR",
        items=[("TARGET_ERROR", "Target Error", "Trace until every incidence cell's albedo reaches a relative "
                                                "standard error"),
               ("PATHS", "Fixed Paths", "Trace a fixed number of light paths per incidence cell")],
        description="How long the Monte-Carlo transport runs")
    target_error: FloatProperty(
        name="Target Error", default=_REQUEST.target_rel_stderr, **_bounds.TARGET_REL_STDERR.limits(),
        soft_min=0.002, soft_max=0.1,
        precision=4, step=0.1, subtype="FACTOR",
        description="Relative standard error of every incidence cell's albedo to reach (0.01 = 1 %)")
    paths_per_cell: IntProperty(
        name="Paths per Cell", default=20000, **_bounds.PATHS_PER_CELL.limits(), soft_min=100, soft_max=1_000_000,
        description="Light paths traced per incidence cell of the transport")
    seed: IntProperty(
        name="Seed", default=_REQUEST.seed, min=_bounds.SEED.low,  # the top: Blender's integers are 32-bit
        description="Seed of the transport's random streams: the same seed gives the same tables")
    n_around: IntProperty(
        name="Cells Around", default=_REQUEST.n_around, **_bounds.N_AROUND.limits(), soft_max=64,
        description="Spatial cells around the yarn's circumference in the BSSRDF (the paper: 16)")
    n_along: IntProperty(
        name="Cells Along", default=_REQUEST.n_along, **_bounds.N_ALONG.limits(), soft_max=64,
        description="Spatial cells along the yarn in the BSSRDF (the paper: 8); an odd count lets the bake "
                    "trace a quarter of the incidence cells by mirror symmetry, an even count a half")
    angular_resolution: IntProperty(
        name="Angular Resolution", default=_REQUEST.angular_resolution, **_bounds.ANGULAR_RESOLUTION.limits(),
        soft_max=32,
        description="N of the N × N equal-solid-angle hemisphere grids of the BSSRDF (the paper: 12, 144 cells)")
    incidence_resolution: IntProperty(
        name="Incidence Resolution", default=0, min=0, max=_bounds.INCIDENCE_RESOLUTION.high, soft_max=33,
        description="N of the N × N sphere grid of incidence directions in the tables, odd; 0: automatic "
                    "(the coarsest grid that meets the bake's lookup and energy checks)")
    tables_dir: StringProperty(
        name="Tables", subtype="DIR_PATH", default="", update=_forget_request,
        description="Folder of baked tables Apply Material uses (set by Bake Tables, or any folder made by "
                    "'python -m precompute bake --out'). Empty: pre-baked tables of an unchanged shipped preset")
    tables_request: StringProperty(
        name="Baked Settings", default="", options={"HIDDEN"},
        description="The settings the tables in Tables were baked from (empty: chosen by hand)")
    fitted_overrides: StringProperty(
        name="Fitted Values", default="", options={"HIDDEN"},
        description="Values a fit set that the panel does not show (JSON pairs of a preset key and its value in "
                    "the preset's units), baked with the rest; cleared when the base medium changes")

    def base_preset(self) -> str:
        """The preset the medium starts from: a shipped preset's name, or the Custom File's absolute path
        (ParameterError when it names none)."""
        if self.base != CUSTOM_BASE:
            return self.base
        if not self.custom_path.strip():
            raise ParameterError("Custom File", self.custom_path, "a preset TOML file")
        return str(pathlib.Path(bpy.path.abspath(self.custom_path)).resolve())

    def base_config(self) -> dict:
        """The TOML content of :meth:`base_preset` (ParameterError naming the Custom File for a missing or
        unreadable one)."""
        try:
            return medium_config(self.base_preset())
        except ParameterError as error:
            if self.base != CUSTOM_BASE:
                raise
            raise ParameterError("Custom File", self.custom_path, error.allowed) from None

    def custom_problem(self) -> str | None:
        """Why the Custom File cannot be the medium (a message for the panel), or None (or not chosen)."""
        if self.base != CUSTOM_BASE:
            return None
        try:
            self.base_config()
        except ParameterError as error:
            return str(error)
        return None

    def set_base(self, name_or_path: str) -> None:
        """Make the medium start from a shipped preset (by name) or a preset file (by path), loading its
        values when it is another than now."""
        if not is_preset_file(name_or_path):
            if self.base != name_or_path:
                self.base = name_or_path
            return
        path = str(pathlib.Path(name_or_path).resolve())
        if self.base == CUSTOM_BASE and self.custom_path and self.base_preset() == path:
            return
        self.custom_path = path
        if self.base != CUSTOM_BASE:
            self.base = CUSTOM_BASE

    def last_colour_match(self) -> ColourMatchOutcome | None:
        """The last Match Colour's outcome as stored, or None."""
        if not self.colour_match:
            return None
        try:
            return ColourMatchOutcome.from_json(self.colour_match)
        except (ValueError, KeyError, TypeError):
            return None

    def load_preset(self, name: str) -> None:
        """Set every exposed value from the preset ``name`` (a shipped one's name or a preset file's path;
        its [transport] table included); ``request()`` is then
        :func:`clothlight.medium_settings.preset_request` of it."""
        config = medium_config(name)
        for prop, key in medium_keys(config).items():
            setattr(self, prop, float(config_value(config, key)))
        self.fitted_overrides = ""
        request = preset_request(name)
        for field in ("n_around", "n_along", "angular_resolution", "seed"):
            setattr(self, field, getattr(request, field))
        self.incidence_resolution = 0 if request.incidence_resolution == "auto" else request.incidence_resolution
        if request.paths_per_cell is not None:
            self.budget, self.paths_per_cell = "PATHS", request.paths_per_cell
        else:
            self.budget, self.target_error = "TARGET_ERROR", request.target_rel_stderr

    def exposed_keys(self) -> dict[str, str]:
        return medium_keys(self.base_config())

    def extra_overrides(self) -> list[tuple[str, float]]:
        """The fitted values the panel does not expose (``fitted_overrides``), as (key, value) pairs."""
        if not self.fitted_overrides:
            return []
        try:
            return [(str(key), float(value)) for key, value in json.loads(self.fitted_overrides)]
        except (ValueError, TypeError):
            return []

    def extra_overrides_text(self) -> str:
        """The fitted values the panel does not expose, as one line ("" for none)."""
        config = self.base_config()
        return ", ".join(f"{shown_key(key, config)} {value:.4g}" for key, value in self.extra_overrides())

    def set_values(self, base: str, overrides) -> None:
        """Make these settings the medium ``base`` (a shipped preset's name or a preset file's path) with
        ``overrides`` ((dotted key, value) pairs, as a :class:`~clothlight.medium_settings.BakeRequest`
        holds them): the exposed values from them or the preset, the rest kept in ``fitted_overrides``.
        The bake settings (budget, seed, grids) stay."""
        self.set_base(base)  # another medium than now: loads the preset's values and bake settings
        values, fitted = exposed_values(medium_config(base), overrides)
        for prop, value in values.items():
            setattr(self, prop, value)
        self.fitted_overrides = fitted_values_json(fitted)

    def request(self) -> BakeRequest:
        """The bake these settings ask for: overrides only where a value differs from the preset
        (ParameterError when the Custom File is missing or unreadable)."""
        config = self.base_config()
        values = {prop: getattr(self, prop) for prop in medium_keys(config)}
        overrides = request_overrides(config, values, self.extra_overrides())
        fixed = self.budget == "PATHS"
        series = None
        if self.use_dye_series and takes_dye_series(config):
            series = (typed_number(self.dye_series_low), typed_number(self.dye_series_high))
        return BakeRequest(
            dye_series=series,
            preset=self.base_preset(), overrides=overrides, seed=self.seed,
            paths_per_cell=self.paths_per_cell if fixed else None,
            target_rel_stderr=None if fixed else self.target_error,
            n_around=self.n_around, n_along=self.n_along,
            angular_resolution=self.angular_resolution, incidence_resolution=self.incidence_resolution or "auto")


def _free_items():
    items = []
    for index, (name, label, unit, low, high, what) in enumerate(FREE_PARAMETERS):
        unit_text = f" {unit}" if unit else " (a fraction, no unit)" if "fraction" in name else " (no unit)"
        items.append((name, label, f"Free {what} ({name}): fitted within {low:g}–{high:g}{unit_text}", 1 << index))
    return items


#: The free parameters a new fit starts with: the dye and the sheen (docs/fitting.md: the sheen's two
#: are profiled for every candidate and cost no evaluations).
DEFAULT_FREE = {"dye_weight_percent", "specular_weight", "specular_slope"}


class ClothLightFitSettings(bpy.types.PropertyGroup):
    """A fit of the yarn medium to a measured cloth BRDF (``python -m clothlight.fit``, docs/fitting.md)."""

    measured_path: StringProperty(
        name="Measurement", subtype="FILE_PATH", default="",
        description="Measured cloth BRDF: a CSV of theta_i, phi_i, theta_o, phi_o in degrees and R, G, B in 1/sr "
                    "(or spectral columns; docs/validation.md). Views in the plane of incidence are fitted, those "
                    "in the perpendicular plane held out")
    free: EnumProperty(
        name="Free Parameters", items=_free_items(), options={"ENUM_FLAG"}, default=DEFAULT_FREE,
        description="The medium's values the fit may change, each within its fit range; the others stay as the "
                    "panel shows them. A particle parameter needs a species of that name in the base medium")
    budget: IntProperty(
        name="Budget (evaluations)", default=150, min=3, soft_min=10, soft_max=400,
        description="Forward-model evaluations at most, the final accurate one included (a count; each takes "
                    "seconds: 150 is about 10 minutes on two cores)")
    time_limit: FloatProperty(
        name="Time Limit (s)", default=0.0, min=0.0, soft_max=3600.0, step=1000, precision=0,
        description="Wall-clock seconds at most for the search; it stops before a generation that would not fit "
                    "with the final evaluation. 0: no limit")
    target_ratios: StringProperty(
        name="Target Ratios", default="",
        description="Colour ratios to meet at normal incidence and view (θi = 0, θo ≤ 10°), as X/Y=value with X, "
                    "Y two of R, G, B (ratios of linear Rec. 709 BRDF channels, no unit), comma-separated: "
                    "e.g. B/R=0.08,G/R=0.011. Empty: none")
    max_back_front: FloatProperty(
        name="Max Back/Front", default=0.0, min=0.0, soft_max=2.0, precision=2, step=5,
        description="The largest luminance ratio (no unit) of the cloth lit from straight behind over lit from "
                    "the front, at normal view: real cloth is darker from behind (e.g. 0.5). 0: not constrained")
    seed: IntProperty(
        name="Seed", default=0, min=0,
        description="Seed of the optimiser and of every forward evaluation (an integer): the same seed gives "
                    "the same fit")
    dye_series: BoolProperty(
        name="Dye Series", default=False,
        description="For a fit whose only free medium parameter is the dye (the sheen may be free too): one "
                    "Monte-Carlo transport for the dye's whole fit range (0.1–10 % of fibre weight), every "
                    "candidate read from it in about a second and without noise between candidates")
    out_dir: StringProperty(
        name="Output Folder", subtype="DIR_PATH", default="",
        description="Folder the fit writes (fitted preset.toml, fit.json, report.md), as a whole: new, or an "
                    "earlier fit's, which it replaces. Empty: fits/<measurement name> in the add-on's user folder")
    load_result: BoolProperty(
        name="Load Result", default=True,
        description="After a fit, set the medium's values to the fitted ones (Bake Tables then bakes the fitted "
                    "medium)")
    last_result: StringProperty(
        name="Last Fit", default="", options={"HIDDEN"},
        description="The last fit's outcome (JSON: folder, fitted preset, relative RMS, fitted values)")

    def free_names(self) -> tuple[str, ...]:
        """The free parameters ticked, in the order of :data:`clothlight.fit_job.FREE_PARAMETERS`."""
        return tuple(name for name, *_ in FREE_PARAMETERS if name in self.free)

    def request(self, medium, default_out: str | pathlib.Path) -> FitRequest:
        """The fit these settings ask for, from the medium settings ``medium`` as they are; the output
        folder ``default_out`` / <measurement name> when none is set."""
        measured = bpy.path.abspath(self.measured_path) if self.measured_path else ""
        if self.out_dir:
            out = bpy.path.abspath(self.out_dir)
        else:
            out = str(pathlib.Path(default_out) / (pathlib.Path(measured).stem or "fit"))
        free = self.free_names()
        # Dye Series is offered (drawn) only for a fit of the dye alone: hidden, it asks for nothing.
        dye_alone = [name for name in free if not name.startswith("specular_")] == ["dye_weight_percent"]
        return FitRequest(measured=measured, out=out, free=free, medium=medium.request(),
                          target_ratios=self.target_ratios, max_back_front=self.max_back_front or None,
                          budget=self.budget, budget_seconds=self.time_limit or None, seed=self.seed,
                          dye_series=self.dye_series and dye_alone)

    def last(self) -> dict | None:
        """The last fit's outcome as stored (folder, preset, relative_rms, held_out_rms, base, overrides)."""
        if not self.last_result:
            return None
        try:
            return json.loads(self.last_result)
        except ValueError:
            return None


def _is_sun(_self, obj) -> bool:
    return obj.type == "LIGHT" and obj.data.type == "SUN"


def _forget_other_density(settings, _context) -> None:
    """The Cloth Bake folder holds another density's cloth: Apply Garment Material must find or bake this one."""
    settings.cloth_tables_dir = ""


class ClothLightSceneSettings(bpy.types.PropertyGroup):
    weave: PointerProperty(type=ClothLightWeaveSettings)
    medium: PointerProperty(type=ClothLightMediumSettings)
    fit: PointerProperty(type=ClothLightFitSettings)
    material_mode: EnumProperty(
        name="Lighting", default="GENERAL",
        items=[("GENERAL", "General", "Any lights and world: the baked BRDF as a fitted mixture of Cycles "
                                      "closures (approximate, renders with all of Cycles' lighting)"),
               ("SUN", "Sun (Exact)", "The baked BRDF evaluated exactly for one sun lamp, shadowed by the yarns; "
                                      "other lights are ignored (validation, measurements)")],
        description="How the yarn material is lit")
    sun: PointerProperty(
        name="Sun", type=bpy.types.Object, poll=_is_sun,
        description="Sun lamp of a sun-mode material; its direction and strength follow the lamp. "
                    "Empty: the scene's first sun")
    cloth_tables_dir: StringProperty(
        name="Cloth Bake", subtype="DIR_PATH",
        description="Folder of a cloth bake (python -m clothlight.garment bake): the cloth BSDF measured on "
                    "the woven sample, for garment meshes")
    garment_threads_per_cm: IntProperty(
        name="Thread Count", default=DEFAULT_THREADS_PER_CM, **THREADS_PER_CM.limits(),
        update=_forget_other_density,
        description="Density of the cloth's warp and weft, threads per cm (both alike; the validation weave's "
                    f"yarns, spaced 10/N mm). {DEFAULT_THREADS_PER_CM}: the validation weave's, whose cloth "
                    "tables ship with the shipped presets. Another count needs a new cloth response: Bake Cloth "
                    "traces it once per density (about 30 s on 2 cores; where Embree is missing it renders it, "
                    "about 45 min), then seconds per yarn. Changing it clears the Cloth Bake folder")
    garment_open_weave: BoolProperty(
        name="Open Weave", default=True,
        description="Let light through the gaps between yarns (a transparent closure weighted by the measured "
                    "coverage). Off: faster, for dense cloth or cloth seen from afar")
    garment_transmission: BoolProperty(
        name="Transmission", default=True,
        description="Let light through the yarns (translucent and fibre-transmission closures): back-lit fabric "
                    "glows. Off: the cloth passes no light and renders at about a Principled BSDF's cost, for "
                    "garments lit from the viewer's side")
    garment_yarn_detail: BoolProperty(
        name="Yarn Detail", default=False,
        description="Show the yarns for close-ups with the cloth bake's weave detail texture (their normals and "
                    "the gaps between them), at the weave's real size on each mesh")
    garment_weave_repeats: FloatProperty(
        name="Weave Repeats per UV", default=0.0, min=0.0, soft_max=5000.0,
        description="Yarn Detail's weave repeats per UV unit (the garment's length along u over the weave's "
                    "repeat, both in mm). 0: from each mesh's size in the scene's units and its UV map")


CLASSES = (ClothLightWeaveSettings, ClothLightMediumSettings, ClothLightFitSettings, ClothLightSceneSettings)

__all__ = ["ClothLightFitSettings", "ClothLightMediumSettings", "ClothLightSceneSettings", "ClothLightWeaveSettings",
           "ParameterError", "millimetre_scale", "parse_draft"]
