"""numba kernels of the ``montecarlo`` sky: backward (adjoint) path tracing with Stokes vectors.

Private: plain floats and arrays, no options, no units (metres, m^-1, cosines). The public
model :mod:`skydome.models.simulated.montecarlo` validates its inputs and calls
:func:`trace`.

Geometry as in :mod:`skydome.transport._kernels`: planet of radius ``R`` centred on the
origin, top of the atmosphere at ``Rt``, observer on the +z axis at distance ``r0``, so that
the global frame at the observer is East-North-Up.

Estimator (per direction, per wavelength, per path):

* the camera ray's first collision is forced inside the air by inverting its tabulated
  optical depth (weight 1 - T); where the camera ray meets the ground the uncollided branch
  (weight T) is followed as well;
* every later free path by delta tracking (Woodcock) against the majorant
  mu_bar = sum_c beta_e,c max rho_c along the segment (exact for any density profile);
* at a real collision the throughput is multiplied by the local single-scattering albedo
  mu_s(x) / mu_t(x) (ozone absorption included in mu_t);
* next-event estimation towards the sun at every vertex: a direction uniform in the solar
  cone (the disc), transmittance of the shadow ray from the column table (the same table as
  ``single_scattering``; zero where the ray hits the planet);
* the continuation direction is sampled from the phase function of one constituent chosen
  with probability beta_s,c rho_c / mu_s (HG analytically, Cornette-Shanks by rejection from
  HG, Rayleigh by rejection from the uniform sphere, a tabulated phase function by
  inverting its cumulative distribution), the Lambertian ground by cosine sampling;
* Russian roulette after ``RR_ORDER`` scattering orders.

With ``segment_sun`` (unpolarised only) the next-event estimate of each collision in the
air is replaced by its expected value given the segment's direction, integrated along the
segment before it is tracked (:func:`_segment_sun`): for the camera ray with the forced
collision of weight 1 - T and pdf mu_t e^-tau / (1 - T), and for a later segment with
delta tracking's pdf mu_t e^-tau, the expected contribution of the next collision's
next event is

    E_sun int_0^t_end T(0, t) sum_c mu_s,c(t) p_c(theta_s(t)) T_sun(t) dt,

the estimator's own integrand times the collision density, so the path is unchanged and
the estimate stays unbiased up to the quadrature. The ground's next event is kept. In
twilight most collisions lie in the earth's shadow and the sunlit air is reached only by
the rare path that collides there; the integral gathers the sunlit part of every segment
instead, so that a path's estimate is rarely zero (the sunlit air above the shadow is what
lights the deep-twilight sky). With it the camera ray's first collision is drawn from a
one-sample mixture of the optical depth's density and a uniform one (CAMERA_MIX), so that a
collision high on the ray, near the sunlit air, is not a rare event of large weight.

Polarisation (Stokes vector (I, Q, U, V)): the path carries the 4x4 matrix A that maps a
Stokes vector of the current backward segment (in its reference frame) to the camera's
frame. At a scattering vertex A <- A L(phi) F(Theta) / F11(Theta) with L the rotation from the
scattering-plane frame to the current frame and F the scattering matrix in the scattering
plane (Hansen & Travis 1974, eq. 2.15 for Rayleigh with depolarisation; HG, isotropic and
tabulated phase functions depolarise, F = F11 diag(1, 0, 0, 0)). Frames are kept as
a unit vector ``a`` (parallel axis) perpendicular to the propagation direction k; the
perpendicular axis is b = k x a.
"""

from __future__ import annotations

import math

import numpy as np
from skydome._kernel_cache import njit, prange

from skydome.transport._geometry import (radius_along, radius_along_above, ray_hits_ground,
                                        ray_segment, safe_sqrt)
from skydome.transport._kernels import _sort_small
from skydome.transport._tables import lookup_columns
from skydome.transport._medium import EXPONENTIAL, UNIFORM, profile_density
from skydome.transport._phase import (CORNETTE_SHANKS, HENYEY_GREENSTEIN, RAYLEIGH, TABULATED,
                                      phase_value, rayleigh_gamma, rayleigh_rho,
                                      sample_henyey_greenstein, sample_tabulated, tabulated_phase)
from skydome.transport._quadrature import geometric_edge, geometric_node, geometric_step

RR_ORDER = 4          # Russian roulette from this scattering order on
N_CAMERA = 128        # optical-depth nodes per piece of the camera ray
SCALE_M = 500.0       # node spacing scale [m] (as the transport quadrature)
INV_4PI = 1.0 / (4.0 * math.pi)
TWO_PI = 2.0 * math.pi


# -- random numbers: SplitMix64 (Steele, Lea & Flood 2014), one stream per (direction, lambda) ---
@njit(cache=True)
def _mix64(z):
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


@njit(cache=True)
def _stream_seed(seed, i, l):
    """Seed of the stream for direction i and wavelength l (independent of threads)."""
    z = _mix64(np.uint64(seed) + np.uint64(0x9E3779B97F4A7C15))
    z = _mix64(z ^ (np.uint64(i) * np.uint64(0xD1B54A32D192ED03)))
    return _mix64(z ^ (np.uint64(l) * np.uint64(0x8CB92BA72F3D8DD7) + np.uint64(1)))


@njit(cache=True)
def _rand(state):
    """Uniform double in [0, 1); ``state`` is a uint64 array of length 1."""
    state[0] += np.uint64(0x9E3779B97F4A7C15)
    z = _mix64(state[0])
    return float(z >> np.uint64(11)) * (1.0 / 9007199254740992.0)


