"""Where the specular highlight of a twisted yarn sits and which way its streak runs (issue 43, twist).

The model is the specular yarn of P. Irawan and S. Marschner, "Specular reflection from woven cloth",
ACM Trans. Graph. 31(1), article 11, 2012: a yarn is a bundle of smooth, specular fibres wound as a
helix about its centreline at the twist angle α.  A smooth cylinder of tangent t reflects the
direction ω_i only onto the cone of directions ω_o with t·ω_o = −t·ω_i (the "cone of reflection"), so
a fibre can send light from ω_i to ω_o only where

    t · h = 0,        h = (ω_i + ω_o) / |ω_i + ω_o|  (the half vector),

its reflecting normal then being h itself.  The highlight of a twisted yarn therefore lies where the
helix's tangent turns perpendicular to h, and each fibre's glint is a streak along that fibre: the
streak makes the fibre's angle with the yarn axis.  Irawan and Marschner use this condition to place
the highlight across the yarn; what follows writes it out for ClothLight's yarns (:mod:`.plies`),
crimp included (the equations are numbered here, not as in the paper).

The helix.  A yarn's centreline c(u) (u its arc length, mm) carries the sweep frame of
:mod:`.geometry`: tangent T, a binormal B in the cloth plane and N = T × B; its cross-section is the
ellipse of semi-axes a (along B) and b (along N), mm.  A fibre at the fraction r of the envelope's
radius and at the angle φ about the axis (0 on the +B side, π/2 towards N: the unit disc of
:mod:`.plies` mapped onto the ellipse) sits at

    P(u) = c(u) + r·(a·cos φ·B + b·sin φ·N(u)),    φ = φ₀ + ω·u,    ω = tan α / √(a·b)  (rad/mm),

the right-handed (Z) helix of :func:`.plies.twist_rate`, α the twist angle at the envelope (r = 1).
A crimped centreline turns in its own T–N plane: T′ = κ·N, N′ = −κ·T (κ the curvature, 1/mm,
positive where the yarn bends towards N), so the fibre's tangent is, up to its length,

    t ∝ (1 − κ·r·b·sin φ)·T + ω·r·(−a·sin φ·B + b·cos φ·N).                              (1)

The highlight's place across the yarn.  With (1), t·h = 0 reads

    (−ω·r·a·h_B − κ·r·b·h_T)·sin φ + ω·r·b·h_N·cos φ = −h_T,                               (2)

(h_T = h·T and so on), that is A·sin(φ + γ) = −h_T with A = √(p² + q²), γ = atan2(q, p) for the
coefficients p, q of sin φ and cos φ.  Of its two roots the highlight is chiefly the one where the
fibre's reflecting normal h faces out of the yarn (the envelope's outward normal ∝ b·cos φ·B + a·sin φ·N
has the larger component along h; the other can still show on a ply's flank); where |h_T| > A no
fibre at that radius reflects.  Along a straight yarn a fibre starting at φ₀ passes φ* at
u = (φ* − φ₀)/ω, once a turn.  An untwisted yarn
(ω = 0) on a straight centreline lights up only where h ⊥ T, all round at once.

The streak's tilt.  Seen along N (from above, for a yarn lying in the cloth), the fibre at the
highlight runs at the angle

    τ = atan2(t·B, t·T) = atan2(−ω·r·a·sin φ*, 1 − κ·r·b·sin φ*)                            (3)

from the yarn's axis, in degrees.  On the top of a yarn (0 < φ* < π) a Z twist tilts it towards −B
(τ < 0) and an S twist would tilt it the other way; at the top of a straight yarn (φ* = π/2, r = 1)
tan τ = a·ω = tan α·√(a/b): the flattened yarn shows its twist steeper from above than α.
"""

from __future__ import annotations

import math

import numpy as np

from .plies import twist_rate


