// skydome: the fitted sky model (skydome.models.fitted) in GLSL ES 3.00 / GLSL 3.30, over
// its bake (`skydome export luts --model fitted`: textures sky and sun, luts.json).
//
// The bake holds, for one atmosphere and observer altitude, the model's angular table in
// CIE XYZ at every sun elevation of its range (luts.json "elevation_axis"): one layer of
// the 2-D array texture `sky` per elevation, N_PHI texels wide (the azimuth from the sun's
// vertical plane) and N_SKY + N_GROUND high (the zenith angle: the sky's rows from the
// horizon up, then the ground's from the horizon down). skydomeFittedSky mirrors the CPU
// kernel skydome.models.fitted._kernels.lookup line for line (the inverse mappings of
// fitted._grid, then the Catmull-Rom spline through four rows along the zenith angle and
// linear weights between two columns in azimuth: eight texels, read with texelFetch, no
// hardware filtering) in the two layers around the sun's elevation, and interpolates
// between the layers geometrically (linearly in ln XYZ; linearly where a value is 0).
// Sampler state: any (texelFetch).
//
// The sun's disc (skydomeFittedSunDisc, skydomeFittedSkyWithSun): the transmitted sun's
// mean radiance (texture sun) times Neckel's (2005) centre-to-limb law per channel (the
// struct's limb, from luts.json), as skydome.render draws the disc into an XYZ image: its
// integral over the disc is the CPU model's sun_radiance x the disc's solid angle.
//
// Frame: East-North-Up (x east, y north, z up), unit vectors, azimuth from north towards
// east. Values: CIE 1931 XYZ, Y in cd m^-2, for a sun at 1 au, times irradianceScale
// (Sun.irradiance_scale = 1 / distance_au^2).

const float SKYDOME_FITTED_PI = 3.14159265358979;

// Fill from luts.json: view_grid.n_sky, n_ground, n_phi, theta_h_rad, inv_sky,
// inv_ground, eps_rad, a_phi; elevation_axis.first_deg, step_deg, count;
// sun_elevation_axis.first_deg, step_deg, count; sun.angular_radius_rad;
// sun.limb_darkening.coefficients_xyz (six rows: the X, Y, Z coefficients of mu^0..mu^5);
// irradianceScale from the sun's distance (1 at 1 au).
struct SkydomeFitted {
    int nSky;
    int nGround;
    int nPhi;
    float thetaH;             // the horizon's zenith angle [rad] (pi/2 + the dip)
    float invSky;             // 1 / (thetaH - eps)
    float invGround;          // 1 / (pi - thetaH - eps)
    float eps;                // the end nodes' distance from the horizon [rad]
    float aPhi;               // the linear share of the azimuth mapping
    float elevationFirstDeg;
    float elevationStepDeg;
    int elevationCount;
    float sunElevationFirstDeg;   // the sun texture's own (finer) axis
    float sunElevationStepDeg;
    int sunElevationCount;
    float sunAngularRadius;   // [rad]
    float irradianceScale;
    vec3 limb[6];             // I(mu) / I_mean = sum_k limb[k] mu^k per channel X, Y, Z
};

// the sun's elevation [deg] from its unit direction
float skydomeFittedSunElevationDeg(vec3 sunDir) {
    return degrees(atan(sunDir.z, length(sunDir.xy)));
}

// (node i0, node i1 = i0 + 1 or i0, fraction w) of an elevation on an axis of count
// nodes from first in steps of step [deg], clamped to its range
void skydomeFittedAxis(float first, float step, int count, float elevationDeg, out int i0,
                       out int i1, out float w) {
    float x = (elevationDeg - first) / step;
    x = clamp(x, 0.0, float(count - 1));
    i0 = min(int(x), max(count - 2, 0));
    i1 = min(i0 + 1, count - 1);
    w = x - float(i0);
}

// between two values of neighbouring elevations: geometric (linear in ln) where both are
// positive, linear where either is 0 (a value the model clamped to 0)
vec3 skydomeFittedBlend(vec3 a, vec3 b, float w) {
    vec3 geo = exp(mix(log(max(a, vec3(1e-30))), log(max(b, vec3(1e-30))), w));
    return mix(mix(a, b, w), geo, greaterThan(min(a, b), vec3(0.0)));
}

// one texel, interpolated between two layers
vec3 skydomeFittedTexel(sampler2DArray sky, int row, int col, int i0, int i1, float w) {
    return skydomeFittedBlend(texelFetch(sky, ivec3(col, row, i0), 0).rgb,
                              texelFetch(sky, ivec3(col, row, i1), 0).rgb, w);
}

