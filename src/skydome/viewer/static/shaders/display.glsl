// Display pass: linear XYZ (float render target) -> the canvas, mirroring
// skydome.render.image.SkyImage.to_srgb line by line: linear sRGB x exposure k
// (render.display.ev100_to_exposure: k = 1 / (1.2 x 2^EV100), [LdR14]), the display
// transform of render.display.display_transform (default "hue-preserving"), the sRGB
// transfer curve (spectra.srgb_encode); or false colour.
precision highp float;
uniform highp sampler2D u_xyz;
uniform int u_mode;          // 0: photographic, 1: false-colour luminance
uniform float u_k;           // exposure multiplier [m^2 cd^-1]
uniform int u_transform;     // 0 hue-preserving, 1 filmic, 2 reinhard, 3 clamp (the page's #transform)
uniform vec2 u_log_range;    // log10 of the luminance at the ends of the false-colour scale
out vec4 o_rgb;

// skydome.spectra.xyz_to_linear_srgb (IEC 61966-2-1 primaries, D65), rows of M^-1
vec3 xyz_to_linear_srgb(vec3 c) {
    return vec3(3.2409699419 * c.x - 1.5373831776 * c.y - 0.4986107603 * c.z,
               -0.9692436363 * c.x + 1.8759675015 * c.y + 0.0415550574 * c.z,
                0.0556300797 * c.x - 0.2039769589 * c.y + 1.0569715142 * c.z);
}

// spectra.srgb_encode: [IEC] 5.2, input clipped to [0, 1]
float srgb_encode(float v) {
    v = clamp(v, 0.0, 1.0);
    return v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}

// render.display: _LUMA (Rec. 709 weights), _WHITE_START, _WHITE_FULL
const vec3 LUMA = vec3(0.2126, 0.7152, 0.0722);
const float WHITE_START = 4.0, WHITE_FULL = 64.0;

// display.aces_fit: [Nar15] x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14), clipped to [0, 1]
vec3 aces_fit(vec3 x) {
    x = max(x, vec3(0.0));
    return clamp(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

// display._into_gamut: a colour with a negative component moves towards the grey of equal
// luminance until its smallest component is 0 (black if the luminance is not positive)
vec3 into_gamut(vec3 rgb) {
    float Y = dot(rgb, LUMA);
    float lo = min(rgb.r, min(rgb.g, rgb.b));
    if (!(lo < 0.0)) return rgb;
    float Yb = max(Y, 0.0);
    float t = Yb > 0.0 ? Yb / (Yb - lo) : 0.0;
    return max(Yb + t * (rgb - Yb), vec3(0.0));
}

// display.display_transform: linear display values in [0, 1] of exposed linear sRGB
vec3 display_transform(vec3 rgb, int transform) {
    if (transform == 1) return aces_fit(rgb);                              // "filmic"
    if (transform == 2) { vec3 x = max(rgb, vec3(0.0)); return clamp(x / (1.0 + x), 0.0, 1.0); }
    if (transform == 3) return clamp(rgb, 0.0, 1.0);                       // "clamp"
    rgb = into_gamut(rgb);                                                 // "hue-preserving"
    float m = max(rgb.r, max(rgb.g, rgb.b));
    float fm = aces_fit(vec3(m)).x;
    vec3 out_ = m > 0.0 ? rgb * (fm / m) : vec3(0.0);
    // path to white, logarithmic in the over-exposure from 4 to 64 x the display's white
    float w = clamp(log2(max(m, 1e-30) / WHITE_START) / log2(WHITE_FULL / WHITE_START), 0.0, 1.0);
    out_ = out_ * (1.0 - w) + fm * w;
    return clamp(out_, 0.0, 1.0);
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
    if (t.a == 0.0) { o_rgb = vec4(0.16, 0.15, 0.14, 1.0); return; }   // not rendered
    if (u_mode == 1) {
        float lg = log(max(t.y, 1e-6)) / log(10.0);
        o_rgb = vec4(ramp((lg - u_log_range.x) / (u_log_range.y - u_log_range.x)), 1.0);
        return;
    }
    // SkyImage.to_srgb: rgb = linear_srgb x k; per-channel transforms clip negatives first
    vec3 rgb = xyz_to_linear_srgb(t.xyz) * u_k;
    if (u_transform != 0) rgb = max(rgb, vec3(0.0));
    vec3 d = display_transform(rgb, u_transform);
    o_rgb = vec4(srgb_encode(d.r), srgb_encode(d.g), srgb_encode(d.b), 1.0);
}
