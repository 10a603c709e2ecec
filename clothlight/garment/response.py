"""The cloth response: what each camera sample of the cloth gonioreflectometer sees, in the yarn's
own frame, rendered once per weave and gonioreflectometer settings (issue 44).

The cloth gonioreflectometer (:mod:`.goniometry`) renders the woven sample in sun mode: a camera
sample on a yarn emits ``(ρ(ω_i, ω_o) + ρ_u(ω_i, ω_o) + w f_s) E`` where the sun reaches it
(``osl/cloth_yarn.osl``), ω_i and ω_o the directions toward the sun and the camera in the yarn's
frame, and a patch's ρ is the weighted mean over its projection (:func:`.goniometry.patch_rho`).
What the measurement takes of the weave is geometry: for each camera sample, those two directions
and whether the sun reaches it.  A :class:`GarmentResponse` records it
(``clothlight.blender.garment.measure.measure_response``: the shader's ``LookupIncidence`` and
``LookupExit`` outputs, one camera sample per pixel, so that no pixel blends two lookups): per view
(side, exit cell), the lit samples' patch, weight and directions, and per patch the summed weight
and the summed weight of yarn seen.  :mod:`.response_measurement` turns it and any yarn's tables
into the cloth measurement in seconds, without a render.

It is the validation sweep's cloth response (:mod:`clothlight.validation.response`, one patch per
view) generalised to the garment's many patches per render.  Directions are unit 3-vectors in the
yarn frame (x along the yarn axis, z the outward normal).
"""

from __future__ import annotations

import json
import pathlib
from dataclasses import dataclass

import numpy as np

from precompute.errors import ParameterError

from .goniometry import SIDES

#: Format tag of a stored response (``.npz``).
SCHEMA = "clothlight-garment-response/1"
#: A :class:`ResponseView`'s per-sample arrays, as a response stores them (views one after another).
SAMPLE_ARRAYS = ("patch", "weight", "incidence", "exit")


@dataclass(frozen=True)
class ResponseView:
    """One view of the response: exit cell ``exit_cell`` of ``side``, seen under every sun.

    ``patch`` (S,) the incidence cell (region) of each camera sample the sun reaches on a yarn and
    ``weight`` (S,) the fraction of its pixel inside that patch (:func:`.goniometry.patch_weights`:
    a sample anywhere in its pixel stands for the pixel's mean); ``incidence`` and ``exit`` (S, 3)
    float32 the yarn-frame directions toward the sun and the camera there, as the shader looks ρ
    up; ``counted`` (N_i²,) every patch's summed pixel weight (lit, shadowed and gap alike) and
    ``covered`` (N_i²,) the summed weight of the samples that see yarn (coverage = covered / counted)."""

    side: str
    exit_cell: int
    patch: np.ndarray
    weight: np.ndarray
    incidence: np.ndarray
    exit: np.ndarray
    counted: np.ndarray
    covered: np.ndarray


def view_samples(side: str, exit_cell: int, incidence_lookup: np.ndarray, exit_lookup: np.ndarray,
                 seen: np.ndarray, index: np.ndarray, weight: np.ndarray, patches: int) -> ResponseView:
    """A :class:`ResponseView` from one render of the shader's lookups, one camera sample a pixel.

    ``incidence_lookup``, ``exit_lookup`` (H, W, ≥3): the ``LookupIncidence`` and ``LookupExit``
    outputs, 0.5 + 0.5 ω per pixel, the incidence black where another yarn shadows the sample;
    ``seen`` (H, W): the film alpha, 1 where the sample met yarn; ``index`` and ``weight`` (H, W):
    :func:`.goniometry.patch_weights` of the view; ``patches``: N_i²."""
    in_patch = (index >= 0) & (index < patches)
    lit = in_patch & (seen > 0.0) & (np.sum(incidence_lookup[..., :3], axis=-1) > 0.0)

    def directions(lookup):
        return (2.0 * lookup[..., :3][lit] - 1.0).astype(np.float32)

    return ResponseView(side, int(exit_cell), index[lit].astype(np.uint16), weight[lit].astype(np.float32),
                        directions(incidence_lookup), directions(exit_lookup),
                        np.bincount(index[in_patch], weight[in_patch], patches),
                        np.bincount(index[in_patch], (weight * seen)[in_patch], patches))