# -- phase functions and scattering matrices (the phase functions live in transport._phase) --
@njit(cache=True)
def phase(code, g, rho, c):
    """Normalised phase function [sr^-1] of an analytic code with asymmetry g (HG, CS) or
    depolarisation ratio rho (Rayleigh): :func:`skydome.transport._phase.phase_value`."""
    return phase_value(code, rayleigh_gamma(rho) if code == RAYLEIGH else g, c)


@njit(cache=True)
def matrix_ratios(code, rho, c):
    """(F12, F22, F33, F44) / F11 of the scattering matrix in the scattering plane.

    Rayleigh (Hansen & Travis 1974 eq. 2.15, Delta = (1 - rho)/(1 + rho/2),
    Delta' = (1 - 2 rho)/(1 - rho)):  F11 = Delta 3/4 (1 + c^2) + 1 - Delta,
    F12 = -Delta 3/4 (1 - c^2), F22 = Delta 3/4 (1 + c^2), F33 = Delta 3/2 c,
    F44 = Delta Delta' 3/2 c.  Cornette-Shanks: the Rayleigh shape with rho = 0 (its
    (1 + c^2) factor is the Rayleigh one).  HG, isotropic and tabulated: depolarising,
    F = F11 diag(1,0,0,0).
    """
    if code == RAYLEIGH:
        delta = (1.0 - rho) / (1.0 + 0.5 * rho)
        deltap = (1.0 - 2.0 * rho) / (1.0 - rho) if rho < 1.0 else 0.0
        f11 = delta * 0.75 * (1.0 + c * c) + 1.0 - delta
        return (-delta * 0.75 * (1.0 - c * c) / f11, delta * 0.75 * (1.0 + c * c) / f11,
                delta * 1.5 * c / f11, delta * deltap * 1.5 * c / f11)
    if code == CORNETTE_SHANKS:
        f11 = 1.0 + c * c
        return -(1.0 - c * c) / f11, 1.0, 2.0 * c / f11, 2.0 * c / f11
    return 0.0, 0.0, 0.0, 0.0


@njit(cache=True)
def sample_cos(code, g, rho, state):
    """Cosine of the scattering angle drawn from an analytic phase function."""
    if code == HENYEY_GREENSTEIN or code == CORNETTE_SHANKS:
        while True:
            c = sample_henyey_greenstein(g, _rand(state))     # HG inversion
            if code == HENYEY_GREENSTEIN:
                return c
            if _rand(state) * 2.0 <= 1.0 + c * c:            # CS = HG (1 + c^2) x const
                return c
    if code == RAYLEIGH:
        while True:
            c = 2.0 * _rand(state) - 1.0
            if _rand(state) * 2.0 <= (1.0 + rho) + (1.0 - rho) * c * c:
                return c
    return 2.0 * _rand(state) - 1.0


@njit(cache=True)
def rotate_about(wx, wy, wz, c, phi):
    """Unit vector at angle acos(c) from the unit vector w with azimuth phi about w."""
    s = safe_sqrt(1.0 - c * c)
    # orthonormal basis (Duff et al. 2017)
    sign = 1.0 if wz >= 0.0 else -1.0
    a = -1.0 / (sign + wz)
    b = wx * wy * a
    t1x, t1y, t1z = 1.0 + sign * wx * wx * a, sign * b, -sign * wx
    t2x, t2y, t2z = b, sign + wy * wy * a, -wy
    cp = math.cos(phi) * s
    sp = math.sin(phi) * s
    ox = c * wx + cp * t1x + sp * t2x
    oy = c * wy + cp * t1y + sp * t2y
    oz = c * wz + cp * t1z + sp * t2z
    n = math.sqrt(ox * ox + oy * oy + oz * oz)
    return ox / n, oy / n, oz / n


@njit(cache=True)
def _cross(ax, ay, az, bx, by, bz):
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


@njit(cache=True)
def _plane_frames(kox, koy, koz, kix, kiy, kiz, ax, ay, az):
    """Scattering plane of k_in -> k_out (propagation directions). Returns (cos 2phi,
    sin 2phi) of the rotation L from the scattering-plane frame of the outgoing beam to its
    current frame (parallel axis a), and the scattering-plane parallel axis of the incoming
    beam (a = n x k, n = k_in x k_out / |.|): (cos 2phi, sin 2phi, a_in)."""
    tx, ty, tz = _cross(kix, kiy, kiz, kox, koy, koz)
    nn = math.sqrt(tx * tx + ty * ty + tz * tz)
    if nn < 1e-12:
        # forward/backward scattering: any plane; keep the current frame
        return 1.0, 0.0, ax, ay, az
    n0, n1, n2 = tx / nn, ty / nn, tz / nn
    # outgoing scattering-plane axes: a_sp = n x k_out, b_sp = k_out x a_sp = n
    asx = n1 * koz - n2 * koy
    asy = n2 * kox - n0 * koz
    asz = n0 * koy - n1 * kox
    c = asx * ax + asy * ay + asz * az
    s = n0 * ax + n1 * ay + n2 * az
    h = c * c + s * s
    if h <= 0.0:
        c, s, h = 1.0, 0.0, 1.0
    return ((c * c - s * s) / h, 2.0 * c * s / h,
            n1 * kiz - n2 * kiy, n2 * kix - n0 * kiz, n0 * kiy - n1 * kix)


# -- the path's per-wavelength constituent data: one (N_ROWS, nc) array --------------------------
P0, P1, EXT, SCA, MUS, PHP = 0, 1, 2, 3, 4, 5
N_ROWS = 6
# rows of the (2, nc) int64 array of codes
PROFILE, PHASE = 0, 1