def fibre_tangent(yarn_tangent, binormal, phase_rad, radius_fraction: float, twist_angle_deg: float,
                  semi_axes_mm: tuple[float, float], curvature_per_mm: float = 0.0) -> np.ndarray:
    """Unit tangent (3,) of the helical fibre at angle ``phase_rad`` (rad, 0 on +B, π/2 towards N)
    and at ``radius_fraction`` of the envelope, on a yarn of unit tangent ``yarn_tangent`` and
    binormal ``binormal`` twisted right-handed at ``twist_angle_deg`` (degrees, at the envelope),
    cross-section semi-axes ``semi_axes_mm`` (mm) and centreline curvature ``curvature_per_mm``
    (1/mm, towards N): eq. (1) of the module docstring."""
    tangent, binormal = np.asarray(yarn_tangent, float), np.asarray(binormal, float)
    normal = np.cross(tangent, binormal)
    a, b = semi_axes_mm
    omega = twist_rate(twist_angle_deg, semi_axes_mm)
    r, sin, cos = radius_fraction, math.sin(phase_rad), math.cos(phase_rad)
    t = (1.0 - curvature_per_mm * r * b * sin) * tangent + omega * r * (-a * sin * binormal + b * cos * normal)
    return t / np.linalg.norm(t)


def highlight_phases(half_vector, yarn_tangent, binormal, radius_fraction: float, twist_angle_deg: float,
                     semi_axes_mm: tuple[float, float], curvature_per_mm: float = 0.0) -> list[float]:
    """The angles φ about the yarn's axis (rad, in (−π, π], 0 on +B, π/2 towards N) where the helical
    fibres at ``radius_fraction`` of the envelope meet Irawan and Marschner's specular condition
    t·h = 0: the roots of eq. (2) of the module docstring (none, one or two), the one whose reflecting
    normal h faces out of the yarn most squarely first (the envelope's outward normal there closest to
    h; the other is the highlight's twin on the yarn's far side, which a ply's flank can still show).
    ``half_vector`` is h, a unit vector; the other arguments as :func:`fibre_tangent`.  None where no
    fibre at that radius reflects (|h·T| larger than the twist can turn the fibres) and, for an
    untwisted straight yarn, none (the condition then holds all round or nowhere)."""
    h = np.asarray(half_vector, float)
    tangent, binormal = np.asarray(yarn_tangent, float), np.asarray(binormal, float)
    normal = np.cross(tangent, binormal)
    a, b = semi_axes_mm
    omega = twist_rate(twist_angle_deg, semi_axes_mm)
    r = radius_fraction
    h_t, h_b, h_n = h @ tangent, h @ binormal, h @ normal
    p = -omega * r * a * h_b - curvature_per_mm * r * b * h_t
    q = omega * r * b * h_n
    amplitude = math.hypot(p, q)
    if amplitude == 0.0 or abs(h_t) > amplitude:
        return []
    gamma = math.atan2(q, p)
    base = math.asin(-h_t / amplitude)
    roots = [math.atan2(math.sin(phi), math.cos(phi)) for phi in (base - gamma, math.pi - base - gamma)]
    # the envelope's outward normal at φ is ∝ b·cos φ·B + a·sin φ·N
    facing = {phi: b * math.cos(phi) * h_b + a * math.sin(phi) * h_n for phi in roots}
    return sorted(set(roots), key=lambda phi: -facing[phi])


def highlight_phase(half_vector, yarn_tangent, binormal, radius_fraction: float, twist_angle_deg: float,
                    semi_axes_mm: tuple[float, float], curvature_per_mm: float = 0.0) -> float:
    """The first of :func:`highlight_phases` (rad): where the highlight faces h most squarely; NaN
    where there is none or where it would face away from h (the yarn's underside)."""
    roots = highlight_phases(half_vector, yarn_tangent, binormal, radius_fraction, twist_angle_deg, semi_axes_mm,
                             curvature_per_mm)
    if not roots:
        return math.nan
    phi = roots[0]
    a, b = semi_axes_mm
    h = np.asarray(half_vector, float)
    binormal = np.asarray(binormal, float)
    outward = b * math.cos(phi) * binormal + a * math.sin(phi) * np.cross(np.asarray(yarn_tangent, float), binormal)
    return phi if outward @ h > 0.0 else math.nan


def streak_tilt_deg(phase_rad: float, radius_fraction: float, twist_angle_deg: float,
                    semi_axes_mm: tuple[float, float], curvature_per_mm: float = 0.0) -> float:
    """The angle (degrees) from the yarn's axis to the fibre at ``phase_rad`` seen along N, positive
    towards +B: eq. (3) of the module docstring, the tilt of the highlight's streak when the phase is
    :func:`highlight_phase`'s.  Negative on the top of a right-handed (Z) yarn."""
    a, b = semi_axes_mm
    omega = twist_rate(twist_angle_deg, semi_axes_mm)
    sin = math.sin(phase_rad)
    return math.degrees(math.atan2(-omega * radius_fraction * a * sin,
                                   1.0 - curvature_per_mm * radius_fraction * b * sin))


