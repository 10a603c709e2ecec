"""One code path for a validation sweep (paper §4 and §6).

The add-on's operator, ``python -m clothlight.validate`` and a real Blender
(``blender -b -P scripts/validate_blender.py -- …``) all run :class:`ValidationRun`: a sweep as a
sequence of steps, one render each, so that a modal operator can interleave them with the UI and
:func:`run_validation` can run them in one go.

For every material asked for (the yarn material reading baked tables, the paper's §6 baseline) the
rig renders every (θi, θv) and measures the calibrated cloth BRDF (``yarn_scene`` with full path
tracing, every other material with direct light only); then, for the colour checks of
§6.1, the sample at normal view lit from the front (θi = 0) and from behind (θi = 180°).  With a
measurement the paper's normalisation and the metrics are added.  With several sample azimuths
(:attr:`.rig.RigSettings.sample_azimuths_deg`) all of it is rendered at each turn of the sample
about its normal and every view and swatch is the mean over the turns, as a measured isotropic BRDF
averages the weave over its azimuth.  Outputs in ``out_dir``:
``results.json``, ``report.md``, ``sweeps.png`` (and ``sweeps_paper_normalised.png`` with a
measurement), ``swatches/*.png`` and the float renders under ``renders/``.
"""

from __future__ import annotations

import atexit
import math
import pathlib
import time
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass, replace

import bpy
import numpy as np

from ..garment.material import build_garment_material, cloth_tables_from_bake
from ..materials import GENERAL_MODE, SUN_MODE, build_baseline_material, build_yarn_material, yarn_tables_folder
from ...mesh_attributes import YARN_TANGENT
from ...yarn_tables import yarn_tables_from_bake
from ...validation.framing import (
    DEFAULT_MATERIALS,
    GARMENT_MATERIALS,
    MATERIALS,
    PATH_TRACED_MATERIALS,
    YARN_MATERIALS,
    ParameterError,
)
from ...validation.measure import (
    apply_paper_normalisation,
    channel_ratios,
    find_view,
    mean_over_turns,
    paper_normalisation_factor,
)
from precompute.fit.measured_data import read_measurement, relative_rms_error, rms_error, shape_correlation
from precompute.tables.folder import check_output_folder, staged_folder
from ...validation.report import VALIDATION_FOLDER_NAMES, swatch_exposure, write_report, write_swatch_png
from ..measurement_render import worker_threads
from ...weave import WeaveParameters
from .rig import RigSettings, build_rig, calibration_plane

MATERIAL_LABELS = {
    "yarn": "ClothLight yarn BRDF",
    "yarn_general": "ClothLight yarn BRDF, general-lighting closure mixture",
    "yarn_scene": "ClothLight yarn BRDF in a scene: general-lighting material, full path tracing, light between yarns",
    "baseline": "baseline: Lambert (0.6/π, 0, 0) + Cook–Torrance m = 0.8",
    "garment": "ClothLight cloth BSDF on a flat patch (garment material, sun mode)",
    "garment_general": "ClothLight cloth BSDF on a flat patch (garment material, general-lighting mixture)",
}
#: The paper's Table 1 (§6.1): B/R and G/R at normal illumination and view.
PAPER_TABLE1 = {
    "real red cotton": {"B/R": 0.08, "G/R": 0.011},
    "the paper's model (range)": {"B/R": [0.05, 0.25], "G/R": [0.001, 0.017]},
}
#: Incidences of the §6.1 colour swatches: lit from the front, and from straight behind, degrees.
SWATCH_INCIDENCES_DEG = {"front": 0.0, "back": 180.0}
SCHEMA = "clothlight-validation/1"


class ValidationCancelled(Exception):
    """The sweep was cancelled; the rig was removed and nothing was written but renders."""


@dataclass(frozen=True)
class Progress:
    """``done`` of ``total`` renders finished; ``what`` names the last one."""

    done: int
    total: int
    what: str


