// ClothLight shared OSL math: direction grids of the baked tables and the cloth specular term.
// Mirrors precompute/tables/grids.py exactly (tests hold the two together).
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

// Smith's Lambda of the Beckmann distribution of rms slope m for a direction at cos_theta to the
// normal (Walter et al. 2007, eq. 27 in closed form): G1 = 1 / (1 + Lambda).
float cl_beckmann_lambda(float cos_theta, float m)
{
    float c = clamp(cos_theta, 1e-6, 1.0);
    float a = c / (m * sqrt(max(1.0 - c * c, 1e-12)));
    return 0.5 * (erf(a) - 1.0) + exp(-a * a) / (2.0 * a * sqrt(M_PI));
}

// Cook-Torrance specular BRDF (1/sr) about the normal Nc (paper section 5.2, refs [10], [21]):
// f = F(v.h) D(h) G / (4 (n.l)(n.v)) with the normalized Beckmann distribution
// D = exp(-tan^2(a)/m^2) / (pi m^2 cos^4(a)), a = angle(n, h), m = rms slope, the exact dielectric
// Fresnel F, and as geometric attenuation the height-correlated Smith term of the same Beckmann
// surface, G = 1 / (1 + Lambda(v) + Lambda(l)).  Cook and Torrance's V-cavity G is not the
// shadowing of a Beckmann surface, and Smith's is what Cycles' own Beckmann closures use, so the
// exact (sun) and the general-lighting modes share one specular term.  L and V point away.
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
    float G = 1.0 / (1.0 + cl_beckmann_lambda(nv, m) + cl_beckmann_lambda(nl, m));
    return cl_fresnel_dielectric(vh, eta) * D * G / (4.0 * nl * nv);
}

// The cloth's specular radiance per irradiance (1/sr) at a yarn surface point of outward shading
// normal N_out: Cook-Torrance about the cloth normal Nc times (n_c.l).  A yarn surface turned away
// from the light reflects none of it (the light would have to cross the yarn first); Cycles
// answers the same for its reflection closures (it takes a light behind the shading normal as
// transmission), so both lighting modes agree.
float cl_cloth_specular(vector Nc, vector N_out, vector L, vector V, float m, float eta)
{
    if (dot(N_out, L) <= 0.0)
        return 0.0;
    return cl_cook_torrance(Nc, L, V, m, eta) * max(dot(Nc, L), 0.0);
}

// The cloth normal on the viewer's side (V toward the viewer): a sheet has the same sheen on
// both faces, each about its own normal.
vector cl_cloth_normal_toward(vector Nc, vector V)
{
    vector n = normalize(Nc);
    return dot(n, V) < 0.0 ? -n : n;
}

// The general modes' closure for that term on a yarn face of shading normal N: Cycles'
// reflection-only dielectric Beckmann lobe about Nc (cl_cook_torrance: Smith shadowing, exact
// Fresnel).  Cycles keeps such a closure's light where sign(N.l) = sign(N.Nc) sign(Nc.l) (its
// bump-shadowing test): on faces turned below the cloth plane that is light from behind the face,
// which cl_cloth_specular cuts, and never light the face receives, so those faces get none.
closure color cl_cloth_specular_closure(vector Nc, normal N, float weight, float m, float eta)
{
    closure color lobe = 0;
    if (dot(N, Nc) > 0.0)
        lobe = weight * dielectric_bsdf(Nc, vector(0), color(1), color(0), m, m, eta, "beckmann");
    return lobe;
}

