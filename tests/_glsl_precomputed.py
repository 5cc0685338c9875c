"""A numpy transcription of src/skydome/export/glsl/precomputed.glsl, function by function
and line by line (vectorised over rays, float64), with GLSL ``texture()`` emulated: LINEAR
filtering, CLAMP_TO_EDGE, texel centres at (i + 0.5) / n (OpenGL 4.6 section 8.14.2).

Textures are numpy arrays as the bake writes them: 2-D (height, width, 4), 3-D and 2-D
arrays (depth or layers, height, width, 4); ``atm`` is a dict with the fields of the GLSL
struct SkydomeAtmosphere (:func:`atmosphere_from_desc`)."""

from __future__ import annotations

import numpy as np

PI = 3.14159265358979
MU_WIDTH = 0.0349065850398866
MU_S_CENTRE = 1.6057029118347832
MU_S_WIDTH = 0.10471975511965977


def atmosphere_from_desc(desc: dict) -> dict:
    """The GLSL struct's fields filled from luts.json, as the shader's host code would."""
    return {"bottomRadius": desc["bottom_radius_m"], "topRadius": desc["top_radius_m"],
            "muSMin": desc["mu_s_min"], "sunAngularRadius": desc["sun"]["angular_radius_rad"],
            "sunSolidAngle": desc["sun"]["solid_angle_sr"],
            "solarIrradiance": np.asarray(desc["sun"]["solar_irradiance_xyz"]),
            "rayleighGamma": desc["rayleigh"]["gamma"], "miePhaseCode": desc["mie"]["phase_code"],
            "mieG": desc["mie"]["g"], "nuSize": desc["sizes"]["nu"],
            "nWavelengths": desc["n_wavelengths"],
            "extinction": np.pad(np.asarray(desc["extinction_per_km"]).T,
                                 ((0, 0), (0, 4 - len(desc["extinction_per_km"])))),
            "xyzWeights": np.asarray(desc["xyz_weights"]),
            "groundAlbedo": np.asarray(desc["ground_albedo"])}


# -- GLSL texture() with LINEAR filtering and CLAMP_TO_EDGE (GL 4.6 section 8.14.2) --------
def _axis(u, n):
    x = np.asarray(u, dtype=np.float64) * n - 0.5
    i0 = np.floor(x)
    f = x - i0
    i0 = i0.astype(int)
    return np.clip(i0, 0, n - 1), np.clip(i0 + 1, 0, n - 1), f[..., None]


def texture2d(tex, uv):
    """tex (height, width, c); uv (..., 2) = (u along width, v along height)."""
    h, w = tex.shape[:2]
    x0, x1, fx = _axis(uv[..., 0], w)
    y0, y1, fy = _axis(uv[..., 1], h)
    return ((1 - fy) * ((1 - fx) * tex[y0, x0] + fx * tex[y0, x1])
            + fy * ((1 - fx) * tex[y1, x0] + fx * tex[y1, x1]))


def texture3d(tex, uvw):
    """tex (depth, height, width, c); uvw (..., 3). (The texels gathered by flat index,
    np.take on the (texels, c) view: the same values as tex[z, y, x], faster.)"""
    d, h, w = tex.shape[:3]
    flat = tex.reshape(-1, tex.shape[-1])
    x0, x1, fx = _axis(uvw[..., 0], w)
    y0, y1, fy = _axis(uvw[..., 1], h)
    z0, z1, fz = _axis(uvw[..., 2], d)
    out = 0.0
    for zi, wz in ((z0, 1 - fz), (z1, fz)):
        for yi, wy in ((y0, 1 - fy), (y1, fy)):
            row = (zi * h + yi) * w
            for xi, wx in ((x0, 1 - fx), (x1, fx)):
                out = out + wz * wy * wx * np.take(flat, row + xi, axis=0)
    return out


def texture2darray(tex, uv, layer):
    """sampler2DArray: bilinear in (u, v), the layer rounded to the nearest integer."""
    k = int(np.clip(np.floor(layer + 0.5), 0, tex.shape[0] - 1))
    return texture2d(tex[k], uv)


def textureSize(tex):
    """(width, height[, depth]) as GLSL's textureSize."""
    return np.array(tex.shape[:-1][::-1], dtype=np.float64)


# -- geometry -------------------------------------------------------------------------------
def rho_(r, R):
    return np.sqrt(np.maximum((r - R) * (r + R), 0.0))