class ValidationRun:
    """A validation sweep, checked on construction, run by iterating :meth:`steps`.

    Parameters
    ----------
    sample
        A ClothLight sample object (copied, never changed), WeaveParameters, or None for
        :data:`clothlight.blender.validation.rig.VALIDATION_WEAVE` (see :func:`.rig.build_rig`).
    out_dir
        Folder for the outputs (created).
    materials
        Names from :data:`MATERIALS`; default: both when ``tables_dir`` is given, else the baseline.
    tables_dir
        A bake folder (``python -m precompute bake --out DIR``, or a cache entry): the yarn material's
        tables.  None: those of the sample object's ClothLight yarn material, if it has one.
    cloth_dir
        A cloth bake folder (``python -m clothlight.garment bake``): the garment material's
        tables, swept on a flat patch in place of the sample.
    measured_csv
        A measurement file (:mod:`.measured_data` format), or None.
    settings
        Angles, framing and render settings (:class:`.rig.RigSettings`), the sample's azimuths
        included: every view and swatch is rendered at each and averaged.
    swatches
        Also render the front- and back-lit colour swatches (§6.1).
    specular_weight
        The yarn materials' SpecularWeight in place of the bake's (``summary.json`` → ``specular``),
        e.g. 0 to measure the cloth without its sheen; None keeps the bake's.

    Raises ParameterError (or MeasurementFormatError naming the row) before any render.
    """

    def __init__(self, sample=None, out_dir="clothlight_validation", *, materials=None, tables_dir=None,
                 cloth_dir=None, measured_csv=None, settings: RigSettings = RigSettings(), swatches: bool = True,
                 specular_weight: float | None = None):
        if materials is None:
            materials = DEFAULT_MATERIALS if tables_dir is not None else ("baseline",)
        materials = tuple(materials)
        unknown = [m for m in materials if m not in MATERIALS]
        if not materials or unknown or len(set(materials)) != len(materials):
            raise ParameterError("materials", materials, f"distinct names from {MATERIALS}")
        self.materials = tuple(m for m in MATERIALS if m in materials)
        self.tables = None
        if set(YARN_MATERIALS) & set(self.materials):
            if tables_dir is None and isinstance(sample, bpy.types.Object):
                tables_dir = tables_of_sample(sample)
            if tables_dir is None:
                raise ParameterError("tables_dir", None, "a bake folder (python -m precompute bake --out DIR) "
                                                         "for the yarn material")
            try:
                self.tables = yarn_tables_from_bake(tables_dir)
            except (FileNotFoundError, ValueError, KeyError) as error:
                raise ParameterError("tables_dir", str(tables_dir), f"a complete bake folder ({error})") from None
        self.specular_weight = specular_weight
        if specular_weight is not None:
            if isinstance(specular_weight, bool) or not (isinstance(specular_weight, (int, float))
                                                         and math.isfinite(specular_weight) and specular_weight >= 0):
                raise ParameterError("specular_weight", specular_weight, "a finite number ≥ 0")
            if self.tables is not None:
                self.tables = replace(
                    self.tables, specular={**self.tables.specular, "weight": float(specular_weight),
                                           "source": f"{self.tables.specular['source']}, weight set to "
                                                     f"{specular_weight:g} for this sweep"})
        self.cloth_tables = None
        if set(GARMENT_MATERIALS) & set(self.materials):
            try:
                self.cloth_tables = cloth_tables_from_bake(cloth_dir) if cloth_dir is not None else None
            except (FileNotFoundError, ValueError, KeyError) as error:
                raise ParameterError("cloth_dir", str(cloth_dir), f"a complete cloth bake folder ({error})") from None
            if self.cloth_tables is None:
                raise ParameterError("cloth_dir", None, "a cloth bake folder (python -m clothlight.garment bake) "
                                                        "for the garment material")
        self.measured_csv = None if measured_csv is None else pathlib.Path(measured_csv)
        if self.measured_csv is not None and not self.measured_csv.is_file():
            raise ParameterError("measured_csv", str(measured_csv), "an existing measurement file")
        self.measurement = read_measurement(self.measured_csv) if self.measured_csv is not None else None
        self.sample = sample
        self.out_dir = check_output_folder(out_dir, VALIDATION_FOLDER_NAMES, "out_dir", job="validation")
        self._folder = self.out_dir  # the staging folder while a sweep writes
        self.settings = settings
        self.swatches = bool(swatches)
        per_material = (len(settings.incidences_deg) * len(settings.views_deg)
                        + (len(SWATCH_INCIDENCES_DEG) if swatches else 0))
        self.total = len(self.materials) * len(settings.sample_azimuths_deg) * per_material
        self.results: dict | None = None

    def steps(self) -> Iterator[Progress]:
        """Build the rig, render one view per iteration (yielding the progress after it), then
        write the outputs into :attr:`results`.  Closing the iterator early removes the rig."""
        start = time.perf_counter()
        rig = build_rig(self.sample, self.settings)
        created = []
        try:
            if set(YARN_MATERIALS) & set(self.materials) and YARN_TANGENT not in rig.sample.data.attributes:
                raise ParameterError("sample", getattr(self.sample, "name", self.sample),
                                     f"a mesh with the '{YARN_TANGENT}' attribute for the yarn material")
            with staged_folder(self.out_dir, VALIDATION_FOLDER_NAMES, "out_dir", job="validation") as folder:
                self._folder = folder
                yield from self._sweep(rig, created, start)
        finally:
            self._folder = self.out_dir
            rig.remove()
            for material in created:
                try:
                    bpy.data.materials.remove(material)
                except ReferenceError:  # already removed, e.g. by the user while the sweep ran
                    pass

    def _sweep(self, rig, created: list, start: float) -> Iterator[Progress]:
        """The renders of :meth:`steps` into :attr:`_folder`, then the results and the report."""
        turns, swatches, seconds = {}, {}, {}
        done = 0
        for kind in self.materials:
            material_start = time.perf_counter()
            created.append(self._dress(rig, kind))
            turns[kind], images = {}, {}
            for azimuth in self.settings.sample_azimuths_deg:
                rig.set_azimuth(azimuth)
                views = []
                for theta_i in self.settings.incidences_deg:
                    rig.set_incidence(theta_i)
                    for theta_v in self.settings.views_deg:
                        rig.set_view(theta_v)
                        views.append(rig.measure(self._render_path(kind, theta_i, theta_v, azimuth=azimuth)))
                        done += 1
                        yield Progress(done, self.total,
                                       f"{kind}: θi = {theta_i:g}°, θv = {theta_v:g}°{self._turn_label(azimuth)}")
                turns[kind][azimuth] = views
                if self.swatches:
                    images[azimuth] = {}
                    rig.set_view(0.0)
                    for side, theta_i in SWATCH_INCIDENCES_DEG.items():
                        rig.set_incidence(theta_i)
                        images[azimuth][side] = rig.render(self._render_path(kind, swatch=side, azimuth=azimuth))
                        done += 1
                        yield Progress(done, self.total,
                                       f"{kind}: swatch lit from the {side}{self._turn_label(azimuth)}")
            if images:
                swatches[kind] = self._swatch_entries(kind, images)
            seconds[kind] = time.perf_counter() - material_start
        self.results = self._assemble(rig, turns, swatches, seconds, time.perf_counter() - start)
        self.results["files"] = write_report(self.results, self._folder)
        # A last step before the folder is swapped in: a stop asked for while the report was written
        # still leaves nothing.
        yield Progress(done, self.total, "report written")

    @property
    def _turned(self) -> bool:
        """Whether the sample is measured at more than one turn (file names then carry the azimuth)."""
        return len(self.settings.sample_azimuths_deg) > 1

    def _turn_label(self, azimuth: float) -> str:
        return f", α = {azimuth:g}°" if self._turned else ""

    def _turn_suffix(self, azimuth: float) -> str:
        """What a render's or swatch's file name gets for its turn: the azimuth, where there are several."""
        return f"_a{azimuth:05.1f}" if self._turned else ""

    def _render_path(self, kind: str, theta_i: float = 0.0, theta_v: float = 0.0, swatch: str | None = None,
                     azimuth: float = 0.0):
        turn = self._turn_suffix(azimuth)
        name = f"swatch_{swatch}{turn}.exr" if swatch else f"i{theta_i:+05.1f}_v{theta_v:+05.1f}{turn}.exr"
        return self._folder / "renders" / kind / name

    def _swatch_entries(self, kind: str, images: dict) -> dict:
        """The §6.1 swatches of ``kind`` from their renders ({azimuth: {side: pixels}}): mean colour
        (over the turns), ratios, PNG (the first turn's; with several turns one per turn in ``turns``)."""
        entries = {}
        exposure = swatch_exposure(*(pixels for sides in images.values() for pixels in sides.values()))
        for side in next(iter(images.values())):
            means, pngs = [], []
            for azimuth, sides in images.items():
                pixels = sides[side]
                means.append(pixels[..., :3].astype(np.float64).mean(axis=(0, 1)) / self.settings.sun_irradiance)
                name = f"{kind}_{side}{self._turn_suffix(azimuth)}.png"
                png = write_swatch_png(pixels, self._folder / "swatches" / name, exposure)
                pngs.append(str(png.relative_to(self._folder)))
            mean = np.mean(means, axis=0)
            entries[side] = {"theta_i_deg": SWATCH_INCIDENCES_DEG[side], "mean_rgb_per_irradiance": mean.tolist(),
                             "ratios": channel_ratios(mean), "png": pngs[0]}
            if self._turned:
                entries[side]["turns"] = [{"azimuth_deg": azimuth, "mean_rgb_per_irradiance": m.tolist(), "png": png}
                                          for azimuth, m, png in zip(images, means, pngs)]
        return entries

    def _dress(self, rig, kind: str, material=None):
        """Put the material of ``kind`` (built unless given) on ``rig``, with its light paths; the
        material.  Garment materials are swept on a flat patch in place of the sample."""
        if material is None:
            # Script nodes compile through the context scene's render engine: make it the rig's.
            with bpy.context.temp_override(scene=rig.scene):
                material = self._build_material(kind)
        if kind in GARMENT_MATERIALS and rig.sample.name != GARMENT_PATCH:
            rig.replace_sample(garment_patch(rig))
        rig.use_material(material)
        rig.use_path_tracing(kind in PATH_TRACED_MATERIALS)
        return material

    def run_on_cluster(self, scheduler: str, progress: Callable[[int, int, str], None] | None = None,
                       cancel: Callable[[], bool] | None = None) -> dict:
        """The sweep with its renders as tasks of a dask cluster (``scheduler``: ``"local"`` or an
        address, :mod:`precompute.distributed`): one task per material and incidence (all its views)
        and per swatch, each worker rendering in a rig of its own.  The same results and files as
        :meth:`steps` (the renders come back as their EXR files); the sample must be a weave (or
        None), which every worker builds.  ``progress`` after every task; ``cancel()`` stops them all
        (ValidationCancelled)."""

        if self.sample is not None and not isinstance(self.sample, WeaveParameters):
            raise ParameterError("scheduler", scheduler, "no scheduler for a sample object: a cluster's workers "
                                                         "build the sample from a weave")
        start = time.perf_counter()
        from precompute import distributed
        inputs = {"sample": self.sample, "settings": self.settings, "materials": self.materials,
                  "specular_weight": self.specular_weight,
                  "tables": distributed.folder_payload(self.tables.brdf_path.parent) if self.tables else None,
                  "cloth": (distributed.folder_payload(self.cloth_tables.lobe_path.parent) if self.cloth_tables
                            else None)}
        azimuths = self.settings.sample_azimuths_deg
        tasks = [(kind, theta_i, tuple(self.settings.views_deg), None, azimuth)
                 for kind in self.materials for azimuth in azimuths for theta_i in self.settings.incidences_deg]
        if self.swatches:
            tasks += [(kind, theta_i, (0.0,), side, azimuth) for kind in self.materials for azimuth in azimuths
                      for side, theta_i in SWATCH_INCIDENCES_DEG.items()]
        done = []

        def task_done(index: int) -> None:
            kind, theta_i, views, side, azimuth = tasks[index]
            done.append(len(views))
            if progress is not None:
                what = f"swatch lit from the {side}" if side else f"θi = {theta_i:g}°, all views"
                progress(sum(done), self.total, f"{kind}: {what}{self._turn_label(azimuth)}")

        rig = build_rig(self.sample, self.settings)
        try:
            if set(GARMENT_MATERIALS) & set(self.materials):
                rig.replace_sample(garment_patch(rig))  # as the last material of steps() leaves it
            with distributed.open_executor(scheduler, code=SWEEP_CODE) as executor:
                shared = executor.share(inputs)
                try:
                    results = executor.map(render_sweep_task, [(shared, *task) for task in tasks],
                                           progress=task_done, cancel=cancel)
                except KeyboardInterrupt:
                    if cancel is not None and cancel():
                        raise ValidationCancelled("validation cancelled; nothing was written") from None
                    raise
            with staged_folder(self.out_dir, VALIDATION_FOLDER_NAMES, "out_dir", job="validation") as folder:
                self._folder = folder
                turns = {kind: {azimuth: [] for azimuth in azimuths} for kind in self.materials}
                images = {kind: {} for kind in self.materials}
                seconds = dict.fromkeys(self.materials, 0.0)
                for (kind, theta_i, views, side, azimuth), (measured, files, task_seconds) in zip(tasks, results):
                    seconds[kind] += task_seconds
                    for theta_v, exr in zip(views, files):
                        path = self._render_path(kind, theta_i, theta_v, swatch=side, azimuth=azimuth)
                        path.parent.mkdir(parents=True, exist_ok=True)
                        path.write_bytes(exr.tobytes())
                    if side:
                        images[kind].setdefault(azimuth, {})[side] = measured
                    else:
                        turns[kind][azimuth] += measured
                swatches = {kind: self._swatch_entries(kind, images[kind]) for kind in self.materials if images[kind]}
                self.results = self._assemble(rig, turns, swatches, seconds, time.perf_counter() - start)
                self.results["files"] = write_report(self.results, self._folder)
                if progress is not None:  # as steps(): a stop asked for now still leaves nothing
                    progress(self.total, self.total, "report written")
                if cancel is not None and cancel():
                    raise ValidationCancelled("validation cancelled; nothing was written")
        finally:
            self._folder = self.out_dir
            rig.remove()
        return self.results

    def _build_material(self, kind: str):
        if kind == "yarn":
            return build_yarn_material(self.tables, name="ClothLight Gonioreflectometer Yarn", mode=SUN_MODE)
        if kind in GARMENT_MATERIALS:
            return build_garment_material(self.cloth_tables, name=f"ClothLight Gonioreflectometer {kind}",
                                          mode=SUN_MODE if kind == "garment" else GENERAL_MODE)
        if kind in ("yarn_general", "yarn_scene"):
            # the same material; yarn_scene differs only in the rig's light paths (use_path_tracing)
            title = "General" if kind == "yarn_general" else "Scene"
            return build_yarn_material(self.tables, name=f"ClothLight Gonioreflectometer Yarn {title}",
                                       mode=GENERAL_MODE)
        return build_baseline_material(name="ClothLight Gonioreflectometer Baseline", mode=SUN_MODE)

    def _assemble(self, rig, turns, swatches, seconds, total_seconds) -> dict:
        """The results from each material's views at each turn (``turns``: {kind: {azimuth: views}})
        and its swatch entries: every view the mean over the turns (:func:`.measure.mean_over_turns`)."""
        s = self.settings
        curves = {kind: mean_over_turns(list(by_turn.values())) for kind, by_turn in turns.items()}
        results = {
            "schema": SCHEMA,
            "settings": {
                "incidences_deg": list(s.incidences_deg), "views_deg": list(s.views_deg),
                "resolution": s.resolution, "samples": s.samples, "seed": s.seed,
                "patch_mm": rig.patch_mm, "sun_irradiance_w_per_m2": s.sun_irradiance,
                "sample": {"name": getattr(self.sample, "name", None) or "ClothLight woven sample (built)",
                           "size_mm": [2 * h for h in rig.bounds.half_size],
                           "thickness_mm": 2 * rig.bounds.half_thickness,
                           "weave": _weave_description(rig.sample)},
                "tables_dir": str(self.tables.brdf_path.parent) if self.tables else None,
                "yarn_specular": dict(self.tables.specular) if self.tables and self.tables.specular else None,
                "cloth_dir": str(self.cloth_tables.lobe_path.parent) if self.cloth_tables else None,
                "measured_csv": str(self.measured_csv) if self.measured_csv else None,
            },
            # the warp's azimuths from the plane of incidence at which every view and swatch was
            # rendered and averaged (the sun and cameras turned about the sample's normal)
            "sample_azimuths_deg": list(s.sample_azimuths_deg),
            "units": {
                "angles": "degrees; θv negative on the light's side, θv = θi the mirror direction",
                "rgb_sum": "sum of linear RGB pixel values (W m⁻² sr⁻¹) over cloth pixels",
                "sum_over_cos_rgb": "the paper's step-5 sum Σ L_p a_p / cos θv, W m⁻² sr⁻¹ · mm²",
                "brdf_rgb": "calibrated cloth BRDF, 1/sr",
                "paper_normalised_rgb": "brdf_rgb × the paper's normalisation coefficient, 1/sr",
            },
            "materials": {},
            "paper_table1": PAPER_TABLE1,
            "seconds": {"total": total_seconds, **seconds},
        }
        measured_normal = self.measurement.at(0.0, 0.0) if self.measurement is not None else None
        for kind, views in curves.items():
            normal = find_view(views, 0.0, 0.0)
            entry = {"label": MATERIAL_LABELS[kind],
                     "table1": channel_ratios(normal.brdf_rgb) if normal is not None else None,
                     "paper_normalisation_factor": None, "metrics": None}
            if measured_normal is not None and normal is not None and sum(normal.brdf_rgb) > 0:
                entry["paper_normalisation_factor"] = paper_normalisation_factor(normal.brdf_rgb, measured_normal)
                apply_paper_normalisation(views, entry["paper_normalisation_factor"])
            if self.measurement is not None:
                entry["metrics"] = compare_with_measurement(views, self.measurement)
            entry["views"] = [asdict(v) for v in views]
            if self._turned:
                entry["turns"] = [{"azimuth_deg": azimuth, "views": [asdict(v) for v in turn]}
                                  for azimuth, turn in turns[kind].items()]
            if kind in swatches:
                entry["swatches"] = swatches[kind]
            results["materials"][kind] = entry
        if "yarn" in curves and "yarn_general" in curves:
            results["general_vs_sun"] = compare_sweeps(curves["yarn_general"], curves["yarn"])
        if "yarn_general" in curves and "yarn_scene" in curves:
            results["interreflection"] = interreflection(curves["yarn_scene"], curves["yarn_general"],
                                                         swatches.get("yarn_scene"), swatches.get("yarn_general"))
        for kind in GARMENT_MATERIALS:
            # The yarn sample as the paper's model has it, and in a scene: the cloth tables carry the
            # light between yarns that only the second has.
            for sample in ("yarn", "yarn_scene"):
                if sample in curves and kind in curves:
                    results[f"{kind}_vs_{sample}"] = compare_sweeps(curves[kind], curves[sample])
        if set(GARMENT_MATERIALS) <= set(curves):
            # The closure mixture's own error: the general mode against the cloth BSDF it stands for.
            results["garment_general_vs_garment"] = compare_sweeps(curves["garment_general"], curves["garment"])
        if self.measurement is not None:
            m = self.measurement
            results["measurement"] = {
                "path": str(self.measured_csv), "direction_pairs": len(m.angles_deg),
                "spectral": m.wavelengths_nm is not None, "gamut_clipping": m.gamut_clipping,
                "comments": list(m.comments),
                "table1": channel_ratios(measured_normal) if measured_normal is not None else None,
                "in_plane": {f"{theta_i:g}": [[float(x), *map(float, rgb)] for x, rgb in zip(*m.in_plane(theta_i))]
                             for theta_i in s.incidences_deg},
            }
        return results