@njit(cache=True, inline="always")
def _segment_majorant(ic, cw, R, r, mu, t_end):
    """sum_c beta_e,c max rho_c over the altitudes the segment [0, t_end] spans."""
    r_end = radius_along(r, mu, t_end)
    t_low = min(max(-r * mu, 0.0), t_end)
    r_low = radius_along(r, mu, t_low)
    h_lo = max(r_low - R, 0.0)
    h_hi = max(max(r, r_end) - R, h_lo)
    mj = 0.0
    for c in range(ic.shape[1]):
        if cw[EXT, c] <= 0.0:
            continue
        code = ic[PROFILE, c]
        p0 = cw[P0, c]
        p1 = cw[P1, c]
        if code == EXPONENTIAL:
            d = profile_density(code, p0, p1, h_lo)
        elif code == UNIFORM:
            d = 1.0 if h_lo < p0 else 0.0
        else:   # tent / gaussian peak at p0
            if h_lo <= p0 <= h_hi:
                d = 1.0
            else:
                d = max(profile_density(code, p0, p1, h_lo), profile_density(code, p0, p1, h_hi))
        mj += cw[EXT, c] * d
    return mj * (1.0 + 1e-9)


@njit(cache=True, inline="always")
def _camera_columns(ic, cw, R, r, mu, t0, t1, node_t, node_tau):
    """Cumulative optical depth along the camera ray at nodes t_k in [t0, t1]: the ray is
    split at its lowest point and each piece gets N_CAMERA nodes at the cell edges of the
    geometric rule of ``transport._quadrature`` (spaced geometrically away from the dense
    end); each interval is integrated by Simpson's rule. Returns the number of nodes
    (node_tau[0] = 0)."""
    node_t[0] = t0
    node_tau[0] = 0.0
    nn = 1
    if t1 <= t0:
        return nn
    tmin = min(max(-r * mu, t0), t1)
    nc = ic.shape[1]
    for piece in range(2):
        if piece == 0:
            a, b = t0, tmin
        else:
            a, b = tmin, t1
        length = b - a
        if length <= 0.0:
            continue
        dv = geometric_step(length, N_CAMERA, SCALE_M)
        for kk in range(1, N_CAMERA + 1):
            if piece == 0:
                t = b - geometric_edge(N_CAMERA - kk, dv, SCALE_M)
            else:
                t = a + geometric_edge(kk, dv, SCALE_M)
            if kk == N_CAMERA:
                t = b
            tp = node_t[nn - 1]
            tm = 0.5 * (tp + t)
            sacc = 0.0
            for q in range(3):
                tt = tp if q == 0 else (tm if q == 1 else t)
                wq = 1.0 if q != 1 else 4.0
                rr = radius_along_above(r, mu, tt, R)
                for c in range(nc):
                    if cw[EXT, c] > 0.0:
                        sacc += wq * cw[EXT, c] * profile_density(ic[PROFILE, c], cw[P0, c],
                                                                  cw[P1, c], rr - R)
            node_t[nn] = t
            node_tau[nn] = node_tau[nn - 1] + (t - tp) / 6.0 * sacc
            nn += 1
    return nn


@njit(cache=True)
def _sun_sample(sx, sy, sz, cos_alpha, state):
    """A direction uniform in the solar cone of half-angle acos(cos_alpha) about s."""
    c = 1.0 - _rand(state) * (1.0 - cos_alpha)
    return rotate_about(sx, sy, sz, c, TWO_PI * _rand(state))


@njit(cache=True)
def _mat_apply(A, v0, v1, v2, v3, est, scale, polarised):
    """est += scale * A v."""
    if polarised:
        for j in range(4):
            est[j] += scale * (A[j, 0] * v0 + A[j, 1] * v1 + A[j, 2] * v2 + A[j, 3] * v3)
    else:
        est[0] += scale * A[0, 0] * v0


@njit(cache=True)
def _mat_rot_scatter(A, c2, s2, f12, f22, f33, f44):
    """A <- A L(c2, s2) F with F = [[1,f12,0,0],[f12,f22,0,0],[0,0,f33,0],[0,0,0,f44]]
    (F divided by F11) and L = [[1,0,0,0],[0,c2,s2,0],[0,-s2,c2,0],[0,0,0,1]]."""
    for j in range(4):
        a0, a1, a2, a3 = A[j, 0], A[j, 1], A[j, 2], A[j, 3]
        # B = A L
        b1 = a1 * c2 - a2 * s2
        b2 = a1 * s2 + a2 * c2
        A[j, 0] = a0 + b1 * f12
        A[j, 1] = a0 * f12 + b1 * f22
        A[j, 2] = b2 * f33
        A[j, 3] = a3 * f44


# -- the steps of a path ------------------------------------------------------------------------
# The steps below are inlined into the path loop (``inline="always"``). In numba every array
# handed to an inlined function costs a reference-count update (its argument becomes a copy of
# the variable), and so does every array read out of a NamedTuple. So the steps take few
# arrays: the path's 3-vectors (vertex, direction, Stokes frame, the sampled sun direction)
# are scalars, returned as tuples where a step changes them; the per-wavelength constituent
# data are the rows of one (N_ROWS, nc) array ``cw`` and the codes the rows of one (2, nc)
# array ``ic``, both filled by :func:`_trace_one` once per (direction, wavelength) from the
# Medium record.


