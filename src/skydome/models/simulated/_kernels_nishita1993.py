"""numba kernels of the ``nishita1993`` model (the earth seen from anywhere).

Private: plain floats and arrays, lengths in metres. Imported lazily by
:mod:`skydome.models.simulated.nishita1993`, never at package import.

Geometry ([NSTN93] sec. 3 and 4): the planet is a sphere of radius ``R`` centred on the
origin, the atmosphere ends at radius ``Rt``; the camera sits at distance ``r0`` from the
centre on the +z axis of the East-North-Up frame of the sub-camera point (so its frame
is that point's ENU frame shifted up by the camera altitude). Sunlight is parallel.

Optical-depth table ([NSTN93] sec. 4.1, fig. 3): the atmosphere is cut by ``n_s``
concentric spheres and by cylinders whose common axis passes through the planet's centre
parallel to the sunlight. Because the light is parallel and the atmosphere spherically
symmetric, the column from any point to the sun depends only on the point's sphere (its
radius r) and cylinder (its distance c from the axis) and on which side of the plane
through the centre normal to the sunlight it lies; the columns at the lattice points
(sphere i x cylinder j x side) are computed once and interpolated bilinearly in (sphere
index, cylinder index). The spheres are spaced so that the density changes by about the
same amount between neighbours. Departure from the paper: the cylinders are chosen per
sphere (see :func:`_lattice_mu`) and log(column) is interpolated; one shared set of
cylinders interpolated linearly was 10-30 % wrong near the sun's horizon.

View ray ([NSTN93] sec. 4.2): sample points are the view ray's crossings of the same
spheres (plus its end points and lowest point), each interval split into ``substeps``
equal pieces, and the view column and the in-scattering integral use the trapezoidal
rule ([NSTN93] eqs. 1-3).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from skydome._kernel_cache import njit, prange

from skydome.transport._geometry import clamp_cosine, radius_along_above, ray_hits_ground, safe_sqrt
from skydome.transport._medium import profile_density, scatterer_indices
from skydome.transport._phase import phase_fill
from skydome.transport._quadrature import column_quadrature, medium_columns

SURFACE_ALBEDO, SURFACE_OCEAN, SURFACE_TEXTURE, SURFACE_EARTH = 0, 1, 2, 3


# -- sphere / cylinder index mapping -----------------------------------------------------------
@njit(cache=True)
def sphere_u(h, H, top, w):
    """Monotone map of altitude h [m] in [0, top] to [0, 1]: a blend (weight w) of the
    linear map h/top and the relative density drop (1 - exp(-h/H)) / (1 - exp(-top/H))."""
    h = min(max(h, 0.0), top)
    return (1.0 - w) * (-math.expm1(-h / H)) / (-math.expm1(-top / H)) + w * h / top


@njit(cache=True)
def _frac_sphere(r, R, H, top, w, n_s):
    return sphere_u(r - R, H, top, w) * (n_s - 1)


@njit(cache=True)
def _lattice_mu(r, R, j, n_j, side):
    """Cosine of the sun's zenith angle at lattice point j of the sphere of radius r.

    Sun side (0): the cylinder through the point where mu_s = (j / (n_j - 1))^2 (dense
    towards the sun's horizon). Far side (1): the cylinder of radius
    c = R + (r - R) j / (n_j - 1), from the shadow boundary c = R to the horizon c = r."""
    x = j / (n_j - 1.0)
    if side == 0:
        return x * x
    c = R + (r - R) * x
    return -safe_sqrt(r * r - c * c) / r


class LightTable(NamedTuple):
    """The optical-depth table and the view-ray sampling of one model ([NSTN93] sec. 4)."""

    sph_r: np.ndarray      # (n_s,) radii of the spheres [m]
    table: np.ndarray      # (n_c, 2, n_s, n_j) log(column + 1 m), see build_table
    H: float               # spacing scale height of the spheres [m]
    top: float             # Rt - R [m]
    w: float               # linear weight of the sphere spacing
    n_in: int              # inner nodes (unused by the look-up, kept for the record)
    exact: bool            # integrate every light path instead of the table
    n_light: int           # quadrature nodes of an exact light path
    ts: float              # geometric node scale [m]
    substeps: int          # view-ray pieces between sphere crossings


class Surface(NamedTuple):
    """The surface seen where a view ray hits the ground ([NSTN93] sec. 5)."""

    code: int              # SURFACE_ALBEDO, SURFACE_OCEAN, SURFACE_TEXTURE or SURFACE_EARTH
    albedo: np.ndarray     # (nl,) Lambertian albedo
    mu_grid: np.ndarray    # (n_mu,) sun cosines of the skylight table
    e_sky: np.ndarray      # (n_mu, nl) diffuse sky irradiance [W m^-2 nm^-1]
    water_c: np.ndarray    # (nl,) attenuation coefficient of the water [m^-1]
    water_b: np.ndarray    # (nl,) scattering coefficient of the water [m^-1]
    n_water: float         # refractive index of the water
    sigma2: float          # mean square slope of the sea surface (Cox & Munk 1954)
    tex: np.ndarray        # (th, tw, 4) texture albedo R, G, B and land fraction
    tex_basis: np.ndarray  # (3, nl) spectra of the texture's R, G, B
    rot: np.ndarray        # (3, 3) local ENU -> earth-fixed


class _Work(NamedTuple):
    res: np.ndarray        # (nl,) radiance of the ray
    t_nodes: np.ndarray    # (2 n_s + 4,) sample distances
    acc: np.ndarray        # (nc, nl) in-scattering integrals
    dcol: np.ndarray       # (nc,) view column
    scol: np.ndarray       # (nc,) light column
    rho: np.ndarray        # (nc,) densities at the node
    rho_prev: np.ndarray   # (nc,) ... at the previous node
    f_prev: np.ndarray     # (nc, nl) integrand at the previous node
    phs: np.ndarray        # (nl,) phase function


@njit(parallel=True, cache=True)
def build_table(m, sph_r, n_j, n_light, ts):
    """log(column + 1 m) to the sun (column: relative density integrated [m]) at every
    lattice point, shape (n_c, 2, n_s, n_j): side 0 on the sun's side of the plane through
    the centre normal to the sunlight, side 1 behind it (see :func:`_lattice_mu`)."""
    nc = m.profile_code.shape[0]
    n_s = sph_r.shape[0]
    out = np.zeros((nc, 2, n_s, n_j))
    for idx in prange(n_s * n_j):
        i = idx // n_j
        j = idx % n_j
        r = sph_r[i]
        for side in range(2):
            mu = _lattice_mu(r, m.R, j, n_j, side)
            for k in range(nc):
                col = column_quadrature(m.profile_code[k], m.profile_p0[k], m.profile_p1[k], r,
                                        mu, m.R, m.Rt, n_light, ts, False)
                out[k, side, i, j] = math.log(col + 1.0)
    return out


@njit(cache=True)
def table_columns(table, r, mu_s, R, H, top, w, n_in, out):
    """Bilinear look-up (in sphere index x cylinder index, of log(column + 1 m)) of the
    columns to the sun from (r, mu_s) into ``out`` (n_c,)."""
    n_s = table.shape[2]
    n_j = table.shape[3]
    fi = _frac_sphere(r, R, H, top, w, n_s)
    if mu_s >= 0.0:
        side = 0
        fj = math.sqrt(mu_s) * (n_j - 1)
    else:
        side = 1
        c = r * safe_sqrt(1.0 - mu_s * mu_s)
        fj = (n_j - 1.0) if r - R <= 0.0 else (c - R) / (r - R) * (n_j - 1)
    i = min(max(int(fi), 0), n_s - 2)
    j = min(max(int(fj), 0), n_j - 2)
    a = min(max(fi - i, 0.0), 1.0)
    b = min(max(fj - j, 0.0), 1.0)
    for k in range(table.shape[0]):
        v = ((1.0 - a) * ((1.0 - b) * table[k, side, i, j] + b * table[k, side, i, j + 1])
             + a * ((1.0 - b) * table[k, side, i + 1, j] + b * table[k, side, i + 1, j + 1]))
        out[k] = max(math.exp(v) - 1.0, 0.0)


@njit(cache=True)
def sun_columns(lt, m, r, mu_s, out):
    """Columns from (r, mu_s) to the sun into ``out``; False in the earth's shadow."""
    if ray_hits_ground(r, mu_s, m.R):
        return False
    if lt.exact:
        medium_columns(m, r, mu_s, lt.n_light, lt.ts, True, out)
    else:
        table_columns(lt.table, r, mu_s, m.R, lt.H, lt.top, lt.w, lt.n_in, out)
    return True


# -- surface --------------------------------------------------------------------------------------
@njit(cache=True)
def fresnel(cos_i, n):
    """Unpolarised Fresnel reflectance of a smooth air-water interface for a ray meeting
    it at incidence cosine cos_i from the air side (relative index n)."""
    ci = min(max(cos_i, 0.0), 1.0)
    st2 = (1.0 - ci * ci) / (n * n)
    if st2 >= 1.0:
        return 1.0
    ct = math.sqrt(1.0 - st2)
    rs = (ci - n * ct) / (ci + n * ct)
    rp = (n * ci - ct) / (n * ci + ct)
    return 0.5 * (rs * rs + rp * rp)


@njit(cache=True)
def cox_munk_glint(sx, sy, sz, vx, vy, vz, nx, ny, nz, sigma2, n):
    """Sun glint of a rough sea: reflected radiance per unit of normal solar irradiance
    [sr^-1] for the sun in direction s and the viewer in direction v (unit vectors away from
    the surface), the mean surface normal n.

    Facets with an isotropic Gaussian distribution of slopes ([CM54], mean square slope
    ``sigma2``), each a Fresnel mirror: the facets that reflect s into v have the normal
    h = (s + v) / |s + v|, tilted by beta from n, and
    ``L / E_n = F(s.h) p(tan beta) / (4 mu_v cos^4 beta)``, p(tan beta) =
    exp(-tan^2 beta / sigma2) / (pi sigma2) ([CM54] eq. 5 with the Gram-Charlier terms
    dropped; the reflection geometry of [CM54] sec. 5). No shadowing by the waves."""
    mu_s = sx * nx + sy * ny + sz * nz
    mu_v = vx * nx + vy * ny + vz * nz
    if mu_s <= 0.0 or mu_v <= 0.0:
        return 0.0
    hx = sx + vx
    hy = sy + vy
    hz = sz + vz
    hn = math.sqrt(hx * hx + hy * hy + hz * hz)
    if hn < 1e-12:
        return 0.0
    cb = (hx * nx + hy * ny + hz * nz) / hn                 # cos(beta), facet tilt
    if cb <= 0.0:
        return 0.0
    cw = (hx * sx + hy * sy + hz * sz) / hn                 # cos of the incidence on the facet
    tan2 = (1.0 - cb * cb) / (cb * cb)
    x = tan2 / sigma2
    if x > 700.0:
        return 0.0
    p = math.exp(-x) / (math.pi * sigma2)                   # [CM54] slope density
    cb2 = cb * cb
    return fresnel(cw, n) * p / (4.0 * max(mu_v, 1e-6) * cb2 * cb2)


@njit(cache=True)
def cox_munk_glint_many(s, v, n, sigma2, n_water, out):
    """:func:`cox_munk_glint` for the sun s (3,) and arrays of viewer directions v (m, 3)
    over the mean normal n (3,) (for tests)."""
    for i in range(v.shape[0]):
        out[i] = cox_munk_glint(s[0], s[1], s[2], v[i, 0], v[i, 1], v[i, 2], n[0], n[1], n[2],
                                sigma2, n_water)


@njit(cache=True)
def _interp_irradiance(mu_grid, e_grid, mu, l):
    n = mu_grid.shape[0]
    if mu <= mu_grid[0]:
        return e_grid[0, l] if mu == mu_grid[0] else 0.0
    if mu >= mu_grid[n - 1]:
        return e_grid[n - 1, l]
    f = (mu - mu_grid[0]) / (mu_grid[n - 1] - mu_grid[0]) * (n - 1)
    i = min(int(f), n - 2)
    a = f - i
    return (1.0 - a) * e_grid[i, l] + a * e_grid[i + 1, l]


# -- the view rays --------------------------------------------------------------------------------
@njit(cache=True)
def _nodes(r0, mu, R, Rt, sph_r, substeps, t_nodes):
    """Fill t_nodes with the increasing distances of the view ray's sample points; return
    (count, hits_ground). The ray's part inside the atmosphere is cut at the spheres."""
    disc_t = r0 * r0 * (mu * mu - 1.0) + Rt * Rt
    if disc_t < 0.0:
        return 0, False
    tm = -r0 * mu                        # distance to the lowest point of the ray
    t_far = tm + math.sqrt(disc_t)
    if t_far <= 0.0:
        return 0, False
    t0 = max(tm - math.sqrt(disc_t), 0.0)
    t1 = t_far
    disc_g = r0 * r0 * (mu * mu - 1.0) + R * R
    hits = mu < 0.0 and disc_g >= 0.0
    if hits:
        t1 = max(tm - math.sqrt(disc_g), t0)
    n_s = sph_r.shape[0]
    # breakpoints in increasing t: t0, near-side crossings (spheres top down), lowest
    # point, far-side crossings (bottom up), t1
    m = 0
    t_nodes[m] = t0
    m += 1
    for k in range(n_s - 1, -1, -1):
        d = r0 * r0 * (mu * mu - 1.0) + sph_r[k] * sph_r[k]
        if d > 0.0:
            t = tm - math.sqrt(d)
            if t > t_nodes[m - 1] and t < t1:
                t_nodes[m] = t
                m += 1
    if tm > t_nodes[m - 1] and tm < t1:
        t_nodes[m] = tm
        m += 1
    for k in range(n_s):
        d = r0 * r0 * (mu * mu - 1.0) + sph_r[k] * sph_r[k]
        if d > 0.0:
            t = tm + math.sqrt(d)
            if t > t_nodes[m - 1] and t < t1:
                t_nodes[m] = t
                m += 1
    if t1 > t_nodes[m - 1]:
        t_nodes[m] = t1
        m += 1
    return m, hits


@njit(cache=True, fastmath=True)
def _in_scattering(d, r0, sun, m, e_sun, lt, wk):
    """Single scattering along the view ray into wk.res ([NSTN93] eqs. 1-3, trapezoidal
    rule at the sample points), the view column in wk.dcol; returns (count of sample
    points, hits the ground)."""
    m_R = m.R
    m_Rt = m.Rt
    m_extinction = m.extinction
    m_profile_code = m.profile_code
    m_profile_p0 = m.profile_p0
    m_profile_p1 = m.profile_p1
    m_scattering = m.scattering
    wk_acc = wk.acc
    wk_dcol = wk.dcol
    wk_f_prev = wk.f_prev
    wk_phs = wk.phs
    wk_res = wk.res
    wk_rho = wk.rho
    wk_rho_prev = wk.rho_prev
    wk_scol = wk.scol
    wk_t_nodes = wk.t_nodes
    lt_sph_r = lt.sph_r
    lt_substeps = lt.substeps
    nc = m_profile_code.shape[0]
    nl = e_sun.shape[0]
    R = m_R
    for l in range(nl):
        wk_res[l] = 0.0
    mu = d[2]
    nu = d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2]       # cos of the scattering angle
    n_pts, hits = _nodes(r0, mu, R, m_Rt, lt_sph_r, lt_substeps, wk_t_nodes)
    if n_pts < 2:
        return n_pts, hits
    sidx = scatterer_indices(m)          # the scattering terms of these only
    ns = sidx.shape[0]
    for c in range(nc):
        wk_dcol[c] = 0.0
        for l in range(nl):
            wk_acc[c, l] = 0.0
    t_prev = wk_t_nodes[0]
    first = True
    substeps = lt_substeps
    for q in range(n_pts - 1):
        ta = wk_t_nodes[q]
        tb = wk_t_nodes[q + 1]
        for s in range(0 if first else 1, substeps + 1):
            t = ta + (tb - ta) * s / substeps
            rr = radius_along_above(r0, mu, t, R)
            h = t - t_prev
            for c in range(nc):
                wk_rho[c] = profile_density(m_profile_code[c], m_profile_p0[c], m_profile_p1[c],
                                            rr - R)
                if not first:
                    wk_dcol[c] += 0.5 * h * (wk_rho_prev[c] + wk_rho[c])      # [NSTN93] eq. 2
            mu_s = (r0 * sun[2] + t * nu) / rr
            lit = sun_columns(lt, m, rr, mu_s, wk_scol)
            for l in range(nl):
                tau = 0.0
                for c in range(nc):
                    tau += m_extinction[c, l] * (wk_dcol[c] + wk_scol[c])
                e = math.exp(-tau) if lit else 0.0
                for k in range(ns):
                    c = sidx[k]
                    f = wk_rho[c] * e
                    if not first:
                        wk_acc[c, l] += 0.5 * h * (wk_f_prev[c, l] + f)        # [NSTN93] eq. 1
                    wk_f_prev[c, l] = f
            for c in range(nc):
                wk_rho_prev[c] = wk_rho[c]
            t_prev = t
            first = False
    for k in range(ns):
        c = sidx[k]
        phase_fill(m, c, nu, wk_phs)
        for l in range(nl):
            wk_res[l] += e_sun[l] * m_scattering[c, l] * wk_phs[l] * wk_acc[c, l]
    return n_pts, hits


