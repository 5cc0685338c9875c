"""The 4-D tables' mappings: node <-> (r, mu, mu_s, nu), as inverse pairs, and the
interpolation cells (node, fraction) of a continuous coordinate.

After [Bru17] GetScatteringTextureUvwzFromRMuMuSNu and its inverse; node i of an axis of n
nodes at x = i / (n - 1). r and nu are [Bru17]'s; the mu axis (see :func:`mu_unit`) and the
mu_s axis (see :func:`mu_s_unit`) are this package's own mappings, which depend on angles
alone, so that they resolve the sky at any planet radius.
"""

from __future__ import annotations

import math

from skydome._kernel_cache import njit

import numpy as np

from skydome.models.simulated.precomputed._geometry import (clamp_cos, distance_to_ground,
                                                             distance_to_top, ray_nodes)



# -- table mappings -------------------------------------------------------------------------------
# the mu_s mapping's knee: node density peaks at this sun zenith angle [rad] and falls off
# over MU_S_WIDTH (see mu_s_unit)
MU_S_CENTRE = math.radians(92.0)
MU_S_WIDTH = math.radians(6.0)
MU_WIDTH_DEG = 2.0


@njit(cache=True)
def _mu_s_u(th):
    return math.asinh((th - MU_S_CENTRE) / MU_S_WIDTH)


@njit(cache=True)
def mu_s_frame(mu_s_min):
    """The constants of :func:`mu_s_unit` for one ``mu_s_min``: (theta_max, u(theta_max),
    1 / (u(theta_max) - u(0))), so that a kernel computes them once."""
    th_max = math.acos(clamp_cos(mu_s_min))
    top = _mu_s_u(th_max)
    return th_max, top, 1.0 / (top - _mu_s_u(0.0))


@njit(cache=True)
def mu_s_unit_framed(mu_s, frame):
    """:func:`mu_s_unit` with the constants ``frame`` of :func:`mu_s_frame`."""
    th = math.acos(clamp_cos(mu_s))
    x = (frame[1] - _mu_s_u(min(th, frame[0]))) * frame[2]
    return min(max(x, 0.0), 1.0)


@njit(cache=True)
def mu_s_unit(mu_s, mu_s_min):
    """mu_s mapping to [0, 1] (0 at mu_s_min, clamped below; 1 at the zenith):
    x = (u(theta_max) - u(theta_s)) / (u(theta_max) - u(0)), u(theta) = asinh((theta - 92 deg)
    / 6 deg), theta_s = acos(mu_s), theta_max = acos(mu_s_min).

    Not [Bru17]'s mapping, which follows the distance to the top of the atmosphere towards
    the sun: at the earth's radius it gives sun zeniths 0-60 deg only 3.3 of 31 cells, and
    at a radius of 1e8 m it squeezes them into the last 1.5 cells (the sky between was
    +42 % off). This one depends on the sun's zenith angle alone, so it is the same for
    every planet radius; its node density, 1 / sqrt(6^2 + (theta - 92)^2) per degree, is
    highest around sunset and civil twilight, where the sky changes fastest with the sun's
    elevation, and 15x lower at the zenith, where it changes slowly. Cells for 64 nodes
    (sun zenith bands 0-30, 30-60, 60-80, 80-90, 90-96, 96-102, 102-108 deg): 4.8, 8.0,
    11.4, 13.7, 11.7, 8.1, 5.2; [Bru17]'s at 64 nodes: 1.1, 5.5, 14.4, 18.3, 11.4, 7.6, 4.6."""
    return mu_s_unit_framed(mu_s, mu_s_frame(mu_s_min))


@njit(cache=True)
def mu_s_from_unit(x, mu_s_min):
    """Inverse of :func:`mu_s_unit`."""
    top = _mu_s_u(math.acos(clamp_cos(mu_s_min)))
    u = top - min(max(x, 0.0), 1.0) * (top - _mu_s_u(0.0))
    return clamp_cos(math.cos(max(MU_S_CENTRE + MU_S_WIDTH * math.sinh(u), 0.0)))


@njit(cache=True)
def cell_r(ir, n_r, R, Rt):
    H = math.sqrt(Rt * Rt - R * R)
    rho = H * ir / (n_r - 1.0)
    return math.sqrt(rho * rho + R * R)


