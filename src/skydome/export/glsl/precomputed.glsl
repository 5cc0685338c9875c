// skydome: rendering from the precomputed LUT bake (`skydome export luts --model precomputed`)
// in GLSL ES 3.00 / GLSL 3.30: the sky, the sun's disc, the ground and aerial perspective.
//
// The bake holds E. Bruneton's (2017) textures in CIE XYZ (luts.json describes them):
//   scattering            sampler3D  XYZ of Rayleigh single scattering (no phase function)
//   single_mie_scattering sampler3D  XYZ of single Mie scattering (no phase function)
//   multiple_scattering   sampler3D  XYZ of orders 2..N (radiance)
//   transmittance         sampler2D  XYZ-weighted transmittance to the top of the atmosphere
//   optical_depth         sampler2D  column of each constituent to the top [km] (RGBA = 4)
//   irradiance            sampler2D  XYZ of the sky's irradiance on a horizontal surface
//   irradiance_spectral   sampler2DArray  the same per table wavelength (4 per layer)
// Sampler state: LINEAR filtering, CLAMP_TO_EDGE, no mip maps. Node i of an axis of n nodes
// lies at the unit coordinate x = i / (n - 1), i.e. at the texture coordinate
// u = (x (n - 1) + 0.5) / n (the texel centres).
//
// Frame: any frame with the planet's centre at the origin; lengths in metres; directions
// unit vectors. Values: CIE 1931 XYZ, Y in cd m^-2, for a sun at 1 au (multiply by the sun's
// 1/d^2 factor). Convert to linear sRGB with luts.json "xyz_to_linear_srgb".
//
// The equations (written here from the papers, not taken from any implementation):
//   [BN08] E. Bruneton, F. Neyret, "Precomputed Atmospheric Scattering", EGSR 2008:
//          eq. 1-2 (transmittance T(x, y) = exp(-sum_c beta_e,c * column_c)), eq. 7-9 (the
//          radiance L = T L0 + S[L](x, v, s), single scattering stored without its phase).
//   [Bru17] E. Bruneton, "Precomputed Atmospheric Scattering: a New Implementation" (2017),
//          its documented functions GetSkyRadiance, GetSkyRadianceToPoint,
//          GetSunAndSkyIrradiance: the in-scattering between two points is
//          S(x) - T(x, y) S(y); the irradiance of a point is the transmitted sun times the
//          cosine plus the sky irradiance E times (1 + n.up) / 2.
// The mu and mu_s axes of the 4-D table are skydome's own mappings (luts.json "mappings";
// skydome.models.simulated.precomputed._mapping), not [Bru17]'s.

const float SKYDOME_PC_PI = 3.14159265358979;
// the mu axis' width (2 deg) and the mu_s axis' knee (92 deg) and width (6 deg) [rad]
const float SKYDOME_PC_MU_WIDTH = 0.0349065850398866;
const float SKYDOME_PC_MU_S_CENTRE = 1.6057029118347832;
const float SKYDOME_PC_MU_S_WIDTH = 0.10471975511965977;
// the largest number of table wavelengths the spectral functions take
const int SKYDOME_PC_MAX_WAVELENGTHS = 32;

// The atmosphere's constants (luts.json): fill once per bake.
struct SkydomeAtmosphere {
    float bottomRadius;         // R [m]: "bottom_radius_m"
    float topRadius;            // Rt [m]: "top_radius_m"
    float muSMin;               // "mu_s_min"
    float sunAngularRadius;     // [rad]: "sun"."angular_radius_rad"
    float sunSolidAngle;        // [sr]: "sun"."solid_angle_sr"
    vec3 solarIrradiance;       // XYZ [lx] at 1 au: "sun"."solar_irradiance_xyz"
    float rayleighGamma;        // "rayleigh"."gamma"
    int miePhaseCode;           // "mie"."phase_code": 1 Henyey-Greenstein, 2 Cornette-Shanks,
    float mieG;                 // 3 isotropic; "mie"."g"
    int nuSize;                 // "sizes"."nu" (the 4-D table's nu nodes)
    int nWavelengths;           // "n_wavelengths" (<= SKYDOME_PC_MAX_WAVELENGTHS)
    // per table wavelength j: beta_e of the constituents [km^-1] ("extinction_per_km"[c][j]
    // in channel c), the XYZ weight K_j ("xyz_weights"[j]) and the ground albedo
    vec4 extinction[SKYDOME_PC_MAX_WAVELENGTHS];
    vec3 xyzWeights[SKYDOME_PC_MAX_WAVELENGTHS];
    float groundAlbedo[SKYDOME_PC_MAX_WAVELENGTHS];
};

// -- geometry ([Bru17] "Distance to the top/bottom atmosphere boundary") ------------------------
// r^2 - R^2 and r^2 (mu^2 - 1) + R^2 as products of differences: no cancellation in float32
float skydomePcRho(float r, float R) {
    return sqrt(max((r - R) * (r + R), 0.0));
}

bool skydomePcHitsGround(float r, float mu, float R) {
    return mu < 0.0 && (r * mu) * (r * mu) - (r - R) * (r + R) >= 0.0;
}

float skydomePcDistanceToTop(float r, float mu, float Rt) {
    return max(-r * mu + sqrt(max((r * mu) * (r * mu) + (Rt - r) * (Rt + r), 0.0)), 0.0);
}

float skydomePcDistanceToGround(float r, float mu, float R) {
    return max(-r * mu - sqrt(max((r * mu) * (r * mu) - (r - R) * (r + R), 0.0)), 0.0);
}

// radius of the point at distance d along (r, mu), clamped to the shell
float skydomePcRadiusAlong(float r, float mu, float d, float R, float Rt) {
    return clamp(sqrt(max(d * d + 2.0 * r * mu * d + r * r, 0.0)), R, Rt);
}

// unit coordinate x in [0, 1] on an axis of n nodes -> texture coordinate of that point
float skydomePcUnitToTexel(float x, float n) {
    return (clamp(x, 0.0, 1.0) * (n - 1.0) + 0.5) / n;
}

// -- phase functions [sr^-1] ------------------------------------------------------------------
// Rayleigh with depolarisation (Hansen & Travis 1974 eq. 2.15), gamma = rho / (2 - rho)
float skydomeRayleighPhase(float gamma, float nu) {
    return 3.0 / (16.0 * SKYDOME_PC_PI) * ((1.0 + 3.0 * gamma) + (1.0 - gamma) * nu * nu)
        / (1.0 + 2.0 * gamma);
}

