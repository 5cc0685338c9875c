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

// [Bru17] GetIrradianceTextureUvFromRMuS: linear in r and mu_s (rows r, columns mu_s)
vec2 skydomeIrradianceUv(float r, float muS, float R, float Rt, vec2 size) {
    return vec2(skydomePcUnitToTexel(0.5 * (muS + 1.0), size.x),
                skydomePcUnitToTexel((r - R) / (Rt - R), size.y));
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
    skyIrradiance = texture(irradiance, skydomeIrradianceUv(r, muS, atm.bottomRadius,
                                                            atm.topRadius, size)).rgb
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
    vec2 uv = skydomeIrradianceUv(R, muG, R, Rt, isize.xy);
    vec3 xyz = vec3(0.0);
    for (int k = 0; k < SKYDOME_PC_MAX_WAVELENGTHS / 4; ++k) {
        if (4 * k >= atm.nWavelengths) break;
        vec4 e = texture(irradianceSpectral, vec3(uv, float(k)));
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
