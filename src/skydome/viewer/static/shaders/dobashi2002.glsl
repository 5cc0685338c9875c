// dobashi2002: aerial perspective and light shafts over the synthetic mountain scene, after
// Dobashi, Yamamoto & Nishita 2002 ([DYN02] secs. 3-5). Mirrors
// skydome.effects.dobashi2002 function by function (names in the comments):
// synthetic_mountains' ray march over the heightmap gives the depth of the surface;
// the in-scattered light and the transmittance come from the 2D tables of build_tables
// (J_c, D_c on (distance, view zenith cosine), sent by the server in XYZ per constituent),
// and the shadow test at the sampling planes perpendicular to the view axis reads the
// top of the terrain's shadow volume (shadow_volume_top, computed on the heightmap grid).
// Float32: the altitude along a ray is h0 + (t^2 + 2 r0 t mu) / (r + r0), the same number
// as sqrt(r0^2 + t^2 + 2 r0 t mu) - R without the cancellation of 6360 km terms.
precision highp sampler2D;
precision highp sampler2DArray;
uniform highp sampler2DArray u_tables; // layer c, texel (mu node, t node): (J~_c XYZ, D_c)
uniform highp sampler2D u_grid;        // heightmap grid: (height, shadow-volume top, Lambert, cell max)
uniform ivec2 u_table_size;            // n_angle, n_distance
uniform vec2 u_mu_range;               // first and last view-cosine node
uniform float u_extent;                // table extent = depth of the last plane = march range [m]
uniform ivec2 u_grid_size;             // nx, ny
uniform vec2 u_grid_origin, u_grid_step;
uniform float u_hmax;                  // highest terrain [m]
uniform vec3 u_eye;                    // camera (east, north, altitude) [m]
uniform float u_planet_radius, u_datum_radius;
uniform int u_march_steps, u_nc, u_shafts, u_n_planes, u_output;
uniform ivec4 u_phase_codes;
uniform vec4 u_phase_params;
uniform vec4 u_ext[NW];                // extinction of each constituent [m^-1] per wavelength
uniform vec3 u_tw[NW];                 // CIE weights x direct sunlight at the eye / pi
uniform vec3 u_albedo;
uniform float u_fill;
uniform mat3 u_srgb_to_xyz, u_xyz_to_srgb;

const int MAX_MARCH_STEPS = 1500;      // dobashi2002.MARCH_STEPS
const int MAX_PLANES = 128;

// Heightmap.sample: bilinear sample of grid channel ch at (x, y) [m]; `outside` beyond it
float heightmap_sample(int ch, float x, float y, float outside) {
    float fx = (x - u_grid_origin.x) / u_grid_step.x;
    float fy = (y - u_grid_origin.y) / u_grid_step.y;
    int nx = u_grid_size.x, ny = u_grid_size.y;
    if (!(fx >= 0.0 && fx <= float(nx - 1) && fy >= 0.0 && fy <= float(ny - 1))) return outside;
    int i = min(int(fx), nx - 2), j = min(int(fy), ny - 2);
    float wx = fx - float(i), wy = fy - float(j);
    float a = texelFetch(u_grid, ivec2(i, j), 0)[ch], b = texelFetch(u_grid, ivec2(i + 1, j), 0)[ch];
    float c = texelFetch(u_grid, ivec2(i, j + 1), 0)[ch], e = texelFetch(u_grid, ivec2(i + 1, j + 1), 0)[ch];
    return (1.0 - wy) * ((1.0 - wx) * a + wx * b) + wy * ((1.0 - wx) * c + wx * e);
}

// the highest height a heightmap_sample(0, x, y, 0) can return at (x, y): grid channel 3
// holds it per cell (a speed-up of the march only: where the ray is above it, the sample
// cannot be a hit, so it is skipped; the result is the same)
float cell_max(float x, float y) {
    float fx = (x - u_grid_origin.x) / u_grid_step.x;
    float fy = (y - u_grid_origin.y) / u_grid_step.y;
    int nx = u_grid_size.x, ny = u_grid_size.y;
    if (!(fx >= 0.0 && fx <= float(nx - 1) && fy >= 0.0 && fy <= float(ny - 1))) return 0.0;
    return texelFetch(u_grid, ivec2(min(int(fx), nx - 2), min(int(fy), ny - 2)), 0).w;
}

// _ray_altitude: altitude [m] at distance t along a ray leaving radius r0 = R + h0 with
// zenith cosine mu (float32 form, see the header)
float ray_altitude(float t, float mu, float R, float h0) {
    float r0 = R + h0;
    float q = t * (t + 2.0 * r0 * mu);               // r^2 - r0^2
    float r = sqrt(max(r0 * r0 + q, 0.0));
    return h0 + q / (r + r0);
}

// ScatteringTables._coords + _lookup: (J~_c XYZ, D_c) at (t, mu), linear in t between the
// quadratic nodes t_k = extent (k / (n - 1))^2, linear in mu between uniform nodes
vec4 table_lookup(int c, float t, float mu) {
    int na = u_table_size.x, nd = u_table_size.y;
    float tmax = u_extent, tc = clamp(t, 0.0, tmax);
    float u = sqrt(tc / tmax) * float(nd - 1);
    int i = min(int(u), nd - 2);
    float ki = float(i) / float(nd - 1), ki1 = float(i + 1) / float(nd - 1);
    float ti = tmax * ki * ki, ti1 = tmax * ki1 * ki1;
    float wt = clamp((tc - ti) / (ti1 - ti), 0.0, 1.0);
    float lo = u_mu_range.x, hi = u_mu_range.y;
    float fa = (clamp(mu, lo, hi) - lo) / ((hi - lo) / float(na - 1));
    int j = min(int(fa), na - 2);
    float wa = fa - float(j);
    vec4 a = texelFetch(u_tables, ivec3(j, i, c), 0), b = texelFetch(u_tables, ivec3(j + 1, i, c), 0);
    vec4 p = texelFetch(u_tables, ivec3(j, i + 1, c), 0), q = texelFetch(u_tables, ivec3(j + 1, i + 1, c), 0);
    return (1.0 - wt) * ((1.0 - wa) * a + wa * b) + wt * ((1.0 - wa) * p + wa * q);
}

