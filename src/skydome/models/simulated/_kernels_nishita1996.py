"""numba kernels of the ``nishita1996`` model (private; imported lazily by the model).

Plain floats and arrays, metres and m^-1. The frame is planet-centred: x points towards
the sun's azimuth, z through the observer, the observer at (0, 0, r0).

* Cylindrical optical-depth table ([NDKY96] sec. 3.2): the optical depth from a point to
  the sun depends only on the point's distance ``rc`` from the axis through the planet's
  centre parallel to the sunlight and on its coordinate ``z`` along that axis. Along each
  line rc = const the column towards the sun is accumulated once, from the top of the
  atmosphere downwards.
* Sky-sphere directions ([NDKY96] sec. 4): the light arriving at a point is approximated by
  the light from a fixed set of directions d_k; each direction owns the cell of the sphere
  nearer to it than to any other, and the phase function is integrated over that cell.
  The light of order n-1 from each d_k is stored on a lattice of points covering the part
  of the atmosphere the observer sees; order n is gathered along rays through it.
"""

from __future__ import annotations

import math

import numpy as np
from skydome._kernel_cache import njit, prange

from skydome.transport._geometry import ray_segment_xyz, safe_sqrt
from skydome.transport._medium import profile_density
from skydome.transport._phase import TABULATED, phase_fill, phase_of
from skydome.transport._quadrature import piece_bounds, piece_nodes, simpson


@njit(cache=True)
def n_phase_wavelengths(m):
    """1 when no constituent's phase function depends on the wavelength, else nl: the
    wavelength axis of the phase-cell weights."""
    for c in range(m.phase_code.shape[0]):
        if m.phase_code[c] == TABULATED:
            return m.extinction.shape[1]
    return 1


@njit(parallel=True, cache=True)
def phase_cell_weights(m, cosm, dw, owner, K):
    """Phase integrals over the sky-sphere cells ([NDKY96] sec. 4): W[c, lw, j, k] =
    int_cell_j P_c(w . d_k) dw over the fine grid (cosines cosm (nf, K), solid angles dw,
    cell of each fine direction ``owner``), normalised so that sum_j W = 1 (energy
    conservation); lw indexes the wavelengths of spectral (tabulated) phase functions."""
    nc = m.profile_code.shape[0]
    nlw = n_phase_wavelengths(m)
    nf = cosm.shape[0]
    W = np.zeros((nc, nlw, K, K))
    for ck in prange(nc * nlw):
        c = ck // nlw
        lw = ck % nlw
        for f in range(nf):
            j = owner[f]
            for k in range(K):
                W[c, lw, j, k] += phase_of(m, c, lw, cosm[f, k]) * dw[f]
        for k in range(K):
            tot = 0.0
            for j in range(K):
                tot += W[c, lw, j, k]
            for j in range(K):
                W[c, lw, j, k] /= tot
    return W


# -- cylindrical optical-depth table -----------------------------------------------------------
@njit(cache=True)
def _line_column(m, rc, za, zb, n_sub, col):
    """Add the column densities between z = za and z = zb (za < zb) along the line at
    distance rc from the axis to ``col`` (Simpson's rule with n_sub intervals)."""
    codes = m.profile_code
    p0s = m.profile_p0
    p1s = m.profile_p1
    R = m.R
    nc = codes.shape[0]
    h = (zb - za) / n_sub
    for k in range(n_sub + 1):
        z = za + k * h
        w = 1.0 if (k == 0 or k == n_sub) else (4.0 if k % 2 == 1 else 2.0)
        alt = math.sqrt(rc * rc + z * z) - R
        for c in range(nc):
            col[c] += w * h / 3.0 * profile_density(codes[c], p0s[c], p1s[c], alt)