// Henyey-Greenstein (code 1), Cornette-Shanks (code 2), isotropic (otherwise)
float skydomeMiePhase(int code, float g, float nu) {
    float den = 1.0 + g * g - 2.0 * g * nu;
    float hg = (1.0 - g * g) / (den * sqrt(den)) / (4.0 * SKYDOME_PC_PI);
    if (code == 1) return hg;
    if (code == 2) return 3.0 / (2.0 * (2.0 + g * g)) * (1.0 + nu * nu) * hg;
    return 1.0 / (4.0 * SKYDOME_PC_PI);
}

// -- texture coordinates ----------------------------------------------------------------------
// [Bru17] GetTransmittanceTextureUvFromRMu (texture: rows r, columns mu)
vec2 skydomeTransmittanceUv(float r, float mu, float R, float Rt, vec2 size) {
    float H = sqrt((Rt - R) * (Rt + R));
    float rho = skydomePcRho(r, R);
    float d = skydomePcDistanceToTop(r, mu, Rt);
    float dMin = Rt - r;
    float dMax = rho + H;
    float xMu = dMax <= dMin ? 0.0 : clamp((d - dMin) / (dMax - dMin), 0.0, 1.0);
    return vec2(skydomePcUnitToTexel(xMu, size.x), skydomePcUnitToTexel(rho / H, size.y));
}

// the mu_s axis: x = (u(theta_max) - u(theta_s)) / (u(theta_max) - u(0)),
// u(theta) = asinh((theta - 92 deg) / 6 deg), theta_max = acos(mu_s_min)
float skydomePcMuSUnit(float muS, float muSMin) {
    float thMax = acos(clamp(muSMin, -1.0, 1.0));
    float th = min(acos(clamp(muS, -1.0, 1.0)), thMax);
    float top = asinh((thMax - SKYDOME_PC_MU_S_CENTRE) / SKYDOME_PC_MU_S_WIDTH);
    float zen = asinh((0.0 - SKYDOME_PC_MU_S_CENTRE) / SKYDOME_PC_MU_S_WIDTH);
    float u = asinh((th - SKYDOME_PC_MU_S_CENTRE) / SKYDOME_PC_MU_S_WIDTH);
    return clamp((top - u) / (top - zen), 0.0, 1.0);
}

// the irradiance table at (r, mu_s): rows r, linear in r ([Bru17]
// GetIrradianceTextureUvFromRMuS); columns mu_s on the sun mapping above (skydomePcMuSUnit,
// not [Bru17]'s (mu_s + 1) / 2). The twilight irradiance falls exponentially with the sun's
// depression, so the two mu_s nodes are read at their texel centres (filtered in r alone)
// and mixed geometrically by skydomeGeometricMix: uv0, uv1 the nodes, f the fraction
void skydomeIrradianceUv(float r, float muS, float R, float Rt, float muSMin, vec2 size,
                         out vec2 uv0, out vec2 uv1, out float f) {
    float x = skydomePcMuSUnit(muS, muSMin) * (size.x - 1.0);
    float i = min(floor(x), size.x - 2.0);
    f = x - i;
    float v = skydomePcUnitToTexel((r - R) / (Rt - R), size.y);
    uv0 = vec2((i + 0.5) / size.x, v);
    uv1 = vec2((i + 1.5) / size.x, v);
}

// lo (hi / lo)^f where both are positive (exact for a value exponential in mu_s), else
// linear
vec4 skydomeGeometricMix(vec4 lo, vec4 hi, float f) {
    vec4 geo = lo * exp(f * log(max(hi, vec4(1e-37)) / max(lo, vec4(1e-37))));
    return mix(mix(lo, hi, f), geo, vec4(greaterThan(min(lo, hi), vec4(0.0))));
}

// the mu axis: x = asinh(e / w) / asinh(e_max / w) on the ray's half, e the angle from the
// local horizon (whose dip below the horizontal is atan(rho / R)), 0 at the horizon
float skydomePcMuUnit(float r, float mu, bool ground, float R) {
    float dip = atan(skydomePcRho(r, R), R);
    float a = asin(clamp(mu, -1.0, 1.0));
    float e = ground ? -dip - a : a + dip;
    float eMax = ground ? 0.5 * SKYDOME_PC_PI - dip : 0.5 * SKYDOME_PC_PI + dip;
    float top = asinh(max(eMax, 0.0) / SKYDOME_PC_MU_WIDTH);
    if (top <= 0.0) return 0.0;
    return clamp(asinh(max(e, 0.0) / SKYDOME_PC_MU_WIDTH) / top, 0.0, 1.0);
}

// (continuous nu node, u of mu_s inside a nu block, v of mu, w of r) of the 4-D table packed
// as width = n_nu * n_mu_s, height = n_mu, depth = n_r ([Bru17] GetScattering's packing);
// ground rays on the first half of the mu axis (horizon .. nadir), sky rays on the second
// (zenith .. horizon), each looked up inside its half
vec4 skydomeScatteringUvwz(float r, float mu, float muS, float nu, bool ground,
                           SkydomeAtmosphere atm, vec3 size) {
    float R = atm.bottomRadius;
    float Rt = atm.topRadius;
    float nNu = float(atm.nuSize);
    float nMuS = size.x / nNu;
    float nMu = size.y;
    float half_ = floor(0.5 * nMu);
    float H = sqrt((Rt - R) * (Rt + R));
    float w = skydomePcUnitToTexel(skydomePcRho(r, R) / H, size.z);
    float xMu = skydomePcMuUnit(r, mu, ground, R);
    float fMu = ground ? xMu * (half_ - 1.0) : half_ + (1.0 - xMu) * (half_ - 1.0);
    float v = (fMu + 0.5) / nMu;
    float u = skydomePcUnitToTexel(skydomePcMuSUnit(muS, atm.muSMin), nMuS);
    float fNu = clamp(0.5 * (nu + 1.0), 0.0, 1.0) * (nNu - 1.0);
    return vec4(fNu, u, v, w);
}

// the 4-D look-up: two nu blocks filtered in hardware (mu_s, mu, r), mixed by hand in nu
vec3 skydomeLookup4D(sampler3D tex, vec4 uvwz, float nNu) {
    float i = min(floor(uvwz.x), nNu - 2.0);
    float f = uvwz.x - i;
    vec3 a = texture(tex, vec3((i + uvwz.y) / nNu, uvwz.z, uvwz.w)).rgb;
    vec3 b = texture(tex, vec3((i + 1.0 + uvwz.y) / nNu, uvwz.z, uvwz.w)).rgb;
    return a * (1.0 - f) + b * f;
}