@njit(cache=True)
def _texture_rgb(sf, nx, ny, nz):
    """Texture albedo (r, g, b) and land fraction at the surface normal n (latitude /
    longitude of the point; sf.rot: local ENU -> earth-fixed)."""
    rot = sf.rot
    ex = rot[0, 0] * nx + rot[0, 1] * ny + rot[0, 2] * nz
    ey = rot[1, 0] * nx + rot[1, 1] * ny + rot[1, 2] * nz
    ez = rot[2, 0] * nx + rot[2, 1] * ny + rot[2, 2] * nz
    lat = math.asin(clamp_cosine(ez))
    lon = math.atan2(ey, ex)
    tex = sf.tex
    th = tex.shape[0]
    tw = tex.shape[1]
    # bilinear between pixel centres; rows clamped at the poles, columns wrap
    fy = min(max((0.5 - lat / math.pi) * th - 0.5, 0.0), th - 1.0)
    fx = (lon / (2.0 * math.pi) + 0.5) * tw - 0.5
    r0 = min(int(fy), th - 1)
    r1 = min(r0 + 1, th - 1)
    a = fy - r0
    c0f = math.floor(fx)
    b = fx - c0f
    c0 = int(c0f) % tw
    c1 = (c0 + 1) % tw
    # weights times the land fraction: the colour is the mean of the land's colours only
    w00 = (1.0 - a) * (1.0 - b) * tex[r0, c0, 3]
    w01 = (1.0 - a) * b * tex[r0, c1, 3]
    w10 = a * (1.0 - b) * tex[r1, c0, 3]
    w11 = a * b * tex[r1, c1, 3]
    land = w00 + w01 + w10 + w11
    if land <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    v0 = (w00 * tex[r0, c0, 0] + w01 * tex[r0, c1, 0] + w10 * tex[r1, c0, 0]
          + w11 * tex[r1, c1, 0]) / land
    v1 = (w00 * tex[r0, c0, 1] + w01 * tex[r0, c1, 1] + w10 * tex[r1, c0, 1]
          + w11 * tex[r1, c1, 1]) / land
    v2 = (w00 * tex[r0, c0, 2] + w01 * tex[r0, c1, 2] + w10 * tex[r1, c0, 2]
          + w11 * tex[r1, c1, 2]) / land
    return v0, v1, v2, land