GARMENT_PATCH = "ClothLight Gonioreflectometer Garment Patch"


def garment_patch(rig):
    """A flat square as large as the rig's sample, with a UV map whose u runs along the warp (+x):
    the cloth the garment material is measured on."""
    size = 2.0 * min(rig.bounds.half_size)
    plane = calibration_plane(size, name=GARMENT_PATCH)
    plane.location = rig.bounds.center
    uv = plane.data.uv_layers.new(name="UVMap")
    corners = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
    for loop in plane.data.loops:
        uv.data[loop.index].uv = corners[loop.vertex_index]
    return plane


def tables_of_sample(sample) -> str | None:
    """The bake folder of the first ClothLight yarn material on the object ``sample``, or None."""
    for slot in sample.material_slots:
        folder = yarn_tables_folder(slot.material) if slot.material is not None else None
        if folder:
            return str(pathlib.Path(bpy.path.abspath(folder)))
    return None


def _weave_description(sample) -> dict | None:
    weave = sample.get("clothlight_weave")
    return weave.to_dict() if weave is not None else None


def compare_with_measurement(views, measurement) -> dict | None:
    """RMS, relative RMS and shape correlation of a sweep against a measurement, over the views the
    measurement has (in-plane, same θi and θv), per channel and for R, G, B together; for the
    calibrated BRDF and, when set, the paper-normalised one.  None when no view was measured."""
    pairs = [(v, measurement.at(v.theta_i_deg, v.theta_v_deg)) for v in views]
    pairs = [(v, m) for v, m in pairs if m is not None]
    if not pairs:
        return None
    measured = np.array([m for _, m in pairs])
    metrics = {"views_compared": len(pairs)}
    for quantity in ("brdf_rgb", "paper_normalised_rgb"):
        if not all(getattr(v, quantity) for v, _ in pairs):
            continue
        model = np.array([getattr(v, quantity) for v, _ in pairs])
        by_channel = {}
        for name, columns in (("R", [0]), ("G", [1]), ("B", [2]), ("RGB", [0, 1, 2])):
            a, b = model[:, columns], measured[:, columns]
            by_channel[name] = {"rms": rms_error(a, b), "relative_rms": relative_rms_error(a, b),
                                "shape_correlation": shape_correlation(a, b)}
        metrics[quantity] = by_channel
    return metrics