// The Catmull-Rom spline's weights (Catmull & Rom 1974) of the four consecutive rows r0 ..
// r0 + 3 of a part of the grid (nu rows) for the cell iu at the fraction f: inside, the rows
// iu - 1 .. iu + 2; in the part's first and last cells the row beyond its end is the
// straight line through its two end rows, folded into the weights ([_kernels.lookup]).
void skydomeFittedRowWeights(int iu, int nu, float f, out int r0, out vec4 wr) {
    float f2 = f * f;
    float f3 = f2 * f;
    float wm = -0.5 * f3 + f2 - 0.5 * f;
    float w0 = 1.5 * f3 - 2.5 * f2 + 1.0;
    float w1 = -1.5 * f3 + 2.0 * f2 + 0.5 * f;
    float w2 = 0.5 * f3 - 0.5 * f2;
    bool lo = iu == 0;
    bool hi = iu == nu - 2;
    wr = lo ? vec4(w0 + 2.0 * wm, w1 - wm, w2, 0.0)
            : (hi ? vec4(0.0, wm, w0 - w2, w1 + 2.0 * w2) : vec4(wm, w0, w1, w2));
    r0 = lo ? 0 : (hi ? iu - 2 : iu - 1);
}

// The sky (and the ground below the horizon) seen from direction dir with the sun at
// sunDir: XYZ, Y in cd m^-2 ([_kernels.lookup]).
vec3 skydomeFittedSky(sampler2DArray sky, SkydomeFitted f, vec3 dir, vec3 sunDir) {
    int i0;
    int i1;
    float w;
    skydomeFittedAxis(f.elevationFirstDeg, f.elevationStepDeg, f.elevationCount,
                      skydomeFittedSunElevationDeg(sunDir), i0, i1, w);
    // the sun's azimuth (sin, cos); a sun at the zenith: azimuth 0
    float ns = length(sunDir.xy);
    float sinAz = ns > 0.0 ? sunDir.x / ns : 0.0;
    float cosAz = ns > 0.0 ? sunDir.y / ns : 1.0;
    // zenith angle: pi/2 - atan(z, rho) keeps float32's digits at the horizon
    float th = 0.5 * SKYDOME_FITTED_PI - atan(dir.z, length(dir.xy));
    bool isSky = th < f.thetaH;
    float uSky = sqrt(max(1.0 - th * f.invSky, 0.0)) * float(f.nSky - 1);
    float uGround = sqrt(max((th - f.thetaH - f.eps) * f.invGround, 0.0))
                  * float(f.nGround - 1);
    float u = isSky ? uSky : uGround;
    int base = isSky ? 0 : f.nSky;
    int nu = isSky ? f.nSky : f.nGround;
    int iu = min(int(u), nu - 2);
    float fu = u - float(iu);
    // azimuth from the sun's vertical plane, folded into [0, pi]
    float cp = dir.x * sinAz + dir.y * cosAz;
    float sp = abs(dir.x * cosAz - dir.y * sinAz);
    bool zero = sp == 0.0 && cp == 0.0;           // the zenith or the nadir: phi = 0
    float phi = (zero ? 0.0 : atan(sp, cp)) * (1.0 / SKYDOME_FITTED_PI);
    float a = f.aPhi;
    float b = 1.0 - f.aPhi;
    float t = (-a + sqrt(a * a + 4.0 * b * phi)) / (2.0 * b) * float(f.nPhi - 1);
    int it = min(int(t), f.nPhi - 2);
    float ft = max(t - float(it), 0.0);
    int r0;
    vec4 wr;
    skydomeFittedRowWeights(iu, nu, fu, r0, wr);
    vec3 xyz = vec3(0.0);
    for (int k = 0; k < 4; ++k) {
        int row = base + r0 + k;
        xyz += wr[k] * ((1.0 - ft) * skydomeFittedTexel(sky, row, it, i0, i1, w)
                        + ft * skydomeFittedTexel(sky, row, it + 1, i0, i1, w));
    }
    return max(xyz, vec3(0.0)) * f.irradianceScale;
}

// Fraction of the sun's disc above the observer's horizon
// (skydome.models.fitted.FittedSky.sun_visible_fraction).
float skydomeFittedSunVisibleFraction(SkydomeFitted f, float elevationRad) {
    // the reference's rule ([Bru17] GetTransmittanceToSun; FittedSky.sun_visible_fraction):
    // a smoothstep over the disc's radius in the sun's zenith cosine around the horizon's,
    // cos(thetaH) = -sqrt(1 - (R / r)^2), the radius there sin(thetaH) alpha
    float e = sin(f.thetaH) * f.sunAngularRadius;
    return smoothstep(0.0, 1.0, (sin(elevationRad) - cos(f.thetaH) + e) / (2.0 * e));
}

// The mean radiance of the sun's disc seen through the air: XYZ, Y in cd m^-2 (texture
// sun on its own axis, interpolated geometrically in elevation as the sky), over the parts
// of the disc above the horizon; its mean over the whole disc (FittedSky.sun_radiance) is
// skydomeFittedSunMeanRadiance; skydomeFittedSunDisc spreads it over the disc.
vec3 skydomeFittedSunRadiance(sampler2D sun, SkydomeFitted f, vec3 sunDir) {
    int i0;
    int i1;
    float w;
    skydomeFittedAxis(f.sunElevationFirstDeg, f.sunElevationStepDeg, f.sunElevationCount,
                      skydomeFittedSunElevationDeg(sunDir), i0, i1, w);
    return skydomeFittedBlend(texelFetch(sun, ivec2(i0, 0), 0).rgb,
                              texelFetch(sun, ivec2(i1, 0), 0).rgb, w) * f.irradianceScale;
}