@njit(parallel=True, cache=True)
def build_cylinder_table(m, n_lo, n_hi, n_u, n_sub):
    """Columns to the sun on the cylindrical grid ([NDKY96] fig. 3).

    lower part (rc < R, lines that start on the sunlit ground): rc_i = R (1 - (1 - s)^3),
    s = i / (n_lo - 1); along the line the node j sits at altitude u_j = (Rt - R) w^2,
    w = j / (n_u - 1). Upper part (R <= rc <= Rt): rc_i = R + (Rt - R) s^2; node j at
    u = sign(w) (Rt - rc) w^2 with w = 2 j / (n_u - 1) - 1, where u = sign(z) (r - rc).
    Returns (lower (nc, n_lo, n_u), upper (nc, n_hi, n_u)).
    """
    R = m.R
    Rt = m.Rt
    nc = m.profile_code.shape[0]
    lo = np.zeros((nc, n_lo, n_u))
    hi = np.zeros((nc, n_hi, n_u))
    H = Rt - R
    for i in prange(n_lo + n_hi):
        col = np.zeros(nc)
        zs = np.zeros(n_u)
        if i < n_lo:
            s = i / (n_lo - 1.0)
            rc = R * (1.0 - (1.0 - s) ** 3)
            for j in range(n_u):
                w = j / (n_u - 1.0)
                r = R + H * w * w
                zs[j] = safe_sqrt(r * r - rc * rc)
        else:
            s = (i - n_lo) / (n_hi - 1.0)
            rc = R + H * s * s
            for j in range(n_u):
                w = 2.0 * j / (n_u - 1.0) - 1.0
                u = (Rt - rc) * w * w
                r = rc + u
                z = safe_sqrt(r * r - rc * rc)
                zs[j] = z if w >= 0 else -z
        # accumulate from the top (largest z) downwards
        for c in range(nc):
            col[c] = 0.0
        for j in range(n_u - 1, -1, -1):
            if j < n_u - 1:
                _line_column(m, rc, zs[j], zs[j + 1], n_sub, col)
            for c in range(nc):
                if i < n_lo:
                    lo[c, i, j] = col[c]
                else:
                    hi[c, i - n_lo, j] = col[c]
    return lo, hi


@njit(cache=True)
def cylinder_lookup(lo, hi, R, Rt, px, py, pz, sx, sy, sz, out):
    """Columns from point p towards the sun direction s (bilinear); False in the shadow."""
    nc = lo.shape[0]
    z = px * sx + py * sy + pz * sz
    qx = px - z * sx
    qy = py - z * sy
    qz = pz - z * sz
    rc = math.sqrt(qx * qx + qy * qy + qz * qz)
    r = math.sqrt(rc * rc + z * z)
    H = Rt - R
    n_u = lo.shape[2]
    if rc < R:
        if z < 0.0:
            return False
        n_lo = lo.shape[1]
        s = 1.0 - (max(1.0 - rc / R, 0.0)) ** (1.0 / 3.0)
        fi = s * (n_lo - 1)
        w = math.sqrt(min(max((r - R) / H, 0.0), 1.0))
        fj = w * (n_u - 1)
        i = min(int(fi), n_lo - 2)
        j = min(int(fj), n_u - 2)
        a = fi - i
        b = fj - j
        for c in range(nc):
            out[c] = ((1 - a) * ((1 - b) * lo[c, i, j] + b * lo[c, i, j + 1])
                      + a * ((1 - b) * lo[c, i + 1, j] + b * lo[c, i + 1, j + 1]))
        return True
    if rc >= Rt:
        for c in range(nc):
            out[c] = 0.0
        return True
    n_hi = hi.shape[1]
    s = math.sqrt((rc - R) / H)
    fi = s * (n_hi - 1)
    i = min(int(fi), n_hi - 2)
    a = fi - i
    # each line has its own u range; interpolate in w on both neighbouring lines
    u = r - rc
    if z < 0.0:
        u = -u
    for c in range(nc):
        out[c] = 0.0
    for side in range(2):
        ii = i + side
        wgt = (1.0 - a) if side == 0 else a
        rci = R + H * (ii / (n_hi - 1.0)) ** 2
        span = Rt - rci
        if span <= 0.0:
            continue
        w = math.sqrt(min(abs(u) / span, 1.0))
        if u < 0.0:
            w = -w
        fj = (w + 1.0) * 0.5 * (n_u - 1)
        j = min(max(int(fj), 0), n_u - 2)
        b = fj - j
        for c in range(nc):
            out[c] += wgt * ((1 - b) * hi[c, ii, j] + b * hi[c, ii, j + 1])
    return True


