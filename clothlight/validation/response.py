"""The cloth response: the gonioreflectometer's sun-mode sweep as a linear map of the yarn tables.

In sun mode every cloth pixel of a view emits ``(ρ(ω_i, ω_o) + ρ_u(ω_i, ω_o) + w f_s) E`` where no
other yarn shadows it (``osl/cloth_yarn.osl``), and the calibrated cloth BRDF of the view is the sum
of those pixels over ``N² E cos θi`` (:func:`.measure.measure_view` with the rig's framing: every
pixel covers (P/N)² of cloth).  The shader reads ρ as a fixed blend of 16 atlas pixels
(:func:`precompute.tables.layout.rho_taps`) and ρ_u as a fixed blend of attenuation-table pixels
(:func:`precompute.optics.ballistic.unscattered_cone_weights`), so the whole view is linear in the tables::

    f_cloth(view) = A_ρ(view) · atlas + A_u(view) · attenuation + w · f_CT(view; m) · s(view)

with ``s`` the lit samples whose face is turned to the sun (the specular's mask).  A render records,
per camera sample, the yarn-frame directions ρ is read at and whether the sun reaches it
(:mod:`.response_render`, the shader's ``LocalIncidence``, ``LocalExit`` and ``SunLit`` outputs);
those samples define A_ρ, A_u and s for any table layout, so one set of renders per weave and rig
serves every medium: a cloth BRDF sweep in milliseconds instead of minutes (issue 19's "cloth
operator"; docs/fitting.md).  No Blender here.

A view is (θi, θv, φv, α): the sun at zenith θi on the −x side of the plane of incidence (θi > 90°:
behind the cloth, as the §6.1 swatch lit from behind at 180°), the
camera at zenith θv and azimuth φv from that plane (φv = 0 with θv signed as in :mod:`.framing`:
negative on the light's side; φv = 90°: the perpendicular plane), and the sample turned by −α
about its normal (sun and camera turned by α), so that a set of α averages the weave's anisotropy
as an isotropic instrument does.
"""

from __future__ import annotations

import functools
import math
import pathlib
from dataclasses import dataclass

import numpy as np


from precompute.errors import ParameterError
from precompute.optics import ballistic as _ballistic
from precompute.tables import layout as _table_layout

#: Format tag of a stored response (``.npz``).
SCHEMA = "clothlight-response/1"


@dataclass(frozen=True)
class ResponseView:
    """One view's lit cloth samples.

    ``theta_i_deg``, ``theta_v_deg``, ``phi_v_deg``, ``sample_azimuth_deg``: the view (module
    docstring), degrees.  ``incidence``, ``exit`` (S, 3): the yarn-frame directions toward the sun
    and the camera at each camera sample the sun reaches.  ``samples_per_side``: N, camera samples
    along the patch side (the image is N × N, one sample per pixel).
    """

    theta_i_deg: float
    theta_v_deg: float
    phi_v_deg: float
    sample_azimuth_deg: float
    incidence: np.ndarray
    exit: np.ndarray
    samples_per_side: int

    @property
    def calibration(self) -> float:
        """Cloth BRDF (1/sr) per unit of summed sample radiance over unit irradiance: 1 / (N² |cos θi|)
        (θi > 90°: the sun behind the cloth, the BTDF)."""
        return 1.0 / (self.samples_per_side**2 * abs(math.cos(math.radians(self.theta_i_deg))))

    @property
    def toward_camera(self) -> np.ndarray:
        """Unit vector toward the camera in the frame of the plane of incidence (sun on −x)."""
        t, p = math.radians(self.theta_v_deg), math.radians(self.phi_v_deg)
        return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])

    @property
    def toward_sun(self) -> np.ndarray:
        t = math.radians(self.theta_i_deg)
        return np.array([-math.sin(t), 0.0, math.cos(t)])


@dataclass(frozen=True)
class TableLayout:
    """What the linear map of a table depends on: the atlas' grids, the attenuation table's length,
    the yarn's boundary index and the sun mode's cone (the shader's ``UnscatteredSpread``)."""

    incidence_resolution: int
    exit_resolution: int
    unscattered_samples: int
    index: float
    unscattered_spread: float