@njit(cache=True)
def _sun_transmittance(m, scol, l, direct):
    """exp(-tau) of the light column scol at wavelength l; 0 when not ``direct``."""
    if not direct:
        return 0.0
    tau = 0.0
    for c in range(m.profile_code.shape[0]):
        tau += m.extinction[c, l] * scol[c]
    return math.exp(-tau)


@njit(cache=True, fastmath=True)
def _ocean(d, sun, m, e_sun, sf, wk, nx, ny, nz, mu_s, mu_v, direct, weight):
    """Add ``weight`` x the light leaving the sea surface, attenuated towards the camera:
    the sun's glint on the rough surface (:func:`cox_munk_glint`), Fresnel reflection of
    the skylight, and the light scattered once in the water and refracted out ([NSTN93]
    sec. 5)."""
    m_extinction = m.extinction
    m_profile_code = m.profile_code
    wk_dcol = wk.dcol
    wk_res = wk.res
    wk_scol = wk.scol
    sf_e_sky = sf.e_sky
    sf_mu_grid = sf.mu_grid
    sf_n_water = sf.n_water
    sf_water_b = sf.water_b
    sf_water_c = sf.water_c
    nc = m_profile_code.shape[0]
    nl = e_sun.shape[0]
    n = sf_n_water
    r_v = fresnel(mu_v, n)
    r_s = fresnel(mu_s, n) if mu_s > 0.0 else 1.0
    mv_w = safe_sqrt(1.0 - (1.0 - mu_v * mu_v) / (n * n))   # refracted cosines
    ms_w = safe_sqrt(1.0 - (1.0 - mu_s * mu_s) / (n * n))
    # scattering angle in the water between the refracted sunbeam (going down) and the
    # refracted view ray (going up): directions in the local frame
    sv = safe_sqrt(1.0 - mv_w * mv_w)
    ss = safe_sqrt(1.0 - ms_w * ms_w)
    # horizontal unit vectors of the view ray (towards the camera) and of the sun
    vhx = -d[0] + mu_v * nx
    vhy = -d[1] + mu_v * ny
    vhz = -d[2] + mu_v * nz
    shx = sun[0] - mu_s * nx
    shy = sun[1] - mu_s * ny
    shz = sun[2] - mu_s * nz
    vn = math.sqrt(vhx * vhx + vhy * vhy + vhz * vhz)
    sn = math.sqrt(shx * shx + shy * shy + shz * shz)
    cphi = 0.0
    if vn > 1e-12 and sn > 1e-12:
        cphi = (vhx * shx + vhy * shy + vhz * shz) / (vn * sn)
    # propagation directions in the water: the refracted sunbeam going down, away from
    # the sun, k_s = -ss s_h - ms_w n; the refracted view ray going up towards the
    # camera, k_v = sv v_h + mv_w n; the scattering angle psi between them
    cos_psi = -(ss * sv * cphi) - ms_w * mv_w
    p_w = (1.0 + 0.835 * cos_psi * cos_psi) / (4.0 * math.pi * (1.0 + 0.835 / 3.0))
    mbar = 0.842
    glint = 0.0
    if direct:
        glint = cox_munk_glint(sun[0], sun[1], sun[2], -d[0], -d[1], -d[2], nx, ny, nz,
                               sf.sigma2, n)
    for l in range(nl):
        t_sun = _sun_transmittance(m, wk_scol, l, direct)
        e_dir = e_sun[l] * t_sun * max(mu_s, 0.0)
        e_dif = _interp_irradiance(sf_mu_grid, sf_e_sky, mu_s, l)
        cw = sf_water_c[l]
        up = sf_water_b[l] * (p_w * e_dir * (1.0 - r_s) / (cw * (ms_w + mv_w))
                              + e_dif * (1.0 - 0.066) / (4.0 * math.pi) / (cw * (mbar + mv_w)))
        l_surf = (e_sun[l] * t_sun * glint + r_v * e_dif / math.pi
                  + (1.0 - r_v) / (n * n) * up)
        wk_res[l] += weight * l_surf * _view_transmittance(m_extinction, wk_dcol, l, nc)


