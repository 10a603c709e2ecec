"""Write clothlight/validation/data/synthetic_red_cotton.csv: a SYNTHETIC measurement for examples.

It is NOT measured data.  It is an analytic model shaped like what the paper reports for real red
cotton, so that the importer, the metrics, the plots and the report have something to work on:

* at normal incidence and view its colour ratios are the paper's Table 1 values for real red
  cotton, B/R = 0.08 and G/R = 0.011;
* it grows toward grazing incidence and view (§6.2: "the BRDF of cloth grows with the increasing
  incidence and viewing angles"), most on the mirror side (Figure 4).

The model (angles in the plane of incidence; θv signed, negative on the light's side):

    f_rgb(θi, θv) = (ρ/π) (1 + a (2 − cos θi − cos|θv|)) · (1, 0.011, 0.08)            red body
                    + (1 − cos θi cos θv) · CT(θi, θv)                                   white sheen

with ρ = 0.3, a = 0.5, and CT the Cook–Torrance BRDF about the cloth normal (normalised Beckmann
distribution, rms slope m = 0.5; V-cavity shadowing; Fresnel of a dielectric of index 1.557).  The
factor (1 − cos θi cos θv) stands in for fibres masking the surface reflection near the normal: it
removes the white specular at normal incidence and view, where Table 1 leaves it no room.

Rows: θi = 0, 30, 45, 60° and θv = −60 … 70° in 10° steps, light at φi = 180°, so φo = 180° on
the light's side and 0° on the mirror side (precompute/fit/measured_data.py).

    python scripts/make_synthetic_measurement.py
"""

import math
import pathlib

OUT = pathlib.Path(__file__).resolve().parents[1] / "clothlight" / "validation" / "data" / "synthetic_red_cotton.csv"
ALBEDO = 0.3
GROWTH = 0.5
TINT = (1.0, 0.011, 0.08)
SLOPE = 0.5
INDEX = 1.557


def fresnel(c: float, n: float = INDEX) -> float:
    """Unpolarised Fresnel reflectance of a dielectric (Cook & Torrance's form), c = cos of the angle to the
    facet normal."""
    g = math.sqrt(n * n - 1.0 + c * c)
    return 0.5 * ((g - c) / (g + c)) ** 2 * (1.0 + ((c * (g + c) - 1.0) / (c * (g - c) + 1.0)) ** 2)


def cook_torrance(theta_i: float, theta_v: float, m: float = SLOPE) -> float:
    """Cook–Torrance BRDF (1/sr) for the light at −θi and the view at θv (radians) in the x-z plane."""
    light = (-math.sin(theta_i), 0.0, math.cos(theta_i))
    view = (math.sin(theta_v), 0.0, math.cos(theta_v))
    half = [a + b for a, b in zip(light, view)]
    norm = math.sqrt(sum(x * x for x in half))
    half = [x / norm for x in half]
    nh, nl, nv = half[2], light[2], view[2]
    vh = sum(a * b for a, b in zip(view, half))
    d = math.exp(-(1.0 - nh * nh) / (nh * nh * m * m)) / (math.pi * m * m * nh**4)
    g = min(1.0, 2.0 * nh * nv / vh, 2.0 * nh * nl / vh)
    return fresnel(vh) * d * g / (4.0 * nl * nv)


def synthetic_brdf(theta_i_deg: float, theta_v_deg: float) -> list[float]:
    ti, tv = math.radians(theta_i_deg), math.radians(theta_v_deg)
    body = ALBEDO / math.pi * (1.0 + GROWTH * (2.0 - math.cos(ti) - math.cos(tv)))
    sheen = (1.0 - math.cos(ti) * math.cos(tv)) * cook_torrance(ti, tv)
    return [body * tint + sheen for tint in TINT]


def main() -> None:
    lines = ["# SYNTHETIC data, NOT a measurement: written by scripts/make_synthetic_measurement.py",
             "# from an analytic model shaped like the paper's red cotton (see that script).",
             "# BRDF in 1/sr per linear Rec.709 channel; angles in degrees; light at phi_i = 180.",
             "theta_i,phi_i,theta_o,phi_o,R,G,B"]
    for theta_i in (0, 30, 45, 60):
        for theta_v in range(-60, 71, 10):
            phi_o = 180 if theta_v < 0 else 0
            rgb = synthetic_brdf(theta_i, theta_v)
            lines.append(f"{theta_i},180,{abs(theta_v)},{phi_o}," + ",".join(f"{x:.6g}" for x in rgb))
    OUT.write_text("\n".join(lines) + "\n")
    print(OUT)


if __name__ == "__main__":
    main()