def compare_sweeps(views, reference_views) -> dict:
    """How far one sweep's calibrated BRDF is from another's, over the views they share.

    Per channel and for R, G, B together: ``relative_rms`` (RMS difference over the RMS of the
    reference, :func:`.measured_data.relative_rms_error`) and ``rms_view_ratio`` (RMS over views
    of model / reference − 1: every view counts alike, dark ones too), and the view of the worst
    red ratio.  This is the check of the yarn shader's general-lighting mode against its exact
    sun mode."""
    shared, ratio = view_ratios(views, reference_views)
    reference = {(v.theta_i_deg, v.theta_v_deg): np.array(v.brdf_rgb) for v in reference_views}
    model = np.array([v.brdf_rgb for v in shared], dtype=float).reshape(-1, 3)
    exact = np.array([reference[(v.theta_i_deg, v.theta_v_deg)] for v in shared], dtype=float).reshape(-1, 3)
    comparison = {"views_compared": len(shared)}
    for name, columns in (("R", [0]), ("G", [1]), ("B", [2]), ("RGB", [0, 1, 2])):
        deviation = ratio[:, columns] - 1.0
        comparison[name] = {"relative_rms": relative_rms_error(model[:, columns], exact[:, columns]),
                            "rms_view_ratio": float(np.sqrt(np.nanmean(deviation**2)))
                            if np.any(np.isfinite(deviation)) else None}
    if np.any(np.isfinite(ratio[:, 0])):
        worst = int(np.nanargmax(np.abs(ratio[:, 0] - 1.0)))
        comparison["worst_red"] = {"theta_i_deg": shared[worst].theta_i_deg,
                                   "theta_v_deg": shared[worst].theta_v_deg, "ratio": float(ratio[worst, 0])}
    return comparison


