// hillaire2020, the per-frame sky-view LUT: [Hil20] S. Hillaire, "A Scalable and
// Production Ready Sky and Atmosphere Rendering Technique", EGSR 2020, sec. 5.3, marched
// with the transmittance LUT (sec. 4.1) and the multiple-scattering LUT Psi_ms (sec. 5.5,
// eq. 11) that skydome builds (Hillaire2020Sky.tables). Mirrors
// skydome.models.simulated._kernels_hillaire2020 (skyview_angles, build_skyview, march,
// _trans_weights, _ms_weights, _bilerp) and skydome.transport._kernels (table_coords,
// ray_segment, ray_hits_ground; profile_density and phase_value in transport.glsl). Wavelengths in groups of
// four (vec4); the output texel is XYZ = sum_l K_l L_l, K the weights that turn the
// table grid into CIE XYZ as the CPU model does (skydome.viewer.scene._hillaire).
// Float32: r^2 - R^2 and Rt^2 - r^2 are carried as h (2R + h) and (Ht - h)(Rt + r).
precision highp float;
precision highp int;
precision highp sampler2DArray;


uniform highp sampler2DArray u_tlut;    // [i_r = y, j_mu = x, layer = wavelength group]
uniform highp sampler2DArray u_mslut;   // [i_h = y, j_mus = x, layer]
uniform ivec2 u_tlut_size;              // (n_mu, n_r)
uniform ivec2 u_mslut_size;             // (n_m, n_h)
uniform ivec2 u_sv_size;                // (W, H) of the sky-view LUT
uniform float u_R, u_Rt, u_h0, u_ts;    // planet, top radius; observer altitude; segment scale [m]
uniform float u_sz;                     // cos of the sun zenith angle at the observer
uniform int u_n_steps;
uniform int u_use_ms;
uniform int u_nc;
uniform ivec4 u_codes;                  // density profile code per constituent
uniform vec4 u_p0, u_p1;
uniform ivec4 u_phase_codes;
uniform vec4 u_phase_params;
uniform vec4 u_beta_s[4 * NG];          // [c * NG + g]: scattering of constituent c, group g
uniform vec4 u_beta_e[4 * NG];
uniform vec4 u_albedo[NG];
uniform vec3 u_K[4 * NG];               // XYZ weight per table wavelength

#ifdef AP_VOLUME
layout(location = 0) out vec4 o_xyz;   // in-scattered radiance, XYZ
layout(location = 1) out vec4 o_t;     // transmittance, XYZ of the sun's spectrum through it
uniform vec3 u_KT[4 * NG];             // XYZ weight of the transmittance per table wavelength
uniform int u_ap_size;                 // n_v = n_u = n_s
uniform float u_ap_km_per_slice;
#else
out vec4 o_xyz;
#endif

float log1p_(float x) { return x < 1e-4 ? x * (1.0 - 0.5 * x) : log(1.0 + x); }
float expm1_(float x) { return abs(x) < 1e-3 ? x * (1.0 + 0.5 * x * (1.0 + x / 3.0)) : exp(x) - 1.0; }
vec4 one_minus_exp_neg(vec4 x) {   // -expm1(-x), accurate for small x
    return mix(1.0 - exp(-x), x * (1.0 - 0.5 * x * (1.0 - x / 3.0)), lessThan(x, vec4(1e-3)));
}

// r^2 - R^2 = h (2R + h) and the ray's discriminants, without float32 cancellation
float rho2(float h) { return h * (2.0 * u_R + h); }
bool ray_hits_ground(float r, float h, float mu) { return mu < 0.0 && r * r * mu * mu - rho2(h) >= 0.0; }
float distance_to_top(float r, float h, float mu) {
    float disc = ((u_Rt - u_R) - h) * (u_Rt + r) + r * r * mu * mu;
    return -r * mu + sqrt(max(disc, 0.0));
}

// skydome.transport._kernels.table_coords (Bruneton 2017 GetTransmittanceTextureUvFromRMu)
vec2 table_coords(float r, float h, float mu) {
    float H = sqrt(u_Rt * u_Rt - u_R * u_R);
    float rho = sqrt(max(rho2(h), 0.0));
    float d = distance_to_top(r, h, mu);
    float d_min = (u_Rt - u_R) - h, d_max = rho + H;
    float x_mu = d_max <= d_min ? 0.0 : (d - d_min) / (d_max - d_min);
    return vec2(rho / H, clamp(x_mu, 0.0, 1.0));
}

// _bilerp over a texel cell of a 2-D array texture: i along y, j along x
vec4 bilerp(highp sampler2DArray tab, int i, int j, float a, float b, int g) {
    vec4 t00 = texelFetch(tab, ivec3(j, i, g), 0), t01 = texelFetch(tab, ivec3(j + 1, i, g), 0);
    vec4 t10 = texelFetch(tab, ivec3(j, i + 1, g), 0), t11 = texelFetch(tab, ivec3(j + 1, i + 1, g), 0);
    return (1.0 - a) * ((1.0 - b) * t00 + b * t01) + a * ((1.0 - b) * t10 + b * t11);
}