# -- rays -----------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def ray_buffers(n, nc, nl):
    """Zeroed work arrays of :func:`ray_nodes` for ``n`` nodes per piece, nc constituents
    and nl wavelengths: pos (2n+1, 3), wts (2n+1,), rho (2n+1, nc), trans (2n+1, nl),
    t_end (1,)."""
    k = 2 * n + 1
    return (np.zeros((k, 3)), np.zeros(k), np.zeros((k, nc)), np.zeros((k, nl)),
            np.zeros(1))


@njit(cache=True)
def ray_nodes(px, py, pz, dx, dy, dz, m, n, ts, pos, wts, rho, trans, t_end):
    """Quadrature nodes along the ray from p along d through the medium m: positions pos
    (m, 3), weights wts [m], relative densities rho (m, nc) and the transmittance from p to
    each node trans (m, nl) (optical depth by Simpson's rule between nodes). The ray is
    split at its lowest point; each piece has n midpoint nodes spaced geometrically from
    its dense end (scale ts, the rule of ``transport._quadrature``). Returns (m,
    hits_ground); t_end[0] = distance to the end, and trans[m] holds the transmittance to
    the end point."""
    codes = m.profile_code
    p0s = m.profile_p0
    p1s = m.profile_p1
    beta_e = m.extinction
    R = m.R
    nc = codes.shape[0]
    nl = beta_e.shape[1]
    t0, t1, hits = ray_segment_xyz(px, py, pz, dx, dy, dz, R, m.Rt)
    t_end[0] = t1
    if t1 < t0 or (t1 == t0 and not hits):
        for l in range(nl):
            trans[0, l] = 1.0
        return 0, False
    a_ = t0
    b_ = t0
    cnt = 0
    b = px * dx + py * dy + pz * dz
    tmin = min(max(-b, t0), t1)
    k_out = 0
    t_prev = t0
    dcol = np.zeros(nc)
    rho_prev = np.zeros(nc)
    xr = math.sqrt(px * px + py * py + pz * pz + 2 * b * t0 + t0 * t0)
    for c in range(nc):
        rho_prev[c] = profile_density(codes[c], p0s[c], p1s[c], xr - R)
    tq = np.empty(n)
    wq = np.empty(n)
    no_bits = np.empty(0, dtype=np.int64)      # piece_nodes's scalar form: no scratch
    for piece in range(3):
        if piece < 2:
            a_, b_, dense_at_b = piece_bounds(piece, t0, tmin, t1)
            if b_ - a_ <= 0.0:
                continue
            cnt = piece_nodes(a_, b_, dense_at_b, n, ts, True, tq, wq, 0, False, no_bits,
                              no_bits.view(np.float64))
        else:
            tq[0] = t1
            wq[0] = 0.0
            cnt = 1
        for kk in range(cnt):
            t = tq[kk]
            w = wq[kk]
            qx = px + t * dx
            qy = py + t * dy
            qz = pz + t * dz
            rr = math.sqrt(qx * qx + qy * qy + qz * qz)
            tm = 0.5 * (t + t_prev)
            rm = math.sqrt((px + tm * dx) ** 2 + (py + tm * dy) ** 2 + (pz + tm * dz) ** 2)
            hh = t - t_prev
            for c in range(nc):
                rc_ = profile_density(codes[c], p0s[c], p1s[c], rr - R)
                rmid = profile_density(codes[c], p0s[c], p1s[c], rm - R)
                dcol[c] += simpson(rho_prev[c], rmid, rc_, hh)
                rho_prev[c] = rc_
                rho[k_out, c] = rc_
            t_prev = t
            pos[k_out, 0] = qx
            pos[k_out, 1] = qy
            pos[k_out, 2] = qz
            wts[k_out] = w
            for l in range(nl):
                s = 0.0
                for c in range(nc):
                    s += beta_e[c, l] * dcol[c]
                trans[k_out, l] = math.exp(-s)
            k_out += 1
    return k_out - 1, hits


