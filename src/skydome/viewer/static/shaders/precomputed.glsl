// precomputed: Bruneton (2017) table look-ups ([Bru17] GetScattering with the 4-D -> 3-D
// packing; [BN08] eqs. 1-9 for what the tables hold) over the tables skydome bakes
// (skydome.export.luts.bake_precomputed: XYZ per table cell, Bruneton's layout). Mirrors
// precomputed._render.render_observer with the table's own (r, mu_s) slice
// (_lookup.sky_lookup_acc), and the mappings of precomputed._mapping: r_index, mu_index,
// mu_s_unit, _split. Rays that hit the ground add the Lambertian ground lit by the sun and
// the sky ([Bru17] GetSunAndSkyIrradiance) seen through the air in front of it ([Bru17]
// GetSkyRadianceToPoint: the in-scattering from the ground half of the mu axis plus the
// transmittance to the ground point), a product of spectra computed on the table
// wavelengths (bake_precomputed(ground=True)) and reduced to XYZ with the bake's weights
// K_j. Float32: r^2 - R^2 is carried as h (2R + h).
precision highp sampler3D;
uniform highp sampler3D u_ms;     // orders 2..N, XYZ
uniform highp sampler3D u_ss0;    // single scattering of constituent 0 (no phase), XYZ
uniform highp sampler3D u_ss1;    // constituent 1
uniform ivec4 u_sizes;            // n_r, n_mu, n_mu_s, n_nu
uniform float u_R, u_Rt, u_mu_s_min, u_h0, u_irradiance_scale;
uniform int u_nsc;
uniform ivec2 u_pc;
uniform vec2 u_pp;
// the ground: spectral tables, four table wavelengths per texel (layer k channel c =
// wavelength 4 k + c), the ground albedo and the XYZ weights K_j per table wavelength
uniform highp sampler3D u_tr;     // transmittance to the top (z layer, y r, x mu)
uniform highp sampler3D u_irr;    // sky irradiance E(r, mu_s) (z layer, y r, x mu_s)
uniform ivec3 u_ground_sizes;     // transmittance n_r, n_mu; irradiance n_mu_s
uniform int u_nl;                 // table wavelengths (<= 16)
uniform float u_albedo[16];
uniform vec3 u_K[16];
uniform float u_sun_alpha;        // the sun's angular radius [rad] (the tables')

// _split: integer node and fraction of a continuous index f on an axis of n nodes
void split_(float f, int n, out int i, out float t) {
    f = clamp(f, 0.0, float(n) - 1.0);
    i = min(int(f), n - 2);
    t = f - float(i);
}

float rho2_(float h) { return h * (2.0 * u_R + h); }

// the mu_s mapping's knee (_mapping.MU_S_CENTRE, MU_S_WIDTH): 92 deg and 6 deg [rad]
const float MU_S_CENTRE = 1.6057029118347832;
const float MU_S_WIDTH = 0.10471975511965978;

// _mu_s_u: u(theta) = asinh((theta - 92 deg) / 6 deg)
float mu_s_u(float th) {
    return asinh((th - MU_S_CENTRE) / MU_S_WIDTH);
}

// mu_s_unit: mu_s mapping to [0, 1] (0 at mu_s_min, clamped below; 1 at the zenith):
// x = (u(theta_max) - u(theta_s)) / (u(theta_max) - u(0)), theta_s = acos(mu_s),
// theta_max = acos(mu_s_min) (skydome's mapping, not [Bru17]'s; independent of R)
float mu_s_unit(float mu_s, float mu_s_min) {
    float th = acos(clamp1(mu_s));
    float th_max = acos(clamp1(mu_s_min));
    float top = mu_s_u(th_max);
    float x = (top - mu_s_u(min(th, th_max))) / (top - mu_s_u(0.0));
    return clamp(x, 0.0, 1.0);
}

// the mu mapping's knee (_mapping.MU_WIDTH): 2 deg [rad]
const float MU_WIDTH = 0.03490658503988659;
const float HALF_PI = 1.5707963267948966;

// mu_unit: position of a ray on its half of the mu axis, 0 at the local horizon, 1 at the
// zenith (sky) or the nadir (ground): x = asinh(e / w) / asinh(e_max / w), e the angle
// from the horizon, whose dip below the horizontal is atan(rho / R) (skydome's mapping,
// not [Bru17]'s; the same for every R)
float mu_unit(float h, float mu, bool ground) {
    float dip = atan(sqrt(max(rho2_(h), 0.0)), u_R);
    float a = asin(clamp1(mu));
    float e = ground ? -dip - a : a + dip;
    float top = asinh(max(ground ? HALF_PI - dip : HALF_PI + dip, 0.0) / MU_WIDTH);
    if (top <= 0.0) return 0.0;
    return clamp(asinh(max(e, 0.0) / MU_WIDTH) / top, 0.0, 1.0);
}