// _trans_weights: cell (i, j) and weights (a, b) of the transmittance table at (r, mu)
void trans_weights(float r, float h, float mu, out int i, out int j, out float a, out float b) {
    vec2 x = table_coords(r, h, mu);
    int n_mu = u_tlut_size.x, n_r = u_tlut_size.y;
    float fr = x.x * float(n_r - 1), fm = x.y * float(n_mu - 1);
    i = clamp(int(fr), 0, n_r - 2);
    j = clamp(int(fm), 0, n_mu - 2);
    a = clamp(fr - float(i), 0.0, 1.0);
    b = clamp(fm - float(j), 0.0, 1.0);
}

// _ms_weights: cell and weights of the multiple-scattering table at (h, mu_s)
void ms_weights(float h, float mu_s, out int i, out int j, out float a, out float b) {
    int n_m = u_mslut_size.x, n_h = u_mslut_size.y;
    float fy = clamp(h / (u_Rt - u_R), 0.0, 1.0) * float(n_h - 1);
    float fx = clamp(0.5 * mu_s + 0.5, 0.0, 1.0) * float(n_m - 1);
    i = min(int(fy), n_h - 2);
    j = min(int(fx), n_m - 2);
    a = fy - float(i);
    b = fx - float(j);
}

// skyview_angles: (cos view zenith, cos azimuth from the sun) of texel (row, col), [Hil20] 5.3
vec2 skyview_angles(int row, int col, int H, int W, float r0) {
    int hh = H / 2;
    float cos_beta = sqrt(max(rho2(u_h0), 0.0)) / r0;
    float beta = acos(min(cos_beta, 1.0));
    float zh = PI - beta;
    float theta;
    if (row < hh) {
        float c = float(row) / (float(hh) - 1.0);
        theta = zh * (1.0 - (1.0 - c) * (1.0 - c));
    } else {
        float c = float(row - hh) / (float(hh) - 1.0);
        theta = clamp(zh + beta * c * c, zh + 1e-7, PI);
    }
    float x = float(col) / (float(W) - 1.0);
    return vec2(cos(theta), 1.0 - 2.0 * x * x);
}

// march: [Hil20] eq. 1 with eq. 11's source along the ray (r0, mu, nu) to the top, the
// ground (with the lit Lambertian ground when `ground`) or t_stop > 0; L, T per wavelength
void march(float r0, float mu, float nu, float t_stop, bool ground, out vec4 L[NG], out vec4 T[NG]) {
    float sz = u_sz;
    float phs[4];
    for (int c = 0; c < 4; ++c) phs[c] = c < u_nc ? phase_value(u_phase_codes[c], u_phase_params[c], nu) : 0.0;

    for (int g = 0; g < NG; ++g) { L[g] = vec4(0.0); T[g] = vec4(1.0); }

    // ray_segment(r0, mu, R, Rt): the observer is inside the atmosphere (t0 = 0)
    float t0 = 0.0, t1;
    bool hits = ray_hits_ground(r0, u_h0, mu);
    if (hits) t1 = max(-r0 * mu - sqrt(max(r0 * r0 * mu * mu - rho2(u_h0), 0.0)), 0.0);
    else t1 = distance_to_top(r0, u_h0, mu);
    if (t_stop > 0.0 && t_stop < t1) { t1 = max(t_stop, t0); hits = false; }
    float tmin = clamp(-r0 * mu, t0, t1);           // lowest point of the ray
    float q0 = rho2(u_h0);
    for (int piece = 0; piece < 2; ++piece) {
        float a = piece == 0 ? t0 : tmin, b = piece == 0 ? tmin : t1;
        float length_ = b - a;
        if (length_ <= 0.0) continue;
        float dv = log1p_(length_ / u_ts) / float(u_n_steps);
        for (int kk = 0; kk < 256; ++kk) {
            if (kk >= u_n_steps) break;
            int k = piece == 0 ? u_n_steps - 1 - kk : kk;
            float ua = u_ts * expm1_(float(k) * dv);
            float ub = u_ts * expm1_(float(k + 1) * dv);
            float us = u_ts * expm1_((float(k) + 0.5) * dv);
            float dt = ub - ua;
            float t = piece == 0 ? b - us : a + us;
            // r = sqrt(max(r0^2 + 2 r0 mu t + t^2, R^2)), via q = r^2 - R^2
            float q = max(q0 + 2.0 * r0 * mu * t + t * t, 0.0);
            float r = sqrt(u_R * u_R + q);
            float h = q / (r + u_R);
            float rho[4];
            for (int c = 0; c < 4; ++c) rho[c] = c < u_nc ? profile_density(u_codes[c], u_p0[c], u_p1[c], h) : 0.0;
            float mu_s = clamp((r0 * sz + t * nu) / r, -1.0, 1.0);
            bool lit = !ray_hits_ground(r, h, mu_s);          // earth shadow
            int ti, tj, mi, mj;
            float ta, tb, ma, mb;
            trans_weights(r, h, mu_s, ti, tj, ta, tb);
            ms_weights(h, mu_s, mi, mj, ma, mb);
            for (int g = 0; g < NG; ++g) {
                vec4 se = vec4(0.0), ss = vec4(0.0), ps = vec4(0.0);
                for (int c = 0; c < 4; ++c) {
                    if (c >= u_nc) break;
                    se += u_beta_e[c * NG + g] * rho[c];
                    vec4 sc = u_beta_s[c * NG + g] * rho[c];
                    ss += sc;
                    ps += sc * phs[c];
                }
                vec4 s_src = lit ? bilerp(u_tlut, ti, tj, ta, tb, g) * ps : vec4(0.0);
                if (u_use_ms == 1) s_src += bilerp(u_mslut, mi, mj, ma, mb, g) * ss;   // [Hil20] eq. 11
                vec4 x = se * dt;
                vec4 integ = mix(one_minus_exp_neg(x) / max(se, vec4(1e-30)), dt * (1.0 - 0.5 * x),
                                 lessThanEqual(x, vec4(1e-6)));
                L[g] += T[g] * s_src * integ;
                T[g] *= exp(-x);
            }
        }
    }
    if (hits && ground) {                                // lit Lambertian ground
        float mu_g = (r0 * sz + t1 * nu) / u_R;
        if (mu_g > 0.0) {
            int ti, tj; float ta, tb;
            trans_weights(u_R, 0.0, min(mu_g, 1.0), ti, tj, ta, tb);
            for (int g = 0; g < NG; ++g)
                L[g] += u_albedo[g] / PI * bilerp(u_tlut, ti, tj, ta, tb, g) * mu_g * T[g];
        }
    }
}