// -- transmittance ([BN08] eq. 1-2) -----------------------------------------------------------
// XYZ-weighted transmittance to the top; 0 where the ray meets the ground
vec3 skydomeTransmittanceToTop(sampler2D transmittance, SkydomeAtmosphere atm, float r,
                               float mu) {
    if (skydomePcHitsGround(r, mu, atm.bottomRadius)) return vec3(0.0);
    vec2 size = vec2(textureSize(transmittance, 0));
    return texture(transmittance, skydomeTransmittanceUv(r, mu, atm.bottomRadius,
                                                         atm.topRadius, size)).rgb;
}

// columns of the constituents from (r, mu) to the top [km at reference density]
vec4 skydomeColumns(sampler2D opticalDepth, SkydomeAtmosphere atm, float r, float mu) {
    vec2 size = vec2(textureSize(opticalDepth, 0));
    return texture(opticalDepth, skydomeTransmittanceUv(r, mu, atm.bottomRadius,
                                                        atm.topRadius, size));
}

// transmittance from (r, mu) over a distance d, per XYZ channel weighted by the sun's
// spectrum (sum_j K_j T_j / sum_j K_j): T_j = exp(-beta_e,j . (columns of the segment))
// ([BN08] eq. 1-2), the columns the difference of two columns to the top ([Bru17]
// GetTransmittance; a ground ray's both rays reversed). Differences of columns stay
// accurate near the horizon, where a ratio of two interpolated transmittances does not.
vec3 skydomeTransmittanceAlong(sampler2D opticalDepth, SkydomeAtmosphere atm, float r,
                               float mu, float d, bool ground) {
    float rd = skydomePcRadiusAlong(r, mu, d, atm.bottomRadius, atm.topRadius);
    float mud = clamp((r * mu + d) / rd, -1.0, 1.0);
    vec4 c;
    if (ground) {
        c = skydomeColumns(opticalDepth, atm, rd, -mud) - skydomeColumns(opticalDepth, atm, r, -mu);
    } else {
        c = skydomeColumns(opticalDepth, atm, r, mu) - skydomeColumns(opticalDepth, atm, rd, mud);
    }
    c = max(c, vec4(0.0));
    vec3 t = vec3(0.0);
    for (int j = 0; j < SKYDOME_PC_MAX_WAVELENGTHS; ++j) {
        if (j >= atm.nWavelengths) break;
        t += atm.xyzWeights[j] * exp(-dot(atm.extinction[j], c));
    }
    return min(t / atm.solarIrradiance, vec3(1.0));
}

// -- the sun ----------------------------------------------------------------------------------
// fraction of the sun's disc above the horizon seen from radius r (smoothstep over the disc)
float skydomeSunVisibleFraction(float r, float muS, SkydomeAtmosphere atm) {
    float sinH = atm.bottomRadius / r;
    float cosH = -sqrt(max(1.0 - sinH * sinH, 0.0));
    float e = sinH * atm.sunAngularRadius;
    float x = clamp((muS - cosH + e) / (2.0 * e), 0.0, 1.0);
    return x * x * (3.0 - 2.0 * x);
}

// radiance of the sun's disc seen from radius r with the sun at mu_s, XYZ [cd m^-2]: the
// disc's radiance above the atmosphere times the spectral transmittance ([BN08] eq. 1-2,
// from the columns: exact), reduced with the XYZ weights
vec3 skydomeSunRadiance(sampler2D opticalDepth, SkydomeAtmosphere atm, float r, float muS) {
    vec4 col = skydomeColumns(opticalDepth, atm, r, muS);
    vec3 xyz = vec3(0.0);
    for (int j = 0; j < SKYDOME_PC_MAX_WAVELENGTHS; ++j) {
        if (j >= atm.nWavelengths) break;
        xyz += atm.xyzWeights[j] * exp(-dot(atm.extinction[j], col));
    }
    return xyz * skydomeSunVisibleFraction(r, muS, atm) / atm.sunSolidAngle;
}

// the same from the XYZ-weighted transmittance texture (one fetch; exact per XYZ channel)
vec3 skydomeSunRadianceXYZ(sampler2D transmittance, SkydomeAtmosphere atm, float r,
                           float muS) {
    vec2 size = vec2(textureSize(transmittance, 0));
    vec3 t = texture(transmittance, skydomeTransmittanceUv(r, muS, atm.bottomRadius,
                                                           atm.topRadius, size)).rgb;
    return atm.solarIrradiance / atm.sunSolidAngle * t * skydomeSunVisibleFraction(r, muS, atm);
}

// -- sky radiance ([Bru17] GetSkyRadiance) ----------------------------------------------------
// in-scattered radiance at radius r towards (mu, mu_s, nu) [cd m^-2]: single Rayleigh
// times P_R, single Mie times P_M ([BN08] eq. 7-9: single scattering stored without its
// phase function) and orders 2..N
vec3 skydomeScatteredRadiance(sampler3D scattering, sampler3D singleMie,
                              sampler3D multiple, SkydomeAtmosphere atm, float r, float mu,
                              float muS, float nu, bool ground) {
    vec4 uvwz = skydomeScatteringUvwz(r, mu, muS, nu, ground, atm,
                                      vec3(textureSize(scattering, 0)));
    float nNu = float(atm.nuSize);
    vec3 s = skydomeLookup4D(scattering, uvwz, nNu);
    vec3 m = skydomeLookup4D(singleMie, uvwz, nNu);
    return s * skydomeRayleighPhase(atm.rayleighGamma, nu)
        + m * skydomeMiePhase(atm.miePhaseCode, atm.mieG, nu)
        + skydomeLookup4D(multiple, uvwz, nNu);
}

// the sky's radiance from the camera (position from the planet's centre) along viewRay,
// XYZ [cd m^-2], without the sun's disc and the ground; transmittance to the top (0 for a
// ray that meets the ground). A camera above the atmosphere is moved to where the ray
// enters it ([Bru17] GetSkyRadiance).
vec3 skydomeSkyRadiance(sampler3D scattering, sampler3D singleMie, sampler3D multiple,
                        sampler2D transmittance, SkydomeAtmosphere atm, vec3 camera,
                        vec3 viewRay, vec3 sunDir, out vec3 transmittanceToTop) {
    float r = length(camera);
    float rmu = dot(camera, viewRay);
    float Rt = atm.topRadius;
    if (r > Rt) {
        float disc = rmu * rmu - (r - Rt) * (r + Rt);
        float d = -rmu - sqrt(max(disc, 0.0));
        if (disc < 0.0 || d < 0.0) {
            transmittanceToTop = vec3(1.0);
            return vec3(0.0);
        }
        camera += d * viewRay;
        r = Rt;
        rmu += d;
    }
    float mu = clamp(rmu / r, -1.0, 1.0);
    float muS = clamp(dot(camera, sunDir) / r, -1.0, 1.0);
    float nu = clamp(dot(viewRay, sunDir), -1.0, 1.0);
    bool ground = skydomePcHitsGround(r, mu, atm.bottomRadius);
    transmittanceToTop = skydomeTransmittanceToTop(transmittance, atm, r, mu);
    return skydomeScatteredRadiance(scattering, singleMie, multiple, atm, r, mu, muS, nu,
                                    ground);
}