// The disc's mean radiance, the visible fraction included (FittedSky.sun_radiance in XYZ).
vec3 skydomeFittedSunMeanRadiance(sampler2D sun, SkydomeFitted f, vec3 sunDir) {
    float e = atan(sunDir.z, length(sunDir.xy));
    return skydomeFittedSunRadiance(sun, f, sunDir) * skydomeFittedSunVisibleFraction(f, e);
}

// The sun's centre-to-limb darkening I(mu) / I_mean per channel at gamma [rad] from the
// disc's centre, as skydome.render draws the disc into an XYZ image ([Nec05] at 600, 555
// and 450 nm for X, Y, Z; its mean over the disc is 1); 0 outside the disc.
vec3 skydomeFittedLimbDarkening(SkydomeFitted f, float gamma) {
    float rho = sin(gamma) / sin(f.sunAngularRadius);   // distance from the centre [radii]
    float mu = sqrt(max(1.0 - rho * rho, 0.0));         // cos of the heliocentric angle
    vec3 I = f.limb[5];
    for (int k = 4; k >= 0; --k) I = I * mu + f.limb[k];    // Horner: sum_k limb[k] mu^k
    return gamma < f.sunAngularRadius ? max(I, vec3(0.0)) : vec3(0.0);
}

// Whether direction dir lies inside the sun's disc and above the horizon; gamma: its
// angle from the disc's centre [rad].
bool skydomeFittedInDisc(SkydomeFitted f, vec3 dir, vec3 sunDir, out float gamma) {
    gamma = atan(length(cross(dir, sunDir)), dot(dir, sunDir));
    float th = 0.5 * SKYDOME_FITTED_PI - atan(dir.z, length(dir.xy));
    return gamma < f.sunAngularRadius && th < f.thetaH;
}

// The sun's disc in direction dir: XYZ, Y in cd m^-2; the limb-darkened radiance of the
// disc seen through the air where dir lies inside the disc and above the horizon, else 0.
// Its integral over the disc is FittedSky.sun_radiance x the disc's solid angle.
vec3 skydomeFittedSunDisc(sampler2D sun, SkydomeFitted f, vec3 dir, vec3 sunDir) {
    float gamma;
    if (!skydomeFittedInDisc(f, dir, sunDir, gamma)) return vec3(0.0);
    return skydomeFittedSunRadiance(sun, f, sunDir) * skydomeFittedLimbDarkening(f, gamma);
}

// The sky with the sun's disc: inside the disc and above the horizon the disc's
// (limb-darkened) radiance replaces the sky, as skydome.render draws it.
vec3 skydomeFittedSkyWithSun(sampler2DArray sky, sampler2D sun, SkydomeFitted f, vec3 dir,
                             vec3 sunDir) {
    float gamma;
    if (skydomeFittedInDisc(f, dir, sunDir, gamma))
        return skydomeFittedSunRadiance(sun, f, sunDir) * skydomeFittedLimbDarkening(f, gamma);
    return skydomeFittedSky(sky, f, dir, sunDir);
}

// The sky with the sun's disc over a pixel's footprint, energy-true for a disc larger or
// smaller than the pixel (as skydome.render spreads the disc's flux over the pixels it
// covers): dirDx, dirDy are the view direction's change to the next pixel across and up
// (dFdx(dir), dFdy(dir), taken in uniform control flow). Near the disc the pixel is split
// into n x n parts (n = ceil(16 pixel / disc radius), 2..16); each part inside the disc
// and above the horizon replaces the sky it covers by the disc's radiance there, so the
// pixel gains the flux of the disc that falls into it.
vec3 skydomeFittedSkyWithSunPixel(sampler2DArray sky, sampler2D sun, SkydomeFitted f,
                                  vec3 dir, vec3 dirDx, vec3 dirDy, vec3 sunDir) {
    vec3 L = skydomeFittedSky(sky, f, dir, sunDir);
    float ps = max(length(dirDx), length(dirDy));        // the pixel's size [rad]
    float a = f.sunAngularRadius;
    float gamma = atan(length(cross(dir, sunDir)), dot(dir, sunDir));
    if (!(gamma < a + 1.5 * ps)) return L;
    int n = int(clamp(ceil(16.0 * ps / a), 2.0, 16.0));
    float cover = 0.0;
    vec3 acc = vec3(0.0);
    for (int i = 0; i < 16; ++i) {
        if (i >= n) break;
        for (int j = 0; j < 16; ++j) {
            if (j >= n) break;
            vec3 q = normalize(dir + ((float(i) + 0.5) / float(n) - 0.5) * dirDx
                               + ((float(j) + 0.5) / float(n) - 0.5) * dirDy);
            float g;
            if (skydomeFittedInDisc(f, q, sunDir, g)) {
                cover += 1.0;
                acc += skydomeFittedLimbDarkening(f, g);
            }
        }
    }
    float inv = 1.0 / float(n * n);
    return L * (1.0 - cover * inv) + skydomeFittedSunRadiance(sun, f, sunDir) * acc * inv;
}