class ClothResponse:
    """The linear map from yarn tables to the sun-mode cloth BRDF at a set of views."""

    def __init__(self, views: list[ResponseView], *, metadata: dict | None = None):
        if not views:
            raise ParameterError("views", views, "at least one view")
        self.views = list(views)
        self.metadata = dict(metadata or {})
        self._maps: dict[TableLayout, tuple] = {}

    def angles(self) -> list[tuple[float, float, float, float]]:
        """(θi, θv, φv, α) of every view, degrees."""
        return [(v.theta_i_deg, v.theta_v_deg, v.phi_v_deg, v.sample_azimuth_deg) for v in self.views]

    def _maps_for(self, layout: TableLayout):
        if layout not in self._maps:
            import scipy.sparse

            n_atlas = (layout.incidence_resolution * layout.exit_resolution) ** 2
            rho_rows, unscattered_rows = [], []
            for view in self.views:
                index, weights = _table_layout.rho_taps(layout.incidence_resolution, layout.exit_resolution,
                                                        view.incidence, view.exit)
                rho_rows.append(np.bincount(index.ravel(), weights.ravel(), minlength=n_atlas) * view.calibration)
                cone, length = _ballistic.unscattered_cone_weights(view.incidence, view.exit, layout.index,
                                                                   layout.unscattered_spread)
                lower, fraction = _table_layout.attenuation_taps(layout.unscattered_samples, length)
                row = np.bincount(lower.ravel(), (cone * (1.0 - fraction)).ravel(),
                                  minlength=layout.unscattered_samples)
                row += np.bincount((lower + 1).ravel(), (cone * fraction).ravel(),
                                   minlength=layout.unscattered_samples)
                unscattered_rows.append(row * view.calibration)
            self._maps[layout] = (scipy.sparse.csr_matrix(np.array(rho_rows)), np.array(unscattered_rows))
        return self._maps[layout]

    def atlas_pixels_read(self, layout: TableLayout) -> np.ndarray:
        """The flat indices (row-major) of the BRDF atlas pixels the views read, ascending: their cloth
        BRDF depends on no other pixel, so tables needed only here need only these."""
        rho_map, _ = self._maps_for(layout)
        return np.unique(rho_map.indices)

    def specular_brdf(self, weight: float, slope: float, index: float, fuzz_albedo: float = 0.0,
                      fuzz_depth: float = 0.0, fuzz_asymmetry: float = 0.0, fuzz_tint=(1.0, 1.0, 1.0),
                      fuzz_flatness: float = 0.0) -> np.ndarray:
        """The cloth-scale terms' share of each view's cloth BRDF (n_views, 3), 1/sr, RGB: (w f_CT + f_fuzz)
        (n_c·l) s, the white Cook–Torrance sheen and the fuzz of optical depth ``fuzz_depth``, asymmetry
        ``fuzz_asymmetry`` and flatness ``fuzz_flatness`` (:func:`precompute.optics.lommel_seeliger.fuzz_brdf`)
        about the cloth normal, of albedo ``fuzz_albedo`` times ``fuzz_tint`` per channel, on the lit yarn
        faces turned to the sun (the shader's sun mode cuts both alike)."""
        from precompute.optics.cook_torrance import cook_torrance
        from precompute.optics.lommel_seeliger import fuzz_brdf

        sheen = weight * cook_torrance(self._toward_sun, self._toward_camera, slope, index)
        terms = np.repeat(sheen[:, None], 3, axis=1)
        if fuzz_albedo:
            fuzz = fuzz_brdf(self._toward_sun, self._toward_camera, fuzz_albedo, fuzz_depth, fuzz_asymmetry,
                             fuzz_flatness)
            terms = terms + fuzz[:, None] * np.asarray(fuzz_tint, float)
        return terms * (self._toward_sun[:, 2] * self._specular_share)[:, None]

    def fuzz_transmittance(self, fuzz_depth: float, fuzz_flatness: float = 0.0) -> np.ndarray:
        """(n_views,) the share of each view's yarn light that crosses a fuzz of optical depth
        ``fuzz_depth`` and flatness ``fuzz_flatness`` in and out
        (:func:`precompute.optics.lommel_seeliger.fuzz_transmittance` about the cloth normal, as the
        shader shades the yarn's tables); 1 for ``fuzz_depth`` 0."""
        from precompute.optics.lommel_seeliger import fuzz_transmittance

        return fuzz_transmittance(self._toward_sun[:, 2], self._toward_camera[:, 2], fuzz_depth, fuzz_flatness)

    @functools.cached_property
    def _toward_sun(self) -> np.ndarray:
        return np.array([v.toward_sun for v in self.views])

    @functools.cached_property
    def _toward_camera(self) -> np.ndarray:
        return np.array([v.toward_camera for v in self.views])

    @functools.cached_property
    def _specular_share(self) -> np.ndarray:
        # Lit samples on faces turned to the sun: where the shader's cl_cloth_specular is not cut.
        return np.array([np.count_nonzero(v.incidence[:, 2] > 0.0) * v.calibration for v in self.views])

    def cloth_brdf(self, atlas: np.ndarray, attenuation: np.ndarray | None, layout: TableLayout, *,
                   specular_weight: float, specular_slope: float, specular_index: float | None = None,
                   fuzz_albedo: float = 0.0, fuzz_depth: float = 0.0, fuzz_asymmetry: float = 0.0,
                   fuzz_tint=(1.0, 1.0, 1.0), fuzz_flatness: float = 0.0) -> np.ndarray:
        """The cloth BRDF (n_views, C), 1/sr, that a sun-mode sweep of the yarn material measures.

        ``atlas``: the BRDF atlas image (N_i·N_o, N_i·N_o, C) (``brdf.exr``); ``attenuation``: the
        unscattered light's table (M, C) or (1, M, C) (``unscattered.exr``), or None for a material
        without it; ``layout`` must describe both.  ``specular_weight``, ``specular_slope``,
        ``specular_index``: the shader's ``SpecularWeight``, ``Slope`` (Beckmann rms slope m) and
        ``SpecularIOR`` (None: the layout's host index); ``fuzz_albedo``, ``fuzz_depth``,
        ``fuzz_asymmetry``, ``fuzz_tint``, ``fuzz_flatness``: its ``FuzzAlbedo``, ``FuzzDepth``,
        ``FuzzAsymmetry``, ``FuzzTint`` and ``FuzzFlatness`` (the yarn's light shaded by
        :meth:`fuzz_transmittance`).
        """
        atlas = np.asarray(atlas, float)
        side = layout.incidence_resolution * layout.exit_resolution
        if atlas.ndim != 3 or atlas.shape[:2] != (side, side):
            raise ParameterError("atlas", atlas.shape, f"({side}, {side}, C): the layout's atlas")
        rho_map, unscattered_map = self._maps_for(layout)
        brdf = np.asarray(rho_map @ atlas.reshape(side * side, -1))
        if attenuation is not None:
            attenuation = np.asarray(attenuation, float).reshape(-1, atlas.shape[2])
            if attenuation.shape[0] != layout.unscattered_samples:
                raise ParameterError("attenuation", attenuation.shape,
                                     f"({layout.unscattered_samples}, C): the layout's attenuation table")
            brdf = brdf + unscattered_map @ attenuation
        index = layout.index if specular_index is None else specular_index
        if fuzz_depth:
            brdf = brdf * self.fuzz_transmittance(fuzz_depth, fuzz_flatness)[:, None]
        return brdf + self.specular_brdf(specular_weight, specular_slope, index, fuzz_albedo, fuzz_depth,
                                         fuzz_asymmetry, fuzz_tint, fuzz_flatness)[:, :brdf.shape[1]]

    def save(self, path) -> pathlib.Path:
        """Write the response to ``path`` (``.npz``, compressed)."""
        path = pathlib.Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        counts = np.array([len(v.incidence) for v in self.views])
        arrays = {
            "schema": np.array(SCHEMA),
            "angles_deg": np.array(self.angles(), float),
            "samples_per_side": np.array([v.samples_per_side for v in self.views]),
            "counts": counts,
            "incidence": np.concatenate([v.incidence for v in self.views]).astype(np.float32),
            "exit": np.concatenate([v.exit for v in self.views]).astype(np.float32),
            "metadata": np.array(repr(self.metadata)),
        }
        staging = path.with_name(path.name + ".partial.npz")
        np.savez_compressed(staging, **arrays)
        staging.replace(path)
        return path

    @classmethod
    def load(cls, path) -> ClothResponse:
        """Read a response written by :meth:`save`."""
        import ast

        with np.load(pathlib.Path(path)) as data:
            if str(data["schema"]) != SCHEMA:
                raise ParameterError("response", str(path), f"a {SCHEMA} file")
            bounds = np.concatenate([[0], np.cumsum(data["counts"])])
            incidence, exit_ = data["incidence"].astype(float), data["exit"].astype(float)
            views = [ResponseView(*map(float, angles), incidence[a:b], exit_[a:b], int(n))
                     for angles, a, b, n in zip(data["angles_deg"], bounds[:-1], bounds[1:],
                                                data["samples_per_side"])]
            metadata = ast.literal_eval(str(data["metadata"]))
        return cls(views, metadata=metadata)
