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
  HG, Rayleigh by rejection from the uniform sphere), the Lambertian ground by cosine
  sampling;
* Russian roulette after ``RR_ORDER`` scattering orders.

Polarisation (Stokes vector (I, Q, U, V)): the path carries the 4x4 matrix A that maps a
Stokes vector of the current backward segment (in its reference frame) to the camera's
frame. At a scattering vertex A <- A L(phi) F(Theta) / F11(Theta) with L the rotation from the
scattering-plane frame to the current frame and F the scattering matrix in the scattering
plane (Hansen & Travis 1974, eq. 2.15 for Rayleigh with depolarisation). Frames are kept as
a unit vector ``a`` (parallel axis) perpendicular to the propagation direction k; the
perpendicular axis is b = k x a.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from skydome.transport._kernels import profile_density, ray_segment, sun_columns

RAYLEIGH, HENYEY_GREENSTEIN, CORNETTE_SHANKS, ISOTROPIC = 0, 1, 2, 3
EXPONENTIAL, TENT, UNIFORM, GAUSSIAN = 0, 1, 2, 3
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


# -- phase functions and scattering matrices --------------------------------------------------
@njit(cache=True)
def phase(code, g, rho, c):
    """Normalised phase function [sr^-1]. Rayleigh with depolarisation factor rho:
    3/(8 pi) [(1 + rho) + (1 - rho) c^2] / (2 + rho) (Chandrasekhar 1950; Hansen & Travis
    1974 eq. 2.15, element P11); HG ([KRZ06] eq. 10); Cornette-Shanks ([KRZ06] eq. 11)."""
    if code == RAYLEIGH:
        return 3.0 / (8.0 * math.pi) * ((1.0 + rho) + (1.0 - rho) * c * c) / (2.0 + rho)
    if code == HENYEY_GREENSTEIN:
        d = 1.0 + g * g - 2.0 * g * c
        return (1.0 - g * g) / (d * math.sqrt(d)) * INV_4PI
    if code == CORNETTE_SHANKS:
        d = 1.0 + g * g - 2.0 * g * c
        return 3.0 * (1.0 - g * g) / (2.0 * (2.0 + g * g)) * (1.0 + c * c) / (d * math.sqrt(d)) * INV_4PI
    return INV_4PI


