// ClothLight shared OSL math: direction grids of the baked tables and the cloth specular term.
// Mirrors precompute/grids.py exactly (tests hold the two together).
// Local frame of a yarn surface point: x = yarn axis (tangent), y = n x t, z = outward normal.

#ifndef CLOTHLIGHT_H
#define CLOTHLIGHT_H

#define CL_QUARTER_PI 0.78539816339744830962

// Shirley-Chiu concentric disk -> unit square.
void cl_concentric_disk_to_square(float x, float y, output float s, output float t)
{
    float r = sqrt(x * x + y * y);
    float phi = atan2(y, x);
    if (phi < -CL_QUARTER_PI)
        phi += M_2PI;
    float a, b;
    if (phi < CL_QUARTER_PI) {
        a = r;
        b = phi * a / CL_QUARTER_PI;
    }
    else if (phi < 3.0 * CL_QUARTER_PI) {
        b = r;
        a = -(phi - 2.0 * CL_QUARTER_PI) * b / CL_QUARTER_PI;
    }
    else if (phi < 5.0 * CL_QUARTER_PI) {
        a = -r;
        b = (phi - 4.0 * CL_QUARTER_PI) * a / CL_QUARTER_PI;
    }
    else {
        b = -r;
        a = -(phi - 6.0 * CL_QUARTER_PI) * b / CL_QUARTER_PI;
    }
    s = 0.5 * (a + 1.0);
    t = 0.5 * (b + 1.0);
}

// Equal-area hemisphere (z >= 0) -> unit square (exit directions of the tables).
void cl_hemisphere_to_square(vector d, output float s, output float t)
{
    float z = clamp(d[2], 0.0, 1.0);
    float r = sqrt(1.0 - z);
    float planar = sqrt(d[0] * d[0] + d[1] * d[1]);
    if (planar == 0.0) {
        s = 0.5;
        t = 0.5;
        return;
    }
    cl_concentric_disk_to_square(r * d[0] / planar, r * d[1] / planar, s, t);
}

// Clarberg equal-area octahedral map: unit sphere -> unit square (incidence directions).
void cl_sphere_to_square(vector d, output float s, output float t)
{
    float ax = abs(d[0]);
    float ay = abs(d[1]);
    float az = min(1.0, abs(d[2]));
    float r = sqrt(1.0 - az);
    float a = max(ax, ay);
    float b = min(ax, ay);
    b = (a == 0.0) ? 0.0 : b / a;
    float phi = atan(b) * 2.0 / M_PI;
    if (ax < ay)
        phi = 1.0 - phi;
    float v = phi * r;
    float u = r - v;
    if (d[2] < 0.0) {
        float swap = u;
        u = 1.0 - v;
        v = 1.0 - swap;
    }
    u = (d[0] < 0.0) ? -u : u;
    v = (d[1] < 0.0) ? -v : v;
    s = 0.5 * (u + 1.0);
    t = 0.5 * (v + 1.0);
}

// Unpolarized Fresnel reflectance of a dielectric, light arriving from outside (index 1) at cos_i.
float cl_fresnel_dielectric(float cos_i, float eta)
{
    float c = clamp(cos_i, 0.0, 1.0);
    float sin_t2 = (1.0 - c * c) / (eta * eta);
    if (sin_t2 >= 1.0)
        return 1.0;
    float cos_t = sqrt(1.0 - sin_t2);
    float rs = (c - eta * cos_t) / (c + eta * cos_t);
    float rp = (eta * c - cos_t) / (eta * c + cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

// Cook-Torrance specular BRDF (1/sr) about the normal Nc, Blinn's form (paper refs [10], [21]):
// f = F(v.h) D(h) G / (4 (n.l)(n.v)) with the normalized Beckmann distribution
// D = exp(-tan^2(a)/m^2) / (pi m^2 cos^4(a)), a = angle(n, h), m = rms slope,
// and the V-cavity attenuation G = min(1, 2(n.h)(n.v)/(v.h), 2(n.h)(n.l)/(v.h)).
// L and V point away from the surface.
float cl_cook_torrance(vector Nc, vector L, vector V, float m, float eta)
{
    float nl = dot(Nc, L);
    float nv = dot(Nc, V);
    if (nl <= 0.0 || nv <= 0.0)
        return 0.0;
    vector H = normalize(L + V);
    float nh = max(dot(Nc, H), 1e-6);
    float vh = max(dot(V, H), 1e-6);
    float cos2 = nh * nh;
    float tan2 = (1.0 - cos2) / cos2;
    float D = exp(-tan2 / (m * m)) / (M_PI * m * m * cos2 * cos2);
    float G = min(1.0, min(2.0 * nh * nv / vh, 2.0 * nh * nl / vh));
    return cl_fresnel_dielectric(vh, eta) * D * G / (4.0 * nl * nv);
}

// True when the sun (world direction L) is hidden from P by ANOTHER yarn.  Ng_out is the outward
// geometric normal of the yarn at P.  Light arriving from behind crosses the yarn itself first;
// that self-shadowing is already inside the baked tables, so a ray that starts into its own
// (convex) tube is first carried to where it leaves it.  Hits closer than min_distance (scene
// units) are ignored: a ray leaving a triangle can hit its neighbour across the shared edge.
int cl_sun_occluded(point P, vector Ng_out, vector L, float min_distance)
{
    point origin = P;
    if (dot(Ng_out, L) < 0.0) {
        if (!trace(origin, L, "mindist", min_distance))
            return 0;
        getmessage("trace", "P", origin);
    }
    return trace(origin, L, "mindist", min_distance);
}

#endif