// -- ground ([Bru17] GetSunAndSkyIrradiance; [BN08] eq. 1-2) ------------------------------------
// XYZ irradiance [lx] of a surface at point (from the planet's centre) with the given
// normal: the sun's (transmitted, times the cosine, times the disc's visible fraction) and,
// in skyIrradiance, the sky's (the table's horizontal irradiance times (1 + n.up) / 2)
vec3 skydomeSunAndSkyIrradiance(sampler2D transmittance, sampler2D irradiance,
                                SkydomeAtmosphere atm, vec3 point, vec3 normal, vec3 sunDir,
                                out vec3 skyIrradiance) {
    float r = length(point);
    float muS = clamp(dot(point, sunDir) / r, -1.0, 1.0);
    vec2 size = vec2(textureSize(irradiance, 0));
    vec2 uv0, uv1;
    float fe;
    skydomeIrradianceUv(r, muS, atm.bottomRadius, atm.topRadius, atm.muSMin, size, uv0, uv1, fe);
    skyIrradiance = skydomeGeometricMix(texture(irradiance, uv0), texture(irradiance, uv1),
                                        fe).rgb
        * (1.0 + dot(normal, point) / r) * 0.5;
    vec2 tsize = vec2(textureSize(transmittance, 0));
    vec3 t = texture(transmittance, skydomeTransmittanceUv(r, muS, atm.bottomRadius,
                                                           atm.topRadius, tsize)).rgb;
    return atm.solarIrradiance * t * skydomeSunVisibleFraction(r, muS, atm)
        * max(dot(normal, sunDir), 0.0);
}

// radiance of the Lambertian ground (the bake's albedo) seen from the camera along viewRay,
// through the air in front of it, XYZ [cd m^-2]; 0 for a ray that misses the ground. Per
// table wavelength j: T_view,j albedo_j / pi (f T_sun,j + E_j), f the sun's cosine averaged
// over its disc, the transmittances from the columns and E_j from irradiance_spectral;
// summed with the XYZ weights K_j (the spectral product is not separable in XYZ).
vec3 skydomeGroundRadiance(sampler2D opticalDepth, sampler2DArray irradianceSpectral,
                           SkydomeAtmosphere atm, vec3 camera, vec3 viewRay, vec3 sunDir) {
    float R = atm.bottomRadius;
    float Rt = atm.topRadius;
    float r = length(camera);
    float mu = clamp(dot(camera, viewRay) / r, -1.0, 1.0);
    float muS = clamp(dot(camera, sunDir) / r, -1.0, 1.0);
    float nu = clamp(dot(viewRay, sunDir), -1.0, 1.0);
    if (!skydomePcHitsGround(r, mu, R)) return vec3(0.0);
    float dg = skydomePcDistanceToGround(r, mu, R);
    float muG = clamp((r * muS + dg * nu) / R, -1.0, 1.0);
    float alpha = atm.sunAngularRadius;
    float f = muG < -alpha ? 0.0
        : (muG > alpha ? muG : (muG + alpha) * (muG + alpha) / (4.0 * alpha));
    vec4 cSun = skydomeColumns(opticalDepth, atm, R, muG);
    float rd = skydomePcRadiusAlong(r, mu, dg, R, Rt);
    float mud = clamp((r * mu + dg) / rd, -1.0, 1.0);
    vec4 cView = max(skydomeColumns(opticalDepth, atm, rd, -mud)
                     - skydomeColumns(opticalDepth, atm, r, -mu), vec4(0.0));
    vec3 isize = vec3(textureSize(irradianceSpectral, 0));
    vec2 uv0, uv1;
    float fe;
    skydomeIrradianceUv(R, muG, R, Rt, atm.muSMin, isize.xy, uv0, uv1, fe);
    vec3 xyz = vec3(0.0);
    for (int k = 0; k < SKYDOME_PC_MAX_WAVELENGTHS / 4; ++k) {
        if (4 * k >= atm.nWavelengths) break;
        vec4 e = skydomeGeometricMix(texture(irradianceSpectral, vec3(uv0, float(k))),
                                     texture(irradianceSpectral, vec3(uv1, float(k))), fe);
        for (int c = 0; c < 4; ++c) {
            int j = 4 * k + c;
            if (j >= atm.nWavelengths) break;
            float tSun = exp(-dot(atm.extinction[j], cSun));
            float tView = exp(-dot(atm.extinction[j], cView));
            xyz += atm.xyzWeights[j] * (tView * atm.groundAlbedo[j] / SKYDOME_PC_PI
                                        * (f * tSun + e[c]));
        }
    }
    return xyz;
}

// everything the camera sees along viewRay but the sun's disc: the sky and, for a ray that
// meets it, the ground behind the air; 0 with the sun below mu_s_min (night)
vec3 skydomeRadiance(sampler3D scattering, sampler3D singleMie, sampler3D multiple,
                     sampler2D transmittance, sampler2D opticalDepth,
                     sampler2DArray irradianceSpectral, SkydomeAtmosphere atm, vec3 camera,
                     vec3 viewRay, vec3 sunDir) {
    float r = length(camera);
    if (dot(camera, sunDir) / r < atm.muSMin) return vec3(0.0);
    vec3 t;
    vec3 sky = skydomeSkyRadiance(scattering, singleMie, multiple, transmittance, atm, camera,
                                  viewRay, sunDir, t);
    return max(sky + skydomeGroundRadiance(opticalDepth, irradianceSpectral, atm, camera,
                                           viewRay, sunDir), vec3(0.0));
}

