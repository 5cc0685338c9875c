"""A numpy transcription of src/skydome/export/glsl/fitted.glsl, function by function and
line by line (vectorised over directions, float64), with GLSL ``texelFetch`` emulated by
indexing the bake's arrays as it writes them: ``sky`` (layers, rows, columns, 4), ``sun``
(count, 4); ``f`` is a dict with the fields of the GLSL struct SkydomeFitted
(:func:`struct_from_desc`)."""

from __future__ import annotations

import numpy as np

PI = 3.14159265358979


def struct_from_desc(desc: dict, irradiance_scale: float = 1.0) -> dict:
    """The struct's fields filled from luts.json, as the shader's host code would."""
    g, e, se = desc["view_grid"], desc["elevation_axis"], desc["sun_elevation_axis"]
    return {"nSky": g["n_sky"], "nGround": g["n_ground"], "nPhi": g["n_phi"],
            "thetaH": g["theta_h_rad"], "invSky": g["inv_sky"], "invGround": g["inv_ground"],
            "eps": g["eps_rad"], "aPhi": g["a_phi"], "elevationFirstDeg": e["first_deg"],
            "elevationStepDeg": e["step_deg"], "elevationCount": e["count"],
            "sunElevationFirstDeg": se["first_deg"], "sunElevationStepDeg": se["step_deg"],
            "sunElevationCount": se["count"],
            "sunAngularRadius": desc["sun"]["angular_radius_rad"],
            "irradianceScale": irradiance_scale,
            "limb": desc["sun"]["limb_darkening"]["coefficients_xyz"]}


def sun_elevation_deg(sun_dir):
    return np.degrees(np.arctan2(sun_dir[2], np.hypot(sun_dir[0], sun_dir[1])))


def axis(first, step, count, elevation_deg):
    x = (elevation_deg - first) / step
    x = min(max(x, 0.0), float(count - 1))
    i0 = min(int(x), max(count - 2, 0))
    i1 = min(i0 + 1, count - 1)
    return i0, i1, x - float(i0)


def mix(x, y, a):
    """GLSL mix(x, y, a) = x (1 - a) + y a; with a boolean a, the selection y where a."""
    if isinstance(a, np.ndarray) and a.dtype == bool:
        return np.where(a, y, x)
    return x * (1.0 - a) + y * a


def blend(a, b, w):
    geo = np.exp(mix(np.log(np.maximum(a, 1e-30)), np.log(np.maximum(b, 1e-30)), w))
    return mix(mix(a, b, w), geo, np.minimum(a, b) > 0.0)


def texel(sky, row, col, i0, i1, w):
    return blend(sky[i0, row, col, :3], sky[i1, row, col, :3], w)


def row_weights(iu, nu, fu):
    """skydomeFittedRowWeights: (r0, (..., 4) weights)."""
    f2 = fu * fu
    f3 = f2 * fu
    wm = -0.5 * f3 + f2 - 0.5 * fu
    w0 = 1.5 * f3 - 2.5 * f2 + 1.0
    w1 = -1.5 * f3 + 2.0 * f2 + 0.5 * fu
    w2 = 0.5 * f3 - 0.5 * f2
    lo = (iu == 0)[..., None]
    hi = (iu == nu - 2)[..., None]
    wr = np.where(lo, np.stack([w0 + 2.0 * wm, w1 - wm, w2, 0.0 * fu], -1),
                  np.where(hi, np.stack([0.0 * fu, wm, w0 - w2, w1 + 2.0 * w2], -1),
                           np.stack([wm, w0, w1, w2], -1)))
    r0 = np.where(iu == 0, 0, np.where(iu == nu - 2, iu - 2, iu - 1))
    return r0, wr