@njit(cache=True)
def matrix_ratios(code, rho, c):
    """(F12, F22, F33, F44) / F11 of the scattering matrix in the scattering plane.

    Rayleigh (Hansen & Travis 1974 eq. 2.15, Delta = (1 - rho)/(1 + rho/2),
    Delta' = (1 - 2 rho)/(1 - rho)):  F11 = Delta 3/4 (1 + c^2) + 1 - Delta,
    F12 = -Delta 3/4 (1 - c^2), F22 = Delta 3/4 (1 + c^2), F33 = Delta 3/2 c,
    F44 = Delta Delta' 3/2 c.  Cornette-Shanks: the Rayleigh shape with rho = 0 (its
    (1 + c^2) factor is the Rayleigh one).  HG and isotropic: depolarising, F = F11 diag(1,0,0,0).
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
    """Cosine of the scattering angle drawn from the phase function."""
    if code == HENYEY_GREENSTEIN or code == CORNETTE_SHANKS:
        while True:
            u = _rand(state)
            if abs(g) < 1e-6:
                c = 2.0 * u - 1.0
            else:
                s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u)
                c = (1.0 + g * g - s * s) / (2.0 * g)        # HG inversion
            c = min(max(c, -1.0), 1.0)
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
def rotate_about(w, c, phi, out):
    """out = unit vector at angle acos(c) from w with azimuth phi about w."""
    s = math.sqrt(max(1.0 - c * c, 0.0))
    # orthonormal basis (Duff et al. 2017)
    sign = 1.0 if w[2] >= 0.0 else -1.0
    a = -1.0 / (sign + w[2])
    b = w[0] * w[1] * a
    t1x, t1y, t1z = 1.0 + sign * w[0] * w[0] * a, sign * b, -sign * w[0]
    t2x, t2y, t2z = b, sign + w[1] * w[1] * a, -w[1]
    cp = math.cos(phi) * s
    sp = math.sin(phi) * s
    out[0] = c * w[0] + cp * t1x + sp * t2x
    out[1] = c * w[1] + cp * t1y + sp * t2y
    out[2] = c * w[2] + cp * t1z + sp * t2z
    n = math.sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2])
    out[0] /= n
    out[1] /= n
    out[2] /= n


@njit(cache=True)
def _cross(a, b, out):
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@njit(cache=True)
def _plane_frames(k_out, k_in, a_cur, tmp, a_in):
    """Scattering plane of k_in -> k_out (propagation directions). Returns (cos 2phi,
    sin 2phi) of the rotation L from the scattering-plane frame of the outgoing beam to its
    current frame ``a_cur``, and writes the scattering-plane parallel axis of the incoming
    beam into ``a_in`` (a = n x k, n = k_in x k_out / |.|)."""
    _cross(k_in, k_out, tmp)
    nn = math.sqrt(tmp[0] * tmp[0] + tmp[1] * tmp[1] + tmp[2] * tmp[2])
    if nn < 1e-12:
        # forward/backward scattering: any plane; keep the current frame
        for j in range(3):
            a_in[j] = a_cur[j]
        return 1.0, 0.0
    n0, n1, n2 = tmp[0] / nn, tmp[1] / nn, tmp[2] / nn
    # outgoing scattering-plane axes: a_sp = n x k_out, b_sp = k_out x a_sp = n
    asx = n1 * k_out[2] - n2 * k_out[1]
    asy = n2 * k_out[0] - n0 * k_out[2]
    asz = n0 * k_out[1] - n1 * k_out[0]
    c = asx * a_cur[0] + asy * a_cur[1] + asz * a_cur[2]
    s = n0 * a_cur[0] + n1 * a_cur[1] + n2 * a_cur[2]
    h = c * c + s * s
    if h <= 0.0:
        c, s, h = 1.0, 0.0, 1.0
    a_in[0] = n1 * k_in[2] - n2 * k_in[1]
    a_in[1] = n2 * k_in[0] - n0 * k_in[2]
    a_in[2] = n0 * k_in[1] - n1 * k_in[0]
    return (c * c - s * s) / h, 2.0 * c * s / h


@njit(cache=True)
def _segment_majorant(codes, p0s, p1s, ext_l, r, mu, t_end, R):
    """sum_c beta_e,c max rho_c over the altitudes the segment [0, t_end] spans."""
    r_end = math.sqrt(max(r * r + 2.0 * r * mu * t_end + t_end * t_end, 0.0))
    t_low = min(max(-r * mu, 0.0), t_end)
    r_low = math.sqrt(max(r * r + 2.0 * r * mu * t_low + t_low * t_low, 0.0))
    h_lo = max(r_low - R, 0.0)
    h_hi = max(max(r, r_end) - R, h_lo)
    m = 0.0
    for c in range(codes.shape[0]):
        if ext_l[c] <= 0.0:
            continue
        code = codes[c]
        if code == EXPONENTIAL:
            d = profile_density(code, p0s[c], p1s[c], h_lo)
        elif code == UNIFORM:
            d = 1.0 if h_lo < p0s[c] else 0.0
        else:   # tent / gaussian peak at p0
            if h_lo <= p0s[c] <= h_hi:
                d = 1.0
            else:
                d = max(profile_density(code, p0s[c], p1s[c], h_lo),
                        profile_density(code, p0s[c], p1s[c], h_hi))
        m += ext_l[c] * d
    return m * (1.0 + 1e-9)


@njit(cache=True)
def _camera_columns(codes, p0s, p1s, ext_l, r, mu, R, t0, t1, node_t, node_tau):
    """Cumulative optical depth along the camera ray at nodes t_k in [t0, t1]: the ray is
    split at its lowest point and each piece gets N_CAMERA nodes spaced geometrically away
    from the dense end (the rule of ``transport._kernels.column_quadrature``); each interval
    is integrated by Simpson's rule. Returns the number of nodes (node_tau[0] = 0)."""
    node_t[0] = t0
    node_tau[0] = 0.0
    nn = 1
    if t1 <= t0:
        return nn
    tmin = min(max(-r * mu, t0), t1)
    nc = codes.shape[0]
    for piece in range(2):
        if piece == 0:
            a, b = t0, tmin
        else:
            a, b = tmin, t1
        length = b - a
        if length <= 0.0:
            continue
        vmax = math.log1p(length / SCALE_M)
        dv = vmax / N_CAMERA
        for kk in range(1, N_CAMERA + 1):
            if piece == 0:
                t = b - SCALE_M * math.expm1((N_CAMERA - kk) * dv)
            else:
                t = a + SCALE_M * math.expm1(kk * dv)
            if kk == N_CAMERA:
                t = b
            tp = node_t[nn - 1]
            tm = 0.5 * (tp + t)
            sacc = 0.0
            for q in range(3):
                tt = tp if q == 0 else (tm if q == 1 else t)
                wq = 1.0 if q != 1 else 4.0
                rr = math.sqrt(max(r * r + 2.0 * r * mu * tt + tt * tt, R * R))
                for c in range(nc):
                    if ext_l[c] > 0.0:
                        sacc += wq * ext_l[c] * profile_density(codes[c], p0s[c], p1s[c], rr - R)
            node_t[nn] = t
            node_tau[nn] = node_tau[nn - 1] + (t - tp) / 6.0 * sacc
            nn += 1
    return nn