// -- aerial perspective ([Bru17] GetSkyRadianceToPoint) ---------------------------------------
// in-scattered radiance between the camera and point, XYZ [cd m^-2], S(camera) - T S(point)
// ([BN08] eq. 7-9 over the segment), each phase term apart; transmittance (XYZ-weighted,
// skydomeTransmittanceAlong) in transmittanceOut: T S(point) in XYZ is the three-channel
// approximation of the spectral product. An object of radiance L0 appears as
// transmittanceOut * L0 + the result. The distance is clamped to the end of the ray (ground
// or top of the atmosphere).
vec3 skydomeSkyRadianceToPoint(sampler3D scattering, sampler3D singleMie,
                               sampler3D multiple, sampler2D opticalDepth,
                               SkydomeAtmosphere atm, vec3 camera, vec3 point, vec3 sunDir,
                               out vec3 transmittanceOut) {
    float R = atm.bottomRadius;
    float Rt = atm.topRadius;
    vec3 viewRay = normalize(point - camera);
    float d = length(point - camera);
    float r = length(camera);
    float rmu = dot(camera, viewRay);
    if (r > Rt) {
        float disc = rmu * rmu - (r - Rt) * (r + Rt);
        float dIn = -rmu - sqrt(max(disc, 0.0));
        if (disc < 0.0 || dIn < 0.0) {
            transmittanceOut = vec3(1.0);
            return vec3(0.0);
        }
        camera += dIn * viewRay;
        d -= dIn;
        r = Rt;
        rmu += dIn;
    }
    float mu = clamp(rmu / r, -1.0, 1.0);
    float muS = clamp(dot(camera, sunDir) / r, -1.0, 1.0);
    float nu = clamp(dot(viewRay, sunDir), -1.0, 1.0);
    bool ground = skydomePcHitsGround(r, mu, R);
    float dEnd = ground ? skydomePcDistanceToGround(r, mu, R)
                        : skydomePcDistanceToTop(r, mu, Rt);
    d = clamp(d, 0.0, dEnd);
    transmittanceOut = skydomeTransmittanceAlong(opticalDepth, atm, r, mu, d, ground);
    vec3 size = vec3(textureSize(scattering, 0));
    float nNu = float(atm.nuSize);
    vec4 uvwz0 = skydomeScatteringUvwz(r, mu, muS, nu, ground, atm, size);
    vec3 s = skydomeLookup4D(scattering, uvwz0, nNu);
    vec3 m = skydomeLookup4D(singleMie, uvwz0, nNu);
    vec3 n = skydomeLookup4D(multiple, uvwz0, nNu);
    if (d < dEnd) {
        float rp = skydomePcRadiusAlong(r, mu, d, R, Rt);
        float mup = clamp((r * mu + d) / rp, -1.0, 1.0);
        float muSp = clamp((r * muS + d * nu) / rp, -1.0, 1.0);
        vec4 uvwz1 = skydomeScatteringUvwz(rp, mup, muSp, nu, ground, atm, size);
        s -= transmittanceOut * skydomeLookup4D(scattering, uvwz1, nNu);
        m -= transmittanceOut * skydomeLookup4D(singleMie, uvwz1, nNu);
        n -= transmittanceOut * skydomeLookup4D(multiple, uvwz1, nNu);
    }
    return max(s * skydomeRayleighPhase(atm.rayleighGamma, nu)
               + m * skydomeMiePhase(atm.miePhaseCode, atm.mieG, nu) + n, vec3(0.0));
}

// -- orders 2..N at the observer: the scattering density integrated along the view ray -------
// The CPU model does not read orders 2..N from the 4-D table for the observer's sky: it
// integrates the scattering density J of orders 2..N ([BN08] eq. 7, summed over the orders)
// along each view ray ([BN08] eq. 8),
//   L_ms(x, v) = int_0^d sum_k rho_k(r_t) J_k(theta, phi, r_t, mu_s_t) T(x, x_t) dt,
// on a sky map of the observer's view directions (view zenith angle x azimuth from the
// sun's), then interpolates that map. The bake holds J (texture "scattering_density",
// spectral, four table wavelengths per texel) and these functions do the same: render the
// sky map once per sun and observer altitude (skydomeSkyMapTexel, one texel per fragment
// of a mapPhi x (mapGround + mapSky) target), then read it (skydomeSkyMapLookup) in
// skydomeRadianceMapped and skydomeSkyRadianceToPointMapped. skydomeMultipleScatteringAlong
// integrates one ray; it can also be called per pixel (no map).
const int SKYDOME_PC_MAX_SAMPLES = 64;

// The scattering density's constants (luts.json "scattering_density"): fill once per bake.
struct SkydomeScatteringDensity {
    int nTheta;             // "theta": angle from the sun, nodes uniform over [0, pi]
    int nPhi;               // "phi": azimuth about the sun from its vertical plane (zenith
                            // side), nodes uniform over [0, pi]
    int nR;                 // "r": the r mapping of the 4-D table (rho / H)
    int nMuS;               // "mu_s": the mu_s mapping of the 4-D table
    int nScatterers;        // "scatterers": J's constituents k (<= 4)
    int blockColumns;       // "block_columns": blocks per row of the packed texture
    int scatterer[4];       // "scatterer_constituent"[k]: k's constituent (profile index)
    int profileCode[4];     // per constituent c: 0 exponential exp(-h / p0), 1 tent
    float profileP0[4];     // max(0, 1 - |h - p0| / p1), 2 uniform (1 below p0),
    float profileP1[4];     // 3 gaussian exp(-((h - p0) / p1)^2 / 2) [m]
    int nConstituents;      // "constituents": entries of the profile arrays in use (<= 4)
    int columnNodes;        // "column_nodes": 6 to integrate each ray's columns along the
                            // ray itself (the model's observer_columns), 0 to take the
                            // difference of two columns to the top from opticalDepth
    int samples;            // "quadrature"."samples": nodes per piece of a ray
    float scale;            // "quadrature"."scale_m": ts [m]
    int mapGround;          // "sky_map"."ground": zenith nodes of rays to the ground
    int mapSky;             // "sky_map"."sky": zenith nodes of rays to the sky
    int mapPhi;             // "sky_map"."phi": azimuth nodes over [0, pi]
    float mapGroundLinear;  // "sky_map"."ground_linear", "sky_linear": the linear share a
    float mapSkyLinear;     // of the rows' mapping u(x) = a x + (1 - a) x^2 from the horizon
};

// ln(1 + x) and exp(x) - 1 without cancellation for small x (GLSL has neither)
float skydomePcLog1p(float x) {
    return abs(x) < 1e-4 ? x * (1.0 - 0.5 * x) : log(1.0 + x);
}