def hits_ground(r, mu, R):
    return (mu < 0.0) & ((r * mu) * (r * mu) - (r - R) * (r + R) >= 0.0)


def distance_to_top(r, mu, Rt):
    return np.maximum(-r * mu + np.sqrt(np.maximum((r * mu) * (r * mu) + (Rt - r) * (Rt + r),
                                                   0.0)), 0.0)


def distance_to_ground(r, mu, R):
    return np.maximum(-r * mu - np.sqrt(np.maximum((r * mu) * (r * mu) - (r - R) * (r + R),
                                                   0.0)), 0.0)


def radius_along(r, mu, d, R, Rt):
    return np.clip(np.sqrt(np.maximum(d * d + 2.0 * r * mu * d + r * r, 0.0)), R, Rt)


def unit_to_texel(x, n):
    return (np.clip(x, 0.0, 1.0) * (n - 1.0) + 0.5) / n


# -- phase functions ------------------------------------------------------------------------
def rayleigh_phase(gamma, nu):
    return 3.0 / (16.0 * PI) * ((1.0 + 3.0 * gamma) + (1.0 - gamma) * nu * nu) / (1.0 + 2.0 * gamma)


def mie_phase(code, g, nu):
    den = 1.0 + g * g - 2.0 * g * nu
    hg = (1.0 - g * g) / (den * np.sqrt(den)) / (4.0 * PI)
    if code == 1:
        return hg
    if code == 2:
        return 3.0 / (2.0 * (2.0 + g * g)) * (1.0 + nu * nu) * hg
    return np.full_like(nu, 1.0 / (4.0 * PI))


# -- texture coordinates --------------------------------------------------------------------
def transmittance_uv(r, mu, R, Rt, size):
    H = np.sqrt((Rt - R) * (Rt + R))
    rho = rho_(r, R)
    d = distance_to_top(r, mu, Rt)
    d_min = Rt - r
    d_max = rho + H
    with np.errstate(invalid="ignore", divide="ignore"):
        x_mu = np.where(d_max <= d_min, 0.0, np.clip((d - d_min) / (d_max - d_min), 0.0, 1.0))
    return np.stack(np.broadcast_arrays(unit_to_texel(x_mu, size[0]),
                                        unit_to_texel(rho / H, size[1])), -1)


def mu_s_unit(mu_s, mu_s_min):
    th_max = np.arccos(np.clip(mu_s_min, -1.0, 1.0))
    th = np.minimum(np.arccos(np.clip(mu_s, -1.0, 1.0)), th_max)
    top = np.arcsinh((th_max - MU_S_CENTRE) / MU_S_WIDTH)
    zen = np.arcsinh((0.0 - MU_S_CENTRE) / MU_S_WIDTH)
    u = np.arcsinh((th - MU_S_CENTRE) / MU_S_WIDTH)
    return np.clip((top - u) / (top - zen), 0.0, 1.0)


def irradiance_uv(r, mu_s, R, Rt, mu_s_min, size):
    """skydomeIrradianceUv: the two mu_s nodes' texel centres (uv0, uv1) and the fraction."""
    x = mu_s_unit(mu_s, mu_s_min) * (size[0] - 1.0)
    i = np.minimum(np.floor(x), size[0] - 2.0)
    f = x - i
    v = unit_to_texel((r - R) / (Rt - R), size[1])
    uv0 = np.stack(np.broadcast_arrays((i + 0.5) / size[0], v), -1)
    uv1 = np.stack(np.broadcast_arrays((i + 1.5) / size[0], v), -1)
    return uv0, uv1, np.asarray(f)[..., None]


def geometric_mix(lo, hi, f):
    """skydomeGeometricMix."""
    geo = lo * np.exp(f * np.log(np.maximum(hi, 1e-37) / np.maximum(lo, 1e-37)))
    return np.where(np.minimum(lo, hi) > 0.0, geo, lo + f * (hi - lo))


def mu_unit(r, mu, ground, R):
    dip = np.arctan2(rho_(r, R), R)
    a = np.arcsin(np.clip(mu, -1.0, 1.0))
    e = np.where(ground, -dip - a, a + dip)
    e_max = np.where(ground, 0.5 * PI - dip, 0.5 * PI + dip)
    top = np.arcsinh(np.maximum(e_max, 0.0) / MU_WIDTH)
    with np.errstate(invalid="ignore", divide="ignore"):
        x = np.clip(np.arcsinh(np.maximum(e, 0.0) / MU_WIDTH) / top, 0.0, 1.0)
    return np.where(top <= 0.0, 0.0, x)


