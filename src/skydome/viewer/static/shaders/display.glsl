// Display pass: linear XYZ (float render target) -> the canvas, mirroring
// skydome.imaging.image.SkyImage.to_srgb / _display line by line: linear sRGB x exposure k
// (imaging.display.ev100_to_exposure: k = 1 / (1.2 x 2^EV100), [LdR14]), the Hunt-effect
// chroma gain (imaging.display.scale_chroma by hunt_chroma_gain of the scene's adapting
// luminance, computed by app.js), the display transform of imaging.display.display_transform
// (default "hue-preserving"), the sRGB transfer curve (spectra.srgb_encode); or false colour.
precision highp float;
uniform highp sampler2D u_xyz;
uniform int u_mode;          // 0: photographic, 1: false-colour luminance
uniform float u_k;           // exposure multiplier [m^2 cd^-1]
uniform int u_transform;     // index in imaging.display.DISPLAY_TRANSFORMS: 0 hue-preserving,
                             // 1 agx, 2 aces-hill, 3 filmic, 4 reinhard, 5 clamp (the page's #transform)
uniform float u_gain;        // CIELAB chroma gain (SkyImage.chroma_gain; 1: none)
uniform vec2 u_log_range;    // log10 of the luminance at the ends of the false-colour scale
out vec4 o_rgb;

// skydome.spectra.xyz_to_linear_srgb (IEC 61966-2-1 primaries, D65), rows of M^-1
vec3 xyz_to_linear_srgb(vec3 c) {
    return vec3(3.2409699419 * c.x - 1.5373831776 * c.y - 0.4986107603 * c.z,
               -0.9692436363 * c.x + 1.8759675015 * c.y + 0.0415550574 * c.z,
                0.0556300797 * c.x - 0.2039769589 * c.y + 1.0569715142 * c.z);
}

// skydome.spectra.linear_srgb_to_xyz, rows of M
vec3 linear_srgb_to_xyz(vec3 c) {
    return vec3(dot(vec3(0.412390799266, 0.357584339384, 0.180480788402), c),
                dot(vec3(0.212639005872, 0.715168678768, 0.072192315361), c),
                dot(vec3(0.019330818716, 0.119194779795, 0.950532152250), c));
}

// spectra.srgb_encode: [IEC] 5.2, input clipped to [0, 1]
float srgb_encode(float v) {
    v = clamp(v, 0.0, 1.0);
    return v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}

// imaging.display: _LUMA (Rec. 709 weights), _WHITE_START, _WHITE_FULL
const vec3 LUMA = vec3(0.2126, 0.7152, 0.0722);
const float WHITE_START = 4.0, WHITE_FULL = 64.0;

