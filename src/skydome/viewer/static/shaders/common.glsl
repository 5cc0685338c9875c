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

void main() {
    vec2 px = gl_FragCoord.xy - u_viewport.xy;
    vec2 size = u_viewport.zw;
    vec3 d = u_projection == 1 ? equirect(px, size, 0.5 * PI)
           : u_projection == 3 ? equirect(px, size, PI)
           : u_projection == 2 ? fisheye(px, size) : pinhole(px, size);
    vec3 xyz = max(sky_xyz(d), vec3(0.0));
    // alpha: 1 sky above the horizon, 0.5 rendered below it, 0 not rendered
    o_xyz = vec4(xyz, (g_masked || (d.z < 0.0 && u_shows_ground == 0)) ? 0.0 : d.z < 0.0 ? 0.5 : 1.0);
}
