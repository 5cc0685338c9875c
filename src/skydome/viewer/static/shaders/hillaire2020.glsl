// hillaire2020, the sky pass: bilinear look-up of the per-frame sky-view LUT
// (hillaire2020_lut.glsl), mirroring _kernels_hillaire2020.lookup_skyview ([Hil20] 5.3):
// rows interpolated within the half (above / below the horizon) of the direction.
precision highp sampler2D;
uniform highp sampler2D u_skyview;      // XYZ per texel, (W, H) = u_sv_size
uniform ivec2 u_sv_size;
uniform float u_R;
uniform float u_h0;
uniform highp sampler2D u_ap_l, u_ap_t;  // aerial-perspective volume: texel (col n + k, row)
uniform int u_ap_size;
uniform float u_ap_km_per_slice;
uniform int u_output;                    // 0 the sky; 1, 2 in-scattering, transmittance to u_ap_distance
uniform float u_ap_distance;             // [m]
uniform vec3 u_sun_xyz;                  // XYZ of the sunlight (transmittance 1)

// lookup_aerial_perspective ([Hil20] 5.4): trilinear in the volume (inverse of
// ap_direction; slice coordinate w = sqrt(slice / n_s); below half a slice the values fade
// linearly to none at distance 0; beyond the last slice clamped). L and T in XYZ.
void lookup_aerial_perspective(vec3 d, float dist, out vec3 L, out vec3 T) {
    int n = u_ap_size;
    float dz = clamp1(d.z);
    float s = asin(dz) / (0.5 * PI);
    float ss = sqrt(abs(s));
    if (s < 0.0) ss = -ss;
    float fr = (0.5 * ss + 0.5) * float(n - 1);
    int ir = clamp(int(fr), 0, n - 2);
    float a = clamp(fr - float(ir), 0.0, 1.0);
    float nd = length(d.xy), ns = length(u_sun.xy);
    float cphi = (nd < 1e-12 || ns < 1e-12) ? 1.0 : clamp1(dot(d.xy, u_sun.xy) / (nd * ns));
    float fx = sqrt(max(0.5 - 0.5 * cphi, 0.0)) * float(n - 1);
    int jc = min(int(fx), n - 2);
    float b = fx - float(jc);
    float sl = dist / (u_ap_km_per_slice * 1000.0);
    float weight = 1.0;
    if (sl < 0.5) { weight = max(2.0 * sl, 0.0); sl = 0.5; }
    float fz = sqrt(sl / float(n)) * float(n) - 0.5;
    fz = clamp(fz, 0.0, float(n) - 1.0);
    int kz = min(int(fz), n - 2);
    float cz = fz - float(kz);
    vec3 vl = vec3(0.0), vt = vec3(0.0);
    for (int di = 0; di < 2; ++di)
        for (int dj = 0; dj < 2; ++dj)
            for (int dk = 0; dk < 2; ++dk) {
                float w = (di == 1 ? a : 1.0 - a) * (dj == 1 ? b : 1.0 - b) * (dk == 1 ? cz : 1.0 - cz);
                ivec2 px = ivec2((jc + dj) * n + kz + dk, ir + di);
                vl += w * texelFetch(u_ap_l, px, 0).xyz;
                vt += w * texelFetch(u_ap_t, px, 0).xyz;
            }
    L = weight * vl;
    // out_t = 1 - weight (1 - vt) per wavelength: in XYZ of the sunlight, the sunlight's
    // XYZ (the texel of an empty froxel, T = 1) minus weight x its loss
    T = u_sun_xyz - weight * (u_sun_xyz - vt);
}

vec4 sv(int row, int col) { return texelFetch(u_skyview, ivec2(col, row), 0); }

vec3 sky_xyz(vec3 d) {
    if (u_output == 1 || u_output == 2) {
        vec3 L, T;
        lookup_aerial_perspective(d, u_ap_distance, L, T);
        return u_output == 1 ? L : T;
    }
    int H = u_sv_size.y, W = u_sv_size.x, hh = H / 2;
    float r0 = u_R + u_h0;
    float rho2 = u_h0 * (2.0 * u_R + u_h0);
    float beta = acos(min(sqrt(max(rho2, 0.0)) / r0, 1.0));
    float zh = PI - beta;
    float mu = clamp1(d.z);
    float theta = acos(mu);
    float fr;
    int base;
    if (!(mu < 0.0 && r0 * r0 * mu * mu - rho2 >= 0.0)) {      // !ray_hits_ground
        float c = 1.0 - sqrt(max(1.0 - theta / zh, 0.0));
        fr = clamp(c, 0.0, 1.0) * float(hh - 1);
        base = 0;
    } else {
        float c = beta > 0.0 ? sqrt(max((theta - zh) / beta, 0.0)) : 0.0;
        fr = clamp(c, 0.0, 1.0) * float(hh - 1);
        base = hh;
    }
    int ir = min(int(fr), hh - 2);
    float a = fr - float(ir);
    ir += base;
    // _rel_azimuth_cos
    float nd = length(d.xy), ns = length(u_sun.xy);
    float cphi = (nd < 1e-12 || ns < 1e-12) ? 1.0 : clamp1(dot(d.xy, u_sun.xy) / (nd * ns));
    float fx = sqrt(max(0.5 - 0.5 * cphi, 0.0)) * float(W - 1);
    int jc = min(int(fx), W - 2);
    float b = fx - float(jc);
    vec4 v = (1.0 - a) * ((1.0 - b) * sv(ir, jc) + b * sv(ir, jc + 1))
           + a * ((1.0 - b) * sv(ir + 1, jc) + b * sv(ir + 1, jc + 1));
    return v.xyz;
}