@njit(cache=True, fastmath=True)
def _surface(d, r0, sun, m, e_sun, lt, sf, wk, t):
    """Add the light of the surface point at distance t along the view ray, attenuated
    towards the camera ([NSTN93] sec. 5): ocean, or Lambertian (albedo or texture) lit by
    the attenuated sun and the skylight table."""
    m_R = m.R
    m_extinction = m.extinction
    m_profile_code = m.profile_code
    wk_dcol = wk.dcol
    wk_res = wk.res
    wk_scol = wk.scol
    sf_albedo = sf.albedo
    sf_code = sf.code
    sf_e_sky = sf.e_sky
    sf_mu_grid = sf.mu_grid
    sf_tex_basis = sf.tex_basis
    nc = m_profile_code.shape[0]
    nl = e_sun.shape[0]
    # the surface point seen, its normal and the sun there
    px = t * d[0]
    py = t * d[1]
    pz = r0 + t * d[2]
    pn = math.sqrt(px * px + py * py + pz * pz)
    nx = px / pn
    ny = py / pn
    nz = pz / pn
    mu_s = nx * sun[0] + ny * sun[1] + nz * sun[2]
    mu_v = -(nx * d[0] + ny * d[1] + nz * d[2])             # cos of the viewing angle there
    direct = sun_columns(lt, m, m_R * (1.0 + 1e-12), mu_s, wk_scol) and mu_s > 0.0
    if sf_code == SURFACE_OCEAN:
        _ocean(d, sun, m, e_sun, sf, wk, nx, ny, nz, mu_s, mu_v, direct, 1.0)
        return
    tr = 0.0
    tg = 0.0
    tb = 0.0
    land = 1.0
    if sf_code == SURFACE_TEXTURE or sf_code == SURFACE_EARTH:
        tr, tg, tb, land = _texture_rgb(sf, nx, ny, nz)
    if sf_code == SURFACE_EARTH:
        if land < 1.0:
            _ocean(d, sun, m, e_sun, sf, wk, nx, ny, nz, mu_s, mu_v, direct, 1.0 - land)
        if land <= 0.0:
            return
    else:
        land = 1.0
    for l in range(nl):
        if sf_code == SURFACE_TEXTURE or sf_code == SURFACE_EARTH:
            a = tr * sf_tex_basis[0, l] + tg * sf_tex_basis[1, l] + tb * sf_tex_basis[2, l]
        else:
            a = sf_albedo[l]
        e_tot = (e_sun[l] * _sun_transmittance(m, wk_scol, l, direct) * max(mu_s, 0.0)
                 + _interp_irradiance(sf_mu_grid, sf_e_sky, mu_s, l))
        wk_res[l] += land * a / math.pi * e_tot * _view_transmittance(m_extinction, wk_dcol, l, nc)