def straight_yarn_highlight(half_vector, twist_angle_deg: float, semi_axes_mm: tuple[float, float],
                            radius_fraction: float = 1.0) -> tuple[float, float]:
    """A straight yarn along +x with binormal +y in the cloth plane (N = +z), its surface fibres
    (``radius_fraction`` 1) or those deeper in: the highlight's angle about the axis φ* (degrees)
    and its streak's tilt (degrees, module docstring); (NaN, NaN) where no fibre reflects."""
    phase = highlight_phase(half_vector, (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), radius_fraction, twist_angle_deg,
                            semi_axes_mm)
    if math.isnan(phase):
        return math.nan, math.nan
    return math.degrees(phase), streak_tilt_deg(phase, radius_fraction, twist_angle_deg, semi_axes_mm)


def highlight_arc_mm(phase_rad: float, start_phase_rad: float, twist_angle_deg: float,
                     semi_axes_mm: tuple[float, float]) -> float:
    """Where along a straight yarn (arc length, mm, in [0, 2π/ω)) the fibre that starts at
    ``start_phase_rad`` passes the highlight's angle ``phase_rad``: u = (φ* − φ₀)/ω, once a turn."""
    omega = twist_rate(twist_angle_deg, semi_axes_mm)
    return ((phase_rad - start_phase_rad) % (2.0 * math.pi)) / omega


def measure_highlights(mesh, params, light_direction, view_direction) -> dict[str, np.ndarray]:
    """Find the highlight on a built woven mesh (:func:`.geometry.build_woven_mesh` of ``params``) as
    Irawan and Marschner's specular fibres would show it, with nothing of the prediction above.

    The fibres are the mesh's own helical lines: around every ply, the vertex at the same place on
    each ring (``segments_around`` lines a ply, which :mod:`.plies` winds about the yarn's axis).
    Along each line, where the sign of t·h changes between two segments (t a segment's direction,
    h the half vector of the unit ``light_direction`` ω_i and ``view_direction`` ω_o, both pointing
    away from the cloth), the fibre reflects ω_i into ω_o; a crossing counts where the mesh's
    surface there (its area-weighted vertex normal) faces both the light and the view and lies on
    the upper half of its yarn (towards N).  Returns, one entry a crossing, the yarn, where the
    crossing sits in the unit disc of its yarn's envelope (``radius_fraction``; ``phase_rad``, 0
    on +B, π/2 towards N), the fibre's measured ``tilt_deg`` seen along N (atan2(t·B, t·T), degrees),
    and the centreline's unit ``yarn_tangent``, ``binormal`` and ``curvature_per_mm`` (1/mm, towards N)
    there: what the prediction needs to be evaluated at the same place."""
    omega_i, omega_o = np.asarray(light_direction, float), np.asarray(view_direction, float)
    half = (omega_i + omega_o) / np.linalg.norm(omega_i + omega_o)
    vertices, faces = mesh.vertices, mesh.faces
    face_normal = np.cross(vertices[faces[:, 1]] - vertices[faces[:, 0]], vertices[faces[:, 2]] - vertices[faces[:, 0]])
    vertex_normal = np.zeros_like(vertices)
    np.add.at(vertex_normal, faces.ravel(), np.repeat(face_normal, 3, axis=0))   # area-weighted
    vertex_normal /= np.linalg.norm(vertex_normal, axis=1, keepdims=True)
    a, b = params.cross_section_mm
    around, plies = params.segments_around, params.ply_count
    found = {key: [] for key in ("yarn", "radius_fraction", "phase_rad", "tilt_deg", "yarn_tangent", "binormal",
                                 "curvature_per_mm")}
    for yarn, centre in enumerate(mesh.centerlines):
        binormal = np.array([0.0, 1.0, 0.0]) if yarn < params.warp_count else np.array([1.0, 0.0, 0.0])
        step = np.diff(centre, axis=0)
        length = np.linalg.norm(step, axis=1)
        yarn_tangent = step / length[:, None]                          # per segment
        for ply in range(plies):
            chosen = np.flatnonzero((mesh.yarn_id == yarn) & (mesh.ply_index == ply))[:-2]   # cap centres last
            rings = vertices[chosen].reshape(-1, around, 3)
            normals = vertex_normal[chosen].reshape(-1, around, 3)
            segment = np.diff(rings, axis=0)                           # (n − 1, around, 3)
            segment /= np.linalg.norm(segment, axis=-1, keepdims=True)
            along = segment @ half
            ring, line = np.nonzero(along[:-1] * along[1:] < 0.0)     # between segments ring, ring + 1
            weight = (along[ring, line] / (along[ring, line] - along[ring + 1, line]))[:, None]
            tangent = (1.0 - weight) * segment[ring, line] + weight * segment[ring + 1, line]
            tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
            # between the middles of segments ring and ring + 1
            point = 0.5 * (rings[ring + 1, line] + (1.0 - weight) * rings[ring, line] + weight * rings[ring + 2, line])
            centre_point = 0.5 * (centre[ring + 1] + (1.0 - weight) * centre[ring] + weight * centre[ring + 2])
            axis = (1.0 - weight) * yarn_tangent[ring] + weight * yarn_tangent[ring + 1]
            axis /= np.linalg.norm(axis, axis=1, keepdims=True)
            normal_axis = np.cross(axis, binormal)
            curvature = np.sum((yarn_tangent[ring + 1] - yarn_tangent[ring]) * normal_axis, axis=1) \
                / (0.5 * (length[ring] + length[ring + 1]))
            surface = normals[ring + 1, line]
            offset = point - centre_point
            x, y = offset @ binormal / a, np.sum(offset * normal_axis, axis=1) / b
            keep = (surface @ omega_i > 0.0) & (surface @ omega_o > 0.0) & (y > 0.0)
            found["yarn"].append(np.full(keep.sum(), yarn))
            found["radius_fraction"].append(np.hypot(x, y)[keep])
            found["phase_rad"].append(np.arctan2(y, x)[keep])
            found["tilt_deg"].append(np.degrees(np.arctan2(tangent @ binormal, np.sum(tangent * axis, axis=1)))[keep])
            found["yarn_tangent"].append(axis[keep])
            found["binormal"].append(np.broadcast_to(binormal, axis.shape)[keep])
            found["curvature_per_mm"].append(curvature[keep])
    return {key: np.concatenate(value) for key, value in found.items()}