float skydomePcExpm1(float x) {
    return abs(x) < 1e-4 ? x * (1.0 + 0.5 * x) : exp(x) - 1.0;
}

// relative density of a constituent at altitude h [m] (skydome.atmosphere.profiles)
float skydomePcProfile(int code, float p0, float p1, float h) {
    if (code == 0) return exp(-max(h, 0.0) / p0);
    if (code == 1) return max(0.0, 1.0 - abs(h - p0) / p1);
    if (code == 2) return h < p0 ? 1.0 : 0.0;
    if (code == 3) {
        float x = (h - p0) / p1;
        return exp(-0.5 * x * x);
    }
    return 0.0;
}

// the 6-point Gauss-Legendre rule on [0, 1] (nodes (1 + xi) / 2, weights w / 2 of the
// rule on [-1, 1]: xi = +-0.2386191860831969, +-0.6612093864662645, +-0.9324695142031521,
// w = 0.4679139345726910, 0.3607615730481386, 0.1713244923791704; Abramowitz & Stegun
// table 25.4) that integrates a ray's columns between two of its nodes (columnNodes = 6)
const float SKYDOME_PC_GL6_X[6] = float[6](0.033765242898423975, 0.16939530676686776,
    0.3806904069584016, 0.6193095930415985, 0.8306046932331322, 0.966234757101576);
const float SKYDOME_PC_GL6_W[6] = float[6](0.0856622461895852, 0.1803807865240693,
    0.2339569672863455, 0.2339569672863455, 0.1803807865240693, 0.0856622461895852);

// the constituents' columns [m at reference density] between the distances t0 and t1
// along the ray from radius r, zenith cosine mu (the model's _lookup.columns_along):
// the 6-point rule over [t0, t1] of each profile in use (nConstituents of them)
vec4 skydomePcColumnsAlong(SkydomeScatteringDensity dens, float r, float mu, float t0,
                           float t1, float R, float Rt) {
    vec4 col = vec4(0.0);
    float h = t1 - t0;
    if (h <= 0.0) return col;
    for (int i = 0; i < 6; ++i) {
        float alt = skydomePcRadiusAlong(r, mu, t0 + SKYDOME_PC_GL6_X[i] * h, R, Rt) - R;
        for (int c = 0; c < 4; ++c) {
            if (c >= dens.nConstituents) break;
            col[c] += SKYDOME_PC_GL6_W[i] * h * skydomePcProfile(dens.profileCode[c],
                                                                dens.profileP0[c],
                                                                dens.profileP1[c], alt);
        }
    }
    return col;
}

// node k of the quadrature on the piece [a, b] of a ray, dense at b (denseAtB) or at a: the
// midpoint rule in v = ln(1 + u / ts), u the distance from the dense end, n nodes,
// u_k = ts (exp((k + 1/2) dv) - 1), weight (u_k + ts) dv, dv = ln(1 + (b - a) / ts) / n;
// returns (distance along the ray, weight) [m]
vec2 skydomePcPieceNode(float a, float b, bool denseAtB, int k, int n, float ts) {
    float dv = skydomePcLog1p((b - a) / ts) / float(n);
    float u = ts * skydomePcExpm1((float(k) + 0.5) * dv);
    return vec2(denseAtB ? b - u : a + u, (u + ts) * dv);
}

// optical depths of the table wavelengths 4 l .. 4 l + 3 for the columns col [km]
vec4 skydomePcTau4(SkydomeAtmosphere atm, int l, vec4 col) {
    vec4 tau;
    for (int c = 0; c < 4; ++c) {
        tau[c] = dot(atm.extinction[min(4 * l + c, SKYDOME_PC_MAX_WAVELENGTHS - 1)], col);
    }
    return tau;
}

// texture coordinate in the packed scattering density of block b (((theta node) *
// nScatterers + k) * layers + layer) at the continuous nodes (fMuS, fR, fPhi): blocks of
// nMuS x nR x nPhi texels, blockColumns of them along x, the rest in slabs along z
vec3 skydomePcDensityUvw(SkydomeScatteringDensity dens, int b, float fMuS, float fR,
                         float fPhi, vec3 size) {
    int bx = b % dens.blockColumns;
    int bz = b / dens.blockColumns;
    return vec3((float(bx * dens.nMuS) + fMuS + 0.5) / size.x, (fR + 0.5) / size.y,
                (float(bz * dens.nPhi) + fPhi + 0.5) / size.z);
}