@njit(cache=True, inline="always")
def _mixture_phase(ic, cw, ph_table, l, cth, nc):
    """sum_c mu_s,c P_c(cos theta): the constituents' phase functions weighted by their
    local scattering coefficients cw[MUS] (tabulated ones at wavelength index l)."""
    p = 0.0
    for c in range(nc):
        if cw[MUS, c] > 0.0:
            code = ic[PHASE, c]
            if code == TABULATED:
                p += tabulated_phase(ph_table, c, l, cth) * cw[MUS, c]
            else:
                p += phase_value(code, cw[PHP, c], cth) * cw[MUS, c]
    return p


@njit(cache=True, inline="always")
def _bracket(nodes, n_nodes, x):
    """(lo, lo + 1): the interval of the ascending nodes[:n_nodes] that holds x, by
    bisection (nodes[lo] <= x; the last interval for x beyond the end)."""
    lo = 0
    hi = n_nodes - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if nodes[mid] <= x:
            lo = mid
        else:
            hi = mid
    return lo, hi


@njit(cache=True, inline="always")
def _forced_collision(ic, cw, R, node_t, node_tau, state, cam_r0, cam_mu, n_nodes, tau_cam):
    """The camera ray's first collision, forced inside the air by inverting its tabulated
    optical depth: tau* = -ln(1 - xi (1 - T)). Returns (ok, t, mu_t of the interval, mu_s)
    and the local scattering coefficients in cw[MUS]."""
    w0 = -math.expm1(-tau_cam)
    target = -math.log1p(-_rand(state) * w0)
    lo, hi = _bracket(node_tau, n_nodes, target)
    dtau = node_tau[hi] - node_tau[lo]
    if dtau <= 0.0:
        return False, 0.0, 0.0, 0.0          # (measure zero: xi at the very end)
    mut = dtau / (node_t[hi] - node_t[lo])     # extinction of the interval
    t = node_t[lo] + (target - node_tau[lo]) / mut
    rr = radius_along(cam_r0, cam_mu, t)
    mus = 0.0
    for c in range(ic.shape[1]):
        cw[MUS, c] = cw[SCA, c] * profile_density(ic[PROFILE, c], cw[P0, c], cw[P1, c], rr - R)
        mus += cw[MUS, c]
    return True, t, mut, mus


@njit(cache=True, inline="always")
def _uniform_collision(ic, cw, R, node_t, node_tau, state, cam_r0, cam_mu, n_nodes, tau_cam):
    """The camera ray's first collision drawn uniformly in distance over the air
    (segment_sun's second sampler, see :func:`_trace_one`). Returns (ok, t, mu_t of its
    interval, mu_s, q): q = the density of :func:`_forced_collision` at t times the ray's
    length, mu_t e^-tau L / (1 - T), and the local scattering coefficients in cw[MUS]."""
    length = node_t[n_nodes - 1] - node_t[0]
    t = node_t[0] + _rand(state) * length
    lo, hi = _bracket(node_t, n_nodes, t)
    dt = node_t[hi] - node_t[lo]
    if dt <= 0.0 or length <= 0.0:
        return False, 0.0, 0.0, 0.0, 0.0
    mut = (node_tau[hi] - node_tau[lo]) / dt
    tau = node_tau[lo] + mut * (t - node_t[lo])
    q = mut * math.exp(-tau) * length / -math.expm1(-tau_cam)
    rr = radius_along(cam_r0, cam_mu, t)
    mus = 0.0
    for c in range(ic.shape[1]):
        cw[MUS, c] = cw[SCA, c] * profile_density(ic[PROFILE, c], cw[P0, c], cw[P1, c], rr - R)
        mus += cw[MUS, c]
    return mut > 0.0, t, mut, mus, q


@njit(cache=True, inline="always")
def _forced_density(node_t, node_tau, n_nodes, tau_cam, t):
    """The density of :func:`_forced_collision` at distance t, mu_t e^-tau / (1 - T)
    (mu_t of t's interval, tau linear in it)."""
    lo, hi = _bracket(node_t, n_nodes, t)
    dt = node_t[hi] - node_t[lo]
    if dt <= 0.0:
        return 0.0
    mut = (node_tau[hi] - node_tau[lo]) / dt
    return mut * math.exp(-(node_tau[lo] + mut * (t - node_t[lo]))) / -math.expm1(-tau_cam)


@njit(cache=True, inline="always")
def _delta_track(ic, cw, R, state, r, mu, t0, t_end):
    """Delta tracking (Woodcock) along [0, t_end] against the segment's majorant.
    Returns (collided, t, mu_t, mu_s) at the real collision (per constituent in cw[MUS])."""
    nc = ic.shape[1]
    mbar = _segment_majorant(ic, cw, R, r, mu, t_end)
    t = 0.0
    mut = 0.0
    mus = 0.0
    if t_end > t0 and mbar > 0.0:
        while True:
            t -= math.log(1.0 - _rand(state)) / mbar
            if t >= t_end:
                break
            # local extinction mu_t and scattering mu_s
            hh = radius_along(r, mu, t) - R
            mut = 0.0
            mus = 0.0
            for c in range(nc):
                d = profile_density(ic[PROFILE, c], cw[P0, c], cw[P1, c], hh)
                mut += cw[EXT, c] * d
                cw[MUS, c] = cw[SCA, c] * d
                mus += cw[MUS, c]
            if _rand(state) * mbar < mut:
                return True, t, mut, mus
    return False, t, mut, mus