@njit(cache=True)
def single_along(px, py, pz, dx, dy, dz, sx, sy, sz, m, e_sun, lo, hi, n, ts, out,
                 pos, wts, rho, trans, t_end, col, phs):
    """Single-scattered radiance arriving at p from direction d ([NDKY96] eq. 1; survey
    eqs. 15-16) with the sun columns from the cylindrical table, plus the sunlit ground
    (Lambertian) where the ray hits it. Writes out (nl,); phs (nc, nl) is work space for
    the phase functions."""
    R = m.R
    Rt = m.Rt
    beta_e = m.extinction
    beta_s = m.scattering
    nc = m.profile_code.shape[0]
    nl = e_sun.shape[0]
    for l in range(nl):
        out[l] = 0.0
    n_pts, hits = ray_nodes(px, py, pz, dx, dy, dz, m, n, ts, pos, wts, rho, trans, t_end)
    nu = dx * sx + dy * sy + dz * sz
    for c in range(nc):
        phase_fill(m, c, nu, phs[c])
    for k in range(n_pts):
        if not cylinder_lookup(lo, hi, R, Rt, pos[k, 0], pos[k, 1], pos[k, 2], sx, sy, sz, col):
            continue
        for l in range(nl):
            s = 0.0
            for c in range(nc):
                s += beta_e[c, l] * col[c]
            ts_ = math.exp(-s) * trans[k, l] * wts[k]
            acc = 0.0
            for c in range(nc):
                acc += beta_s[c, l] * rho[k, c] * phs[c, l]
            out[l] += e_sun[l] * acc * ts_
    if hits:
        gx = pos[n_pts, 0]
        gy = pos[n_pts, 1]
        gz = pos[n_pts, 2]
        rg = math.sqrt(gx * gx + gy * gy + gz * gz)
        mu_s = (gx * sx + gy * sy + gz * sz) / rg
        if mu_s > 0.0:
            f = (R * (1.0 + 1e-9)) / rg
            cylinder_lookup(lo, hi, R, Rt, gx * f, gy * f, gz * f, sx, sy, sz, col)
            for l in range(nl):
                s = 0.0
                for c in range(nc):
                    s += beta_e[c, l] * col[c]
                out[l] += m.albedo[l] / math.pi * e_sun[l] * mu_s * math.exp(-s) * trans[n_pts, l]
    return n_pts, hits


# -- lattice --------------------------------------------------------------------------------------
@njit(cache=True)
def lattice_coords(qx, qy, qz, R, D, Htop, nx, nh):
    """Fractional lattice indices (fx, fy, fh) of point q. Lattice nodes: x = D sign(s) s^2,
    s in [-1, 1] (nx nodes), same for y; h = Htop w^2, w in [0, 1] (nh nodes); the node
    (x, y, h) sits at (R + h) unit(x, y, R) (gnomonic projection about the observer)."""
    r = math.sqrt(qx * qx + qy * qy + qz * qz)
    z = max(qz, 1.0)
    x = R * qx / z
    y = R * qy / z
    sx = math.sqrt(min(abs(x) / D, 1.0))
    if x < 0:
        sx = -sx
    sy = math.sqrt(min(abs(y) / D, 1.0))
    if y < 0:
        sy = -sy
    w = math.sqrt(min(max((r - R) / Htop, 0.0), 1.0))
    return (sx + 1.0) * 0.5 * (nx - 1), (sy + 1.0) * 0.5 * (nx - 1), w * (nh - 1)


@njit(cache=True)
def _corner(f, n):
    i = min(max(int(f), 0), n - 2)
    return i, min(max(f - i, 0.0), 1.0)


@njit(cache=True)
def lattice_interp(field, fx, fy, fh, k, out):
    """Trilinear interpolation of field[ix, iy, ih, k, :] into out (nl,)."""
    nx = field.shape[0]
    nh = field.shape[2]
    nl = field.shape[4]
    ix, ax = _corner(fx, nx)
    iy, ay = _corner(fy, nx)
    ih, ah = _corner(fh, nh)
    for l in range(nl):
        out[l] = 0.0
    for a in range(2):
        wa = ax if a else 1.0 - ax
        for b in range(2):
            wb = ay if b else 1.0 - ay
            for c in range(2):
                wc = ah if c else 1.0 - ah
                w = wa * wb * wc
                if w == 0.0:
                    continue
                for l in range(nl):
                    out[l] += w * field[ix + a, iy + b, ih + c, k, l]


