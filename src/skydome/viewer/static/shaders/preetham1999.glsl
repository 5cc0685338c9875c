// preetham1999: [PSS99] A. J. Preetham, P. Shirley, B. Smits, "A Practical Analytic Model
// for Daylight", SIGGRAPH 99. Mirrors skydome.models.analytic._kernels_analytic.preetham
// line for line; the coefficients come from skydome.viewer.scene._preetham:
// u_coef rows x, y, Y of Perez A..E ([PSS99] Appendix A.2), u_zen = zenith value / F(0, theta_s).

uniform float u_coef[15];
uniform vec3 u_zen;
uniform float u_cos_floor;

// [PSS99] eq. 3 (Perez form): F(theta, gamma) = (1 + A exp(B / cos theta))
//                                              (1 + C exp(D gamma) + E cos^2 gamma)
float _perez_form(float c, float cos_g, float gamma, int k) {
    int o = 5 * k;
    return (1.0 + u_coef[o] * exp(u_coef[o + 1] / c))
         * (1.0 + u_coef[o + 2] * exp(u_coef[o + 3] * gamma) + u_coef[o + 4] * cos_g * cos_g);
}

vec3 sky_xyz(vec3 d) {
    if (d.z < 0.0) return vec3(0.0);                 // below the horizon: XYZ = 0
    float cg = clamp1(dot(d, u_sun));
    float gamma = angle_between(d, u_sun);           // acos(cg) in the CPU kernel
    float c = max(d.z, u_cos_floor);
    float x = u_zen.x * _perez_form(c, cg, gamma, 0);   // [PSS99] eq. 3, x
    float y = u_zen.y * _perez_form(c, cg, gamma, 1);   // [PSS99] eq. 3, y
    float Y = max(u_zen.z * _perez_form(c, cg, gamma, 2), 0.0);  // [PSS99] eq. 3, Y
    return vec3(x * Y / y, Y, (1.0 - x - y) * Y / y);   // xyY -> XYZ
}