@njit(cache=True, inline="always")
def _next_event_sun(ic, cw, ph_table, table, scol, A, est, state, R, Rt, l, sx, sy, sz,
                    cos_alpha, px, py, pz, wx, wy, wz, ax, ay, az, rloc, mus, scale, polarised):
    """Next-event estimation towards the sun disc from the vertex p (backward direction w,
    Stokes frame a): est += scale x transmittance x phase-weighted mixture / mu_s (with the
    Stokes rotation when polarised)."""
    nc = ic.shape[1]
    wsx, wsy, wsz = _sun_sample(sx, sy, sz, cos_alpha, state)
    mu_s = (px * wsx + py * wsy + pz * wsz) / rloc
    if ray_hits_ground(rloc, mu_s, R):
        return                                  # in the earth's shadow
    lookup_columns(table, rloc, mu_s, R, Rt, scol)
    tau = 0.0
    for c in range(nc):
        tau += cw[EXT, c] * scol[c]
    tr = math.exp(-tau)
    cth = wsx * wx + wsy * wy + wsz * wz
    if polarised:
        # k_out = -w leaves the vertex, k_in = -ws arrives at it
        c2, s2r, _bx, _by, _bz = _plane_frames(-wx, -wy, -wz, -wsx, -wsy, -wsz, ax, ay, az)
        v0 = 0.0
        v1 = 0.0
        for c in range(nc):
            if cw[MUS, c] > 0.0:
                code = ic[PHASE, c]
                param = cw[PHP, c]
                if code == TABULATED:
                    p = tabulated_phase(ph_table, c, l, cth) * cw[MUS, c]
                else:
                    p = phase_value(code, param, cth) * cw[MUS, c]
                f12, _f22, _f33, _f44 = matrix_ratios(
                    code, rayleigh_rho(param) if code == RAYLEIGH else 0.0, cth)
                v0 += p
                v1 += p * f12
        # L(phi) (v0, v1, 0, 0)
        _mat_apply(A, v0, c2 * v1, -s2r * v1, 0.0, est, scale / mus * tr, True)
    else:
        est[0] += scale * _mixture_phase(ic, cw, ph_table, l, cth, nc) / mus * tr


N_SEGMENT = 48       # geometric midpoint nodes per piece of a segment (segment_sun)
CAMERA_MIX = 0.5     # segment_sun: share of camera-ray collisions drawn by optical depth


@njit(cache=True)
def _shadow_cuts(px, py, pz, wx, wy, wz, sx, sy, sz, R, t_end, cuts, n):
    """Append to cuts[n:] the distances in (0, t_end) where the ray p + t w crosses the
    boundary of the planet's shadow for the sun direction s: the cylinder of radius R
    about the axis through the centre along s, on the night side ((p + t w) . s < 0).
    With the parts of p and w perpendicular to s, |p_perp + t w_perp|^2 = R^2 gives
    a t^2 + 2 b t + c = 0, a = 1 - (w.s)^2, b = p.w - (p.s)(w.s), c = |p|^2 - (p.s)^2 - R^2.
    Returns the new count."""
    ws = wx * sx + wy * sy + wz * sz
    ps = px * sx + py * sy + pz * sz
    a = 1.0 - ws * ws
    if a <= 1e-14:
        return n
    b = px * wx + py * wy + pz * wz - ps * ws
    c = px * px + py * py + pz * pz - ps * ps - R * R
    disc = b * b - a * c
    if disc <= 0.0:
        return n
    sq = math.sqrt(disc)
    for sign in (-1.0, 1.0):
        t = (-b + sign * sq) / a
        if 0.0 < t < t_end and ps + t * ws < 0.0:
            cuts[n] = t
            n += 1
    return n


@njit(cache=True)
def _segment_sun(ic, cw, ph_table, table, scol, cuts, state, R, Rt, l, sx, sy, sz, cos_alpha,
                 px, py, pz, wx, wy, wz, t_end):
    """The expected next-event estimate of the next collision along the segment
    p + t w, t in [0, t_end] (per unit solar irradiance and path weight):
    int_0^t_end T(0, t) sum_c mu_s,c(t) p_c(w_s . w) T_sun(t) dt with w_s one direction
    drawn uniformly in the sun's disc for the whole segment (as the vertex estimate draws
    one per vertex), T_sun(t) = 0 in the planet's shadow for w_s.

    Quadrature: the segment is cut at its lowest point and at the shadow boundary's
    crossings (:func:`_shadow_cuts`), so that on each piece the integrand is smooth and
    either lit or dark; each piece gets N_SEGMENT nodes of the geometric midpoint rule of
    ``transport._quadrature`` dense at its lower end; T(0, t) accumulates the extinction
    at the nodes (midpoint rule, half the own node's share)."""
    nc = ic.shape[1]
    if t_end <= 0.0:
        return 0.0
    wsx, wsy, wsz = _sun_sample(sx, sy, sz, cos_alpha, state)
    cth = wsx * wx + wsy * wy + wsz * wz
    r = math.sqrt(px * px + py * py + pz * pz)
    mu = (px * wx + py * wy + pz * wz) / r
    n = 0
    cuts[n] = 0.0
    n += 1
    t_low = -r * mu
    if 0.0 < t_low < t_end:
        cuts[n] = t_low
        n += 1
    n = _shadow_cuts(px, py, pz, wx, wy, wz, wsx, wsy, wsz, R, t_end, cuts, n)
    cuts[n] = t_end
    n += 1
    _sort_small(cuts, n)                     # the (at most 5) cuts in order
    # phase function mixture per constituent (the angle to the sun is fixed on the segment)
    total = 0.0
    tau = 0.0
    for k in range(n - 1):
        a = cuts[k]
        b = cuts[k + 1]
        if b - a <= 0.0:
            continue
        tm = 0.5 * (a + b)
        qx, qy, qz = px + tm * wx, py + tm * wy, pz + tm * wz
        rm = math.sqrt(qx * qx + qy * qy + qz * qz)
        lit = not ray_hits_ground(rm, (qx * wsx + qy * wsy + qz * wsz) / rm, R)
        dense_at_b = b <= t_low            # the piece before the lowest point descends
        dv = geometric_step(b - a, N_SEGMENT, SCALE_M)
        for kk in range(N_SEGMENT):
            kq = N_SEGMENT - 1 - kk if dense_at_b else kk
            u, w = geometric_node(kq, dv, SCALE_M)
            t = b - u if dense_at_b else a + u
            qx, qy, qz = px + t * wx, py + t * wy, pz + t * wz
            rq = math.sqrt(qx * qx + qy * qy + qz * qz)
            h = rq - R
            mut = 0.0
            for c in range(nc):
                d = profile_density(ic[PROFILE, c], cw[P0, c], cw[P1, c], h)
                mut += cw[EXT, c] * d
                cw[MUS, c] = cw[SCA, c] * d
            tau_node = tau + 0.5 * mut * w
            if lit:
                mu_s = (qx * wsx + qy * wsy + qz * wsz) / rq
                if not ray_hits_ground(rq, mu_s, R):
                    lookup_columns(table, rq, mu_s, R, Rt, scol)
                    ts = 0.0
                    for c in range(nc):
                        ts += cw[EXT, c] * scol[c]
                    p = _mixture_phase(ic, cw, ph_table, l, cth, nc)
                    total += w * math.exp(-tau_node - ts) * p
            tau += mut * w
    return total