def scattering_uvwz(r, mu, mu_s, nu, ground, atm, size):
    R, Rt = atm["bottomRadius"], atm["topRadius"]
    n_nu = float(atm["nuSize"])
    n_mu_s = size[0] / n_nu
    n_mu = size[1]
    half = np.floor(0.5 * n_mu)
    H = np.sqrt((Rt - R) * (Rt + R))
    w = unit_to_texel(rho_(r, R) / H, size[2])
    x_mu = mu_unit(r, mu, ground, R)
    f_mu = np.where(ground, x_mu * (half - 1.0), half + (1.0 - x_mu) * (half - 1.0))
    v = (f_mu + 0.5) / n_mu
    u = unit_to_texel(mu_s_unit(mu_s, atm["muSMin"]), n_mu_s)
    f_nu = np.clip(0.5 * (nu + 1.0), 0.0, 1.0) * (n_nu - 1.0)
    return np.stack(np.broadcast_arrays(f_nu, u, v, w), -1)


def lookup_4d(tex, uvwz, n_nu):
    i = np.minimum(np.floor(uvwz[..., 0]), n_nu - 2.0)
    f = (uvwz[..., 0] - i)[..., None]
    a = texture3d(tex, np.stack([(i + uvwz[..., 1]) / n_nu, uvwz[..., 2], uvwz[..., 3]],
                                -1))[..., :3]
    b = texture3d(tex, np.stack([(i + 1.0 + uvwz[..., 1]) / n_nu, uvwz[..., 2], uvwz[..., 3]],
                                -1))[..., :3]
    return a * (1.0 - f) + b * f


# -- transmittance --------------------------------------------------------------------------
def transmittance_to_top(trans, atm, r, mu):
    v = texture2d(trans, transmittance_uv(r, mu, atm["bottomRadius"], atm["topRadius"],
                                          textureSize(trans)))[..., :3]
    return np.where(hits_ground(r, mu, atm["bottomRadius"])[..., None], 0.0, v)


def columns(od, atm, r, mu):
    return texture2d(od, transmittance_uv(r, mu, atm["bottomRadius"], atm["topRadius"],
                                          textureSize(od)))


def transmittance_along(od, atm, r, mu, d, ground):
    rd = radius_along(r, mu, d, atm["bottomRadius"], atm["topRadius"])
    mud = np.clip((r * mu + d) / rd, -1.0, 1.0)
    g = ground[..., None]
    c = np.where(g, columns(od, atm, rd, -mud) - columns(od, atm, r, -mu),
                 columns(od, atm, r, mu) - columns(od, atm, rd, mud))
    c = np.maximum(c, 0.0)
    t = 0.0
    for j in range(atm["nWavelengths"]):
        t = t + atm["xyzWeights"][j] * np.exp(-c @ atm["extinction"][j])[..., None]
    return np.minimum(t / atm["solarIrradiance"], 1.0)


