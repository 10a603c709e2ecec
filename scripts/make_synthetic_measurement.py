"""Write clothlight/validation/data/synthetic_red_cotton.csv: a SYNTHETIC measurement for examples.

It is not measured data.  It follows a documented analytic model shaped like the paper's
graphs of real red cotton — a red diffuse part that grows toward grazing views plus a white
Cook–Torrance specular — so that the importer, metrics and plots have something to work on:

    f_rgb(θi, θv) = (0.25 / π) (1 + 0.8 (1 − cos θv)) · (1, 0.011, 0.08)
                    + Cook–Torrance(m = 0.5, n = 1.557) about the cloth normal, white.

Rows cover θi = 0, 30, 45, 60° and θv = −60 … 70° in the plane of incidence (light at φi = 180°).
"""

import math
import pathlib

OUT = pathlib.Path(__file__).resolve().parents[1] / "clothlight" / "validation" / "data" / "synthetic_red_cotton.csv"


def fresnel(c, n=1.557):
    g = math.sqrt(n * n - 1 + c * c)
    return 0.5 * ((g - c) / (g + c)) ** 2 * (1 + ((c * (g + c) - 1) / (c * (g - c) + 1)) ** 2)


def cook_torrance(theta_i, theta_v, m=0.5):
    l = (-math.sin(theta_i), 0.0, math.cos(theta_i))
    v = (math.sin(theta_v), 0.0, math.cos(theta_v))
    h = [a + b for a, b in zip(l, v)]
    norm = math.sqrt(sum(x * x for x in h))
    h = [x / norm for x in h]
    nh, nl, nv = h[2], l[2], v[2]
    vh = sum(a * b for a, b in zip(v, h))
    d = math.exp(-((1 - nh * nh) / (nh * nh)) / m**2) / (math.pi * m**2 * nh**4)
    g = min(1.0, 2 * nh * nv / vh, 2 * nh * nl / vh)
    return fresnel(vh) * d * g / (4 * nl * nv)


def main() -> None:
    lines = ["# SYNTHETIC data, not a measurement: made by scripts/make_synthetic_measurement.py",
             "# from a documented analytic model (see that script). BRDF in 1/sr, angles in degrees.",
             "theta_i,phi_i,theta_o,phi_o,R,G,B"]
    for theta_i in (0, 30, 45, 60):
        for theta_v in range(-60, 71, 10):
            ti, tv = math.radians(theta_i), math.radians(theta_v)
            diffuse = 0.25 / math.pi * (1 + 0.8 * (1 - math.cos(tv)))
            specular = cook_torrance(ti, tv)
            rgb = [diffuse * tint + specular for tint in (1.0, 0.011, 0.08)]
            phi_o = 180 if theta_v < 0 else 0
            lines.append(f"{theta_i},180,{abs(theta_v)},{phi_o}," + ",".join(f"{x:.6g}" for x in rgb))
    OUT.write_text("\n".join(lines) + "\n")
    print(OUT)


if __name__ == "__main__":
    main()