# the view-zenith (mu) mapping's knee: node density peaks at the local horizon and falls off
# over MU_WIDTH (see mu_unit)
MU_WIDTH = math.radians(MU_WIDTH_DEG)


@njit(cache=True)
def horizon_dip(r, R):
    """Angle of the local horizon below the horizontal at radius r [rad]: atan(rho / R),
    rho = sqrt(r^2 - R^2) (= acos(R / r), without its cancellation near r = R); the horizon
    ray has mu_h = -sin(dip)."""
    rho = math.sqrt(max(r * r - R * R, 0.0))
    return math.atan2(rho, R)


@njit(cache=True)
def _mu_frame(dip, ground):
    """asinh(e_max / w): e_max the largest angle from the horizon of the half (pi/2 + dip
    above it, pi/2 - dip below it)."""
    e_max = 0.5 * math.pi - dip if ground else 0.5 * math.pi + dip
    return math.asinh(max(e_max, 0.0) / MU_WIDTH)


@njit(cache=True)
def mu_frame(r, R):
    """The constants of :func:`mu_unit` at radius r: (dip, asinh(e_max / w) of the sky half,
    that of the ground half), so that a kernel with a fixed r computes them once."""
    dip = horizon_dip(r, R)
    return dip, _mu_frame(dip, False), _mu_frame(dip, True)


@njit(cache=True)
def mu_unit_framed(mu, ground, frame):
    """:func:`mu_unit` with the constants ``frame`` of :func:`mu_frame`."""
    dip = frame[0]
    a = math.asin(clamp_cos(mu))
    e = -dip - a if ground else a + dip
    top = frame[2] if ground else frame[1]
    if top <= 0.0:
        return 0.0
    return min(max(math.asinh(max(e, 0.0) / MU_WIDTH) / top, 0.0), 1.0)


@njit(cache=True)
def mu_unit(r, mu, ground, R):
    """Position of a ray on its half of the mu axis, in [0, 1]: 0 at the horizon of radius r,
    1 at the zenith (sky rays) or the nadir (ground rays):
    x = asinh(e / w) / asinh(e_max / w), e the ray's angle from the local horizon
    (asin(mu) + dip above it, -dip - asin(mu) below it, dip = :func:`horizon_dip`), w =
    MU_WIDTH_DEG.

    Not [Bru17]'s mapping (linear in the distance to the top of the atmosphere or to the
    ground), which follows the planet's curvature: at a radius of 1e8 m and an 8 km top it
    puts view zeniths 0-70 deg in the first 1.2 % of the sky half (less than one of 64
    nodes: up to 10.7 % off DISORT), and at the earth's radius (100 km top) it gives them
    11 of 64 nodes at the ground and 5 at 30 km. This one depends on the angle from the
    local horizon, so a given view direction has about the same node at any planet radius
    (22 of 64 there at the ground, 21 at 1e8 m): node density 1 / sqrt(w^2 + e^2), highest
    at the horizon (where the sky and the ground change fastest with the angle) and 45x
    lower at the zenith and the nadir; the split between the halves stays at the horizon
    of radius r, exactly."""
    dip = horizon_dip(r, R)
    top = _mu_frame(dip, ground)
    return mu_unit_framed(mu, ground, (dip, top, top))


@njit(cache=True)
def mu_from_unit(x, r, ground, R):
    """Inverse of :func:`mu_unit`: the mu of position x of a half at radius r."""
    dip = horizon_dip(r, R)
    e = MU_WIDTH * math.sinh(min(max(x, 0.0), 1.0) * _mu_frame(dip, ground))
    return clamp_cos(math.sin(-dip - e if ground else e - dip))


@njit(cache=True)
def cell_mu(imu, n_mu, r, R, Rt):
    """(mu, hits_ground) of node imu of the mu axis at radius r (inverse mapping): nodes
    0 .. n/2-1 the ground half from the horizon to the nadir, n/2 .. n-1 the sky half from
    the zenith to the horizon (:func:`mu_unit`)."""
    half = n_mu // 2
    if imu < half:
        return mu_from_unit(imu / (half - 1.0), r, True, R), True
    return mu_from_unit(1.0 - (imu - half) / (half - 1.0), r, False, R), False