def view_ratios(views, reference_views) -> tuple[list, np.ndarray]:
    """The views two sweeps share and, per view and channel, one sweep's calibrated BRDF over the
    other's (NaN where the reference is 0): (shared views, ratios of shape (views, 3))."""
    reference = {(v.theta_i_deg, v.theta_v_deg): np.array(v.brdf_rgb) for v in reference_views}
    shared = [v for v in views if (v.theta_i_deg, v.theta_v_deg) in reference]
    model = np.array([v.brdf_rgb for v in shared], dtype=float).reshape(-1, 3)
    exact = np.array([reference[(v.theta_i_deg, v.theta_v_deg)] for v in shared], dtype=float).reshape(-1, 3)
    with np.errstate(divide="ignore", invalid="ignore"):
        return shared, np.where(exact > 0, model / exact, np.nan)


def interreflection(scene_views, direct_views, scene_swatches=None, direct_swatches=None) -> dict:
    """What light between yarns adds: the general-lighting yarn material path traced in a scene
    (``yarn_scene``) over the same material under direct light only (``yarn_general``).

    ``views``: per shared view θi, θv, ``ratio_rgb`` (scene / direct per channel; None where the
    direct value is 0) and ``added_brdf_rgb`` (scene − direct, 1/sr); per channel R, G, B and for
    the sum R + G + B (``RGB``): the ``mean`` and ``min`` of the ratio over views and its ``max``
    with the view where it is (``max_at``);
    ``comparison``: :func:`compare_sweeps` of the two; ``swatches``: per side (front, back), when
    both were rendered, the ratio of the swatches' mean radiance (``ratio_rgb``; None for a channel
    whose direct light is below 10⁻⁶ of the swatch's brightest, e.g. green lit from behind) and what
    the scene adds to it over the irradiance (``added_rgb_per_irradiance``, 1/sr)."""
    shared, ratio = view_ratios(scene_views, direct_views)
    reference = {(v.theta_i_deg, v.theta_v_deg): np.array(v.brdf_rgb, dtype=float) for v in direct_views}
    direct = {key: float(rgb.sum()) for key, rgb in reference.items()}
    with np.errstate(divide="ignore", invalid="ignore"):
        total = np.array([sum(v.brdf_rgb) / direct[(v.theta_i_deg, v.theta_v_deg)]
                          if direct[(v.theta_i_deg, v.theta_v_deg)] > 0 else np.nan for v in shared])
    result = {"views_compared": len(shared),
              "views": [{"theta_i_deg": v.theta_i_deg, "theta_v_deg": v.theta_v_deg,
                         "ratio_rgb": [float(r) if np.isfinite(r) else None for r in row],
                         "added_brdf_rgb": (np.array(v.brdf_rgb) - reference[(v.theta_i_deg, v.theta_v_deg)]).tolist()}
                        for v, row in zip(shared, ratio)]}
    for name, values in (("R", ratio[:, 0]), ("G", ratio[:, 1]), ("B", ratio[:, 2]), ("RGB", total)):
        if not np.any(np.isfinite(values)):
            result[name] = None
            continue
        worst = int(np.nanargmax(values))
        result[name] = {"mean": float(np.nanmean(values)), "min": float(np.nanmin(values)),
                        "max": float(values[worst]),
                        "max_at": {"theta_i_deg": shared[worst].theta_i_deg, "theta_v_deg": shared[worst].theta_v_deg}}
    result["comparison"] = compare_sweeps(scene_views, direct_views)
    if scene_swatches and direct_swatches:
        result["swatches"] = {}
        for side in (side for side in scene_swatches if side in direct_swatches):
            a = np.array(scene_swatches[side]["mean_rgb_per_irradiance"])
            b = np.array(direct_swatches[side]["mean_rgb_per_irradiance"])
            with np.errstate(divide="ignore", invalid="ignore"):  # None where the direct light is ~0
                ratio = np.where(b > 1e-6 * b.max(initial=0.0), a / b, np.nan)
            result["swatches"][side] = {"ratio_rgb": [float(x) if np.isfinite(x) else None for x in ratio],
                                        "added_rgb_per_irradiance": (a - b).tolist()}
    return result