class GarmentResponse:
    """The cloth gonioreflectometer's views as lit camera samples (module docstring): what
    :mod:`.response_measurement` reads.

    ``views``: one :class:`ResponseView` per (side, exit cell), front cells first;
    ``incidence_resolution``, ``exit_resolution``: N_i, N_o of the cloth tables; ``shape``: what the
    measurement records of its scene (``patch_mm``, ``sample_size_mm``, ``half_thickness_mm``);
    ``metadata``: how it was rendered (samples per patch side, render seconds)."""

    def __init__(self, views: list[ResponseView], incidence_resolution: int, exit_resolution: int, shape: dict,
                 metadata: dict | None = None):
        expected = [(side, cell) for side in SIDES for cell in range(exit_resolution**2)]
        if [(v.side, v.exit_cell) for v in views] != expected:
            raise ParameterError("views", len(views), f"the {len(expected)} (side, exit cell) views in order")
        self.views = list(views)
        self.incidence_resolution = int(incidence_resolution)
        self.exit_resolution = int(exit_resolution)
        self.shape = dict(shape)
        self.metadata = dict(metadata or {})

    @property
    def sample_count(self) -> int:
        """Lit camera samples over all views."""
        return int(sum(len(v.patch) for v in self.views))

    def per_side(self, values: list[np.ndarray]) -> dict:
        """Per-view arrays (N_i², …) in view order → per side (N_i², N_o², …), as the tables hold them."""
        n_o2 = self.exit_resolution**2
        return {side: np.stack(values[k * n_o2:(k + 1) * n_o2], axis=1) for k, side in enumerate(SIDES)}

    def coverage(self) -> dict:
        """Per side (N_o²,): the fraction of the cloth hidden by yarn along each exit cell's view,
        the mean over the patches (as the render-based measurement takes it)."""
        per_view = [np.mean(v.covered / v.counted) for v in self.views]
        n_o2 = self.exit_resolution**2
        return {side: np.array(per_view[k * n_o2:(k + 1) * n_o2]) for k, side in enumerate(SIDES)}

    def save(self, path) -> pathlib.Path:
        """Write the response to ``path`` (``.npz``), whole or not at all; uncompressed, as a new
        weave's cloth tables wait for it (compressing takes 20 times as long and saves a quarter)."""
        path = pathlib.Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        arrays = {
            "schema": np.array(SCHEMA),
            "resolutions": np.array([self.incidence_resolution, self.exit_resolution]),
            "shape": np.array(json.dumps(self.shape)),
            "metadata": np.array(json.dumps(self.metadata)),
            "counts": np.array([len(v.patch) for v in self.views]),
            "counted": np.stack([v.counted for v in self.views]),
            "covered": np.stack([v.covered for v in self.views]),
        }
        for name in SAMPLE_ARRAYS:
            arrays[name] = np.concatenate([getattr(v, name) for v in self.views])
        staging = path.with_name(path.name + ".partial.npz")
        np.savez(staging, **arrays)
        staging.replace(path)
        return path

    @classmethod
    def load(cls, path) -> GarmentResponse:
        """Read a response written by :meth:`save`."""
        with np.load(pathlib.Path(path)) as data:
            if str(data["schema"]) != SCHEMA:
                raise ParameterError("response", str(path), f"a {SCHEMA} file")
            n_i, n_o = (int(n) for n in data["resolutions"])
            bounds = np.concatenate([[0], np.cumsum(data["counts"])])
            arrays = {name: data[name] for name in SAMPLE_ARRAYS}
            keys = [(side, cell) for side in SIDES for cell in range(n_o**2)]
            views = [ResponseView(side, cell, *(arrays[name][a:b] for name in SAMPLE_ARRAYS), counted, covered)
                     for (side, cell), a, b, counted, covered in zip(keys, bounds[:-1], bounds[1:], data["counted"],
                                                                     data["covered"])]
            return cls(views, n_i, n_o, json.loads(str(data["shape"])), json.loads(str(data["metadata"])))
