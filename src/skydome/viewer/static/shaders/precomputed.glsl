// precomputed: Bruneton (2017) table look-ups ([Bru17] GetScattering with the 4-D -> 3-D
// packing; [BN08] eqs. 1-9 for what the tables hold) over the tables skydome bakes
// (skydome.export.luts.bake_precomputed: XYZ per table cell, Bruneton's layout). Mirrors
// precomputed._render.render_observer for rays that do not hit the ground, with the
// table's own (r, mu_s) slice (_lookup.sky_lookup_acc), and the mappings of
// precomputed._mapping: r_index, mu_index, mu_s_unit, _split. Float32: r^2 - R^2 is
// carried as h (2R + h).
precision highp sampler3D;
uniform highp sampler3D u_ms;     // orders 2..N, XYZ
uniform highp sampler3D u_ss0;    // single scattering of constituent 0 (no phase), XYZ
uniform highp sampler3D u_ss1;    // constituent 1
uniform ivec4 u_sizes;            // n_r, n_mu, n_mu_s, n_nu
uniform float u_R, u_Rt, u_mu_s_min, u_h0, u_irradiance_scale;
uniform int u_nsc;
uniform ivec2 u_pc;
uniform vec2 u_pp;

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

// mu_index for a ray that does not hit the ground: the upper half of the mu axis
void mu_index_sky(float r, float h, float mu, float H, int n_mu, out int i, out float b) {
    float rho = sqrt(max(rho2_(h), 0.0));
    int half_ = n_mu / 2;
    float rmu = r * mu;
    float disc = rmu * rmu - rho2_(h);                       // r^2 mu^2 - r^2 + R^2
    float d = -rmu + sqrt(max(disc + H * H, 0.0));
    float d_min = (u_Rt - u_R) - h, d_max = rho + H;
    float x = (d - d_min) / (d_max - d_min);
    split_(x * (float(half_) - 1.0), half_, i, b);
    i += half_;
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
    if (mu < 0.0 && r * r * mu * mu - rho2_(h) >= 0.0) {    // hits_ground: not rendered
        g_masked = true;
        return vec3(0.0);
    }
    float H = sqrt(u_Rt * u_Rt - u_R * u_R);
    float nu = clamp1(dot(d, u_sun));
    int ir, im, ims, inu;
    float a, b, c, e;
    split_(sqrt(max(rho2_(h), 0.0)) / H * float(u_sizes.x - 1), u_sizes.x, ir, a);   // r_index
    mu_index_sky(r, h, mu, H, u_sizes.y, im, b);
    split_(mu_s_unit(mu_s, u_mu_s_min) * float(u_sizes.z - 1), u_sizes.z, ims, c);
    split_((nu + 1.0) * 0.5 * float(u_sizes.w - 1), u_sizes.w, inu, e);
    vec3 acc = quad(u_ms, ir, a, im, b, ims, c, inu, e);
    acc += phase_value(u_pc.x, u_pp.x, nu) * quad(u_ss0, ir, a, im, b, ims, c, inu, e);
    if (u_nsc > 1) acc += phase_value(u_pc.y, u_pp.y, nu) * quad(u_ss1, ir, a, im, b, ims, c, inu, e);
    return acc * u_irradiance_scale;
}