// orders 2..N arriving at radius r along the ray of zenith cosine mu (to the ground where
// ground is set, else to the top), the sun at zenith cosine muS and at cosine nu from the
// ray: XYZ [cd m^-2]. Per table wavelength j, sum over the quadrature nodes t_q of
// w_q T_j(x, x_q) sum_k rho_k(r_q) J_k,j(theta, phi_q, r_q, mu_s_q) ([BN08] eq. 8), T from
// the columns from x to x_q: with columnNodes = 6 integrated along the ray itself from
// node to node in order of distance (skydomePcColumnsAlong; the model's observer_columns:
// the difference below steps where an observer inside haze crosses an r node of the
// column table), else the difference of two columns to the top (both rays reversed for a
// ray to the ground, [Bru17] GetTransmittance); rho_k the exact density profile, J
// interpolated linearly in each of its four axes (theta by hand, the others in hardware),
// then the XYZ weights K_j.
vec3 skydomeMultipleScatteringAlong(sampler3D density, sampler2D opticalDepth,
                                    SkydomeAtmosphere atm, SkydomeScatteringDensity dens,
                                    float r, float mu, float muS, float nu, bool ground) {
    float R = atm.bottomRadius;
    float Rt = atm.topRadius;
    float H = sqrt((Rt - R) * (Rt + R));
    vec3 size = vec3(textureSize(density, 0));
    int layers = (atm.nWavelengths + 3) / 4;
    float d = ground ? skydomePcDistanceToGround(r, mu, R)
                     : skydomePcDistanceToTop(r, mu, Rt);
    float tLow = clamp(-r * mu, 0.0, d);
    float fTheta = clamp(acos(clamp(nu, -1.0, 1.0)) / SKYDOME_PC_PI * float(dens.nTheta - 1),
                         0.0, float(dens.nTheta - 1));
    int it = min(int(fTheta), dens.nTheta - 2);
    float jb = fTheta - float(it);
    // the observer's columns to the top: read only where the ray's columns are differences
    // of the table's (columnNodes 0)
    vec4 c0 = dens.columnNodes > 0 ? vec4(0.0)
                                   : skydomeColumns(opticalDepth, atm, r, ground ? -mu : mu);
    vec4 acc[SKYDOME_PC_MAX_WAVELENGTHS / 4];
    for (int l = 0; l < SKYDOME_PC_MAX_WAVELENGTHS / 4; ++l) acc[l] = vec4(0.0);
    // the ray's pieces as the model's (transport/_quadrature.py, ray_nodes): from the start
    // to the lowest point on two halves, the first dense at the start (none below 4
    // samples), the second at the lowest point, then from the lowest point to the end,
    // dense at its start; samples nodes each, visited in order of distance (the second
    // piece's from its last node) so that the columns accumulate from node to node
    int n0 = dens.samples >= 4 ? dens.samples : 0;
    vec4 colAlong = vec4(0.0);      // columns from the observer to tPrev [m]
    float tPrev = 0.0;
    float hm = 0.5 * tLow;
    for (int piece = 0; piece < 3; ++piece) {
        float a = piece == 0 ? 0.0 : (piece == 1 ? (n0 > 0 ? hm : 0.0) : tLow);
        float b = piece == 0 ? hm : (piece == 1 ? tLow : d);
        int n = piece == 0 ? n0 : dens.samples;
        if (b - a <= 0.0 || n <= 0) continue;
        for (int q = 0; q < SKYDOME_PC_MAX_SAMPLES; ++q) {
            if (q >= n) break;
            vec2 node = skydomePcPieceNode(a, b, piece == 1, piece == 1 ? n - 1 - q : q, n,
                                           dens.scale);
            float t = node.x;
            float rt = skydomePcRadiusAlong(r, mu, t, R, Rt);
            float mt = clamp((r * mu + t) / rt, -1.0, 1.0);
            float muSt = clamp((r * muS + t * nu) / rt, -1.0, 1.0);
            vec4 col;
            if (dens.columnNodes > 0) {
                colAlong += skydomePcColumnsAlong(dens, r, mu, tPrev, t, R, Rt);
                tPrev = max(tPrev, t);
                col = colAlong * 1e-3;      // km, the unit of extinction's km^-1
            } else {
                vec4 c1 = skydomeColumns(opticalDepth, atm, rt, ground ? -mt : mt);
                col = max(ground ? c1 - c0 : c0 - c1, vec4(0.0));
            }
            float fR = clamp(skydomePcRho(rt, R) / H * float(dens.nR - 1), 0.0,
                             float(dens.nR - 1));
            float fMuS = skydomePcMuSUnit(muSt, atm.muSMin) * float(dens.nMuS - 1);
            float den = sqrt(max((1.0 - nu * nu) * (1.0 - muSt * muSt), 0.0));
            float cphi = den < 1e-9 ? 1.0 : clamp((mt - nu * muSt) / den, -1.0, 1.0);
            float fPhi = clamp(acos(cphi) / SKYDOME_PC_PI * float(dens.nPhi - 1), 0.0,
                               float(dens.nPhi - 1));
            float rho[4];
            for (int k = 0; k < 4; ++k) {
                rho[k] = 0.0;
                if (k >= dens.nScatterers) continue;
                int cI = dens.scatterer[k];
                rho[k] = skydomePcProfile(dens.profileCode[cI], dens.profileP0[cI],
                                          dens.profileP1[cI], rt - R);
            }
            for (int l = 0; l < SKYDOME_PC_MAX_WAVELENGTHS / 4; ++l) {
                if (l >= layers) break;
                vec4 tau = skydomePcTau4(atm, l, col);
                vec4 j = vec4(0.0);
                for (int k = 0; k < 4; ++k) {
                    if (k >= dens.nScatterers) break;
                    int b0 = ((it * dens.nScatterers) + k) * layers + l;
                    int b1 = (((it + 1) * dens.nScatterers) + k) * layers + l;
                    vec4 j0 = texture(density,
                                      skydomePcDensityUvw(dens, b0, fMuS, fR, fPhi, size));
                    vec4 j1 = texture(density,
                                      skydomePcDensityUvw(dens, b1, fMuS, fR, fPhi, size));
                    j += rho[k] * (j0 * (1.0 - jb) + j1 * jb);
                }
                acc[l] += node.y * exp(-tau) * j;
            }
        }
    }
    vec3 xyz = vec3(0.0);
    for (int j = 0; j < SKYDOME_PC_MAX_WAVELENGTHS; ++j) {
        if (j >= atm.nWavelengths) break;
        xyz += atm.xyzWeights[j] * acc[j / 4][j % 4];
    }
    return xyz;
}

// the rows' mapping of the sky map (the model's _multiple.map_nodes): x uniform over [0, 1]
// from the horizon (0) to the far end (1: the zenith, or the nadir for rays to the ground),
// u(x) = a x + (1 - a) x^2 the fraction of the angle from the horizon; rows a times the
// uniform spacing at the horizon, where the sky changes fastest
float skydomePcMapUnit(float x, float a) {
    return a * x + (1.0 - a) * x * x;
}

// its inverse: x in [0, 1] with u(x) = u (u clamped to [0, 1]; the root without cancellation)
float skydomePcMapInverse(float u, float a) {
    u = clamp(u, 0.0, 1.0);
    return u <= 0.0 ? 0.0 : 2.0 * u / (a + sqrt(a * a + 4.0 * (1.0 - a) * u));
}

// zenith angle of the observer's horizon at radius r (pi / 2 on the ground)
float skydomePcHorizonZenith(float r, float R) {
    float s = R / r;
    return acos(-sqrt(max(1.0 - s * s, 0.0)));
}

// texel (phi node, zenith node) of the sky map for an observer at radius r, the sun at
// zenith cosine muS: orders 2..N from that node's direction, XYZ [cd m^-2]. Zenith nodes
// 0 .. mapGround - 1 run from the nadir to the horizon (rays to the ground), mapGround ..
// mapGround + mapSky - 1 from the horizon to the zenith, each part dense at the horizon
// (skydomePcMapUnit); azimuth nodes uniformly over [0, pi] from the sun's.
vec3 skydomeSkyMapTexel(sampler3D density, sampler2D opticalDepth, SkydomeAtmosphere atm,
                        SkydomeScatteringDensity dens, float r, float muS, ivec2 texel) {
    float thH = skydomePcHorizonZenith(r, atm.bottomRadius);
    bool ground = texel.y < dens.mapGround;
    float th = ground
        ? thH + (SKYDOME_PC_PI - thH)
              * skydomePcMapUnit(1.0 - float(texel.y) / float(dens.mapGround - 1),
                                 dens.mapGroundLinear)
        : thH * (1.0 - skydomePcMapUnit(float(texel.y - dens.mapGround)
                                        / float(dens.mapSky - 1), dens.mapSkyLinear));
    float mu = cos(th);
    float cphi = cos(SKYDOME_PC_PI * float(texel.x) / float(dens.mapPhi - 1));
    float sv = sqrt(max(1.0 - mu * mu, 0.0)) * sqrt(max(1.0 - muS * muS, 0.0));
    float nu = clamp(mu * muS + sv * cphi, -1.0, 1.0);
    return skydomeMultipleScatteringAlong(density, opticalDepth, atm, dens, r, mu, muS, nu,
                                          ground);
}

