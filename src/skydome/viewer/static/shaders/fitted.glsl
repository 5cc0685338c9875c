// fitted: skydome's fitted sky model (skydome.models.fitted). The server builds the
// configuration's angular table in CIE XYZ on the CPU (FittedSky.xyz_table: the table that
// FittedSky.xyz looks up) and the page uploads it as an RGBA32F texture, rows = the view
// grid's zenith-angle nodes (N_SKY sky rows from the horizon up, then N_GROUND ground rows
// from the horizon down), columns = its N_PHI azimuth nodes. sky_xyz mirrors the numba
// kernel skydome.models.fitted._kernels.lookup line for line: the inverse mappings of
// fitted._grid, then the Catmull-Rom spline through four rows along the zenith angle, each
// row linear between two columns in azimuth (eight texels, texelFetch: the kernel's own
// weights, no hardware filtering).
precision highp sampler2D;
uniform highp sampler2D u_fitted;  // (N_SKY + N_GROUND) rows x N_PHI columns, XYZ
uniform ivec3 u_fitted_n;          // N_SKY, N_GROUND, N_PHI
uniform float u_theta_h;           // the horizon's zenith angle [rad]
uniform float u_inv_sky;           // 1 / (theta_h - EPS)
uniform float u_inv_ground;        // 1 / (pi - theta_h - EPS)
uniform float u_eps;               // _grid.EPS [rad]
uniform float u_a_phi;             // _grid.A_PHI
uniform vec2 u_sun_az;             // sin, cos of the sun's azimuth (from north towards east)

vec3 fitted_texel(int row, int col) { return texelFetch(u_fitted, ivec2(col, row), 0).rgb; }

vec3 sky_xyz(vec3 d) {
    float rho = length(d.xy);
    // zenith angle; pi/2 - atan(z, rho) keeps float32's digits at the horizon, where the
    // grid is densest (the kernel: atan2(rho, z), the same angle)
    float th = 0.5 * PI - atan(d.z, rho);
    bool sky = th < u_theta_h;
    float u_sky = sqrt(max(1.0 - th * u_inv_sky, 0.0)) * float(u_fitted_n.x - 1);
    float u_ground = sqrt(max((th - u_theta_h - u_eps) * u_inv_ground, 0.0))
                   * float(u_fitted_n.y - 1);
    float u = sky ? u_sky : u_ground;
    int base = sky ? 0 : u_fitted_n.x;
    int nu = sky ? u_fitted_n.x : u_fitted_n.y;
    int iu = min(int(u), nu - 2);
    float fu = u - float(iu);
    // azimuth from the sun's vertical plane, folded into [0, pi]
    float cp = d.x * u_sun_az.x + d.y * u_sun_az.y;
    float sp = abs(d.x * u_sun_az.y - d.y * u_sun_az.x);
    bool zero = sp == 0.0 && cp == 0.0;          // the zenith or the nadir: phi = 0
    float phi = (zero ? 0.0 : atan(sp, cp)) * (1.0 / PI);
    float a = u_a_phi, b = 1.0 - u_a_phi;
    float t = (-a + sqrt(a * a + 4.0 * b * phi)) / (2.0 * b) * float(u_fitted_n.z - 1);
    int it = min(int(t), u_fitted_n.z - 2);
    float ft = max(t - float(it), 0.0);
    // Catmull-Rom weights of the rows r0 .. r0 + 3 (inside the part: iu - 1 .. iu + 2; in
    // its first and last cells the row beyond the end on the line through the two end rows)
    float f2 = fu * fu;
    float f3 = f2 * fu;
    float wm = -0.5 * f3 + f2 - 0.5 * fu;
    float w0 = 1.5 * f3 - 2.5 * f2 + 1.0;
    float w1 = -1.5 * f3 + 2.0 * f2 + 0.5 * fu;
    float w2 = 0.5 * f3 - 0.5 * f2;
    bool lo = iu == 0;
    bool hi = iu == nu - 2;
    vec4 wr = lo ? vec4(w0 + 2.0 * wm, w1 - wm, w2, 0.0)
                 : (hi ? vec4(0.0, wm, w0 - w2, w1 + 2.0 * w2) : vec4(wm, w0, w1, w2));
    int r0 = base + (lo ? 0 : (hi ? iu - 2 : iu - 1));
    vec3 v = vec3(0.0);
    for (int k = 0; k < 4; ++k) {
        v += wr[k] * ((1.0 - ft) * fitted_texel(r0 + k, it) + ft * fitted_texel(r0 + k, it + 1));
    }
    return max(v, vec3(0.0));
}