@njit(cache=True)
def ground_interp(g, fx, fy, out):
    """Bilinear interpolation of g[ix, iy, :] into out (nl,)."""
    nx = g.shape[0]
    nl = g.shape[2]
    ix, ax = _corner(fx, nx)
    iy, ay = _corner(fy, nx)
    for l in range(nl):
        out[l] = ((1 - ax) * ((1 - ay) * g[ix, iy, l] + ay * g[ix, iy + 1, l])
                  + ax * ((1 - ay) * g[ix + 1, iy, l] + ay * g[ix + 1, iy + 1, l]))


@njit(parallel=True, cache=True)
def lattice_single(nodes, dirs, sun, m, e_sun, lo, hi, n, ts, out):
    """Order 1 on the lattice: out[p, k, :] = single-scattered light (and sunlit ground)
    arriving at lattice node p from sky-sphere direction k. With the observer as the one
    node and the view directions as ``dirs``, order 1 towards the observer."""
    npt = nodes.shape[0]
    K = dirs.shape[0]
    nc = m.profile_code.shape[0]
    nl = e_sun.shape[0]
    for idx in prange(npt * K):
        p = idx // K
        k = idx % K
        pos, wts, rho, trans, t_end = ray_buffers(n, nc, nl)
        col = np.zeros(nc)
        res = np.zeros(nl)
        phs = np.zeros((nc, nl))
        single_along(nodes[p, 0], nodes[p, 1], nodes[p, 2], dirs[k, 0], dirs[k, 1], dirs[k, 2],
                     sun[0], sun[1], sun[2], m, e_sun, lo, hi, n, ts, res, pos, wts, rho, trans,
                     t_end, col, phs)
        for l in range(nl):
            out[p, k, l] = res[l]


@njit(parallel=True, cache=True)
def lattice_source(I, rho_nodes, beta_s, W, J):
    """Scattered light leaving each lattice node towards -d_k per metre [NDKY96] eq. 6:
    J[p, k, l] = sum_c beta_s[c, l] rho_c(p) sum_j I[p, j, l] W[c, lw, j, k] (lw = l for
    spectral phase functions, else 0)."""
    npt = I.shape[0]
    K = I.shape[1]
    nl = I.shape[2]
    nc = beta_s.shape[0]
    spectral = W.shape[1] > 1
    for p in prange(npt):
        for k in range(K):
            for l in range(nl):
                lw = l if spectral else 0
                s = 0.0
                for c in range(nc):
                    acc = 0.0
                    for j in range(K):
                        acc += I[p, j, l] * W[c, lw, j, k]
                    s += beta_s[c, l] * rho_nodes[p, c] * acc
                J[p, k, l] = s


@njit(cache=True)
def gather_along(px, py, pz, dx, dy, dz, k, Jf, G, m, D, Htop, n, ts, out, pos, wts, rho, trans,
                 t_end, tmp):
    """Light of the next order arriving at p from direction d: the source Jf[..., k, :]
    (interpolated on the lattice) integrated along the ray with its transmittance, plus the
    ground's Lambertian reflection G of the previous order's irradiance where it hits."""
    nl = out.shape[0]
    nx = Jf.shape[0]
    nh = Jf.shape[2]
    for l in range(nl):
        out[l] = 0.0
    R = m.R
    n_pts, hits = ray_nodes(px, py, pz, dx, dy, dz, m, n, ts, pos, wts, rho, trans, t_end)
    for q in range(n_pts):
        fx, fy, fh = lattice_coords(pos[q, 0], pos[q, 1], pos[q, 2], R, D, Htop, nx, nh)
        lattice_interp(Jf, fx, fy, fh, k, tmp)
        for l in range(nl):
            out[l] += wts[q] * trans[q, l] * tmp[l]
    if hits:
        fx, fy, fh = lattice_coords(pos[n_pts, 0], pos[n_pts, 1], pos[n_pts, 2], R, D, Htop, nx, nh)
        ground_interp(G, fx, fy, tmp)
        for l in range(nl):
            out[l] += trans[n_pts, l] * tmp[l]