@njit(cache=True, inline="always")
def _scatter(ic, cw, ph_cdf, A, state, l, wx, wy, wz, ax, ay, az, mus, polarised):
    """Continue the path: choose a constituent with probability mu_s,c / mu_s, sample its
    phase function, rotate the direction (and the Stokes matrix and frame). Returns the new
    backward direction and Stokes frame (wx, wy, wz, ax, ay, az)."""
    nc = ic.shape[1]
    u = _rand(state) * mus
    cc = nc - 1
    acc = 0.0
    for c in range(nc):
        acc += cw[MUS, c]
        if u < acc:
            cc = c
            break
    while cw[MUS, cc] <= 0.0 and cc > 0:
        cc -= 1
    code = ic[PHASE, cc]
    rho = rayleigh_rho(cw[PHP, cc]) if code == RAYLEIGH else 0.0
    if code == TABULATED:
        cth = sample_tabulated(ph_cdf, cc, l, _rand(state))
    else:
        cth = sample_cos(code, cw[PHP, cc], rho, state)
    wnx, wny, wnz = rotate_about(wx, wy, wz, cth, TWO_PI * _rand(state))
    if polarised:
        # k_out = -w leaves the vertex, k_in = -wn arrives at it
        c2, s2r, ax, ay, az = _plane_frames(-wx, -wy, -wz, -wnx, -wny, -wnz, ax, ay, az)
        f12, f22, f33, f44 = matrix_ratios(code, rho, cth)
        _mat_rot_scatter(A, c2, s2r, f12, f22, f33, f44)
    return wnx, wny, wnz, ax, ay, az


@njit(cache=True, inline="always")
def _ground_vertex(cw, table, scol, A, est, state, R, Rt, sx, sy, sz, cos_alpha, px, py, pz,
                   wx, wy, wz, t_end, scale, polarised):
    """Move the vertex to the ground point (just above it) and add the next-event estimate
    of the sunlit Lambertian ground, scale x albedo / pi E mu_s T (``scale`` includes the
    albedo, E_sun and the path weight). Returns the vertex and the ground normal."""
    px += t_end * wx
    py += t_end * wy
    pz += t_end * wz
    rg = math.sqrt(px * px + py * py + pz * pz)
    f = R * (1.0 + 1e-12) / rg
    px *= f                                  # just above the ground
    py *= f
    pz *= f
    nx = px / (R * (1.0 + 1e-12))            # normal
    ny = py / (R * (1.0 + 1e-12))
    nz = pz / (R * (1.0 + 1e-12))
    if scale <= 0.0:
        return px, py, pz, nx, ny, nz
    wsx, wsy, wsz = _sun_sample(sx, sy, sz, cos_alpha, state)
    mu_s = nx * wsx + ny * wsy + nz * wsz
    if mu_s > 0.0 and not ray_hits_ground(R * (1.0 + 1e-12), mu_s, R):
        lookup_columns(table, R * (1.0 + 1e-12), mu_s, R, Rt, scol)
        tau = 0.0
        for c in range(scol.shape[0]):
            tau += cw[EXT, c] * scol[c]
        # reflected light is unpolarised: only A's first column matters
        _mat_apply(A, 1.0, 0.0, 0.0, 0.0, est, scale / math.pi * mu_s * math.exp(-tau),
                   polarised)
    return px, py, pz, nx, ny, nz