// ---- The cloth's fuzz (precompute/optics/lommel_seeliger.py: its functions named below are the
// NumPy twins).  The white first reflections of the cloth's surface fibres, a Lommel-Seeliger law
// about the cloth normal Nc.  Fibres that reflect light also stand in its way: a fuzz of optical
// depth `depth` > 0 along Nc lets through to the yarns beneath, and back out, only
// T(mu_i, mu_o), and reflects by itself only the light it does not let through.  depth = 0 is the
// fuzz of the presets before it had a depth (a veneer over an unshaded cloth): each function below
// then answers exactly what the shader did before.  Fibres scatter forward: the fuzz's phase function
// is a Henyey-Greenstein one of asymmetry g (0: isotropic, the law itself), and dyed fibres colour
// what they scatter (the shader's FuzzTint multiplies what these functions return).  Fibres lie flat:
// a fuzz whose fibres lie in the cloth's plane in the share `flatness` shows a direction at the cosine
// mu the area s(mu) of what it shows the normal (cl_fuzz_projected_area), its slant optical depth
// depth s(mu) / mu, and scatters in proportion to s_i s_o (0: every function as without it).

// Gauss-Legendre nodes over mu_i in (0, 1) of the general mode's sums (FUZZ_ALBEDO_NODES): numpy's
// leggauss(8) mapped by mu = (x + 1) / 2, weight w / 2 (tests/test_osl_twins.py holds them to it).
// The directional albedo of a layer of finite depth has no closed form.
#define CL_FUZZ_ALBEDO_NODES 8
#define CL_FUZZ_NODE_COSINES {0.019855071751231912, 0.10166676129318664, 0.2372337950418355, 0.4082826787521751, \
                              0.5917173212478248, 0.7627662049581645, 0.8983332387068134, 0.9801449282487681}
#define CL_FUZZ_NODE_WEIGHTS {0.050614268145188344, 0.11119051722668717, 0.15685332293894352, 0.18134189168918088, \
                              0.18134189168918088, 0.15685332293894352, 0.11119051722668717, 0.050614268145188344}
// Midpoint azimuths on (0, pi) of the directional albedo of a fuzz that is not isotropic (FUZZ_ALBEDO_AZIMUTHS).
#define CL_FUZZ_AZIMUTHS 16

// 4 pi p_HG(-L.V; g) (fuzz_phase): the fuzz's phase function relative to an isotropic one between
// the directions toward the light and the viewer, -L.V the cosine of the scattering angle.
float cl_fuzz_phase(float cos_between, float g)
{
    if (g == 0.0)
        return 1.0;
    return (1.0 - g * g) / pow(1.0 + g * g + 2.0 * g * cos_between, 1.5);
}

// s(mu) = 1 - flatness (1 - (2/pi) E(sqrt(1 - mu^2))) (fuzz_projected_area): the area the fuzz shows a
// direction at the cosine mu with Nc over the area it shows Nc, E the complete elliptic integral of
// the second kind by the arithmetic-geometric mean (six steps: within 3e-6 of SciPy's ellipe for
// |mu| >= 1e-3, below which s has reached its grazing value).  1 for no flatness.
float cl_fuzz_projected_area(float mu, float flatness)
{
    if (flatness == 0.0)
        return 1.0;
    float a = 1.0;
    float b = max(abs(mu), 1e-3);
    float sum = 0.5 * (1.0 - b * b);
    float power = 0.5;
    for (int n = 0; n < 6; n++) {
        float c = 0.5 * (a - b);
        b = sqrt(a * b);
        a -= c;
        power *= 2.0;
        sum += power * c * c;
    }
    return 1.0 - flatness * (1.0 - (1.0 - sum) / a);
}

// T(mu_i, mu_o) = exp(-depth (s_i/|mu_i| + s_o/|mu_o|)) (fuzz_transmittance): Beer-Lambert along both
// slant paths through the fuzz.  |mu|: light from behind the cloth crosses the fuzz on its back
// face.  1 without a fuzz depth, 0 at a grazing cosine (an endless path).
float cl_fuzz_transmittance(float mu_i, float mu_o, float depth, float flatness)
{
    if (depth <= 0.0)
        return 1.0;
    float a = abs(mu_i);
    float b = abs(mu_o);
    if (a <= 0.0 || b <= 0.0)
        return 0.0;
    return exp(-depth * (cl_fuzz_projected_area(a, flatness) / a + cl_fuzz_projected_area(b, flatness) / b));
}