// orders 2..N from the sky map (skydomeSkyMapTexel, LINEAR filtering, CLAMP_TO_EDGE) along
// viewRay for the camera it was rendered for (inside the atmosphere), XYZ [cd m^-2]
vec3 skydomeSkyMapLookup(sampler2D skyMap, SkydomeAtmosphere atm,
                         SkydomeScatteringDensity dens, vec3 camera, vec3 viewRay,
                         vec3 sunDir) {
    float r = length(camera);
    vec3 up = camera / r;
    float mu = clamp(dot(viewRay, up), -1.0, 1.0);
    float muS = clamp(dot(sunDir, up), -1.0, 1.0);
    vec3 vh = viewRay - mu * up;
    vec3 sh = sunDir - muS * up;
    float dh = length(vh) * length(sh);
    float cphi = dh > 1e-12 ? clamp(dot(vh, sh) / dh, -1.0, 1.0) : 1.0;
    bool ground = skydomePcHitsGround(r, mu, atm.bottomRadius);
    float thH = skydomePcHorizonZenith(r, atm.bottomRadius);
    float th = acos(mu);
    float nG = float(dens.mapGround);
    float nS = float(dens.mapSky);
    float f = ground
        ? (1.0 - skydomePcMapInverse((th - thH) / max(SKYDOME_PC_PI - thH, 1e-12),
                                     dens.mapGroundLinear)) * (nG - 1.0)
        : nG + skydomePcMapInverse((thH - th) / thH, dens.mapSkyLinear) * (nS - 1.0);
    float nP = float(dens.mapPhi);
    float g = clamp(acos(cphi) / SKYDOME_PC_PI * (nP - 1.0), 0.0, nP - 1.0);
    return texture(skyMap, vec2((g + 0.5) / nP, (f + 0.5) / (nG + nS))).rgb;
}

// skydomeRadiance with orders 2..N from the sky map instead of the 4-D table: the sky and
// the ground as the CPU model renders them (camera inside the atmosphere, the sky map
// rendered for it); 0 with the sun below mu_s_min (night)
vec3 skydomeRadianceMapped(sampler3D scattering, sampler3D singleMie, sampler2D skyMap,
                           sampler2D opticalDepth, sampler2DArray irradianceSpectral,
                           SkydomeAtmosphere atm, SkydomeScatteringDensity dens, vec3 camera,
                           vec3 viewRay, vec3 sunDir) {
    float r = length(camera);
    float mu = clamp(dot(camera, viewRay) / r, -1.0, 1.0);
    float muS = clamp(dot(camera, sunDir) / r, -1.0, 1.0);
    float nu = clamp(dot(viewRay, sunDir), -1.0, 1.0);
    if (muS < atm.muSMin) return vec3(0.0);
    bool ground = skydomePcHitsGround(r, mu, atm.bottomRadius);
    vec4 uvwz = skydomeScatteringUvwz(r, mu, muS, nu, ground, atm,
                                      vec3(textureSize(scattering, 0)));
    float nNu = float(atm.nuSize);
    vec3 single = skydomeLookup4D(scattering, uvwz, nNu)
        * skydomeRayleighPhase(atm.rayleighGamma, nu)
        + skydomeLookup4D(singleMie, uvwz, nNu)
        * skydomeMiePhase(atm.miePhaseCode, atm.mieG, nu);
    vec3 ms = skydomeSkyMapLookup(skyMap, atm, dens, camera, viewRay, sunDir);
    vec3 surface = skydomeGroundRadiance(opticalDepth, irradianceSpectral, atm, camera,
                                         viewRay, sunDir);
    return max(single + ms + surface, vec3(0.0));
}

// skydomeSkyRadianceToPoint with the CPU model's correction at the observer's end: orders
// 2..N there from the sky map instead of the 4-D table, applied in proportion to the
// segment's share of the whole ray's extinction, (1 - T(d)) / (1 - T(end)) per XYZ channel
// (0 at distance 0, all of it at the end of the ray, so that a point at the end of the ray
// gives the sky of skydomeRadianceMapped). Camera inside the atmosphere.
vec3 skydomeSkyRadianceToPointMapped(sampler3D scattering, sampler3D singleMie,
                                     sampler3D multiple, sampler2D skyMap,
                                     sampler2D opticalDepth, SkydomeAtmosphere atm,
                                     SkydomeScatteringDensity dens, vec3 camera, vec3 point,
                                     vec3 sunDir, out vec3 transmittanceOut) {
    vec3 ins = skydomeSkyRadianceToPoint(scattering, singleMie, multiple, opticalDepth, atm,
                                         camera, point, sunDir, transmittanceOut);
    float R = atm.bottomRadius;
    float r = length(camera);
    vec3 viewRay = normalize(point - camera);
    float mu = clamp(dot(camera, viewRay) / r, -1.0, 1.0);
    float muS = clamp(dot(camera, sunDir) / r, -1.0, 1.0);
    float nu = clamp(dot(viewRay, sunDir), -1.0, 1.0);
    bool ground = skydomePcHitsGround(r, mu, R);
    float dEnd = ground ? skydomePcDistanceToGround(r, mu, R)
                        : skydomePcDistanceToTop(r, mu, atm.topRadius);
    vec3 tEnd = skydomeTransmittanceAlong(opticalDepth, atm, r, mu, dEnd, ground);
    vec3 share = clamp((1.0 - transmittanceOut) / max(1.0 - tEnd, vec3(1e-30)), 0.0, 1.0);
    vec4 uvwz = skydomeScatteringUvwz(r, mu, muS, nu, ground, atm,
                                      vec3(textureSize(scattering, 0)));
    vec3 table = skydomeLookup4D(multiple, uvwz, float(atm.nuSize));
    vec3 mapped = skydomeSkyMapLookup(skyMap, atm, dens, camera, viewRay, sunDir);
    return max(ins + share * (mapped - table), vec3(0.0));
}