vec3 to_xyz(vec4 L[NG]) {
    vec3 xyz = vec3(0.0);
    for (int g = 0; g < NG; ++g)
        for (int k = 0; k < 4; ++k) xyz += max(L[g][k], 0.0) * u_K[4 * g + k];
    return xyz;
}

#ifndef AP_VOLUME
// build_skyview: one texel per fragment
void main() {
    int col = int(gl_FragCoord.x), row = int(gl_FragCoord.y);   // texel (row, col)
    float r0 = u_R + u_h0;
    vec2 ang = skyview_angles(row, col, u_sv_size.y, u_sv_size.x, r0);
    float mu = ang.x, cphi = ang.y;
    float sz = u_sz, sx = sqrt(max(1.0 - sz * sz, 0.0));
    float st = sqrt(max(1.0 - mu * mu, 0.0));
    float nu = st * cphi * sx + mu * sz;
    vec4 L[NG], T[NG];
    march(r0, mu, nu, -1.0, true, L, T);
    o_xyz = vec4(to_xyz(L), 1.0);
}
#else
// ap_direction: direction of froxel column (row, col) in the frame where the sun's azimuth
// is +x: elevation = 90 deg s|s|, s = 2 row/(n_v-1) - 1, cos(phi) = 1 - 2 x^2, x = col/(n_u-1)
vec3 ap_direction(int row, int col, int n_v, int n_u) {
    float s = 2.0 * float(row) / (float(n_v) - 1.0) - 1.0;
    float elev = 0.5 * PI * s * abs(s);
    float x = float(col) / (float(n_u) - 1.0);
    float cphi = 1.0 - 2.0 * x * x;
    float sphi = sqrt(max(1.0 - cphi * cphi, 0.0));
    float ce = cos(elev);
    return vec3(ce * cphi, ce * sphi, sin(elev));
}

// build_aerial_perspective ([Hil20] sec. 5.4): froxel (row, col, k) at texel
// (col n_s + k, row); depth_k = km_per_slice n_s ((k + 0.5)/n_s)^2 km; no ground
void main() {
    int n = u_ap_size;
    int x = int(gl_FragCoord.x), row = int(gl_FragCoord.y);
    int col = x / n, k = x - col * n;
    vec3 d = ap_direction(row, col, n, n);
    float sz = u_sz, sx = sqrt(max(1.0 - sz * sz, 0.0));
    float nu = d.x * sx + d.z * sz;
    float f = (float(k) + 0.5) / float(n);
    float depth = u_ap_km_per_slice * 1000.0 * float(n) * f * f;
    vec4 L[NG], T[NG];
    march(u_R + u_h0, d.z, nu, depth, false, L, T);
    vec3 xt = vec3(0.0);
    for (int g = 0; g < NG; ++g)
        for (int c = 0; c < 4; ++c) xt += clamp(T[g][c], 0.0, 1.0) * u_KT[4 * g + c];
    o_xyz = vec4(to_xyz(L), 1.0);
    o_t = vec4(xt, 1.0);
}
#endif
