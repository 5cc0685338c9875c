// Shared by every sky shader: the view direction of a fragment and the output.
// Frame: East-North-Up (x east, y north, z up), azimuth from north towards east, as in
// skydome. The sky shader of each model defines vec3 sky_xyz(vec3 d): CIE 1931 XYZ with
// Y = luminance [cd m^-2] of the sky seen from direction d (unit vector).
precision highp float;
precision highp int;

const float PI = 3.14159265358979;

uniform vec4 u_viewport;      // x0, y0, width, height of the view [pixels]
uniform int u_projection;     // 0: pinhole camera, 1: equirect-hemisphere, 2: fisheye, 3: equirect
uniform vec3 u_fwd;           // camera axes (unit, East-North-Up)
uniform vec3 u_right;
uniform vec3 u_up;
uniform float u_tan_half_fov; // tan(horizontal field of view / 2)
uniform vec3 u_sun;           // unit vector towards the sun
uniform int u_shows_ground;   // 1: the model renders the ground too (else it is masked)

out vec4 o_xyz;

// a sky shader sets this for directions it does not render (shown as ground)
bool g_masked = false;

// skydome._kernels_analytic._clamp1
float clamp1(float x) { return clamp(x, -1.0, 1.0); }

// angle between two unit vectors; atan form, accurate near 0 in float32 (acos(dot) loses
// half the digits there)
float angle_between(vec3 a, vec3 b) { return atan(length(cross(a, b)), dot(a, b)); }

// skydome.imaging.projections.Equirect(hemisphere=True / False).direction_from_pixel at the
// pixel centre: row 0 at the zenith, elevation = 90 deg - span * row / H (span 90 or 180
// deg), azimuth = 360 deg * col / W from north through east.
vec3 equirect(vec2 px, vec2 size, float span) {
    float row = size.y - px.y;            // gl_FragCoord counts rows from the bottom
    float el = 0.5 * PI - span * row / size.y;
    float az = 2.0 * PI * px.x / size.x;
    float ce = cos(el);
    return vec3(ce * sin(az), ce * cos(az), sin(el));
}

// skydome.imaging.projections.Fisheye (Radiance angular fisheye looking up, north at the
// top, east on the left): zenith angle = pi * rho, rho in image widths from the centre.
// On a non-square view the dome is the centred square of side min(width, height).
vec3 fisheye(vec2 px, vec2 size) {
    float side = min(size.x, size.y);
    float x = (px.x - 0.5 * size.x) / side;
    float y = (px.y - 0.5 * size.y) / side;
    float rho = length(vec2(x, y));
    float theta = PI * rho;
    if (theta > 0.5 * PI) return vec3(0.0, 0.0, -1.0);
    float s = rho > 0.0 ? sin(theta) / rho : PI;
    return vec3(-x * s, y * s, cos(theta));
}

vec3 pinhole(vec2 px, vec2 size) {
    vec2 ndc = 2.0 * px / size - 1.0;
    float aspect = size.y / size.x;
    return normalize(u_fwd + ndc.x * u_tan_half_fov * u_right
                     + ndc.y * u_tan_half_fov * aspect * u_up);
}

vec3 sky_xyz(vec3 d);

vec3 view_direction(vec2 px, vec2 size) {
    return u_projection == 1 ? equirect(px, size, 0.5 * PI)
         : u_projection == 3 ? equirect(px, size, PI)
         : u_projection == 2 ? fisheye(px, size) : pinhole(px, size);
}

// The sun's disc, as skydome.imaging.sun_disc.draw_sun_disc draws it into an XYZ image
// (one function for every model; the server sends each model's own numbers):
// u_disc_L the model's mean disc radiance in XYZ (its transmitted sun, `sun_disc_radiance`),
// u_disc_alpha the angular radius [rad], u_limb[k] the coefficients of mu^k of [Nec05]'s
// centre-to-limb law I(mu) / I_mean at the X, Y, Z channels' wavelengths (600, 555,
// 450 nm), so that the disc's mean is u_disc_L. The pixel is split into n x n equal
// parts; each part inside the disc (and above the geometric horizon, as the CPU's samples)
// replaces the sky it covers by the disc's radiance there, so the pixel's mean gains
// the flux of the disc that falls into it: energy-true for a disc larger or smaller than
// a pixel. A sun pixel keeps the sky's alpha.
uniform int u_disc_on;
uniform vec3 u_disc_L;
uniform float u_disc_alpha;
uniform vec3 u_limb[6];

vec3 limb_profile(float theta) {
    float rho = sin(theta) / sin(u_disc_alpha);       // distance from the centre [radii]
    float mu = sqrt(max(0.0, 1.0 - rho * rho));       // cos of the heliocentric angle
    vec3 I = u_limb[5];
    for (int k = 4; k >= 0; --k) I = I * mu + u_limb[k];   // Horner: sum_k A_k mu^k
    return max(I, vec3(0.0));
}

vec3 with_sun_disc(vec3 sky, vec3 d, vec2 px, vec2 size) {
    float a = u_disc_alpha;
    float th = angle_between(d, u_sun);
    // angular size of the pixel (its neighbours' directions)
    float ps = max(angle_between(d, view_direction(px + vec2(1.0, 0.0), size)),
                   angle_between(d, view_direction(px + vec2(0.0, 1.0), size)));
    if (!(th < a + 1.5 * ps)) return sky;
    // parts of at most 1/16 of the disc's radius: >= ~800 inside a disc smaller than the pixel
    int n = int(clamp(ceil(16.0 * ps / a), 2.0, 64.0));
    float cover = 0.0;
    vec3 acc = vec3(0.0);
    for (int i = 0; i < 64; ++i) {
        if (i >= n) break;
        for (int j = 0; j < 64; ++j) {
            if (j >= n) break;
            vec2 q = px + (vec2(float(i), float(j)) + 0.5) / float(n) - 0.5;
            vec3 e = view_direction(q, size);
            float t = angle_between(e, u_sun);
            if (t < a && e.z >= 0.0) { cover += 1.0; acc += limb_profile(t); }
        }
    }
    float inv = 1.0 / float(n * n);
    return sky * (1.0 - cover * inv) + u_disc_L * acc * inv;
}

void main() {
    vec2 px = gl_FragCoord.xy - u_viewport.xy;
    vec2 size = u_viewport.zw;
    vec3 d = view_direction(px, size);
    vec3 xyz = max(sky_xyz(d), vec3(0.0));
    bool shown = !(g_masked || (d.z < 0.0 && u_shows_ground == 0));
    if (u_disc_on == 1 && shown) xyz = with_sun_disc(xyz, d, px, size);
    // alpha: 1 sky above the horizon, 0.5 rendered below it, 0 not rendered
    o_xyz = vec4(xyz, !shown ? 0.0 : d.z < 0.0 ? 0.5 : 1.0);
}