// The share of a uniform sky's light that crosses the fuzz one way, int_0^1 2 mu exp(-depth s(mu)/mu) dmu
// (= 2 E3(depth) for no flatness; hemispherical_transmittance), by the nodes above; 1 without a fuzz depth.
float cl_fuzz_hemispherical_transmittance(float depth, float flatness)
{
    if (depth <= 0.0)
        return 1.0;
    float mu[CL_FUZZ_ALBEDO_NODES] = CL_FUZZ_NODE_COSINES;
    float weight[CL_FUZZ_ALBEDO_NODES] = CL_FUZZ_NODE_WEIGHTS;
    float sum = 0.0;
    for (int k = 0; k < CL_FUZZ_ALBEDO_NODES; k++)
        sum += weight[k] * mu[k] * exp(-depth * cl_fuzz_projected_area(mu[k], flatness) / mu[k]);
    return 2.0 * sum;
}

// The general modes' share of the yarns' light under the fuzz at the view cosine mu_o: they have no
// light direction to take T at, so the light's way in is the sky's, the hemispherical
// transmittance, and its way out the view's own path, exp(-depth s(mu_o) / mu_o).  1 without a fuzz depth.
float cl_fuzz_yarn_share(float mu_o, float depth, float flatness)
{
    if (depth <= 0.0)
        return 1.0;
    float b = max(mu_o, 1e-6);
    return exp(-depth * cl_fuzz_projected_area(b, flatness) / b) * cl_fuzz_hemispherical_transmittance(depth, flatness);
}

// (1 - T) mu_i s_i s_o / (s_i mu_o + s_o mu_i), the layer's light from the light cosine mu_i toward
// the view cosine mu_o per A/2, 1 - T being 1 without a fuzz depth (fuzz_albedo_at_view's integrand).
float cl_fuzz_layer_at(float mu_i, float mu_o, float depth, float flatness)
{
    float s_i = cl_fuzz_projected_area(mu_i, flatness);
    float s_o = cl_fuzz_projected_area(mu_o, flatness);
    float shade = depth > 0.0 ? 1.0 - cl_fuzz_transmittance(mu_i, mu_o, depth, flatness) : 1.0;
    return shade * mu_i * s_i * s_o / (s_i * mu_o + s_o * mu_i);
}

// The fuzz's directional albedo at the view cosine mu_o (> 0) in two parts (fuzz_albedo_sides_at_view):
// the light from lights on the view's side of Nc (azimuth from the view's within 90 degrees: the first
// half of the azimuths) and from the far side, each (A / 2) int_0^1 cl_fuzz_layer_at P dmu_i over its
// side, P the phase function's mean over that side's azimuths.
void cl_fuzz_albedo_sides_at_view(float mu_o, float albedo, float depth, float g, float flatness,
                                  output float near, output float far)
{
    float mu[CL_FUZZ_ALBEDO_NODES] = CL_FUZZ_NODE_COSINES;
    float weight[CL_FUZZ_ALBEDO_NODES] = CL_FUZZ_NODE_WEIGHTS;
    float sin_o = sqrt(max(1.0 - mu_o * mu_o, 0.0));
    near = 0.0;
    far = 0.0;
    for (int k = 0; k < CL_FUZZ_ALBEDO_NODES; k++) {
        float sin_i = sqrt(1.0 - mu[k] * mu[k]);
        float layer = weight[k] * cl_fuzz_layer_at(mu[k], mu_o, depth, flatness);
        for (int j = 0; j < CL_FUZZ_AZIMUTHS; j++) {
            float phi = (j + 0.5) * M_PI / CL_FUZZ_AZIMUTHS;
            float term = layer * cl_fuzz_phase(mu[k] * mu_o + sin_i * sin_o * cos(phi), g);
            if (2 * j < CL_FUZZ_AZIMUTHS)
                near += term;
            else
                far += term;
        }
    }
    near *= 0.5 * albedo / CL_FUZZ_AZIMUTHS;
    far *= 0.5 * albedo / CL_FUZZ_AZIMUTHS;
}