@njit(cache=True)
def _sun_sample(sun, cos_alpha, state, out):
    """A direction uniform in the solar cone of half-angle acos(cos_alpha)."""
    c = 1.0 - _rand(state) * (1.0 - cos_alpha)
    rotate_about(sun, c, TWO_PI * _rand(state), out)


@njit(cache=True)
def _mat_apply(A, v0, v1, v2, v3, est, scale, polarised):
    """est += scale * A v."""
    if polarised:
        for j in range(4):
            est[j] += scale * (A[j, 0] * v0 + A[j, 1] * v1 + A[j, 2] * v2 + A[j, 3] * v3)
    else:
        est[0] += scale * A[0, 0] * v0


@njit(cache=True)
def _mat_rot_scatter(A, c2, s2, f12, f22, f33, f44, tmp):
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


@njit(cache=True)
def _trace_one(i, l, dirs, zen_ref, r0, sun, cos_alpha, R, Rt, codes, p0s, p1s, beta_s, beta_e,
               phase_codes, phase_g, phase_rho, albedo, e_sun, table, n_samples, seed, polarised,
               max_order, mean, err):
    nc = codes.shape[0]
    state = np.empty(1, dtype=np.uint64)
    state[0] = _stream_seed(seed, i, l)
    A = np.empty((4, 4))
    est = np.zeros(4)
    s1 = np.zeros(4)
    s2 = np.zeros(4)
    pos = np.empty(3)
    w = np.empty(3)
    wn = np.empty(3)
    k_out = np.empty(3)
    k_in = np.empty(3)
    a_cur = np.empty(3)
    a_new = np.empty(3)
    tmp = np.empty(3)
    ws = np.empty(3)
    node_t = np.empty(2 * N_CAMERA + 1)
    node_tau = np.empty(2 * N_CAMERA + 1)
    scol = np.empty(nc)
    ext_l = np.empty(nc)
    sca_l = np.empty(nc)
    mus_c = np.empty(nc)
    for c in range(nc):
        ext_l[c] = beta_e[c, l]
        sca_l[c] = beta_s[c, l]
    esun = e_sun[l]
    alb = albedo[l]
    # -- the camera ray: cumulative optical depth for the forced first collision ----------
    cam_r0 = r0
    cam_mu = dirs[i, 2]
    c_t0, c_t1, cam_ground = ray_segment(cam_r0, cam_mu, R, Rt)
    n_nodes = _camera_columns(codes, p0s, p1s, ext_l, cam_r0, cam_mu, R, c_t0, c_t1, node_t,
                              node_tau)
    tau_cam = node_tau[n_nodes - 1]
    t_cam = math.exp(-tau_cam)
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
                for m in range(4):
                    A[j, m] = 1.0 if j == m else 0.0
            pos[0], pos[1], pos[2] = 0.0, 0.0, r0
            for j in range(3):
                w[j] = dirs[i, j]
                a_cur[j] = zen_ref[i, j]
            weight = 1.0
            w0 = 1.0
            order = 0
            first = True
            while True:
                r = math.sqrt(pos[0] * pos[0] + pos[1] * pos[1] + pos[2] * pos[2])
                mu = (pos[0] * w[0] + pos[1] * w[1] + pos[2] * w[2]) / r
                t0, t_end, hits_ground = ray_segment(r, mu, R, Rt)
                if first:
                    first = False
                    mus = 0.0
                    if branch == 1:
                        collided = False
                        t_end = c_t1
                        w0 = t_cam
                    else:
                        # invert the tabulated optical depth: tau* = -ln(1 - xi (1 - T))
                        collided = True
                        w0 = -math.expm1(-tau_cam)
                        target = -math.log1p(-_rand(state) * w0)
                        lo = 0
                        hi = n_nodes - 1
                        while hi - lo > 1:
                            mid = (lo + hi) // 2
                            if node_tau[mid] <= target:
                                lo = mid
                            else:
                                hi = mid
                        dtau = node_tau[hi] - node_tau[lo]
                        if dtau <= 0.0:
                            break                   # (measure zero: xi at the very end)
                        mut = dtau / (node_t[hi] - node_t[lo])     # extinction of the interval
                        t = node_t[lo] + (target - node_tau[lo]) / mut
                        rr = math.sqrt(max(cam_r0 * cam_r0 + 2.0 * cam_r0 * cam_mu * t + t * t, 0.0))
                        for c in range(nc):
                            mus_c[c] = sca_l[c] * profile_density(codes[c], p0s[c], p1s[c], rr - R)
                            mus += mus_c[c]
                else:
                    # -- delta tracking along [0, t_end] --------------------------------------
                    mbar = _segment_majorant(codes, p0s, p1s, ext_l, r, mu, t_end, R)
                    t = 0.0
                    collided = False
                    mut = 0.0
                    mus = 0.0
                    if t_end > t0 and mbar > 0.0:
                        while True:
                            t -= math.log(1.0 - _rand(state)) / mbar
                            if t >= t_end:
                                break
                            rr = math.sqrt(max(r * r + 2.0 * r * mu * t + t * t, 0.0))
                            mut = 0.0
                            mus = 0.0
                            for c in range(nc):
                                d = profile_density(codes[c], p0s[c], p1s[c], rr - R)
                                mut += ext_l[c] * d
                                mus_c[c] = sca_l[c] * d
                                mus += mus_c[c]
                            if _rand(state) * mbar < mut:
                                collided = True
                                break
                if not collided and not hits_ground:
                    break                                   # leaves the atmosphere
                order += 1
                if collided:
                    for j in range(3):
                        pos[j] += t * w[j]
                    if mus <= 0.0:
                        break                               # pure absorber
                    weight *= mus / mut                     # local single-scattering albedo
                    rloc = math.sqrt(pos[0] * pos[0] + pos[1] * pos[1] + pos[2] * pos[2])
                    for j in range(3):
                        k_out[j] = -w[j]
                    # -- next-event estimation towards the sun disc ---------------------------
                    _sun_sample(sun, cos_alpha, state, ws)
                    mu_s = (pos[0] * ws[0] + pos[1] * ws[1] + pos[2] * ws[2]) / rloc
                    if sun_columns(table, codes, p0s, p1s, rloc, mu_s, R, Rt, False, 0, 1.0, scol):
                        tau = 0.0
                        for c in range(nc):
                            tau += ext_l[c] * scol[c]
                        tr = math.exp(-tau)
                        cth = ws[0] * w[0] + ws[1] * w[1] + ws[2] * w[2]
                        if polarised:
                            for j in range(3):
                                k_in[j] = -ws[j]
                            c2, s2r = _plane_frames(k_out, k_in, a_cur, tmp, a_new)
                            v0 = 0.0
                            v1 = 0.0
                            for c in range(nc):
                                if mus_c[c] > 0.0:
                                    p = phase(phase_codes[c], phase_g[c], phase_rho[c], cth) * mus_c[c]
                                    f12, _f22, _f33, _f44 = matrix_ratios(phase_codes[c], phase_rho[c], cth)
                                    v0 += p
                                    v1 += p * f12
                            # L(phi) (v0, v1, 0, 0)
                            _mat_apply(A, v0, c2 * v1, -s2r * v1, 0.0, est,
                                       w0 * weight / mus * esun * tr, True)
                        else:
                            p = 0.0
                            for c in range(nc):
                                if mus_c[c] > 0.0:
                                    p += phase(phase_codes[c], phase_g[c], phase_rho[c], cth) * mus_c[c]
                            est[0] += w0 * weight * p / mus * esun * tr
                    if max_order >= 0 and order >= max_order:
                        break
                    # -- continue: choose a constituent, sample its phase function ------------
                    u = _rand(state) * mus
                    cc = nc - 1
                    acc = 0.0
                    for c in range(nc):
                        acc += mus_c[c]
                        if u < acc:
                            cc = c
                            break
                    while mus_c[cc] <= 0.0 and cc > 0:
                        cc -= 1
                    cth = sample_cos(phase_codes[cc], phase_g[cc], phase_rho[cc], state)
                    rotate_about(w, cth, TWO_PI * _rand(state), wn)
                    if polarised:
                        for j in range(3):
                            k_in[j] = -wn[j]
                        c2, s2r = _plane_frames(k_out, k_in, a_cur, tmp, a_new)
                        f12, f22, f33, f44 = matrix_ratios(phase_codes[cc], phase_rho[cc], cth)
                        _mat_rot_scatter(A, c2, s2r, f12, f22, f33, f44, tmp)
                        for j in range(3):
                            a_cur[j] = a_new[j]
                    for j in range(3):
                        w[j] = wn[j]
                else:
                    # -- Lambertian ground ----------------------------------------------------
                    for j in range(3):
                        pos[j] += t_end * w[j]
                    rg = math.sqrt(pos[0] * pos[0] + pos[1] * pos[1] + pos[2] * pos[2])
                    for j in range(3):
                        pos[j] *= R * (1.0 + 1e-12) / rg   # just above the ground
                        tmp[j] = pos[j] / (R * (1.0 + 1e-12))  # normal
                    if alb <= 0.0:
                        break
                    _sun_sample(sun, cos_alpha, state, ws)
                    mu_s = tmp[0] * ws[0] + tmp[1] * ws[1] + tmp[2] * ws[2]
                    if mu_s > 0.0 and sun_columns(table, codes, p0s, p1s, R * (1.0 + 1e-12), mu_s, R,
                                                  Rt, False, 0, 1.0, scol):
                        tau = 0.0
                        for c in range(nc):
                            tau += ext_l[c] * scol[c]
                        # reflected light is unpolarised: only A's first column matters
                        _mat_apply(A, 1.0, 0.0, 0.0, 0.0, est,
                                   w0 * weight * alb / math.pi * esun * mu_s * math.exp(-tau),
                                   polarised)
                    if max_order >= 0 and order >= max_order:
                        break
                    weight *= alb
                    # cosine-weighted hemisphere about the normal
                    u1 = _rand(state)
                    rotate_about(tmp, math.sqrt(u1), TWO_PI * _rand(state), w)
                    for j in range(4):          # depolarise: keep the first column
                        A[j, 1] = 0.0
                        A[j, 2] = 0.0
                        A[j, 3] = 0.0
                    # new frame: any axis perpendicular to the new ray
                    _cross(tmp, w, a_cur)
                    nn = math.sqrt(a_cur[0] ** 2 + a_cur[1] ** 2 + a_cur[2] ** 2)
                    if nn < 1e-12:
                        rotate_about(w, 0.0, 0.0, a_cur)
                    else:
                        for j in range(3):
                            a_cur[j] /= nn
                # -- Russian roulette -----------------------------------------------------------
                if order >= RR_ORDER:
                    q = min(0.95, weight)
                    if q <= 0.0 or _rand(state) >= q:
                        break
                    weight /= q      # A stays normalised (A[0, 0] = 1 at the camera)
        nv = 4 if polarised else 1
        for j in range(nv):
            s1[j] += est[j]
            s2[j] += est[j] * est[j]
    n = float(n_samples)
    nv = 4 if polarised else 1
    for j in range(nv):
        m = s1[j] / n
        mean[i, l, j] = m
        var = (s2[j] / n - m * m) * n / (n - 1.0) if n > 1 else 0.0
        err[i, l, j] = math.sqrt(max(var, 0.0) / n)


