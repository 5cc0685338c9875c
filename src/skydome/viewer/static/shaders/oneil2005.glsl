// oneil2005: [ONe05] S. O'Neil, "Accurate Atmospheric Scattering", GPU Gems 2, ch. 16,
// SkyFromAtmosphere with the camera on the ground. Mirrors ONeil2005Sky._integrals and
// _colour; lengths in units of the atmosphere's thickness. u_spec[i] = (1/lambda^4 [um^-4],
// E_sun [W m^-2 nm^-1], 0, 0) per wavelength of skydome's default grid, u_cmf[i] = 683 x the
// CIE 1931 integration weights (SkyModel.xyz).

#define MAX_SAMPLES 16
uniform vec4 u_spec[NW];
uniform vec3 u_cmf[NW];
uniform float u_kr;
uniform float u_km;
uniform float u_g;
uniform float u_scale_depth;
uniform float u_outer_ratio;
uniform int u_samples;

// [ONe05] 16.4 scale(): scaleDepth exp(-0.00287 + x (0.459 + x (3.83 + x (-6.80 + x 5.25))))
float scale_polynomial(float cos_angle) {
    float x = 1.0 - cos_angle;
    return u_scale_depth * exp(-0.00287 + x * (0.459 + x * (3.83 + x * (-6.80 + x * 5.25))));
}

// [ONe05] 16.2 F(theta, g) (Cornette-Shanks form)
float _phase(float c, float g) {
    float g2 = g * g;
    return 1.5 * ((1.0 - g2) / (2.0 + g2)) * (1.0 + c * c) / pow(1.0 + g2 - 2.0 * g * c, 1.5);
}

vec3 sky_xyz(vec3 d) {
    float mu = d.z;
    if (mu <= 0.0) return vec3(0.0);                  // the view path is empty
    float R = 1.0 / (u_outer_ratio - 1.0);           // inner radius [thickness]
    float Ro = R + 1.0;
    float far = -R * mu + sqrt(Ro * Ro - R * R * (1.0 - mu * mu));  // camera at (0, 0, R)
    float start_offset = scale_polynomial(mu);       // depth at the camera is exp(0) = 1
    float seg = far / float(u_samples);              // fSampleLength
    vec3 cam = vec3(0.0, 0.0, R);
    float cos_theta = dot(d, u_sun);
    float fr = 0.75 * (1.0 + cos_theta * cos_theta); // F(theta, 0)
    float fm = _phase(-cos_theta, u_g);              // shaders: fCos = dot(sun, -view)
    vec3 xyz = vec3(0.0);
    for (int j = 0; j < MAX_SAMPLES; ++j) {
        if (j >= u_samples) break;
        float t = (float(j) + 0.5) * seg;
        vec3 P = cam + d * t;
        float height = length(P);
        float depth = exp((R - height) / u_scale_depth);           // fScaleOverScaleDepth
        float light_angle = dot(P, u_sun) / height;
        float camera_angle = dot(d, P) / height;
        float scatter = max(start_offset
                            + depth * (scale_polynomial(light_angle) - scale_polynomial(camera_angle)), 0.0);
        for (int i = 0; i < NW; ++i) {
            float inv_wl4 = u_spec[i].x;
            float k_ext = 4.0 * PI * (u_kr * inv_wl4 + u_km);       // fKr4PI/lambda^4 + fKm4PI
            float front = exp(-scatter * k_ext) * depth * seg;      // v3Attenuate x depth x seg
            // radiance = E_sun (F_R Kr/lambda^4 + F_M Km) front   ([ONe05] 16.2 I_v)
            xyz += u_spec[i].y * (fr * inv_wl4 * u_kr + fm * u_km) * front * u_cmf[i];
        }
    }
    return xyz;
}