// The fuzz's directional albedo at the view cosine mu_o (> 0) (fuzz_albedo_at_view): isotropic, flat
// in no share and without a depth the semi-infinite law's closed form (A / 2)(1 - mu_o ln(1 + 1/mu_o));
// else (A / 2) int_0^1 cl_fuzz_layer_at P(mu_i) dmu_i by the nodes above, P the phase function's mean
// over the azimuth between light and view (1 when isotropic).
float cl_fuzz_albedo_at_view(float mu_o, float albedo, float depth, float g, float flatness)
{
    if (depth <= 0.0 && g == 0.0 && flatness == 0.0)
        return 0.5 * albedo * (1.0 - mu_o * log(1.0 + 1.0 / mu_o));
    if (g != 0.0) {
        float near, far;
        cl_fuzz_albedo_sides_at_view(mu_o, albedo, depth, g, flatness, near, far);
        return near + far;
    }
    float mu[CL_FUZZ_ALBEDO_NODES] = CL_FUZZ_NODE_COSINES;
    float weight[CL_FUZZ_ALBEDO_NODES] = CL_FUZZ_NODE_WEIGHTS;
    float sum = 0.0;
    for (int k = 0; k < CL_FUZZ_ALBEDO_NODES; k++)
        sum += weight[k] * cl_fuzz_layer_at(mu[k], mu_o, depth, flatness);
    return 0.5 * albedo * sum;
}

// The general modes' forward lobe of a fuzz that scatters forward (FUZZ_FORWARD_SLOPE,
// forward_lobe_table): a Beckmann reflection about Nc without a Fresnel factor, and its directional
// albedo a_m and half its excess of far-side light b_m at view angles even from 0 to 90 degrees.
#define CL_FUZZ_FORWARD_SLOPE 0.5
#define CL_FUZZ_FORWARD_POINTS 17
#define CL_FUZZ_FORWARD_ALBEDO {0.9429983746314629, 0.9412738422079397, 0.9362494301777113, 0.9283539178470588, \
                                0.9182469768575782, 0.9067628396613615, 0.8948785895018003, 0.8837264038738433, \
                                0.8745880242687172, 0.8687622934139941, 0.8673753318544225, 0.8713086057342564, \
                                0.8812822615622632, 0.8980201075329203, 0.9224330244705113, 0.9558051481784868, \
                                0.999474201583473}
#define CL_FUZZ_FORWARD_EXCESS {0.0, 0.038815398249673894, 0.07713759092081232, 0.11448408205697216, \
                                0.15040568047939823, 0.184527237887312, 0.21660515924521642, 0.24659299494783635, \
                                0.274684682163827, 0.30128070677875957, 0.3268786195983064, 0.35196839222403703, \
                                0.3769953408507523, 0.40239439154010176, 0.4286753484387816, 0.45654400354875946, \
                                0.4867906180148369}

