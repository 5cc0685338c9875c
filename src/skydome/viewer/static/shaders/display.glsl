// Display pass: linear XYZ (float render target) -> sRGB on the canvas, or false colour.
precision highp float;
uniform highp sampler2D u_xyz;
uniform int u_mode;          // 0: exposure + sRGB, 1: false-colour luminance
uniform float u_white;       // luminance [cd m^-2] shown as white (mode 0)
uniform vec2 u_log_range;    // log10 of the luminance at the ends of the false-colour scale
out vec4 o_rgb;

// skydome.spectra.xyz_to_linear_srgb (IEC 61966-2-1 primaries, D65), rows of M^-1
vec3 xyz_to_linear_srgb(vec3 c) {
    return vec3(3.2409699419 * c.x - 1.5373831776 * c.y - 0.4986107603 * c.z,
               -0.9692436363 * c.x + 1.8759675015 * c.y + 0.0415550574 * c.z,
                0.0556300797 * c.x - 0.2039769589 * c.y + 1.0569715142 * c.z);
}

float srgb_oetf(float v) {
    v = clamp(v, 0.0, 1.0);
    return v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}

// false-colour ramp (black-blue-cyan-green-yellow-red-white), t in [0, 1]; the page's
// scale bar uses the same stops (app.js RAMP)
vec3 ramp(float t) {
    const vec3 s0 = vec3(0.0, 0.0, 0.0), s1 = vec3(0.1, 0.1, 0.8), s2 = vec3(0.0, 0.7, 0.9),
               s3 = vec3(0.1, 0.8, 0.2), s4 = vec3(0.95, 0.9, 0.1), s5 = vec3(0.9, 0.15, 0.1),
               s6 = vec3(1.0, 1.0, 1.0);
    float x = clamp(t, 0.0, 1.0) * 6.0;
    if (x < 1.0) return mix(s0, s1, x);
    if (x < 2.0) return mix(s1, s2, x - 1.0);
    if (x < 3.0) return mix(s2, s3, x - 2.0);
    if (x < 4.0) return mix(s3, s4, x - 3.0);
    if (x < 5.0) return mix(s4, s5, x - 4.0);
    return mix(s5, s6, x - 5.0);
}

void main() {
    vec4 t = texelFetch(u_xyz, ivec2(gl_FragCoord.xy), 0);
    if (t.a == 0.0) { o_rgb = vec4(0.16, 0.15, 0.14, 1.0); return; }   // below the horizon
    if (u_mode == 1) {
        float lg = log(max(t.y, 1e-6)) / log(10.0);
        o_rgb = vec4(ramp((lg - u_log_range.x) / (u_log_range.y - u_log_range.x)), 1.0);
        return;
    }
    vec3 rgb = xyz_to_linear_srgb(t.xyz) / u_white;
    o_rgb = vec4(srgb_oetf(rgb.r), srgb_oetf(rgb.g), srgb_oetf(rgb.b), 1.0);
}