// display.aces_fit: [Nar15] x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14), clipped to [0, 1]
vec3 aces_fit(vec3 x) {
    x = max(x, vec3(0.0));
    return clamp(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

// display.agx [Sob23], [Wre23]: Rec. 709 -> Rec. 2020 and the AgX inset in one matrix
// (_AGX_INSET @ to2020 of display._rec709_rec2020, rows), log2 encoding over
// [_AGX_MIN_EV, _AGX_MAX_EV], the sigmoid fit per channel, the outset, the 2.2 power,
// Rec. 2020 -> Rec. 709
const float AGX_MIN_EV = -12.47393, AGX_MAX_EV = 4.026069;
vec3 agx(vec3 rgb) {
    vec3 x = vec3(dot(vec3(0.544814746488, 0.373787398373, 0.081397855139), rgb),
                  dot(vec3(0.140416948464, 0.754137554567, 0.105445496969), rgb),
                  dot(vec3(0.088810419615, 0.178871756421, 0.732317823964), rgb));
    x = log2(max(x, vec3(1e-10)));
    x = clamp((x - AGX_MIN_EV) / (AGX_MAX_EV - AGX_MIN_EV), 0.0, 1.0);
    // [Wre23] 15.5 x^6 - 40.14 x^5 + 31.96 x^4 - 6.868 x^3 + 0.4298 x^2 + 0.1191 x - 0.00232
    vec3 y = ((((((15.5 * x - 40.14) * x + 31.96) * x - 6.868) * x + 0.4298) * x + 0.1191) * x - 0.00232);
    y = vec3(dot(vec3(1.1271005818144368, -0.11060664309660323, -0.016493938717834573), y),   // _AGX_OUTSET
             dot(vec3(-0.1413297634984383, 1.157823702216272, -0.016493938717834257), y),
             dot(vec3(-0.14132976349843826, -0.11060664309660294, 1.2519364065950405), y));
    y = pow(max(y, vec3(0.0)), vec3(2.2));
    return clamp(vec3(dot(vec3(1.660491002108, -0.587641138789, -0.072849863320), y),      // to709
                      dot(vec3(-0.124550474522, 1.132899897126, -0.008349422604), y),
                      dot(vec3(-0.018150763355, -0.100578898008, 1.118729661363), y)), 0.0, 1.0);
}

// display.aces_hill [Hil16]: input matrix, the RRT + ODT rational fit per channel, output matrix
vec3 aces_hill(vec3 rgb) {
    vec3 v = vec3(dot(vec3(0.59719, 0.35458, 0.04823), rgb),
                  dot(vec3(0.07600, 0.90834, 0.01566), rgb),
                  dot(vec3(0.02840, 0.13383, 0.83777), rgb));
    v = max(v, vec3(0.0));
    v = (v * (v + 0.0245786) - 0.000090537) / (v * (0.983729 * v + 0.4329510) + 0.238081);
    return clamp(vec3(dot(vec3(1.60475, -0.53108, -0.07367), v),
                      dot(vec3(-0.10208, 1.10813, -0.00605), v),
                      dot(vec3(-0.00327, -0.07276, 1.07602), v)), 0.0, 1.0);
}

// imaging._kernels_display._lab_f, _lab_f_inv: the CIELAB function and its inverse [CIE15]
float lab_f(float t) {
    const float d = 6.0 / 29.0;
    return t > d * d * d ? pow(t, 1.0 / 3.0) : t / (3.0 * d * d) + 4.0 / 29.0;
}
float lab_f_inv(float f) {
    const float d = 6.0 / 29.0;
    return f > d ? f * f * f : 3.0 * d * d * (f - 4.0 / 29.0);
}

// display.scale_chroma: the CIELAB chroma [CIE15] (D65 white, spectra.SRGB_WHITE_XY) of
// linear sRGB scaled by gain at constant Y and hue; each colour at Y = 1 first; colours
// with Y <= 0 kept; in-gamut colours boosted at most to the gamut's boundary, colours
// outside it not at all
const vec3 D65_WHITE = vec3(0.950455927052, 1.0, 1.08905775076);
vec3 scale_chroma(vec3 rgb, float gain) {
    if (gain == 1.0) return rgb;
    vec3 xyz = linear_srgb_to_xyz(rgb);
    float Y = xyz.y;
    if (!(Y > 0.0)) return rgb;
    vec3 n = xyz / Y / D65_WHITE;
    float fx = lab_f(n.x), fz = lab_f(n.z), fy = 1.0;   // L* = 100 after the scaling
    float a = gain * 500.0 * (fx - fy), b = gain * 200.0 * (fy - fz);   // [CIE15] a*, b* x gain
    vec3 n2 = vec3(lab_f_inv(fy + a / 500.0), 1.0, lab_f_inv(fy - b / 200.0));
    vec3 out_ = xyz_to_linear_srgb(n2 * D65_WHITE * Y);
    if (min(rgb.r, min(rgb.g, rgb.b)) < 0.0) return rgb;
    float t = 1.0;   // stop where the smallest component reaches 0
    if (out_.r < 0.0) t = min(t, rgb.r / (rgb.r - out_.r));
    if (out_.g < 0.0) t = min(t, rgb.g / (rgb.g - out_.g));
    if (out_.b < 0.0) t = min(t, rgb.b / (rgb.b - out_.b));
    return rgb + clamp(t, 0.0, 1.0) * (out_ - rgb);
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
    if (transform == 1) return agx(rgb);                                   // "agx"
    if (transform == 2) return aces_hill(rgb);                             // "aces-hill"
    if (transform == 3) return aces_fit(rgb);                              // "filmic"
    if (transform == 4) { vec3 x = max(rgb, vec3(0.0)); return clamp(x / (1.0 + x), 0.0, 1.0); }
    if (transform == 5) return clamp(rgb, 0.0, 1.0);                       // "clamp"
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
    // SkyImage._display: rgb = scale_chroma(linear_srgb x k, gain); the per-channel
    // transforms (filmic, reinhard, clamp) clip negatives first
    vec3 rgb = scale_chroma(xyz_to_linear_srgb(t.xyz) * u_k, u_gain);
    if (u_transform >= 3) rgb = max(rgb, vec3(0.0));
    vec3 d = display_transform(rgb, u_transform);
    o_rgb = vec4(srgb_encode(d.r), srgb_encode(d.g), srgb_encode(d.b), 1.0);
}