// mu_index for a ray that does not hit the ground: the upper half of the mu axis (node
// n/2 the zenith, n - 1 the horizon)
void mu_index_sky(float h, float mu, int n_mu, out int i, out float b) {
    int half_ = n_mu / 2;
    split_((1.0 - mu_unit(h, mu, false)) * (float(half_) - 1.0), half_, i, b);
    i += half_;
}

// mu_index for a ray that hits the ground: the lower half of the mu axis (node 0 the
// horizon, n/2 - 1 the nadir)
void mu_index_ground(float h, float mu, int n_mu, out int i, out float b) {
    int half_ = n_mu / 2;
    split_(mu_unit(h, mu, true) * (float(half_) - 1.0), half_, i, b);
}

// transport._geometry.distance_to_ground: -r mu - sqrt(r^2 mu^2 - (r^2 - R^2)), written as
// (r^2 - R^2) / (-r mu + sqrt(...)) (the product of the two roots), exact in float32
float distance_to_ground(float r, float h, float mu) {
    float rho2 = rho2_(h);
    if (rho2 <= 0.0) return 0.0;
    return max(rho2 / (-r * mu + sqrt(max(r * r * mu * mu - rho2, 0.0))), 0.0);
}

// transport._tables.transmittance_cell / transmittance_unit_from_r_mu for (R + h, mu):
// x_r = rho / H, x_mu = (d - d_min) / (d_max - d_min), d the distance to the top
void transmittance_cell(float h, float mu, out int i, out int j, out float a, out float b) {
    float H = sqrt(u_Rt * u_Rt - u_R * u_R);
    float r = u_R + h, rho = sqrt(max(rho2_(h), 0.0));
    float d = max(-r * mu + sqrt(max(r * r * mu * mu - rho2_(h) + H * H, 0.0)), 0.0);
    float d_min = (u_Rt - u_R) - h, d_max = rho + H;
    float x_mu = d_max <= d_min ? 0.0 : clamp((d - d_min) / (d_max - d_min), 0.0, 1.0);
    split_(rho / H * float(u_ground_sizes.x - 1), u_ground_sizes.x, i, a);
    split_(x_mu * float(u_ground_sizes.y - 1), u_ground_sizes.y, j, b);
}

// bilinear look-up of layer k (wavelengths 4k .. 4k+3) of a spectral table at cell (i, j)
vec4 bilerp4(highp sampler3D t, int k, int i, int j, float a, float b) {
    return (1.0 - a) * ((1.0 - b) * texelFetch(t, ivec3(j, i, k), 0) + b * texelFetch(t, ivec3(j + 1, i, k), 0))
         + a * ((1.0 - b) * texelFetch(t, ivec3(j, i + 1, k), 0) + b * texelFetch(t, ivec3(j + 1, i + 1, k), 0));
}

// geometric_lerp: lo (hi / lo)^f where both are positive, else linear
vec4 geometric_mix(vec4 lo, vec4 hi, float f) {
    vec4 geo = lo * exp(f * log(max(hi, vec4(1e-37)) / max(lo, vec4(1e-37))));
    return mix(mix(lo, hi, f), geo, vec4(greaterThan(min(lo, hi), vec4(0.0))));
}