@njit(cache=True, inline="always")
def _ground_bounce(A, state, nx, ny, nz):
    """Continue from the ground: a cosine-weighted direction about the normal n; the
    Stokes matrix depolarised (first column kept) and a new frame. Returns the new backward
    direction and Stokes frame (wx, wy, wz, ax, ay, az)."""
    u1 = _rand(state)
    wx, wy, wz = rotate_about(nx, ny, nz, math.sqrt(u1), TWO_PI * _rand(state))
    for j in range(4):          # depolarise: keep the first column
        A[j, 1] = 0.0
        A[j, 2] = 0.0
        A[j, 3] = 0.0
    # new frame: any axis perpendicular to the new ray
    ax, ay, az = _cross(nx, ny, nz, wx, wy, wz)
    nn = math.sqrt(ax ** 2 + ay ** 2 + az ** 2)
    if nn < 1e-12:
        ax, ay, az = rotate_about(wx, wy, wz, 0.0, 0.0)
    else:
        ax /= nn
        ay /= nn
        az /= nn
    return wx, wy, wz, ax, ay, az


@njit(cache=True)
def _trace_one(i, l, dirs, zen_ref, r0, sun, cos_alpha, m, e_sun, table, n_samples, seed,
               polarised, max_order, mean, err, segment_sun=False):
    """Mean and standard error of n_samples paths for direction i at wavelength l."""
    # -- the record's arrays, read once ---------------------------------------------------
    R = m.R
    Rt = m.Rt
    ph_table = m.phase_table
    ph_cdf = m.phase_cdf
    nc = m.profile_code.shape[0]
    ic = np.empty((2, nc), dtype=np.int64)   # profile and phase codes
    cw = np.empty((N_ROWS, nc))              # per-constituent data at this wavelength
    for c in range(nc):
        ic[PROFILE, c] = m.profile_code[c]
        ic[PHASE, c] = m.phase_code[c]
        cw[P0, c] = m.profile_p0[c]
        cw[P1, c] = m.profile_p1[c]
        cw[EXT, c] = m.extinction[c, l]     # extinction at this wavelength [m^-1]
        cw[SCA, c] = m.scattering[c, l]     # scattering at this wavelength [m^-1]
        cw[MUS, c] = 0.0                    # local scattering coefficients at the vertex
        cw[PHP, c] = m.phase_param[c]
    sx, sy, sz = sun[0], sun[1], sun[2]
    # -- the path's state and work arrays -------------------------------------------------
    state = np.empty(1, dtype=np.uint64)
    state[0] = _stream_seed(seed, i, l)
    A = np.empty((4, 4))                # Stokes matrix to the camera frame
    est = np.zeros(4)                   # estimate of the current sample
    scol = np.empty(nc)                 # light-path columns
    node_t = np.empty(2 * N_CAMERA + 1)      # camera-ray nodes [m]
    node_tau = np.empty(2 * N_CAMERA + 1)    # cumulative optical depth there
    cuts = np.empty(8)                       # segment_sun: the pieces' ends
    esun = e_sun[l]
    alb = m.albedo[l]
    s1 = np.zeros(4)
    s2 = np.zeros(4)
    # -- the camera ray: cumulative optical depth for the forced first collision ----------
    cam_mu = dirs[i, 2]
    c_t0, c_t1, cam_ground = ray_segment(r0, cam_mu, R, Rt)
    n_nodes = _camera_columns(ic, cw, R, r0, cam_mu, c_t0, c_t1, node_t, node_tau)
    tau_cam = node_tau[n_nodes - 1]
    t_cam = math.exp(-tau_cam)
    nv = 4 if polarised else 1
    for _s in range(n_samples):
        for j in range(4):
            est[j] = 0.0
        for branch in range(2):
            # branch 0: the camera ray's first collision, forced inside the air (weight 1 - T);
            # branch 1: the camera ray reaches the ground without collision (weight T)
            if branch == 0 and tau_cam <= 0.0:
                continue
            if branch == 1 and not cam_ground:
                continue
            for j in range(4):
                for k in range(4):
                    A[j, k] = 1.0 if j == k else 0.0
            px, py, pz = 0.0, 0.0, r0                       # vertex [m]
            wx, wy, wz = dirs[i, 0], dirs[i, 1], dirs[i, 2]  # backward direction
            ax, ay, az = zen_ref[i, 0], zen_ref[i, 1], zen_ref[i, 2]  # Stokes frame axis
            weight = 1.0
            w0 = 1.0
            order = 0
            first = True
            while True:
                r = math.sqrt(px * px + py * py + pz * pz)
                mu = (px * wx + py * wy + pz * wz) / r
                t0, t_end, hits_ground = ray_segment(r, mu, R, Rt)
                if segment_sun and (branch == 0 or not first):
                    # the next collision's next event, integrated along the segment (its
                    # forced collision's weight 1 - T cancels for the camera ray)
                    if first:
                        est[0] += esun * _segment_sun(
                            ic, cw, ph_table, table, scol, cuts, state, R, Rt, l, sx, sy, sz,
                            cos_alpha, px, py, pz, wx, wy, wz, c_t1)
                    else:
                        est[0] += w0 * weight * esun * _segment_sun(
                            ic, cw, ph_table, table, scol, cuts, state, R, Rt, l, sx, sy, sz,
                            cos_alpha, px, py, pz, wx, wy, wz, t_end)
                if first:
                    first = False
                    mus = 0.0
                    mut = 0.0
                    t = 0.0
                    if branch == 1:
                        collided = False
                        t_end = c_t1
                        w0 = t_cam
                    else:
                        collided = True
                        w0 = -math.expm1(-tau_cam)
                        if not segment_sun:
                            ok, t, mut, mus = _forced_collision(ic, cw, R, node_t, node_tau,
                                                                state, r0, cam_mu, n_nodes,
                                                                tau_cam)
                        else:
                            # one-sample mixture: with probability CAMERA_MIX the optical
                            # depth's density p1, else uniform in distance, p2 = 1 / L;
                            # weight p1 / (a p1 + (1 - a) p2) = q / (a q + 1 - a), q = p1 L
                            # (the rare collision high on the ray, near the sunlit air,
                            # otherwise a heavy tail of the estimate in deep twilight)
                            if _rand(state) < CAMERA_MIX:
                                ok, t, mut, mus = _forced_collision(ic, cw, R, node_t,
                                                                    node_tau, state, r0, cam_mu,
                                                                    n_nodes, tau_cam)
                                q = _forced_density(node_t, node_tau, n_nodes, tau_cam, t) * (
                                    node_t[n_nodes - 1] - node_t[0])
                            else:
                                ok, t, mut, mus, q = _uniform_collision(
                                    ic, cw, R, node_t, node_tau, state, r0, cam_mu, n_nodes,
                                    tau_cam)
                            w0 *= q / (CAMERA_MIX * q + 1.0 - CAMERA_MIX)
                        if not ok:
                            break
                else:
                    collided, t, mut, mus = _delta_track(ic, cw, R, state, r, mu, t0, t_end)
                if not collided and not hits_ground:
                    break                                   # leaves the atmosphere
                order += 1
                if collided:
                    px += t * wx
                    py += t * wy
                    pz += t * wz
                    if mus <= 0.0:
                        break                               # pure absorber
                    weight *= mus / mut                     # local single-scattering albedo
                    rloc = math.sqrt(px * px + py * py + pz * pz)
                    if not segment_sun:
                        _next_event_sun(ic, cw, ph_table, table, scol, A, est, state, R, Rt,
                                        l, sx, sy, sz, cos_alpha, px, py, pz, wx, wy, wz, ax,
                                        ay, az, rloc, mus, w0 * weight * esun, polarised)
                    if max_order >= 0 and order >= max_order:
                        break
                    wx, wy, wz, ax, ay, az = _scatter(ic, cw, ph_cdf, A, state, l, wx, wy, wz,
                                                      ax, ay, az, mus, polarised)
                else:
                    px, py, pz, nx, ny, nz = _ground_vertex(
                        cw, table, scol, A, est, state, R, Rt, sx, sy, sz, cos_alpha,
                        px, py, pz, wx, wy, wz, t_end,
                        w0 * weight * alb * esun if alb > 0.0 else 0.0, polarised)
                    if alb <= 0.0:
                        break
                    if max_order >= 0 and order >= max_order:
                        break
                    weight *= alb
                    wx, wy, wz, ax, ay, az = _ground_bounce(A, state, nx, ny, nz)
                # -- Russian roulette -----------------------------------------------------------
                if order >= RR_ORDER:
                    q = min(0.95, weight)
                    if q <= 0.0 or _rand(state) >= q:
                        break
                    weight /= q      # A stays normalised (A[0, 0] = 1 at the camera)
        for j in range(nv):
            s1[j] += est[j]
            s2[j] += est[j] * est[j]
    n = float(n_samples)
    for j in range(nv):
        mn = s1[j] / n
        mean[i, l, j] = mn
        var = (s2[j] / n - mn * mn) * n / (n - 1.0) if n > 1 else 0.0
        err[i, l, j] = safe_sqrt(var / n)