@njit(parallel=True, cache=True)
def lattice_gather(nodes, dirs, Jf, G, m, D, Htop, n, ts, out):
    """Order n on the lattice from the order n-1 source Jf (nx, ny, nh, K, nl) and ground
    radiance G (nx, ny, nl): out[p, k, :]."""
    npt = nodes.shape[0]
    K = dirs.shape[0]
    nc = m.profile_code.shape[0]
    nl = Jf.shape[4]
    for idx in prange(npt * K):
        p = idx // K
        k = idx % K
        pos, wts, rho, trans, t_end = ray_buffers(n, nc, nl)
        tmp = np.zeros(nl)
        res = np.zeros(nl)
        gather_along(nodes[p, 0], nodes[p, 1], nodes[p, 2], dirs[k, 0], dirs[k, 1], dirs[k, 2], k,
                     Jf, G, m, D, Htop, n, ts, res, pos, wts, rho, trans, t_end, tmp)
        for l in range(nl):
            out[p, k, l] = res[l]


# -- the observer's view rays ---------------------------------------------------------------------
@njit(parallel=True, cache=True)
def view_gather_orders(vdirs, r0, I_all, G_all, fine_dirs, fine_dw, fine_owner, m, D, Htop, n, ts,
                       out):
    """Orders 2..N towards the observer: out[o, i] is order o + 2 from the lattice light
    I_all[o] (nx, ny, nh, K, nl) of order o + 1 and the ground radiance G_all[o]; the phase
    function of each constituent is integrated over each sky-sphere cell around the view
    direction (cells = fine_owner of the fine grid). The cell integrals and the nodes along
    the view ray are the same for every order, so they are computed once per ray (9x faster
    than one pass per order at 6 orders; same sums to 1e-13)."""
    R = m.R
    beta_s = m.scattering
    nv = vdirs.shape[0]
    nc = m.profile_code.shape[0]
    nlw = n_phase_wavelengths(m)
    n_o = I_all.shape[0]
    nl = I_all.shape[5]
    K = I_all.shape[4]
    nx = I_all.shape[1]
    nh = I_all.shape[3]
    nf = fine_dirs.shape[0]
    for i in prange(nv):
        dx = vdirs[i, 0]
        dy = vdirs[i, 1]
        dz = vdirs[i, 2]
        W = np.zeros((nc, nlw, K))
        for c in range(nc):
            for lw in range(nlw):
                tot = 0.0
                for f in range(nf):
                    cs = fine_dirs[f, 0] * dx + fine_dirs[f, 1] * dy + fine_dirs[f, 2] * dz
                    v = phase_of(m, c, lw, cs) * fine_dw[f]
                    W[c, lw, fine_owner[f]] += v
                    tot += v
                for j in range(K):
                    W[c, lw, j] /= tot          # normalise: sum_j W = 1 (energy conservation)
        pos, wts, rho, trans, t_end = ray_buffers(n, nc, nl)
        tmp = np.zeros(nl)
        sw = np.zeros((K, nl))
        for o in range(n_o):
            for l in range(nl):
                out[o, i, l] = 0.0
        n_pts, hits = ray_nodes(0.0, 0.0, r0, dx, dy, dz, m, n, ts, pos, wts, rho, trans, t_end)
        for q in range(n_pts):
            fx, fy, fh = lattice_coords(pos[q, 0], pos[q, 1], pos[q, 2], R, D, Htop, nx, nh)
            for j in range(K):
                for l in range(nl):
                    s = 0.0
                    for c in range(nc):
                        s += beta_s[c, l] * rho[q, c] * W[c, l if nlw > 1 else 0, j]
                    sw[j, l] = wts[q] * trans[q, l] * s
            for o in range(n_o):
                I = I_all[o]
                for j in range(K):
                    lattice_interp(I, fx, fy, fh, j, tmp)
                    for l in range(nl):
                        out[o, i, l] += sw[j, l] * tmp[l]
        if hits:
            fx, fy, fh = lattice_coords(pos[n_pts, 0], pos[n_pts, 1], pos[n_pts, 2], R, D, Htop, nx, nh)
            for o in range(n_o):
                ground_interp(G_all[o], fx, fy, tmp)
                for l in range(nl):
                    out[o, i, l] += trans[n_pts, l] * tmp[l]