// the ground point's radiance seen from the observer (render_observer's ground branch):
// T_obs(l) rho(l) / pi (f(mu_g) T_sun(l) + E(l)), reduced to XYZ with K_j. T_obs is
// [Bru17] GetTransmittance for a ray that hits the ground (both rays reversed):
// T(R, -mu_d) / T(r, -mu), at most 1; T_sun the transmittance from the ground point to the
// top towards the sun ([Bru17] ComputeDirectIrradiance: f the disc-averaged cosine);
// E the sky irradiance table ([Bru17] GetIrradiance at r = R).
vec3 ground_xyz(float r, float h, float mu, float nu, float mu_s, float dg) {
    float mu_g = clamp1((r * mu_s + dg * nu) / u_R);
    float al = u_sun_alpha;
    float f = mu_g < -al ? 0.0 : mu_g > al ? mu_g : (mu_g + al) * (mu_g + al) / (4.0 * al);
    float mu_d = clamp1((r * mu + dg) / u_R);            // the ray's cosine at the ground point
    int i0, j0, i1, j1, i2, j2, je;
    float a0, b0, a1, b1, a2, b2, be;
    transmittance_cell(0.0, -mu_d, i0, j0, a0, b0);      // ground point, reversed ray
    transmittance_cell(h, -mu, i1, j1, a1, b1);          // observer, reversed ray
    transmittance_cell(0.0, mu_g, i2, j2, a2, b2);       // ground point towards the sun
    // irradiance_lookup_acc at r = R: x_r = 0; mu_s on the sun mapping (mu_s_unit),
    // geometric between its two nodes (geometric_lerp)
    split_(mu_s_unit(mu_g, u_mu_s_min) * float(u_ground_sizes.z - 1), u_ground_sizes.z, je, be);
    vec3 acc = vec3(0.0);
    for (int k = 0; k < 4; ++k) {
        if (4 * k >= u_nl) break;
        vec4 t_obs = min(bilerp4(u_tr, k, i0, j0, a0, b0) / max(bilerp4(u_tr, k, i1, j1, a1, b1), vec4(1e-30)), vec4(1.0));
        vec4 t_sun = bilerp4(u_tr, k, i2, j2, a2, b2);
        vec4 e = geometric_mix(texelFetch(u_irr, ivec3(je, 0, k), 0),
                               texelFetch(u_irr, ivec3(je + 1, 0, k), 0), be);
        vec4 l4 = t_obs * (f * t_sun + e) / PI;
        for (int c = 0; c < 4; ++c) {
            int l = 4 * k + c;
            if (l >= u_nl) break;
            acc += u_K[l] * (u_albedo[l] * l4[c]);
        }
    }
    return acc;
}

vec3 fetch(highp sampler3D t, int ir, int imu, int ims, int inu) {
    return texelFetch(t, ivec3(inu * u_sizes.z + ims, imu, ir), 0).xyz;
}

// quadrilinear interpolation of a table at (r, mu, mu_s, nu) (_quad_acc)
vec3 quad(highp sampler3D t, int ir, float a, int im, float b, int ims, float c, int inu, float e) {
    vec3 acc = vec3(0.0);
    for (int dr = 0; dr < 2; ++dr)
        for (int dm = 0; dm < 2; ++dm)
            for (int ds = 0; ds < 2; ++ds)
                for (int dn = 0; dn < 2; ++dn) {
                    float w = (dr == 1 ? a : 1.0 - a) * (dm == 1 ? b : 1.0 - b)
                            * (ds == 1 ? c : 1.0 - c) * (dn == 1 ? e : 1.0 - e);
                    acc += w * fetch(t, ir + dr, im + dm, ims + ds, inu + dn);
                }
    return acc;
}

vec3 sky_xyz(vec3 d) {
    float mu_s = u_sun.z;
    if (mu_s < u_mu_s_min - 1e-12) return vec3(0.0);        // night
    float r = u_R + u_h0, h = u_h0;
    float mu = clamp1(d.z);
    bool ground = mu < 0.0 && r * r * mu * mu - rho2_(h) >= 0.0;    // ray_hits_ground
    float H = sqrt(u_Rt * u_Rt - u_R * u_R);
    float nu = clamp1(dot(d, u_sun));
    int ir, im, ims, inu;
    float a, b, c, e;
    split_(sqrt(max(rho2_(h), 0.0)) / H * float(u_sizes.x - 1), u_sizes.x, ir, a);   // r_index
    float dg = ground ? distance_to_ground(r, h, mu) : 0.0;
    if (ground) mu_index_ground(h, mu, u_sizes.y, im, b);
    else mu_index_sky(h, mu, u_sizes.y, im, b);
    split_(mu_s_unit(mu_s, u_mu_s_min) * float(u_sizes.z - 1), u_sizes.z, ims, c);
    split_((nu + 1.0) * 0.5 * float(u_sizes.w - 1), u_sizes.w, inu, e);
    vec3 acc = quad(u_ms, ir, a, im, b, ims, c, inu, e);
    acc += phase_value(u_pc.x, u_pp.x, nu) * quad(u_ss0, ir, a, im, b, ims, c, inu, e);
    if (u_nsc > 1) acc += phase_value(u_pc.y, u_pp.y, nu) * quad(u_ss1, ir, a, im, b, ims, c, inu, e);
    if (ground) acc += ground_xyz(r, h, mu, nu, mu_s, dg);
    return acc * u_irradiance_scale;
}