@njit(parallel=True, cache=True)
def trace(dirs, zen_ref, r0, sun, cos_alpha, m, e_sun, table, n_samples, seed, polarised,
          max_order, mean, err, segment_sun=False):
    """Monte Carlo radiance (Stokes vector) from each direction through the medium m,
    ``mean`` and its standard error ``err``, both (n, nl, 4) (only component 0 when not
    ``polarised``).

    ``dirs`` (n, 3) unit vectors the light arrives from; ``zen_ref`` (n, 3) the parallel axis
    of each camera ray's Stokes frame; ``sun`` (3,) unit vector to the sun's centre;
    ``cos_alpha`` cosine of the sun's angular radius; ``table`` the light-path column table;
    ``max_order`` < 0 for no limit; ``segment_sun`` (unpolarised only): the next event of
    each collision in the air integrated along the segment before it (module docstring).
    """
    trace_rows(dirs, zen_ref, r0, sun, cos_alpha, m, e_sun, table, n_samples, seed, polarised,
               max_order, mean, err, 0, dirs.shape[0], segment_sun)


@njit(parallel=True, cache=True)
def trace_rows(dirs, zen_ref, r0, sun, cos_alpha, m, e_sun, table, n_samples, seed, polarised,
               max_order, mean, err, start, stop, segment_sun=False):
    """:func:`trace` for the directions ``start`` .. ``stop`` - 1 only (the others untouched).
    Each (direction, wavelength) keeps the random stream of its index in ``dirs``, so
    tracing the rows in blocks gives the same numbers as tracing them at once."""
    nl = e_sun.shape[0]
    for idx in prange((stop - start) * nl):
        i = start + idx // nl
        l = idx % nl
        _trace_one(i, l, dirs, zen_ref, r0, sun, cos_alpha, m, e_sun, table, n_samples, seed,
                   polarised, max_order, mean, err, segment_sun)


@njit(cache=True)
def sample_cos_many(code, g, rho, n, seed):
    """n cosines drawn by :func:`sample_cos` (for testing the samplers)."""
    state = np.empty(1, dtype=np.uint64)
    state[0] = _stream_seed(seed, 0, 0)
    out = np.empty(n)
    for k in range(n):
        out[k] = sample_cos(code, g, rho, state)
    return out