// eq. (1) without the surface: E_sun sum_c beta_c p_c(theta) J_c(t, mu), in XYZ (the
// server's J~_c holds E_sun beta_c J_c with the CIE weights); D_c in `cols`
vec3 inscatter(float t, float mu, vec4 phase, out vec4 cols) {
    vec3 acc = vec3(0.0);
    cols = vec4(0.0);
    for (int c = 0; c < 4; ++c) {
        if (c >= u_nc) break;
        vec4 v = table_lookup(c, t, mu);
        acc += phase[c] * v.xyz;
        cols[c] = v.w;
    }
    return acc;
}

// _shadowed_integrals, eq. (4): slab-by-slab table differences weighted by the sun's
// visibility at the middle of each slab; planes perpendicular to the view axis at
// z_k = extent (k / n)^2
vec3 shadowed_inscatter(vec3 d, float t_pix, vec4 phase) {
    float cosf = max(dot(d, u_fwd), 1e-6);
    vec3 total = vec3(0.0), j_prev = vec3(0.0);
    float t_prev = 0.0;
    vec4 cols;
    for (int k = 1; k <= MAX_PLANES; ++k) {
        if (k > u_n_planes) break;
        float f = float(k) / float(u_n_planes);
        float t_k = min(u_extent * f * f / cosf, t_pix);
        if (!(t_k > t_prev)) break;                      // every later plane is behind the surface
        vec3 j_k = inscatter(t_k, d.z, phase, cols);
        float t_mid = 0.5 * (t_k + t_prev);
        float alt = ray_altitude(t_mid, d.z, u_planet_radius, u_eye.z);
        float top = heightmap_sample(1, u_eye.x + t_mid * d.x, u_eye.y + t_mid * d.y, -3.0e38);
        if (alt >= top) total += j_k - j_prev;
        j_prev = j_k;
        t_prev = t_k;
    }
    return total;
}

// synthetic_mountains' march: steps t_k = range (k / n)^1.5, the first step below the
// terrain refined by linear interpolation of the height difference; -1 for the sky
float march_terrain(vec3 d) {
    float mu = d.z, t_prev = 0.0;
    for (int k = 1; k <= MAX_MARCH_STEPS; ++k) {
        if (k > u_march_steps) break;
        float t = u_extent * pow(float(k) / float(u_march_steps), 1.5);
        float alt = ray_altitude(t, mu, u_datum_radius, u_eye.z);
        if (mu >= 0.0 && alt > u_hmax) return -1.0;     // rising above the highest terrain
        if (alt > cell_max(u_eye.x + t * d.x, u_eye.y + t * d.y)) { t_prev = t; continue; }
        float ground = heightmap_sample(0, u_eye.x + t * d.x, u_eye.y + t * d.y, 0.0);
        if (alt <= ground) {
            float ap = ray_altitude(t_prev, mu, u_datum_radius, u_eye.z);
            float gp = heightmap_sample(0, u_eye.x + t_prev * d.x, u_eye.y + t_prev * d.y, 0.0);
            float d0 = ap - gp, d1 = alt - ground;
            float frac = clamp(d0 / max(d0 - d1, 1e-9), 0.0, 1.0);
            return t_prev + frac * (t - t_prev);
        }
        t_prev = t;
    }
    return -1.0;
}

vec3 sky_xyz(vec3 d) {
    float t = march_terrain(d);
    if (u_output == 3) return vec3(max(t, 0.0), 0.0, 0.0);
    if (t < 0.0) {                                         // the sky: not part of the effect
        g_masked = u_output == 0;
        return u_output == 2 ? vec3(0.0) : vec3(0.0);
    }
    float nu = clamp1(dot(d, u_sun));
    vec4 phase = vec4(0.0);
    for (int c = 0; c < 4; ++c) phase[c] = phase_value(u_phase_codes[c], u_phase_params[c], nu);
    vec4 cols;
    vec3 L = inscatter(t, d.z, phase, cols);               // eq. (2), V = 1
    if (u_shafts == 1) L = shadowed_inscatter(d, t, phase);
    if (u_output == 1) return L;
    // eq. (3): T = exp(-sum_c beta_ext,c D_c), as the XYZ of a white surface facing the sun
    vec3 xyz_t = vec3(0.0);
    for (int l = 0; l < NW; ++l) xyz_t += u_tw[l] * exp(-dot(u_ext[l], cols));
    if (u_output == 2) return xyz_t;
    // the surface (synthetic_mountains' shading, the mean albedo): Lambert, shadow, fill;
    // outside the heightmap's grid the flat plain, lit at the sun's elevation
    float px = u_eye.x + t * d.x, py = u_eye.y + t * d.y;
    float shade = heightmap_sample(2, px, py, max(u_sun.z, 0.0));
    bool lit = heightmap_sample(0, px, py, 0.0) + 1.0 >= heightmap_sample(1, px, py, -3.0e38);
    vec3 img = u_albedo * ((lit ? shade : 0.0) + u_fill);
    return u_srgb_to_xyz * (img * (u_xyz_to_srgb * xyz_t)) + L;
}