@njit(cache=True, fastmath=True)
def _ray(d, r0, sun, m, e_sun, lt, sf, wk):
    """Radiance of one view ray into wk.res: in-scattering, then the surface it hits."""
    n_pts, hits = _in_scattering(d, r0, sun, m, e_sun, lt, wk)
    if n_pts >= 2 and hits:
        _surface(d, r0, sun, m, e_sun, lt, sf, wk, wk.t_nodes[n_pts - 1])


@njit(cache=True)
def _view_transmittance(beta_e, dcol, l, nc):
    tau = 0.0
    for c in range(nc):
        tau += beta_e[c, l] * dcol[c]
    return math.exp(-tau)


@njit(cache=True)
def _ray_block(i0, i1, dirs, r0, sun, m, e_sun, lt, sf, out):
    """Rays i0..i1-1 of :func:`render_rays` with one set of work arrays (made here, in a
    serial function, see transport._kernels._ray_block)."""
    nc = m.profile_code.shape[0]
    nl = e_sun.shape[0]
    wk = _Work(np.zeros(nl), np.empty(2 * lt.sph_r.shape[0] + 4), np.zeros((nc, nl)),
               np.zeros(nc), np.zeros(nc), np.zeros(nc), np.zeros(nc), np.zeros((nc, nl)),
               np.zeros(nl))
    for i in range(i0, i1):
        _ray(dirs[i], r0, sun, m, e_sun, lt, sf, wk)
        for l in range(nl):
            out[i, l] = max(wk.res[l], 0.0)


@njit(parallel=True, cache=True)
def render_rays(dirs, r0, sun, m, e_sun, lt, sf, out):
    """Radiance [W m^-2 sr^-1 nm^-1] reaching the camera at (0, 0, r0) from each of
    ``dirs`` (n, 3) through the medium m: single scattering along the view ray ([NSTN93]
    eqs. 1-3, light paths from the table lt) plus the attenuated light of the surface sf
    at the point it hits (sec. 5)."""
    n = dirs.shape[0]
    block = 64
    n_blocks = (n + block - 1) // block
    for ib in prange(n_blocks):
        _ray_block(ib * block, min(n, (ib + 1) * block), dirs, r0, sun, m, e_sun, lt, sf, out)


@njit(parallel=True, cache=True)
def lookup_columns(table, r, mu_s, R, H, top, w, n_in, out):
    """Table columns (n, n_c) for arrays of (r, mu_s) (for tests and benchmarks)."""
    for i in prange(r.shape[0]):
        table_columns(table, r[i], mu_s[i], R, H, top, w, n_in, out[i])
