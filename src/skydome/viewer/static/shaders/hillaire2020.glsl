// hillaire2020, the sky pass: bilinear look-up of the per-frame sky-view LUT
// (hillaire2020_lut.glsl), mirroring _kernels_hillaire2020.lookup_skyview ([Hil20] 5.3):
// rows interpolated within the half (above / below the horizon) of the direction.
precision highp sampler2D;
uniform highp sampler2D u_skyview;      // XYZ per texel, (W, H) = u_sv_size
uniform ivec2 u_sv_size;
uniform float u_R;
uniform float u_h0;

vec4 sv(int row, int col) { return texelFetch(u_skyview, ivec2(col, row), 0); }

vec3 sky_xyz(vec3 d) {
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
