// skydome: look-ups of the hillaire2020 LUT bake (`skydome export luts --model hillaire2020`)
// in GLSL ES 3.00 / GLSL 3.30. They reproduce the CPU look-ups of
// skydome.models.simulated._kernels_hillaire2020 (lookup_transmittance, lookup_skyview,
// lookup_aerial_perspective and the Psi_ms look-up of the ray march) with hardware
// bilinear / trilinear filtering: the CPU puts node i of n at x = i / (n - 1), a texture
// puts texel i's centre at u = (i + 0.5) / n, so every unit coordinate x becomes
// u = (x (n - 1) + 0.5) / n. Sampler state: LINEAR filtering, CLAMP_TO_EDGE, no mip maps.
//
// Frame: East-North-Up (x east, y north, z up), unit vectors; lengths in metres. The
// sky-view and aerial-perspective textures hold one sun and observer (luts.json "sun").
// Values: CIE 1931 XYZ, Y in cd m^-2, for a sun at 1 au (see luts.json "units").
//
// References: [Hil20] S. Hillaire, "A Scalable and Production Ready Sky and Atmosphere
// Rendering Technique", CGF 39(4), EGSR 2020, secs. 4.1, 5.3-5.5; [Bru17] E. Bruneton,
// "Precomputed Atmospheric Scattering: a New Implementation" (2017), functions.glsl.

const float SKYDOME_PI = 3.14159265358979;

// unit coordinate x in [0, 1] on an axis of n nodes -> texture coordinate of that point
float skydomeUnitToTexel(float x, float n) {
    return (clamp(x, 0.0, 1.0) * (n - 1.0) + 0.5) / n;
}

// [Bru17] RayIntersectsGround
bool skydomeRayHitsGround(float r, float mu, float R) {
    return mu < 0.0 && r * r * (mu * mu - 1.0) + R * R >= 0.0;
}

// cos of the azimuth between a direction and the sun (1 where either is vertical)
float skydomeRelAzimuthCos(vec3 dir, vec3 sun) {
    float nd = length(dir.xy);
    float ns = length(sun.xy);
    if (nd < 1e-12 || ns < 1e-12) return 1.0;
    return clamp(dot(dir.xy, sun.xy) / (nd * ns), -1.0, 1.0);
}

// -- transmittance (256 x 64): [Bru17] GetTransmittanceTextureUvFromRMu, [Hil20] sec. 4.1 --
vec2 transmittanceUv(float r, float mu, float R, float Rt, vec2 size) {
    float H = sqrt(Rt * Rt - R * R);
    float rho = sqrt(max(r * r - R * R, 0.0));
    float d = -r * mu + sqrt(max(r * r * (mu * mu - 1.0) + Rt * Rt, 0.0));
    float dMin = Rt - r;
    float dMax = rho + H;
    float xMu = dMax <= dMin ? 0.0 : clamp((d - dMin) / (dMax - dMin), 0.0, 1.0);
    return vec2(skydomeUnitToTexel(xMu, size.x), skydomeUnitToTexel(rho / H, size.y));
}

// transmittance from (r, mu) to the top of the atmosphere; 0 where the ray meets the ground
vec3 transmittanceToTop(sampler2D lut, float r, float mu, float R, float Rt) {
    if (skydomeRayHitsGround(r, mu, R)) return vec3(0.0);
    return texture(lut, transmittanceUv(r, mu, R, Rt, vec2(textureSize(lut, 0)))).rgb;
}

// -- multiple scattering Psi_ms (32 x 32): [Hil20] sec. 5.5, linear in mu_s and altitude --
vec2 multipleScatteringUv(float r, float muS, float R, float Rt, vec2 size) {
    return vec2(skydomeUnitToTexel(0.5 * (muS + 1.0), size.x),
                skydomeUnitToTexel((r - R) / (Rt - R), size.y));
}

// -- sky view (192 x 108): [Hil20] sec. 5.3 ------------------------------------------------
// rows 0 .. H/2-1 above the horizon (theta = Zh (1 - (1 - c)^2)), rows H/2 .. H-1 below it
// (theta = Zh + beta c^2); each half is addressed on its own, so that sky and ground never
// blend (the row coordinate stays inside its half's texel centres)
vec2 skyViewUv(vec3 dir, vec3 sun, float r0, float R, vec2 size) {
    float hh = floor(size.y * 0.5);
    float beta = acos(min(sqrt(max(r0 * r0 - R * R, 0.0)) / r0, 1.0));
    float zh = SKYDOME_PI - beta;
    float mu = clamp(dir.z, -1.0, 1.0);
    float theta = acos(mu);
    float c;
    float base;
    if (!skydomeRayHitsGround(r0, mu, R)) {
        c = 1.0 - sqrt(max(1.0 - theta / zh, 0.0));
        base = 0.0;
    } else {
        c = beta > 0.0 ? sqrt(max((theta - zh) / beta, 0.0)) : 0.0;
        base = hh;
    }
    float fr = clamp(c, 0.0, 1.0) * (hh - 1.0);
    float fx = sqrt(max(0.5 - 0.5 * skydomeRelAzimuthCos(dir, sun), 0.0)) * (size.x - 1.0);
    return vec2((fx + 0.5) / size.x, (base + fr + 0.5) / size.y);
}

vec3 skyViewXYZ(sampler2D lut, vec3 dir, vec3 sun, float r0, float R) {
    return texture(lut, skyViewUv(dir, sun, r0, R, vec2(textureSize(lut, 0)))).rgb;
}

// -- aerial perspective (32^3): [Hil20] sec. 5.4 -----------------------------------------
// xyz: the 3-D texture coordinate (u column, v row, w slice); .w: the weight that fades the
// volume out below half a slice (in-scatter x weight, transmittance 1 - weight (1 - T))
vec4 aerialPerspectiveUvw(vec3 dir, float distanceM, vec3 sun, float kmPerSlice, vec3 size) {
    float s = asin(clamp(dir.z, -1.0, 1.0)) / (0.5 * SKYDOME_PI);
    float ss = s < 0.0 ? -sqrt(-s) : sqrt(s);
    float fr = (0.5 * ss + 0.5) * (size.y - 1.0);
    float fx = sqrt(max(0.5 - 0.5 * skydomeRelAzimuthCos(dir, sun), 0.0)) * (size.x - 1.0);
    float sl = distanceM / (kmPerSlice * 1000.0);
    float weight = 1.0;
    if (sl < 0.5) {
        weight = max(2.0 * sl, 0.0);
        sl = 0.5;
    }
    float fz = clamp(sqrt(sl / size.z) * size.z - 0.5, 0.0, size.z - 1.0);
    return vec4((fx + 0.5) / size.x, (fr + 0.5) / size.y, (fz + 0.5) / size.z, weight);
}

// in-scattered XYZ (rgb) and sun-weighted transmittance (a) between the eye and an object
vec4 aerialPerspective(sampler3D vol, vec3 dir, float distanceM, vec3 sun, float kmPerSlice) {
    vec4 c = aerialPerspectiveUvw(dir, distanceM, sun, kmPerSlice, vec3(textureSize(vol, 0)));
    vec4 v = texture(vol, c.xyz);
    return vec4(c.w * v.rgb, 1.0 - c.w * (1.0 - v.a));
}