@njit(parallel=True, cache=True)
def trace(dirs, zen_ref, r0, sun, cos_alpha, R, Rt, codes, p0s, p1s, beta_s, beta_e, phase_codes,
          phase_g, phase_rho, albedo, e_sun, table, n_samples, seed, polarised, max_order,
          mean, err):
    """Monte Carlo radiance (Stokes vector) from each direction, ``mean`` and its standard
    error ``err``, both (n, nl, 4) (only component 0 when not ``polarised``).

    ``dirs`` (n, 3) unit vectors the light arrives from; ``zen_ref`` (n, 3) the parallel axis
    of each camera ray's Stokes frame; ``sun`` (3,) unit vector to the sun's centre;
    ``cos_alpha`` cosine of the sun's angular radius; ``max_order`` < 0 for no limit.
    """
    n = dirs.shape[0]
    nl = e_sun.shape[0]
    for idx in prange(n * nl):
        i = idx // nl
        l = idx % nl
        _trace_one(i, l, dirs, zen_ref, r0, sun, cos_alpha, R, Rt, codes, p0s, p1s, beta_s, beta_e,
                   phase_codes, phase_g, phase_rho, albedo, e_sun, table, n_samples, seed,
                   polarised, max_order, mean, err)


@njit(cache=True)
def sample_cos_many(code, g, rho, n, seed):
    """n cosines drawn by :func:`sample_cos` (for testing the samplers)."""
    state = np.empty(1, dtype=np.uint64)
    state[0] = _stream_seed(seed, 0, 0)
    out = np.empty(n)
    for k in range(n):
        out[k] = sample_cos(code, g, rho, state)
    return out