def fitted_sky(sky, f, d, sun_dir):
    """skydomeFittedSky for directions d (..., 3)."""
    i0, i1, w = axis(f["elevationFirstDeg"], f["elevationStepDeg"], f["elevationCount"],
                     sun_elevation_deg(sun_dir))
    ns = float(np.hypot(sun_dir[0], sun_dir[1]))
    sin_az = sun_dir[0] / ns if ns > 0.0 else 0.0
    cos_az = sun_dir[1] / ns if ns > 0.0 else 1.0
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    th = 0.5 * PI - np.arctan2(z, np.hypot(x, y))
    is_sky = th < f["thetaH"]
    u_sky = np.sqrt(np.maximum(1.0 - th * f["invSky"], 0.0)) * (f["nSky"] - 1)
    u_ground = np.sqrt(np.maximum((th - f["thetaH"] - f["eps"]) * f["invGround"], 0.0)) \
        * (f["nGround"] - 1)
    u = np.where(is_sky, u_sky, u_ground)
    base = np.where(is_sky, 0, f["nSky"])
    nu = np.where(is_sky, f["nSky"], f["nGround"])
    iu = np.minimum(u.astype(int), nu - 2)                     # int(): truncation, u >= 0
    fu = u - iu
    cp = x * sin_az + y * cos_az
    sp = np.abs(x * cos_az - y * sin_az)
    zero = (sp == 0.0) & (cp == 0.0)
    phi = np.where(zero, 0.0, np.arctan2(sp, cp)) * (1.0 / PI)
    a = f["aPhi"]
    b = 1.0 - f["aPhi"]
    t = (-a + np.sqrt(a * a + 4.0 * b * phi)) / (2.0 * b) * (f["nPhi"] - 1)
    it = np.minimum(t.astype(int), f["nPhi"] - 2)
    ft = np.maximum(t - it, 0.0)[..., None]
    r0, wr = row_weights(iu, nu, fu)
    xyz = 0.0
    for k in range(4):
        row = base + r0 + k
        xyz = xyz + wr[..., k:k + 1] * ((1.0 - ft) * texel(sky, row, it, i0, i1, w)
                                        + ft * texel(sky, row, it + 1, i0, i1, w))
    return np.maximum(xyz, 0.0) * f["irradianceScale"]


def sun_visible_fraction(f, elevation_rad):
    e = np.sin(f["thetaH"]) * f["sunAngularRadius"]
    x = min(max((np.sin(elevation_rad) - np.cos(f["thetaH"]) + e) / (2.0 * e), 0.0), 1.0)
    return x * x * (3.0 - 2.0 * x)


def sun_radiance(sun, f, sun_dir):
    i0, i1, w = axis(f["sunElevationFirstDeg"], f["sunElevationStepDeg"],
                     f["sunElevationCount"], sun_elevation_deg(sun_dir))
    return blend(sun[i0, :3], sun[i1, :3], w) * f["irradianceScale"]


def sun_mean_radiance(sun, f, sun_dir):
    e = np.arctan2(sun_dir[2], np.hypot(sun_dir[0], sun_dir[1]))
    return sun_radiance(sun, f, sun_dir) * sun_visible_fraction(f, e)


def limb_darkening(f, gamma):
    """skydomeFittedLimbDarkening for angles gamma (...,): (..., 3)."""
    gamma = np.asarray(gamma, dtype=np.float64)
    rho = np.sin(gamma) / np.sin(f["sunAngularRadius"])
    mu = np.sqrt(np.maximum(1.0 - rho * rho, 0.0))[..., None]
    c = np.asarray(f["limb"], dtype=np.float64)
    out = c[5] * np.ones_like(mu)
    for k in range(4, -1, -1):
        out = out * mu + c[k]
    return np.where((gamma < f["sunAngularRadius"])[..., None], np.maximum(out, 0.0), 0.0)


def in_disc(f, d, sun_dir):
    """skydomeFittedInDisc for directions d (..., 3): (inside, gamma)."""
    gamma = np.arctan2(np.linalg.norm(np.cross(d, sun_dir), axis=-1), d @ sun_dir)
    th = 0.5 * PI - np.arctan2(d[..., 2], np.hypot(d[..., 0], d[..., 1]))
    return (gamma < f["sunAngularRadius"]) & (th < f["thetaH"]), gamma


def sun_disc(sun, f, d, sun_dir):
    """skydomeFittedSunDisc for directions d (..., 3)."""
    inside, gamma = in_disc(f, d, sun_dir)
    val = sun_radiance(sun, f, sun_dir) * limb_darkening(f, gamma)
    return np.where(inside[..., None], val, 0.0)


def sky_with_sun(sky, sun, f, d, sun_dir):
    """skydomeFittedSkyWithSun for directions d (..., 3)."""
    inside, gamma = in_disc(f, d, sun_dir)
    disc = sun_radiance(sun, f, sun_dir) * limb_darkening(f, gamma)
    return np.where(inside[..., None], disc, fitted_sky(sky, f, d, sun_dir))