# -- on a cluster --------------------------------------------------------------------------------

#: The code a sweep's workers run, checked against this checkout's (precompute.distributed).
SWEEP_CODE = {"entries": ("clothlight.blender.validation.run",)}
#: A worker process's rigs: (the inputs' digest, whether the garment patch is swept) → _WorkerSweep.
_worker_sweeps: dict = {}


@dataclass
class _WorkerSweep:
    run: ValidationRun
    rig: object
    materials: dict
    folder: object  # the TemporaryDirectory holding the tables and the renders


def _worker_sweep(inputs: dict, garment: bool) -> _WorkerSweep:
    """This worker's rig for ``inputs`` (built on its first task), with the tables written to disk."""
    import hashlib
    import pickle
    import tempfile

    key = (hashlib.sha256(pickle.dumps(inputs)).hexdigest(), garment)
    if key not in _worker_sweeps:

        from precompute.distributed import write_payload
        folder = tempfile.TemporaryDirectory(prefix="clothlight-sweep-")
        root = pathlib.Path(folder.name)
        run = ValidationRun(inputs["sample"], root / "out", materials=inputs["materials"],
                            tables_dir=write_payload(inputs["tables"], root / "tables") if inputs["tables"] else None,
                            cloth_dir=write_payload(inputs["cloth"], root / "cloth") if inputs["cloth"] else None,
                            settings=inputs["settings"], specular_weight=inputs["specular_weight"])
        rig = build_rig(run.sample, run.settings)
        rig.scene.render.threads_mode = "FIXED"
        rig.scene.render.threads = worker_threads()
        _worker_sweeps[key] = _WorkerSweep(run, rig, {}, folder)
    return _worker_sweeps[key]