def predicted_highlights(found: dict[str, np.ndarray], light_direction, view_direction, twist_angle_deg: float,
                         semi_axes_mm: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """The prediction (eqs. (2), (3)) at each of :func:`measure_highlights`'s crossings, from the
    crossing's radius and its yarn's tangent, binormal and curvature alone: of the highlight's angles
    (:func:`highlight_phases`) the one nearest the crossing's (rad; NaN where there is none) and the
    streak's tilt there (degrees; 0 where there is none)."""
    omega_i, omega_o = np.asarray(light_direction, float), np.asarray(view_direction, float)
    half = (omega_i + omega_o) / np.linalg.norm(omega_i + omega_o)
    phases, tilts = [], []
    for r, measured, tangent, binormal, curvature in zip(found["radius_fraction"], found["phase_rad"],
                                                         found["yarn_tangent"], found["binormal"],
                                                         found["curvature_per_mm"]):
        roots = highlight_phases(half, tangent, binormal, r, twist_angle_deg, semi_axes_mm, curvature)
        if not roots:
            phases.append(math.nan)
            tilts.append(0.0)
            continue
        phase = min(roots, key=lambda phi: abs(math.remainder(phi - measured, 2.0 * math.pi)))
        phases.append(phase)
        tilts.append(streak_tilt_deg(phase, r, twist_angle_deg, semi_axes_mm, curvature))
    return np.array(phases), np.array(tilts)


def streak_tilts_in_image(rgba: np.ndarray, threshold: float = 0.35) -> np.ndarray:
    """The tilts of the highlight streaks on the warps of a render of the sample seen from above, the
    warps running along the image's rows (degrees from the image's x axis, counter-clockwise, within
    ±45°; ``rgba`` (H, W, ≥ 2) bottom row first, as Blender stores it, display values in [0, 1]):
    each connected patch of pixels whose green exceeds ``threshold`` (a white highlight, not the red
    yarn), of at least 12 pixels and at least twice as long as wide, its principal axis."""
    from scipy import ndimage

    labels, count = ndimage.label(np.asarray(rgba)[..., 1] > threshold)
    tilts = []
    for label in range(1, count + 1):
        rows, columns = np.nonzero(labels == label)
        if len(rows) < 12:
            continue
        spread, axes = np.linalg.eigh(np.cov(np.stack([columns - columns.mean(), rows - rows.mean()])))
        if spread[1] < 4.0 * spread[0]:
            continue
        tilt = (math.degrees(math.atan2(axes[1, 1], axes[0, 1])) + 90.0) % 180.0 - 90.0
        if abs(tilt) < 45.0:
            tilts.append(tilt)
    return np.array(tilts)


def _direction(elevation_deg: float, azimuth_deg: float) -> np.ndarray:
    elevation, azimuth = math.radians(elevation_deg), math.radians(azimuth_deg)
    return np.array([math.cos(elevation) * math.cos(azimuth), math.cos(elevation) * math.sin(azimuth),
                     math.sin(elevation)])


#: name → (ω_i, ω_o): the renders' grazing light (15° above the cloth from −y, across the warps)
#: seen from straight above, and a grazing light from an oblique azimuth seen at 60°, which moves
#: the highlight along the yarns (elevation above the cloth, azimuth from +x, degrees).
LIGHTINGS = {"light 15° from −y, view from above": (_direction(15.0, -90.0), _direction(90.0, 0.0)),
             "light 15° from azimuth −60°, view 60° from +y": (_direction(15.0, -60.0), _direction(60.0, 90.0))}

#: What the close-up samples that check the prediction change of the default close-up: the section of
#: the crossings all along, since the prediction's helix winds on a section that does not change along
#: the yarn (a relaxing section, :mod:`.section`, turns the mesh's lines by itself, twisted or not).
TWIST_SAMPLE = {"section_relaxation": 0.0}


def tilt_table(preset: str = "voided_red_cotton", angles_deg=(0.0, 12.0, 24.0, 40.0), lightings=None) -> list[dict]:
    """The prediction against the measurement on the preset's close-up sample (8 × 8 yarns, swept at
    12.5 µm along the yarn and 24 lines around each ply) at each twist angle (degrees) under each
    lighting (name → (ω_i, ω_o), unit vectors away from the cloth; default :data:`LIGHTINGS`): one row
    each with the crossings' count, the share with a predicted highlight, the mean measured and
    predicted tilts there (degrees), the median |difference| of tilt and of the angle about the axis
    (degrees).  ``python -m clothlight.weave.twist_highlight [preset]`` prints it (docs/twist.md)."""
    from .closeup import sheeting_weave
    from .geometry import build_woven_mesh

    lightings = lightings or LIGHTINGS
    rows = []
    for name, (light, view) in lightings.items():
        for angle in angles_deg:
            params = sheeting_weave(preset, twist_angle_deg=angle, warp_count=8, weft_count=8,
                                    segments_per_crossing=32, segments_around=24, **TWIST_SAMPLE)
            found = measure_highlights(build_woven_mesh(params), params, light, view)
            phase, predicted = predicted_highlights(found, light, view, angle, params.cross_section_mm)
            has = ~np.isnan(phase)
            measured = found["tilt_deg"]
            phase_error = np.degrees(np.abs(np.angle(np.exp(1j * (found["phase_rad"][has] - phase[has])))))
            rows.append(dict(lighting=name, twist_deg=angle, crossings=len(measured), predicted_share=has.mean(),
                             measured_deg=(measured[has] if has.any() else measured).mean(),
                             predicted_deg=predicted[has].mean() if has.any() else 0.0,
                             tilt_error_deg=np.median(np.abs(measured - predicted)[has]) if has.any() else
                             np.median(np.abs(measured)),
                             phase_error_deg=np.median(phase_error) if has.any() else math.nan))
    return rows


if __name__ == "__main__":
    import sys

    preset = sys.argv[1] if len(sys.argv) > 1 else "voided_red_cotton"
    print("| lighting | twist | crossings | with a prediction | tilt predicted | tilt measured "
          "| median abs. difference | across: median abs. difference |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for row in tilt_table(preset):
        across = "—" if math.isnan(row["phase_error_deg"]) else f"{row['phase_error_deg']:.2f}°"
        print(f"| {row['lighting']} | {row['twist_deg']:g}° | {row['crossings']} | {row['predicted_share']:.1%} | "
              f"{row['predicted_deg']:.2f}° | {row['measured_deg']:.2f}° | {row['tilt_error_deg']:.2f}° | {across} |")