// The weights of the general modes' diffuse lobe and forward lobe of the fuzz at the view cosine mu_o
// (fuzz_general_lobes): the lobe's share s = b / b_m held to [0, a / a_m], the diffuse d = a - s a_m (>= 0),
// so that both the light the fuzz returns at this view and its excess from far-side lights are kept.
void cl_fuzz_general_lobes(float mu_o, float albedo, float depth, float g, float flatness,
                           output float diffuse_weight, output float forward_weight)
{
    forward_weight = 0.0;
    if (g == 0.0) {
        diffuse_weight = cl_fuzz_albedo_at_view(mu_o, albedo, depth, g, flatness);
        return;
    }
    float near, far;
    cl_fuzz_albedo_sides_at_view(mu_o, albedo, depth, g, flatness, near, far);
    float lobe_albedo[CL_FUZZ_FORWARD_POINTS] = CL_FUZZ_FORWARD_ALBEDO;
    float lobe_excess[CL_FUZZ_FORWARD_POINTS] = CL_FUZZ_FORWARD_EXCESS;
    float x = acos(clamp(mu_o, 0.0, 1.0)) / M_PI_2 * (CL_FUZZ_FORWARD_POINTS - 1);
    int i = min((int)floor(x), CL_FUZZ_FORWARD_POINTS - 2);
    float t = x - i;
    float a_m = mix(lobe_albedo[i], lobe_albedo[i + 1], t);
    float b_m = mix(lobe_excess[i], lobe_excess[i + 1], t);
    float total = near + far;
    if (b_m > 0.0)
        forward_weight = clamp(0.5 * (far - near) / b_m, 0.0, total / a_m);
    diffuse_weight = max(total - forward_weight * a_m, 0.0);
}

// The fuzz's radiance per irradiance (1/sr): the Lommel-Seeliger law A s_i s_o / (4 pi (s_i mu_o +
// s_o mu_i)) about Nc (s = 1 for no flatness) times its phase function of asymmetry g (cl_fuzz_phase)
// times (n_c.l), cut on yarn faces turned away from the light as cl_cloth_specular is; a fuzz of depth
// reflects (1 - T) of it, the light it does not let through (fuzz_brdf).
float cl_cloth_fuzz(vector Nc, vector N_out, vector L, vector V, float albedo, float depth, float g, float flatness)
{
    float mu_i = dot(Nc, L);
    float mu_o = dot(Nc, V);
    if (dot(N_out, L) <= 0.0 || mu_i <= 0.0 || mu_o <= 0.0)
        return 0.0;
    return albedo * cl_fuzz_phase(dot(L, V), g) * cl_fuzz_layer_at(mu_i, mu_o, depth, flatness) / (4.0 * M_PI);
}