def _close_worker_sweeps() -> None:
    for sweep in _worker_sweeps.values():
        sweep.rig.remove()
        for material in sweep.materials.values():
            bpy.data.materials.remove(material)
        sweep.folder.cleanup()
    _worker_sweeps.clear()


# At a worker's exit, before Blender's data is freed (as the cloth measurement's workers do).
atexit.register(_close_worker_sweeps)


def render_sweep_task(inputs: dict, kind: str, theta_i: float, views_deg: tuple, swatch: str | None,
                      azimuth: float = 0.0) -> tuple:
    """A cluster task: the sweep's renders of material ``kind`` at incidence ``theta_i`` with the
    sample turned to ``azimuth`` — every view of ``views_deg`` measured (a list of ViewMeasurement),
    or the ``swatch`` side's pixels — with each render's EXR file (uint8 arrays) and the task's seconds."""
    start = time.perf_counter()
    sweep = _worker_sweep(inputs, kind in GARMENT_MATERIALS)
    rig = sweep.rig
    sweep.materials[kind] = sweep.run._dress(rig, kind, sweep.materials.get(kind))
    rig.set_azimuth(azimuth)
    rig.set_incidence(theta_i)
    measured, files = [], []
    for theta_v in views_deg:
        rig.set_view(theta_v)
        path = sweep.run._render_path(kind, theta_i, theta_v, swatch=swatch, azimuth=azimuth)
        measured.append(rig.render(path) if swatch else rig.measure(path))
        files.append(np.frombuffer(path.read_bytes(), np.uint8))
        path.unlink()
    return (measured[0] if swatch else measured), files, time.perf_counter() - start


def run_validation(sample=None, out_dir="clothlight_validation", *,
                   progress: Callable[[int, int, str], None] | None = None,
                   cancel: Callable[[], bool] | None = None, scheduler: str | None = None, **options) -> dict:
    """Run a whole sweep (see :class:`ValidationRun` for ``sample``, ``out_dir`` and ``options``)
    and return its results (also in ``out_dir/results.json``); with a ``scheduler``, on a cluster
    (:meth:`ValidationRun.run_on_cluster`).

    ``progress(done, total, what)`` is called after every render; ``cancel()`` is asked before
    every render and, when true, the rig is removed and ValidationCancelled raised.
    """
    run = ValidationRun(sample, out_dir, **options)
    if scheduler is not None:
        return run.run_on_cluster(scheduler, progress=progress, cancel=cancel)
    steps = run.steps()
    try:
        while True:
            if cancel is not None and cancel():
                raise ValidationCancelled("validation cancelled; nothing was written")
            try:
                step = next(steps)
            except StopIteration:
                break
            if progress is not None:
                progress(step.done, step.total, step.what)
    finally:
        steps.close()
    return run.results

