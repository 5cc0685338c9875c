// hoffman_preetham2002: [HP02] N. Hoffman, A. J. Preetham, "Rendering Outdoor Light
// Scattering in Real Time", GDC 2002. Mirrors HoffmanPreetham2002.radiance with
// aerial_perspective, per wavelength of skydome's default grid; u_spec[i] = (beta_R,
// beta_M x 1200/8803, E_sun, 0) from skydome.viewer.scene._hoffman ([PSS99] A.1, A.3),
// u_cmf[i] = 683 x the CIE 1931 integration weights (SkyModel.xyz).

uniform vec4 u_spec[NW];
uniform vec3 u_cmf[NW];
uniform float u_g;
uniform int u_hp_phase;        // 1: the [HP02] form (1 - g)^2, 0: Henyey-Greenstein (1 - g^2)
uniform float u_shell_m;       // H: thickness of the homogeneous shell [m]
uniform float u_earth_radius_m;

// [HP02] beta_R(theta) / beta_R = 3 / (16 pi) (1 + cos^2 theta)
float rayleigh_phase(float c) { return 3.0 / (16.0 * PI) * (1.0 + c * c); }

// [HP02] beta_M(theta) / beta_M = (1 - g)^2 / (4 pi (1 + g^2 - 2 g cos theta)^(3/2)); [HG41]
float mie_phase(float c, float g, int hp) {
    float num = hp == 1 ? (1.0 - g) * (1.0 - g) : 1.0 - g * g;
    return num / (4.0 * PI * pow(1.0 + g * g - 2.0 * g * c, 1.5));
}

// shell_path_length: -R u + sqrt(R^2 u^2 + 2 R H + H^2), written as
// (2 R H + H^2) / (R u + sqrt(...)) (the same number without float32 cancellation)
float shell_path_length(float u, float H, float R) {
    float q = 2.0 * R * H + H * H;
    return q / (R * u + sqrt(R * R * u * u + q));
}

vec3 sky_xyz(vec3 d) {
    if (d.z < 0.0) return vec3(0.0);
    float s = shell_path_length(max(d.z, 0.0), u_shell_m, u_earth_radius_m);
    float cos_t = clamp1(dot(d, u_sun));
    float pr = rayleigh_phase(cos_t);
    float pm = mie_phase(cos_t, u_g, u_hp_phase);
    vec3 xyz = vec3(0.0);
    for (int i = 0; i < NW; ++i) {
        float beta_r = u_spec[i].x, beta_m = u_spec[i].y, e_sun = u_spec[i].z;
        float beta = beta_r + beta_m;
        float f_ex = exp(-beta * s);                                   // [HP02] F_ex
        float ang = beta_r * pr + beta_m * pm;                         // [HP02] beta(theta)
        float l_in = beta > 0.0 ? ang / beta * e_sun * (1.0 - f_ex) : 0.0;  // [HP02] L_in
        xyz += max(l_in, 0.0) * u_cmf[i];
    }
    return xyz;
}