// The general modes' closures for the fuzz: a diffuse lobe about Nc and, for a fuzz that scatters
// forward, a Beckmann lobe about Nc, of the weights cl_fuzz_general_lobes gives at this view (an
// isotropic fuzz: the diffuse lobe of its directional albedo alone).  Faces turned below the cloth
// plane get none, as for the sheen.
closure color cl_cloth_fuzz_closure(vector Nc, normal N, vector V, float albedo, float depth, float g,
                                    float flatness)
{
    float mu_o = max(dot(Nc, V), 1e-6);
    closure color lobe = 0;
    if (albedo > 0.0 && dot(N, Nc) > 0.0) {
        float diffuse_weight, forward_weight;
        cl_fuzz_general_lobes(mu_o, albedo, depth, g, flatness, diffuse_weight, forward_weight);
        lobe = diffuse_weight * diffuse(Nc);
        if (forward_weight > 0.0)
            lobe += forward_weight * microfacet("beckmann", Nc, CL_FUZZ_FORWARD_SLOPE, 1.0, 0);
    }
    return lobe;
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

// ---- Baked yarn tables (docs/table-spec.md) -------------------------------------------------

// Right-handed yarn frame from the outward normal and the yarn axis: x = axis, y = n x t, z = n.
void cl_yarn_frame(normal n, vector tangent, output vector x, output vector y, output vector z)
{
    z = normalize(n);
    x = normalize(tangent - dot(tangent, z) * z);
    y = cross(z, x);
}

vector cl_to_frame(vector d, vector x, vector y, vector z)
{
    return vector(dot(d, x), dot(d, y), dot(d, z));
}

// Exit direction of the view I in the yarn frame, on the tables' hemisphere: smooth normals can
// put a silhouette view just below the horizon.
vector cl_exit_direction(vector I, vector x, vector y, vector z)
{
    vector wo = cl_to_frame(normalize(I), x, y, z);
    wo[2] = max(wo[2], 0.0);
    return normalize(wo);
}

// Texture lookup that reproduces the table's cell values at cell centres and interpolates
// linearly between them: zero filter width (no mipmaps, no derivative blur), clamped wrap.
color cl_table_texel(string file, float u, float v)
{
    return texture(file, u, v, 0, 0, 0, 0, "wrap", "clamp", "interp", "linear");
}

// Texture coordinates (u, v; v down, as texture() reads) of an exit direction in one tile of an
// atlas of tiles_x x tiles_y tiles of exit_resolution^2 pixels; (s, t) are the exit direction's
// square coordinates.  (s, t) is held inside the tile's outermost pixel centres so linear filtering
// never reads a neighbouring tile.
void cl_tile_coordinates(int tile_col, int tile_row, int tiles_x, int tiles_y, int exit_resolution,
                         float s, float t, output float u, output float v)
{
    float half_texel = 0.5 / exit_resolution;
    u = (tile_col + clamp(s, half_texel, 1.0 - half_texel)) / tiles_x;
    v = (tile_row + clamp(t, half_texel, 1.0 - half_texel)) / tiles_y;
}

color cl_tile_lookup(string file, int tile_col, int tile_row, int tiles_x, int tiles_y,
                     int exit_resolution, float s, float t)
{
    float u, v;
    cl_tile_coordinates(tile_col, tile_row, tiles_x, tiles_y, exit_resolution, s, t, u, v);
    return cl_table_texel(file, u, v);
}

// Yarn BRDF rho(wi, wo) = L_o / E_perp (1/sr) from the atlas: incidence tiles on the sphere grid
// (blended bilinearly between the four nearest cell centres), exit pixels on the hemisphere grid.
color cl_yarn_rho(string file, int incidence_resolution, int exit_resolution, vector wi, vector wo)
{
    float si, ti, so, to;
    cl_sphere_to_square(wi, si, ti);
    cl_hemisphere_to_square(wo, so, to);
    int n = incidence_resolution;
    float fx = clamp(si * n - 0.5, 0.0, n - 1.0);
    float fy = clamp(ti * n - 0.5, 0.0, n - 1.0);
    int i0 = int(floor(fx));
    int j0 = int(floor(fy));
    int i1 = min(i0 + 1, n - 1);
    int j1 = min(j0 + 1, n - 1);
    float ax = fx - i0;
    float ay = fy - j0;
    color c00 = cl_tile_lookup(file, i0, j0, n, n, exit_resolution, so, to);
    color c10 = cl_tile_lookup(file, i1, j0, n, n, exit_resolution, so, to);
    color c01 = cl_tile_lookup(file, i0, j1, n, n, exit_resolution, so, to);
    color c11 = cl_tile_lookup(file, i1, j1, n, n, exit_resolution, so, to);
    return mix(mix(c00, c10, ax), mix(c01, c11, ax), ay);
}

// ---- Unscattered light through the yarn (precompute/optics/ballistic.py) ---------------------------
// Light that crosses the yarn without scattering, in closed form: refracted in, attenuated along
// equal chords, reflected inside with the same Fresnel F at every hit, refracted out.  Path k
// (k internal reflections) carries (1 - F)^2 F^k A((k + 1) chord), A from the attenuation table
// (one row of `samples` pixels over l/R in [0, CL_UNSCATTERED_MAX_LENGTH]).  Each path's delta
// in wi is spread over a normalised von Mises-Fisher cone of angular spread `spread` (radians).
// precompute.tables.layout.interpolate_unscattered_rho is the NumPy twin.

#define CL_UNSCATTERED_ORDERS 4
#define CL_UNSCATTERED_MAX_LENGTH 8.0
#define CL_UNSCATTERED_MIN_FACTOR 0.003
// The sun mode's cone is zero where kappa (1 - cos) exceeds this (precompute.optics.ballistic.CONE_CUTOFF):
// the path's attenuation lookup is skipped there, most of the sun mode's cost for it.
#define CL_CONE_CUTOFF 14.0

color cl_unscattered_attenuation(string file, int samples, float length_over_radius)
{
    float x = clamp(length_over_radius / CL_UNSCATTERED_MAX_LENGTH, 0.0, 1.0) * (samples - 1);
    return cl_table_texel(file, (x + 0.5) / samples, 0.5);
}

// The unscattered paths that leave toward wo (yarn frame): direction toward the light, (1 - F)^2 F^k
// and length / R of path k, followed backwards hit by hit (precompute.optics.ballistic.unscattered_paths).
void cl_unscattered_paths(vector wo, float eta, output vector toward_light[CL_UNSCATTERED_ORDERS],
                          output float fresnel_factor[CL_UNSCATTERED_ORDERS],
                          output float length_over_radius[CL_UNSCATTERED_ORDERS])
{
    float F = cl_fresnel_dielectric(wo[2], eta);
    // lengths in yarn radii, section centre at the origin
    vector u = vector(-wo[0] / eta, -wo[1] / eta, 0.0);
    u[2] = -sqrt(max(0.0, 1.0 - u[0] * u[0] - u[1] * u[1]));
    float py = 0.0;
    float pz = 1.0;
    float travelled = 0.0;
    float factor = (1.0 - F) * (1.0 - F);
    for (int k = 0; k < CL_UNSCATTERED_ORDERS; k++) {
        float a = max(u[1] * u[1] + u[2] * u[2], 1e-20);
        float b = py * u[1] + pz * u[2];
        float c = py * py + pz * pz - 1.0;
        float step = (-b + sqrt(max(b * b - a * c, 0.0))) / a;
        py += step * u[1];
        pz += step * u[2];
        travelled += step;
        float inv = 1.0 / sqrt(py * py + pz * pz);
        vector n = vector(0.0, py * inv, pz * inv);
        float cos_hit = dot(u, n);
        vector tangential = (u - cos_hit * n) * eta;
        toward_light[k] = tangential + sqrt(max(0.0, 1.0 - dot(tangential, tangential))) * n;
        fresnel_factor[k] = factor;
        length_over_radius[k] = travelled;
        factor *= F;
        u -= 2.0 * cos_hit * n;
    }
}

// Sun mode: rho_u(wi, wo), each path's delta spread over a normalised von Mises-Fisher cone.
color cl_unscattered_rho(string file, int samples, float eta, vector wi, vector wo, float spread)
{
    float kappa = 1.0 / (spread * spread);
    float cone_norm = kappa / (M_2PI * (1.0 - exp(-2.0 * kappa)));
    vector toward_light[CL_UNSCATTERED_ORDERS];
    float fresnel_factor[CL_UNSCATTERED_ORDERS];
    float length_over_radius[CL_UNSCATTERED_ORDERS];
    cl_unscattered_paths(wo, eta, toward_light, fresnel_factor, length_over_radius);
    color rho = 0;
    for (int k = 0; k < CL_UNSCATTERED_ORDERS; k++) {
        float exponent = kappa * (dot(wi, toward_light[k]) - 1.0);
        if (exponent >= -CL_CONE_CUTOFF)
            rho += fresnel_factor[k] * cone_norm * exp(exponent)
                * cl_unscattered_attenuation(file, samples, length_over_radius[k]);
    }
    return rho;
}

// General mode: each path as a narrow lobe about its exact direction that Cycles samples, of unit
// integral (checked by rendering: tests/test_yarn_shader.py).  Light in front of the surface: the
// hair reflection lobe about the axis V - L, whose mirror direction is L; light from behind: GGX
// refraction about the generalised half vector -(V + eta_l L), eta_l large enough for L to be
// reachable.  A path whose light would arrive within ~6 degrees of the view's side plane from behind
// has no such refraction and is left out, and so is a path whose weight (Fresnel factor times
// attenuation, in every channel) is below CL_UNSCATTERED_MIN_FACTOR: each closure costs every light
// sample an evaluation and starts paths of its own, and a path left out carries less than 0.3 % of
// the light reaching the yarn.  In a medium that scatters (the fitted presets) no path is left at all.
// `reach`: the path length l/R from which the attenuation is below CL_UNSCATTERED_MIN_FACTOR in
// every channel (clothlight.yarn_tables.attenuation_reach): longer paths are left out before their
// lookup, which in a medium that scatters is every path.
closure color cl_unscattered_closures(string file, int samples, float reach, float eta, vector wo, vector V,
                                      vector x, vector y, vector z, float roughness)
{
    vector toward_light[CL_UNSCATTERED_ORDERS];
    float fresnel_factor[CL_UNSCATTERED_ORDERS];
    float length_over_radius[CL_UNSCATTERED_ORDERS];
    cl_unscattered_paths(wo, eta, toward_light, fresnel_factor, length_over_radius);
    closure color lobes = 0;
    for (int k = 0; k < CL_UNSCATTERED_ORDERS; k++) {
        if (fresnel_factor[k] < CL_UNSCATTERED_MIN_FACTOR || length_over_radius[k] > reach)
            break;  // the factors fall with k, and the lengths grow
        color weight = fresnel_factor[k] * cl_unscattered_attenuation(file, samples, length_over_radius[k]);
        if (max(weight[0], max(weight[1], weight[2])) < CL_UNSCATTERED_MIN_FACTOR)
            break;
        vector L = normalize(toward_light[k][0] * x + toward_light[k][1] * y + toward_light[k][2] * z);
        if (dot(L, z) >= 0.0) {
            vector axis = V - L;
            if (dot(axis, axis) < 1e-8)  // retro-reflection: any axis across the view mirrors it onto itself
                axis = x - dot(x, V) * V;
            lobes += weight * hair_reflection(z, roughness, roughness, normalize(axis), 0.0);
        }
        else {
            float cos_vl = dot(V, L);
            if (cos_vl < -0.1) {
                float eta_l = max(1.3, -1.5 / cos_vl);
                lobes += weight * microfacet("ggx", normalize(-(V + eta_l * L)), roughness, eta_l, 1);
            }
        }
    }
    return lobes;
}

// Number of closure-mixture lobes: the tiles of lobes.exr (precompute.tables.closure_fit.LOBES).
#define CL_LOBE_COUNT 5

// The general-lighting closure mixture of a baked rho (frame x, z; V the world view): five Cycles
// closures in the order of precompute.tables.closure_fit.LOBES, with the weights of lobes.exr at the view
// (looked up by the material: cloth_yarn_exit.osl).  A lobe of zero weight adds no closure: each
// costs Cycles an evaluation per light sample, and the fit leaves out the minor ones
// (precompute.tables.closure_fit.MIN_LOBE_SHARE).
closure color cl_closure_mixture(color weight[CL_LOBE_COUNT], vector V, vector x, vector z,
                                 float reflection_r1, float reflection_r2, float transmission_r1,
                                 float transmission_r2, float retroreflection_alpha)
{
    closure color mixture = 0;
    if (weight[0] != color(0))
        mixture += weight[0] * diffuse(z);
    if (weight[1] != color(0))
        mixture += weight[1] * translucent(z);
    if (weight[2] != color(0))
        mixture += weight[2] * hair_reflection(z, reflection_r1, reflection_r2, x, 0.0);
    if (weight[3] != color(0))
        mixture += weight[3] * hair_transmission(z, transmission_r1, transmission_r2, x, 0.0);
    if (weight[4] != color(0))
        mixture += weight[4] * microfacet("ggx", V, retroreflection_alpha, 1.0, 0);
    return mixture;
}

#endif