@njit(cache=True)
def cell_nu(inu, n_nu, mu, mu_s):
    nu = -1.0 + 2.0 * inu / (n_nu - 1.0)
    s = math.sqrt(max((1.0 - mu * mu) * (1.0 - mu_s * mu_s), 0.0))
    return min(max(nu, mu * mu_s - s), mu * mu_s + s)


@njit(cache=True)
def _split(f, n):
    """Integer node and fraction of a continuous index f on an axis of n nodes."""
    f = min(max(f, 0.0), n - 1.0)
    i = min(int(f), n - 2)
    return i, f - i


@njit(cache=True)
def r_index(r, n_r, R, Rt):
    H = math.sqrt(Rt * Rt - R * R)
    rho = math.sqrt(max(r * r - R * R, 0.0))
    return _split(rho / H * (n_r - 1), n_r)


@njit(cache=True)
def mu_index_framed(mu, ground, n_mu, frame):
    """:func:`mu_index` with the constants ``frame`` of :func:`mu_frame` (a fixed r)."""
    half = n_mu // 2
    x = mu_unit_framed(mu, ground, frame)
    if ground:
        return _split(x * (half - 1.0), half)
    i, b = _split((1.0 - x) * (half - 1.0), half)
    return i + half, b


@njit(cache=True)
def mu_index(r, mu, ground, n_mu, R, Rt):
    """Node and fraction on the mu axis, staying in the half of the ray's kind
    (:func:`mu_unit`)."""
    return mu_index_framed(mu, ground, n_mu, mu_frame(r, R))


@njit(cache=True, fastmath=True)
def density_mu_s_index(mu_s_t, frame, n_msj):
    """Node and fraction of mu_s_t on the scattering density's mu_s axis (the mapping of
    :func:`mu_s_unit`, its own node count; ``frame`` from :func:`mu_s_frame`)."""
    return _split(mu_s_unit_framed(mu_s_t, frame) * (n_msj - 1), n_msj)


@njit(cache=True, fastmath=True)
def density_phi_index(nu, mu_s_t, mt, n_pj):
    """Node and fraction of the azimuth about the sun, measured from the sun's vertical plane
    on the zenith side, of a ray with local zenith cosine mt and sun cosine nu (local sun
    zenith cosine mu_s_t), on the scattering density's phi axis over [0, pi]."""
    den = math.sqrt(max((1.0 - nu * nu) * (1.0 - mu_s_t * mu_s_t), 0.0))
    cphi = 1.0 if den < 1e-9 else clamp_cos((mt - nu * mu_s_t) / den)
    return _split(math.acos(cphi) / math.pi * (n_pj - 1), n_pj)


# -- the rays of the 4-D table ---------------------------------------------------------------------
@njit(cache=True)
def mu_s_nodes(n_ms, mu_s_min):
    """mu_s of every node of a table's mu_s axis of n_ms nodes."""
    mus = np.empty(n_ms)
    for ims in range(n_ms):
        mus[ims] = mu_s_from_unit(ims / (n_ms - 1.0), mu_s_min)
    return mus


@njit(cache=True)
def table_ray(idx, n_r, n_mu, R, Rt, mus, n_nu, n_q, ts, tq, wq, nus):
    """The view ray of the 4-D table's (r, mu) cell number idx (r major): (ir, imu, r, mu,
    hits_ground, number of quadrature nodes); its nodes and weights in tq, wq
    (:func:`._geometry.ray_nodes`) and nus[ims * n_nu + inu] the nu of every (mu_s, nu)
    node (mu_s at ``mus``)."""
    ir = idx // n_mu
    imu = idx % n_mu
    r = cell_r(ir, n_r, R, Rt)
    mu, ground = cell_mu(imu, n_mu, r, R, Rt)
    for ims in range(mus.shape[0]):
        for inu in range(n_nu):
            nus[ims * n_nu + inu] = cell_nu(inu, n_nu, mu, mus[ims])
    d = distance_to_ground(r, mu, R) if ground else distance_to_top(r, mu, Rt)
    return ir, imu, r, mu, ground, ray_nodes(r, mu, d, n_q, ts, tq, wq)