# -- the sun --------------------------------------------------------------------------------
def sun_visible_fraction(r, mu_s, atm):
    sin_h = atm["bottomRadius"] / r
    cos_h = -np.sqrt(np.maximum(1.0 - sin_h * sin_h, 0.0))
    e = sin_h * atm["sunAngularRadius"]
    x = np.clip((mu_s - cos_h + e) / (2.0 * e), 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def sun_radiance(od, atm, r, mu_s):
    col = columns(od, atm, np.asarray(r, float), np.asarray(mu_s, float))
    xyz = 0.0
    for j in range(atm["nWavelengths"]):
        xyz = xyz + atm["xyzWeights"][j] * np.exp(-np.dot(col, atm["extinction"][j]))[..., None]
    return xyz * sun_visible_fraction(r, mu_s, atm)[..., None] / atm["sunSolidAngle"]


def sun_radiance_xyz(trans, atm, r, mu_s):
    t = texture2d(trans, transmittance_uv(r, mu_s, atm["bottomRadius"], atm["topRadius"],
                                          textureSize(trans)))[..., :3]
    return (atm["solarIrradiance"] / atm["sunSolidAngle"] * t
            * sun_visible_fraction(r, mu_s, atm)[..., None])


# -- sky radiance ---------------------------------------------------------------------------
def scattered_radiance(scat, mie, mult, atm, r, mu, mu_s, nu, ground):
    uvwz = scattering_uvwz(r, mu, mu_s, nu, ground, atm, textureSize(scat))
    n_nu = float(atm["nuSize"])
    s = lookup_4d(scat, uvwz, n_nu)
    m = lookup_4d(mie, uvwz, n_nu)
    return (s * rayleigh_phase(atm["rayleighGamma"], nu)[..., None]
            + m * mie_phase(atm["miePhaseCode"], atm["mieG"], nu)[..., None]
            + lookup_4d(mult, uvwz, n_nu))


def sky_radiance(scat, mie, mult, trans, atm, camera, view, sun):
    """skydomeSkyRadiance for a camera inside the atmosphere (camera (3,), view (n, 3))."""
    r = np.linalg.norm(camera)
    assert r <= atm["topRadius"]
    rmu = view @ camera
    mu = np.clip(rmu / r, -1.0, 1.0)
    mu_s = np.clip(np.dot(camera, sun) / r, -1.0, 1.0) * np.ones_like(mu)
    nu = np.clip(view @ sun, -1.0, 1.0)
    ground = hits_ground(r, mu, atm["bottomRadius"])
    t = transmittance_to_top(trans, atm, r, mu)
    return scattered_radiance(scat, mie, mult, atm, r, mu, mu_s, nu, ground), t


# -- ground ---------------------------------------------------------------------------------
def sun_and_sky_irradiance(trans, irr, atm, point, normal, sun):
    r = np.linalg.norm(point)
    mu_s = np.clip(np.dot(point, sun) / r, -1.0, 1.0)
    uv0, uv1, fe = irradiance_uv(r, mu_s, atm["bottomRadius"], atm["topRadius"], atm["muSMin"],
                                 textureSize(irr))
    sky = (geometric_mix(texture2d(irr, uv0), texture2d(irr, uv1), fe)[..., :3]
           * (1.0 + np.dot(normal, point) / r) * 0.5)
    t = texture2d(trans, transmittance_uv(r, mu_s, atm["bottomRadius"], atm["topRadius"],
                                          textureSize(trans)))[..., :3]
    return (atm["solarIrradiance"] * t * sun_visible_fraction(r, mu_s, atm)
            * max(np.dot(normal, sun), 0.0)), sky


def ground_radiance(od, irr_spec, atm, camera, view, sun):
    R, Rt = atm["bottomRadius"], atm["topRadius"]
    r = np.linalg.norm(camera)
    mu = np.clip(view @ camera / r, -1.0, 1.0)
    mu_s = np.clip(np.dot(camera, sun) / r, -1.0, 1.0)
    nu = np.clip(view @ sun, -1.0, 1.0)
    hit = hits_ground(r, mu, R)
    dg = distance_to_ground(r, mu, R)
    mu_g = np.clip((r * mu_s + dg * nu) / R, -1.0, 1.0)
    alpha = atm["sunAngularRadius"]
    f = np.where(mu_g < -alpha, 0.0,
                 np.where(mu_g > alpha, mu_g, (mu_g + alpha) * (mu_g + alpha) / (4.0 * alpha)))
    c_sun = columns(od, atm, np.full_like(mu, R), mu_g)
    rd = radius_along(r, mu, dg, R, Rt)
    mud = np.clip((r * mu + dg) / rd, -1.0, 1.0)
    c_view = np.maximum(columns(od, atm, rd, -mud) - columns(od, atm, np.full_like(mu, r), -mu),
                        0.0)
    isize = textureSize(irr_spec)
    uv0, uv1, fe = irradiance_uv(R, mu_g, R, Rt, atm["muSMin"], isize[:2])
    xyz = np.zeros(mu.shape + (3,))
    for k in range(8):
        if 4 * k >= atm["nWavelengths"]:
            break
        e = geometric_mix(texture2darray(irr_spec, uv0, float(k)),
                          texture2darray(irr_spec, uv1, float(k)), fe)
        for c in range(4):
            j = 4 * k + c
            if j >= atm["nWavelengths"]:
                break
            t_sun = np.exp(-c_sun @ atm["extinction"][j])
            t_view = np.exp(-c_view @ atm["extinction"][j])
            xyz += atm["xyzWeights"][j] * (t_view * atm["groundAlbedo"][j] / PI
                                           * (f * t_sun + e[..., c]))[..., None]
    return np.where(hit[..., None], xyz, 0.0)


def radiance(scat, mie, mult, trans, od, irr_spec, atm, camera, view, sun):
    """skydomeRadiance: sky and ground, 0 at night."""
    r = np.linalg.norm(camera)
    if np.dot(camera, sun) / r < atm["muSMin"]:
        return np.zeros(view.shape[:-1] + (3,))
    sky, _ = sky_radiance(scat, mie, mult, trans, atm, camera, view, sun)
    return np.maximum(sky + ground_radiance(od, irr_spec, atm, camera, view, sun), 0.0)


# -- aerial perspective ---------------------------------------------------------------------
def sky_radiance_to_point(scat, mie, mult, od, atm, camera, view, dist, sun):
    """skydomeSkyRadianceToPoint for points camera + dist * view (camera inside the
    atmosphere)."""
    R, Rt = atm["bottomRadius"], atm["topRadius"]
    r = np.linalg.norm(camera)
    assert r <= Rt
    rmu = view @ camera
    mu = np.clip(rmu / r, -1.0, 1.0)
    mu_s = np.clip(np.dot(camera, sun) / r, -1.0, 1.0) * np.ones_like(mu)
    nu = np.clip(view @ sun, -1.0, 1.0)
    ground = hits_ground(r, mu, R)
    d_end = np.where(ground, distance_to_ground(r, mu, R), distance_to_top(r, mu, Rt))
    d = np.clip(dist, 0.0, d_end)
    t = transmittance_along(od, atm, np.full_like(mu, r), mu, d, ground)
    size = textureSize(scat)
    n_nu = float(atm["nuSize"])
    uvwz0 = scattering_uvwz(r, mu, mu_s, nu, ground, atm, size)
    s = lookup_4d(scat, uvwz0, n_nu)
    m = lookup_4d(mie, uvwz0, n_nu)
    n = lookup_4d(mult, uvwz0, n_nu)
    rp = radius_along(r, mu, d, R, Rt)
    mup = np.clip((r * mu + d) / rp, -1.0, 1.0)
    mu_sp = np.clip((r * mu_s + d * nu) / rp, -1.0, 1.0)
    uvwz1 = scattering_uvwz(rp, mup, mu_sp, nu, ground, atm, size)
    inner = (d < d_end)[..., None]
    s = s - np.where(inner, t * lookup_4d(scat, uvwz1, n_nu), 0.0)
    m = m - np.where(inner, t * lookup_4d(mie, uvwz1, n_nu), 0.0)
    n = n - np.where(inner, t * lookup_4d(mult, uvwz1, n_nu), 0.0)
    return np.maximum(s * rayleigh_phase(atm["rayleighGamma"], nu)[..., None]
                      + m * mie_phase(atm["miePhaseCode"], atm["mieG"], nu)[..., None] + n,
                      0.0), t


# -- orders 2..N at the observer: the scattering density along the view ray -----------------
MAX_SAMPLES = 64


def density_from_desc(desc: dict) -> dict:
    """The GLSL struct SkydomeScatteringDensity filled from luts.json."""
    s = desc["scattering_density"]
    return {"nTheta": s["theta"], "nPhi": s["phi"], "nR": s["r"], "nMuS": s["mu_s"],
            "nScatterers": s["scatterers"], "blockColumns": s["block_columns"],
            "scatterer": list(s["scatterer_constituent"]),
            "profileCode": list(s["profile_code"]), "profileP0": list(s["profile_p0_m"]),
            "profileP1": list(s["profile_p1_m"]), "nConstituents": s["constituents"],
            "columnNodes": s["column_nodes"], "samples": s["quadrature"]["samples"],
            "scale": s["quadrature"]["scale_m"], "mapGround": s["sky_map"]["ground"],
            "mapSky": s["sky_map"]["sky"], "mapPhi": s["sky_map"]["phi"],
            "mapGroundLinear": s["sky_map"]["ground_linear"],
            "mapSkyLinear": s["sky_map"]["sky_linear"]}


def log1p_(x):
    return np.where(np.abs(x) < 1e-4, x * (1.0 - 0.5 * x), np.log(1.0 + x))


def expm1_(x):
    return np.where(np.abs(x) < 1e-4, x * (1.0 + 0.5 * x), np.exp(x) - 1.0)


def profile(code, p0, p1, h):
    if code == 0:
        return np.exp(-np.maximum(h, 0.0) / p0)
    if code == 1:
        return np.maximum(0.0, 1.0 - np.abs(h - p0) / p1)
    if code == 2:
        return np.where(h < p0, 1.0, 0.0)
    if code == 3:
        x = (h - p0) / p1
        return np.exp(-0.5 * x * x)
    return np.zeros_like(h)


def piece_node(a, b, dense_at_b, k, n, ts):
    with np.errstate(invalid="ignore", divide="ignore"):
        dv = log1p_((b - a) / ts) / float(n)
    u = ts * expm1_((float(k) + 0.5) * dv)
    return (b - u if dense_at_b else a + u), (u + ts) * dv


def tau4(atm, l, col):
    return np.stack([col @ atm["extinction"][min(4 * l + c, len(atm["extinction"]) - 1)]
                     for c in range(4)], -1)


# SKYDOME_PC_GL6_X, SKYDOME_PC_GL6_W as the GLSL file writes them
GL6_X = (0.033765242898423975, 0.16939530676686776, 0.3806904069584016, 0.6193095930415985,
         0.8306046932331322, 0.966234757101576)
GL6_W = (0.0856622461895852, 0.1803807865240693, 0.2339569672863455, 0.2339569672863455,
         0.1803807865240693, 0.0856622461895852)


def columns_along(dens, r, mu, t0, t1, R, Rt):
    """skydomePcColumnsAlong (arrays of rays): (..., 4) columns [m] between t0 and t1."""
    h = t1 - t0
    col = np.zeros(np.shape(h) + (4,))
    for x, w in zip(GL6_X, GL6_W):
        alt = radius_along(r, mu, t0 + x * h, R, Rt) - R
        for c in range(dens["nConstituents"]):
            col[..., c] += w * h * profile(dens["profileCode"][c], dens["profileP0"][c],
                                           dens["profileP1"][c], alt)
    return np.where((h > 0.0)[..., None], col, 0.0)


def density_uvw(dens, b, f_mu_s, f_r, f_phi, size):
    bx = b % dens["blockColumns"]
    bz = b // dens["blockColumns"]
    return np.stack(np.broadcast_arrays((bx * dens["nMuS"] + f_mu_s + 0.5) / size[0],
                                        (f_r + 0.5) / size[1],
                                        (bz * dens["nPhi"] + f_phi + 0.5) / size[2]), -1)


def multiple_scattering_along(density, od, atm, dens, r, mu, mu_s, nu, ground):
    """skydomeMultipleScatteringAlong, vectorised over rays (mu, mu_s, nu, ground arrays; r
    an array or a scalar)."""
    R, Rt = atm["bottomRadius"], atm["topRadius"]
    H = np.sqrt((Rt - R) * (Rt + R))
    size = textureSize(density)
    mu, mu_s, nu, ground = np.broadcast_arrays(*(np.asarray(x) for x in (mu, mu_s, nu, ground)))
    r = np.broadcast_to(np.asarray(r, dtype=np.float64), mu.shape)
    layers = (atm["nWavelengths"] + 3) // 4
    d = np.where(ground, distance_to_ground(r, mu, R), distance_to_top(r, mu, Rt))
    t_low = np.clip(-r * mu, 0.0, d)
    f_theta = np.clip(np.arccos(np.clip(nu, -1.0, 1.0)) / PI * (dens["nTheta"] - 1), 0.0,
                      dens["nTheta"] - 1)
    it = np.minimum(f_theta.astype(int), dens["nTheta"] - 2)
    jb = (f_theta - it)[..., None]
    c0 = (np.zeros(mu.shape + (4,)) if dens["columnNodes"] > 0
          else columns(od, atm, r, np.where(ground, -mu, mu)))
    acc = [np.zeros(mu.shape + (4,)) for _ in range(layers)]
    n0 = dens["samples"] if dens["samples"] >= 4 else 0
    hm = 0.5 * t_low
    col_along = np.zeros(mu.shape + (4,))
    t_prev = np.zeros(mu.shape)
    for piece in range(3):
        a = (np.zeros_like(t_low) if piece == 0
             else (hm if n0 > 0 else np.zeros_like(t_low)) if piece == 1 else t_low)
        b = hm if piece == 0 else t_low if piece == 1 else d
        n = n0 if piece == 0 else dens["samples"]
        live = (b - a > 0.0)[..., None]
        for q in range(min(n, MAX_SAMPLES)):
            t, w = piece_node(a, b, piece == 1, n - 1 - q if piece == 1 else q, n,
                              dens["scale"])
            rt = radius_along(r, mu, t, R, Rt)
            mt = np.clip((r * mu + t) / rt, -1.0, 1.0)
            mu_st = np.clip((r * mu_s + t * nu) / rt, -1.0, 1.0)
            if dens["columnNodes"] > 0:
                # a piece of no length (live false) leaves its t at its start: no column
                with np.errstate(invalid="ignore"):
                    step = np.where(live[..., 0], t, t_prev)
                col_along = col_along + columns_along(dens, r, mu, t_prev, step, R, Rt)
                t_prev = np.maximum(t_prev, step)
                col = col_along * 1e-3
            else:
                c1 = columns(od, atm, rt, np.where(ground, -mt, mt))
                col = np.maximum(np.where(ground[..., None], c1 - c0, c0 - c1), 0.0)
            f_r = np.clip(rho_(rt, R) / H * (dens["nR"] - 1), 0.0, dens["nR"] - 1)
            f_mu_s = mu_s_unit(mu_st, atm["muSMin"]) * (dens["nMuS"] - 1)
            den = np.sqrt(np.maximum((1.0 - nu * nu) * (1.0 - mu_st * mu_st), 0.0))
            with np.errstate(invalid="ignore", divide="ignore"):
                cphi = np.where(den < 1e-9, 1.0, np.clip((mt - nu * mu_st) / den, -1.0, 1.0))
            f_phi = np.clip(np.arccos(cphi) / PI * (dens["nPhi"] - 1), 0.0, dens["nPhi"] - 1)
            rho = []
            for k in range(dens["nScatterers"]):
                ci = dens["scatterer"][k]
                rho.append(profile(dens["profileCode"][ci], dens["profileP0"][ci],
                                   dens["profileP1"][ci], rt - R)[..., None])
            for l in range(layers):
                tau = tau4(atm, l, col)
                j = 0.0
                for k in range(dens["nScatterers"]):
                    b0 = ((it * dens["nScatterers"]) + k) * layers + l
                    b1 = (((it + 1) * dens["nScatterers"]) + k) * layers + l
                    j0 = texture3d(density, density_uvw(dens, b0, f_mu_s, f_r, f_phi, size))
                    j1 = texture3d(density, density_uvw(dens, b1, f_mu_s, f_r, f_phi, size))
                    j = j + rho[k] * (j0 * (1.0 - jb) + j1 * jb)
                acc[l] = acc[l] + np.where(live, w[..., None] * np.exp(-tau) * j, 0.0)
    xyz = np.zeros(mu.shape + (3,))
    for j in range(atm["nWavelengths"]):
        xyz = xyz + atm["xyzWeights"][j] * acc[j // 4][..., j % 4][..., None]
    return xyz


def map_unit(x, a):
    """skydomePcMapUnit."""
    return a * x + (1.0 - a) * x * x


def map_inverse(u, a):
    """skydomePcMapInverse."""
    u = np.clip(u, 0.0, 1.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(u <= 0.0, 0.0, 2.0 * u / (a + np.sqrt(a * a + 4.0 * (1.0 - a) * u)))


def horizon_zenith(r, R):
    s = R / r
    return np.arccos(-np.sqrt(np.maximum(1.0 - s * s, 0.0)))


def sky_map_texel(density, od, atm, dens, r, mu_s, tx, ty):
    """skydomeSkyMapTexel at texels (tx, ty) (integer arrays)."""
    th_h = horizon_zenith(r, atm["bottomRadius"])
    ground = ty < dens["mapGround"]
    th = np.where(ground, th_h + (PI - th_h) * map_unit(1.0 - ty / (dens["mapGround"] - 1.0),
                                                        dens["mapGroundLinear"]),
                  th_h * (1.0 - map_unit((ty - dens["mapGround"]) / (dens["mapSky"] - 1.0),
                                         dens["mapSkyLinear"])))
    mu = np.cos(th)
    cphi = np.cos(PI * tx / (dens["mapPhi"] - 1.0))
    sv = np.sqrt(np.maximum(1.0 - mu * mu, 0.0)) * np.sqrt(max(1.0 - mu_s * mu_s, 0.0))
    nu = np.clip(mu * mu_s + sv * cphi, -1.0, 1.0)
    return multiple_scattering_along(density, od, atm, dens, r, mu, mu_s, nu, ground)


def sky_map(density, od, atm, dens, r, mu_s):
    """The whole sky map as the render target holds it: (mapGround + mapSky, mapPhi, 4),
    XYZ in RGB, one skydomeSkyMapTexel per texel."""
    ty, tx = np.meshgrid(np.arange(dens["mapGround"] + dens["mapSky"]),
                         np.arange(dens["mapPhi"]), indexing="ij")
    out = np.zeros(tx.shape + (4,))
    out[..., :3] = sky_map_texel(density, od, atm, dens, r, mu_s, tx, ty)
    return out


def sky_map_lookup(smap, atm, dens, camera, view, sun):
    """skydomeSkyMapLookup (camera (3,), view (n, 3))."""
    r = np.linalg.norm(camera)
    up = camera / r
    mu = np.clip(view @ up, -1.0, 1.0)
    mu_s = np.clip(np.dot(sun, up), -1.0, 1.0)
    vh = view - mu[..., None] * up
    sh = sun - mu_s * up
    dh = np.linalg.norm(vh, axis=-1) * np.linalg.norm(sh)
    with np.errstate(invalid="ignore", divide="ignore"):
        cphi = np.where(dh > 1e-12, np.clip((vh @ sh) / dh, -1.0, 1.0), 1.0)
    ground = hits_ground(r, mu, atm["bottomRadius"])
    th_h = horizon_zenith(r, atm["bottomRadius"])
    th = np.arccos(mu)
    n_g = float(dens["mapGround"])
    n_s = float(dens["mapSky"])
    f = np.where(ground,
                 (1.0 - map_inverse((th - th_h) / max(PI - th_h, 1e-12),
                                    dens["mapGroundLinear"])) * (n_g - 1.0),
                 n_g + map_inverse((th_h - th) / th_h, dens["mapSkyLinear"]) * (n_s - 1.0))
    n_p = float(dens["mapPhi"])
    g = np.clip(np.arccos(cphi) / PI * (n_p - 1.0), 0.0, n_p - 1.0)
    return texture2d(smap, np.stack([(g + 0.5) / n_p, (f + 0.5) / (n_g + n_s)], -1))[..., :3]


def radiance_mapped(scat, mie, smap, od, irr_spec, atm, dens, camera, view, sun):
    """skydomeRadianceMapped (camera (3,) inside the atmosphere, view (n, 3))."""
    r = np.linalg.norm(camera)
    mu = np.clip(view @ camera / r, -1.0, 1.0)
    mu_s = np.clip(np.dot(camera, sun) / r, -1.0, 1.0)
    nu = np.clip(view @ sun, -1.0, 1.0)
    if mu_s < atm["muSMin"]:
        return np.zeros(view.shape[:-1] + (3,))
    ground = hits_ground(r, mu, atm["bottomRadius"])
    uvwz = scattering_uvwz(r, mu, mu_s, nu, ground, atm, textureSize(scat))
    n_nu = float(atm["nuSize"])
    single = (lookup_4d(scat, uvwz, n_nu) * rayleigh_phase(atm["rayleighGamma"], nu)[..., None]
              + lookup_4d(mie, uvwz, n_nu)
              * mie_phase(atm["miePhaseCode"], atm["mieG"], nu)[..., None])
    ms = sky_map_lookup(smap, atm, dens, camera, view, sun)
    surface = ground_radiance(od, irr_spec, atm, camera, view, sun)
    return np.maximum(single + ms + surface, 0.0)


def sky_radiance_to_point_mapped(scat, mie, mult, smap, od, atm, dens, camera, view, dist,
                                 sun):
    """skydomeSkyRadianceToPointMapped for points camera + dist * view."""
    ins, t = sky_radiance_to_point(scat, mie, mult, od, atm, camera, view, dist, sun)
    R = atm["bottomRadius"]
    r = np.linalg.norm(camera)
    mu = np.clip(view @ camera / r, -1.0, 1.0)
    mu_s = np.clip(np.dot(camera, sun) / r, -1.0, 1.0) * np.ones_like(mu)
    nu = np.clip(view @ sun, -1.0, 1.0)
    ground = hits_ground(r, mu, R)
    d_end = np.where(ground, distance_to_ground(r, mu, R), distance_to_top(r, mu, atm["topRadius"]))
    t_end = transmittance_along(od, atm, np.full_like(mu, r), mu, d_end, ground)
    share = np.clip((1.0 - t) / np.maximum(1.0 - t_end, 1e-30), 0.0, 1.0)
    uvwz = scattering_uvwz(r, mu, mu_s, nu, ground, atm, textureSize(scat))
    table = lookup_4d(mult, uvwz, float(atm["nuSize"]))
    mapped = sky_map_lookup(smap, atm, dens, camera, view, sun)
    return np.maximum(ins + share * (mapped - table), 0.0), t
