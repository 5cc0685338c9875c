"""The precomputation ([Bru17] Model::Precompute): transmittance, single scattering, and per
further order the scattering density, the indirect irradiance and the multiple scattering.

Each step is one function here calling its numba kernel (modules ``_single``, ``_density``,
``_irradiance``, ``_multiple``; called through the module so that a benchmark can time
them). No order's radiance is tabulated: the incident radiance and ground irradiance of
orders >= 3 are ray integrals of the previous order's scattering density, and the stored
multiple-scattering table is one integral of the summed density, built on its first read
(:func:`stored_table_of`, given to the tables by :func:`attach_stored_table_builder`), not
here: the sky's ``radiance()`` does not read it. Working memory: float32
throughout, the orders computed one batch of wavelengths at a time (only the batch's last
order's density kept), the geometric remainder added in place.
"""

from __future__ import annotations

import contextlib
import time

import numpy as np

from skydome._progress import report

QUADRATURE_SCALE_M = 500.0
# integration_samples per Gauss-Legendre node of the precomputation's ray integrals of J
# (_precompute_tables)
RAY_RULE_DIVISOR = 3
# the orders >= 3 summed into the summed density itself where the grids allow it
# (higher_orders_summed; False: one order's density at a time, higher_orders)
SUMMED_ORDERS = True
TABULATED = 4       # skydome.transport._phase.TABULATED (not imported: it loads numba)
# sun angular radius used for the earth's shadow edge [rad] ([Bru17] demo: 0.2666 deg)
SUN_ANGULAR_RADIUS_RAD = float(np.radians(0.2666))


def on_wavelengths(m, sel):
    """The medium m (:class:`skydome.transport._medium.Medium`) on its table wavelengths
    ``sel`` (a slice or indices): every per-wavelength array cut to them, contiguous (a
    batch of the orders' wavelengths)."""
    c = np.ascontiguousarray
    return m._replace(scattering=c(m.scattering[:, sel]), extinction=c(m.extinction[:, sel]),
                      phase_table=c(m.phase_table[..., sel]), phase_cdf=c(m.phase_cdf[..., sel]),
                      albedo=c(m.albedo[sel]))


def tables_medium(t):
    """The :class:`skydome.transport._medium.Medium` of the tables ``t``
    (:class:`._tables.Tables` with a scattering density): the planet, the density profiles
    and the extinction as the precomputation had them; the scattering coefficients and
    phase functions of the scattering constituents (``scattering_index``) in their rows,
    zeros in the others."""
    from skydome.transport._medium import Medium, phase_cdf_table

    c = np.ascontiguousarray
    sc = np.asarray(t.scattering_index, dtype=np.int64)
    nc = int(np.asarray(t.profile_code).size)
    nl = int(np.asarray(t.table_wavelengths_nm).size)
    scat = np.zeros((nc, nl))
    scat[sc] = t.scattering_coefficient
    code = np.zeros(nc, dtype=np.int64)
    code[sc] = t.phase_code
    param = np.zeros(nc)
    param[sc] = t.phase_param
    tab = t.kernel_phase_table
    table = np.zeros((nc,) + tab.shape[1:])
    table[sc] = tab
    return Medium(float(t.planet_radius_m), float(t.top_radius_m),
                  c(t.profile_code, dtype=np.int64), c(t.profile_p0, dtype=np.float64),
                  c(t.profile_p1, dtype=np.float64), scat, c(t.beta_e, dtype=np.float64), code,
                  param, table, c(phase_cdf_table(table)), c(t.ground_albedo, dtype=np.float64))


def transmittance_columns(m, p):
    """Step 1: column densities to the top on Bruneton's (r, mu) mapping ([Bru17]
    ComputeTransmittanceToTopAtmosphereBoundary, kept per constituent so that any
    wavelength's transmittance is exp(-sum_c beta_c col_c)), for the density profiles of
    the medium m (:class:`skydome.transport._medium.Medium`)."""
    from skydome.transport import _kernels as K

    return K.build_column_table(m.profile_code, m.profile_p0, m.profile_p1, m.R, m.Rt,
                                p["transmittance_r_size"], p["transmittance_mu_size"], 128,
                                QUADRATURE_SCALE_M)


def single_scattering(col, m, sc_idx, beta_s, mu_s_min, alpha, p):
    """Step 2: single scattering per scattering constituent (sc_idx of the medium m, their
    scattering coefficients beta_s), no phase ([Bru17] ComputeSingleScattering)."""
    from skydome.models.simulated.precomputed import _single

    nl = m.extinction.shape[1]
    trans = np.exp(-np.einsum("cij,cl->ijl", col, m.extinction)).astype(np.float32)
    ss = np.empty((sc_idx.size, p["scattering_r_size"], p["scattering_mu_size"],
                   p["scattering_mu_s_size"], p["scattering_nu_size"], nl), dtype=np.float32)
    _single.single_scattering_table(col, trans, m, sc_idx, beta_s, mu_s_min, alpha,
                                    p["integration_samples"], QUADRATURE_SCALE_M, ss)
    return ss


class _DensityQuadrature:
    """Step 3b's fixed parts: incident directions (Bruneton's n x 2n over the sphere in the
    sun's frame, kept on phi in [0, pi]), the outgoing grid of J, and the phase matrices.

    Where 2 n_in is a multiple of the outgoing grid's azimuth steps n_out (the defaults:
    32/32 for order 2, 16/32 for the orders >= 3) the phase matrices are kept in the
    azimuthal Fourier basis (``modes``, :func:`._density.azimuth_modes`: exact, the sum over
    incident azimuths is a cyclic convolution), n_in modes per constituent, 3 for a phase
    function of degree <= 2 in the cosine (Rayleigh, isotropic: its higher modes are zero);
    a tabulated phase function has one set per table wavelength. Otherwise the dense
    matrices of :func:`._density.phase_matrix`, factored where the phase function is a
    polynomial of degree <= 2 in the cosine (``left``, ``right``), a tabulated phase
    function one matrix per table wavelength (``per_wavelength[k]``; ``azimuthal=False``
    forces these, for the tests)."""

    def __init__(self, pc, pp, pt, n_th, n_th_out=None, azimuthal=True):
        n_th_out = n_th if n_th_out is None else n_th_out

        self.th_in = (np.arange(n_th) + 0.5) * np.pi / n_th
        self.ph_in = (np.arange(n_th) + 0.5) * np.pi / n_th
        self.d_omega = np.sin(self.th_in) * (np.pi / n_th) ** 2
        # outgoing grid of the scattering density, in the sun's frame: theta (angle from the
        # sun) and phi (azimuth about the sun) in [0, pi]
        self.th_out = np.linspace(0.0, np.pi, 2 * n_th_out + 1)
        self.ph_out = np.linspace(0.0, np.pi, n_th_out + 1)
        self.n_in = self.th_in.size * self.ph_in.size
        self.n_out = self.th_out.size * self.ph_out.size
        self.modes = None
        if azimuthal and (2 * n_th) % n_th_out == 0:
            self._azimuthal(pc, pp, pt, n_th, n_th_out)
        else:
            self._dense(pc, pp, pt)

    def _azimuthal(self, pc, pp, pt, n_th, n_th_out):
        """The phase matrices in the azimuthal Fourier basis (see the class)."""
        from skydome.models.simulated.precomputed import _density

        n = np.arange(n_th)
        # incident radiance -> its cosine coefficients over the incident azimuths phi_b:
        # L_b = sum_n c_n cos(n phi_b), c_n = eps_n / N sum_b L_b cos(n phi_b), eps_0 = 1,
        # eps_n = 2 (the orthogonality of the DCT-II basis on the N midpoint azimuths)
        eps = np.where(n == 0, 1.0, 2.0)
        self.analysis = np.ascontiguousarray(
            eps[:, None] / n_th * np.cos(np.outer(n, self.ph_in)), dtype=np.float32)
        # outgoing azimuths m pi / n_out: m n_th / n_out an integer (shift 1/2 of the
        # differences psi_d), else a half integer (shift 0): every other m when
        # 2 n_th / n_out is odd
        if (2 * n_th // n_th_out) % 2 == 0:
            cls = [(slice(None), 0.5)]
        else:
            cls = [(slice(0, None, 2), 0.5), (slice(1, None, 2), 0.0)]
        self.classes = [sel for sel, _ in cls]
        self.synthesis = [np.ascontiguousarray(np.cos(np.outer(self.ph_out[sel], n)),
                                               dtype=np.float32) for sel, _ in cls]
        self.modes = []
        for k in range(pc.size):
            code = int(pc[k])
            n_m = 3 if code in (0, 3) else n_th
            n_l = pt.shape[2] if code == TABULATED else 1
            sets = []
            for l in range(n_l):
                per_cls = []
                for _, shift in cls:
                    G = np.empty((n_m, self.th_out.size, n_th))
                    _density.azimuth_modes(pc, pp, pt, k, l, self.th_out, self.th_in,
                                           self.d_omega, n_th, shift, G)
                    per_cls.append(np.ascontiguousarray(G, dtype=np.float32))
                sets.append(per_cls)
            self.modes.append(sets)

    def _dense(self, pc, pp, pt):
        """The dense phase matrices (see the class)."""
        from skydome.models.simulated.precomputed import _density

        # P(o.i) = a0 + a1 o.i + a2 (o.i)^2 is exactly left(o) . right(i) with 10 terms, so
        # the Rayleigh part of the product costs 10/256 of the full one (checked against the
        # full matrix to 1e-9 of its largest entry, else the full matrix is used):
        # J = sum_k P_k (L w_k) = [left_k | ...] [right_k (L w_k); ...]
        left, self.right, self.per_wavelength = [], [], []
        for k in range(pc.size):
            P = np.empty((self.n_out, self.n_in))
            _density.phase_matrix(pc, pp, pt, k, 0, self.th_out, self.ph_out, self.th_in,
                                  self.ph_in, self.d_omega, P)
            self.per_wavelength.append(None)
            if int(pc[k]) == TABULATED:
                mats = [P.astype(np.float32)]
                for l in range(1, pt.shape[2]):
                    _density.phase_matrix(pc, pp, pt, k, l, self.th_out, self.ph_out,
                                          self.th_in, self.ph_in, self.d_omega, P)
                    mats.append(P.astype(np.float32))
                self.per_wavelength[k] = mats
                P = np.zeros((self.n_out, 0))
            fac = _density.quadratic_phase_factors(int(pc[k]), float(pp[k]), self.th_out,
                                                   self.ph_out, self.th_in, self.ph_in,
                                                   self.d_omega, P)
            left.append(P if fac is None else fac[0])
            self.right.append(None if fac is None else np.ascontiguousarray(fac[1], np.float32))
        self.left = np.ascontiguousarray(np.hstack(left), dtype=np.float32)
        self.rows = np.cumsum([0] + [m.shape[1] for m in left])


@contextlib.contextmanager
def _without_hugepage_advice():
    """numpy's advice to the kernel to back large arrays with transparent huge pages
    (``madvise(MADV_HUGEPAGE)``, numpy's default on Linux) off meanwhile, restored after.

    With the common kernel setting ``transparent_hugepage/defrag = madvise`` (Debian's and
    Ubuntu's default) an advised page fault compacts memory synchronously when no free huge
    page is at hand: the precomputation's 1.2 GB of new tables then spent 3.1-3.9 s of
    system time in its page faults against 0.7-1.4 s with small pages, for about 1.2 s less
    user time in the huge pages' gathers (2-core EPYC, docs/performance.md). numpy's switch
    is process-wide; arrays allocated meanwhile by other threads get small pages too (a
    matter of speed only). Without numpy's private switch (other numpy versions) nothing
    changes."""
    mod = getattr(np, "_core", None) or getattr(np, "core", None)
    switch = getattr(getattr(mod, "multiarray", None), "_set_madvise_hugepage", None)
    if switch is None:
        yield
        return
    before = switch(False)
    try:
        yield
    finally:
        switch(before)


def precompute(props, wl, p):
    """Every table for the optical properties ``props`` (of the atmosphere on ``wl``) with
    the validated settings ``p`` (a dict of the model's parameters) -> :class:`._tables.Tables`
    (its arrays on small pages: :func:`_without_hugepage_advice`)."""
    with _without_hugepage_advice():
        return _precompute_tables(props, wl, p)


def _precompute_tables(props, wl, p):
    """:func:`precompute`."""
    from skydome.models.simulated.precomputed._tables import Tables
    from skydome.transport._medium import medium_from_properties

    t_start = time.perf_counter()
    R = float(props.planet_radius_m)
    Rt = float(props.top_radius_m)
    mu_s_min = float(np.cos(np.radians(p["max_sun_zenith_deg"])))
    alpha = SUN_ANGULAR_RADIUS_RAD
    codes, p0s, p1s = props.profile_code, props.profile_p0, props.profile_p1
    m = medium_from_properties(props)     # the kernels' atmosphere
    beta_e = m.extinction
    sc_idx = np.nonzero(np.any(props.scattering > 0.0, axis=1))[0].astype(np.int64)
    if sc_idx.size == 0:
        sc_idx = np.array([0], dtype=np.int64)
    beta_s = np.ascontiguousarray(props.scattering[sc_idx])
    pc = np.ascontiguousarray(props.phase_code[sc_idx])
    pp = np.ascontiguousarray(props.phase_param[sc_idx])
    # tabulated phase functions: the atmosphere's table on the table wavelengths (evaluated
    # there by Atmosphere.optical_properties), its scattering constituents' rows
    pt_tab = (None if props.phase_table is None
              else np.ascontiguousarray(props.phase_table[sc_idx], dtype=np.float64))
    pt = pt_tab if pt_tab is not None else np.zeros((sc_idx.size, 2, wl.size))
    albedo = np.ascontiguousarray(props.ground_albedo)
    nl = wl.size
    n_r = p["scattering_r_size"]
    nsc = sc_idx.size
    n_q_ms = max(4, (p["integration_samples"] + 1) // 2)   # J is smooth along the ray
    # the ray integrals of J in the precomputation (the orders >= 3's incident radiance, the
    # ground irradiance of orders >= 2): Gauss-Legendre in v per piece of each ray
    # (transport._quadrature.ray_nodes_rule), RAY_RULE_DIVISOR times fewer nodes than
    # integration_samples (7 at the default): closer to the converged integral than 20
    # midpoint nodes (docs/models.md, "precomputed")
    from skydome.transport._quadrature import gauss_legendre_unit

    rule = gauss_legendre_unit(max(4, -(-p["integration_samples"] // RAY_RULE_DIVISOR)))

    # 1. transmittance; 2. single scattering
    col = transmittance_columns(m, p)
    ss = single_scattering(col, m, sc_idx, beta_s, mu_s_min, alpha, p)
    # the orders of each wavelength are independent of the other wavelengths': order 2 one
    # batch of wavelengths at a time (its working arrays are on the full grids), then the
    # orders >= 3 on their coarser grids, all wavelengths at once where they fit (the ray
    # geometry is the same for every wavelength)
    nb = order_batch_size(p, nl, nsc)
    n_batch = -(-nl // nb)
    hi = high_order_grid(p)
    # the table wavelengths at which the orders >= 3 are computed (all by default with
    # high_order_wavelengths=None; else a subset, the rest from order 2 x the interpolated
    # ratio, see _spectral)
    from skydome.models.simulated.precomputed import _spectral

    absorption = props.extinction - props.scattering      # per row, absorbers folded
    l_hi, l_nodes = _spectral.subset_indices(nl, p.get("high_order_wavelengths"), absorption,
                                             col[:, 0, 0], wl)
    band = _spectral.band_depth(absorption, col[:, 0, 0], props.scattering)
    nl_hi = l_hi.size
    nb_hi = high_order_batch_size(p, nl_hi, nsc)
    n_batch_hi = -(-nl_hi // nb_hi)
    batches = None
    if nl_hi < nl and p["orders"] >= 3:
        batches = subset_batches(p, l_hi, l_nodes, nsc)
        n_batch_hi = len(batches)
    n_steps = 1 + n_batch + max(p["orders"] - 2, 0) * n_batch_hi
    report("precomputing tables: scattering orders", 1, n_steps)
    E = np.zeros((p["irradiance_r_size"], p["irradiance_mu_s_size"], nl))
    J_sum = None
    if p["orders"] >= 2:
        q2 = _DensityQuadrature(pc, pp, pt, p["sphere_samples"])
        # orders >= 3 (smooth: their sources are scattered at least twice) with their own,
        # coarser sphere of incident directions and, with order_table_divisor > 1, an
        # outgoing grid that many times coarser (interpolated up into the summed density)
        div = p["order_table_divisor"]
        n_high = min(p["high_order_sphere_samples"] or p["sphere_samples"], p["sphere_samples"])
        n_out_high = min(p["sphere_samples"], max(ORDER_DENSITY_MIN, p["sphere_samples"] // div))
        q3 = q2 if (n_high, n_out_high) == (p["sphere_samples"],) * 2 else _DensityQuadrature(
            pc, pp, pt, n_high, n_out_high)
        # the scattering density's own mu_s axis (same mapping, its own node count)
        n_ms_j = p["density_mu_s_size"] or p["scattering_mu_s_size"]
        J_sum = np.empty((nsc, q2.th_out.size, q2.ph_out.size, n_r, n_ms_j, nl), dtype=np.float32)
        dE1 = np.zeros(E.shape)   # ground irradiance of order 1 (reflected into order 3)
        tot2 = np.zeros(nl)
        for b, l0 in enumerate(range(0, nl, nb)):
            sl = slice(l0, min(nl, l0 + nb))
            tot2[sl] = second_order_batch(ss[..., sl], col, on_wavelengths(m, sl), sc_idx,
                                          beta_s[:, sl], pc, pp, pt[..., sl], mu_s_min, alpha,
                                          q2, l0, n_ms_j, J_sum[..., sl], dE1[..., sl])
            report("precomputing tables: scattering orders", 2 + b, n_steps)
        E += dE1
        # the default grids: the orders >= 3 summed in J_sum itself (higher_orders_summed),
        # with no table of one order's J, so the single-scattering table stays
        summed = (SUMMED_ORDERS and p["orders"] >= 3 and nl_hi == nl and q3.modes is not None
                  and (q3.th_out.size, q3.ph_out.size) == (q2.th_out.size, q2.ph_out.size)
                  and tuple(hi) == (n_r, n_ms_j))
        if p["orders"] >= 3 and not summed:
            # single scattering is read by order 2 only: its table (0.50 GB at the defaults)
            # is freed for the working arrays of the orders >= 3 (one batch of them then
            # fits: a ray integral's cost is nearly all geometry, shared by a batch's
            # wavelengths) and computed again after them (the same kernel: the same bits)
            ss = None
        if summed:
            higher_orders_summed(J_sum, dE1, tot2, col, m, sc_idx, beta_s, mu_s_min, q3, rule,
                                 p, (1 + n_batch, 1 + n_batch + p["orders"] - 2))
        elif nl_hi == nl:
            for b, l0 in enumerate(range(0, nl, nb_hi)):
                sl = slice(l0, min(nl, l0 + nb_hi))
                higher_orders(J_sum[..., sl], dE1[..., sl], tot2[sl], col, on_wavelengths(m, sl),
                              sc_idx, beta_s[:, sl], mu_s_min, q2, q3, hi, rule, p,
                              (1 + n_batch + b * (p["orders"] - 2), n_steps), l0)
        elif p["orders"] >= 3:
            higher_orders_subset(J_sum, dE1, tot2, l_hi, l_nodes, band, wl, batches, col, m,
                                 sc_idx, beta_s, mu_s_min, q2, q3, hi, rule, p,
                                 (1 + n_batch, n_steps))
        # 3c. the ground irradiance of orders 2..N (+ remainder) at every r node: one ray
        # integral of the summed density (the irradiance is linear in J, as the stored
        # table's radiance is); the orders' own ground reflections needed the ground's row
        # of each order's irradiance only
        E += irradiance_of_density(J_sum, m, sc_idx, col, mu_s_min, rule, E.shape)
    if ss is None:
        ss = single_scattering(col, m, sc_idx, beta_s, mu_s_min, alpha, p)
    # 4. the stored orders 2..N (+ remainder) are not integrated here: the sky's radiance()
    # integrates them at the observer from J_sum; the stored table is built from J_sum on
    # its first read (Tables.build_multiple_scattering -> stored_table_of), with the
    # quadrature and node choice recorded here
    ms = None if J_sum is not None else np.zeros(ss.shape[1:], dtype=np.float32)
    dens = {}
    if J_sum is not None:
        dens = dict(scattering_density=J_sum, profile_code=np.asarray(codes),
                    profile_p0=np.asarray(p0s, dtype=np.float64),
                    profile_p1=np.asarray(p1s, dtype=np.float64), scattering_index=sc_idx)
    tables = Tables(table_wavelengths_nm=np.asarray(wl, dtype=np.float64), columns=col,
                    beta_e=beta_e, single_scattering=ss, multiple_scattering=ms, irradiance=E,
                    phase_code=np.asarray(pc, dtype=np.int64), phase_param=pp, ground_albedo=albedo,
                    scattering_coefficient=beta_s, planet_radius_m=R, top_radius_m=Rt,
                    mu_s_min=mu_s_min, sun_angular_radius_rad=alpha,
                    precompute_seconds=time.perf_counter() - t_start, phase_table=pt_tab,
                    stored_table_samples=n_q_ms, stored_table=p.get("stored_table", "full"),
                    scattering_shape=np.array(ss.shape[1:5], dtype=np.int64),
                    single_scattering_samples=int(p["integration_samples"]), **dens)
    attach_stored_table_builder(tables)
    return tables


def attach_stored_table_builder(tables):
    """Give ``tables`` (:class:`._tables.Tables`) the builder of its stored table of orders
    2..N (:func:`stored_table_of`, :func:`stored_table_slabs`, looked up when called) and,
    where they record how (``single_scattering_samples``, the medium's profiles), of its
    single-scattering table (:func:`single_scattering_of`); returns ``tables``."""
    tables.set_multiple_scattering_builder(lambda t: stored_table_of(t),
                                           lambda t: stored_table_slabs(t))
    if tables.single_scattering_samples > 0 and tables.has_density:
        tables.set_single_scattering_builder(lambda t, rows: single_scattering_of(t, rows))
    return tables


def single_scattering_of(t, rows=None):
    """Step 2 again for the tables ``t`` (:class:`._tables.Tables`), from what they hold (the
    columns, the medium of :func:`tables_medium`, the scattering coefficients, the
    quadrature): the single-scattering table, the same values bit for bit as the
    precomputation's (the same kernel on the same inputs), or only its r nodes
    ``rows = (first, end)`` (:func:`._single.single_scattering_rows`)."""
    from skydome.models.simulated.precomputed import _single

    n_r, n_mu, n_ms, n_nu, nl = t.table_shape
    m = tables_medium(t)
    col = np.ascontiguousarray(t.columns, dtype=np.float64)
    trans = np.exp(-np.einsum("cij,cl->ijl", col, m.extinction)).astype(np.float32)
    beta_s = np.ascontiguousarray(t.scattering_coefficient, dtype=np.float64)
    sc_idx = np.ascontiguousarray(t.scattering_index, dtype=np.int64)
    first, end = (0, n_r) if rows is None else (int(rows[0]), int(rows[1]))
    out = np.empty((sc_idx.size, end - first, n_mu, n_ms, n_nu, nl), dtype=np.float32)
    _single.single_scattering_rows(col, trans, m, sc_idx, beta_s, float(t.mu_s_min),
                                   float(t.sun_angular_radius_rad),
                                   int(t.single_scattering_samples), QUADRATURE_SCALE_M, n_r,
                                   first, out)
    return out


def stored_table_of(t, r_range=None):
    """Step 4 for the tables ``t`` (:class:`._tables.Tables`): the stored table of orders
    2..N (+ remainder), one integral of the summed density over the full table (the
    integral is linear in J: the same as the sum of the orders'), at every node by default;
    ``t.stored_table == "subset"``: the faster approximation on the nodes of
    stored_table_nodes, interpolated in the logarithm. Zeros where the tables hold no
    density (orders < 2). ``r_range`` = (first, end): only those r nodes of the full table
    (the default table only), the same values as the whole table's rows."""
    shape = t.table_shape
    if not t.has_density:
        return np.zeros(shape, dtype=np.float32)
    if t.stored_table_samples < 1:
        raise ValueError(f"stored_table_samples = {t.stored_table_samples} is not valid: the "
                         "tables do not say how to integrate the stored table (>= 1)")
    n_mu_t, n_ms_t, n_nu_t = shape[1:4]
    full = t.stored_table == "full"
    return stored_multiple_scattering(
        t.scattering_density, tables_medium(t), t.scattering_index, t.columns, t.mu_s_min,
        int(t.stored_table_samples), shape,
        nodes=(np.arange(n_mu_t), np.arange(n_ms_t)) if full else None,
        n_nu=n_nu_t if full else MS_NU_SIZE, r_range=r_range)


# working memory of one slab of r nodes of the stored table written straight to a file
# (stored_table_slabs) [bytes]
STORED_SLAB_BYTES = 32_000_000


def stored_table_slabs(t, slab_bytes=None):
    """The stored table of :func:`stored_table_of` as consecutive slabs of r nodes (float32,
    C order; concatenated along r they are the table), each within ``slab_bytes`` (at least
    one r node; default ``STORED_SLAB_BYTES``), so that a writer holds one slab at a time;
    the subset table in one piece (its interpolation reads every r node)."""
    shape = t.table_shape
    slab_bytes = STORED_SLAB_BYTES if slab_bytes is None else slab_bytes
    if t.stored_table != "full" or not t.has_density:
        yield stored_table_of(t)
        return
    per_r = 4 * int(np.prod(shape[1:]))
    step = max(1, int(slab_bytes) // per_r)
    for a in range(0, shape[0], step):
        yield stored_table_of(t, (a, min(shape[0], a + step)))


# the stored multiple-scattering table's computed nodes (see stored_table_nodes): per half
# of the mu axis, (distance from the horizon in nodes, as a fraction of the half, below
# which, step between computed nodes); every MS_MU_S_STEP-th mu_s node; MS_NU_SIZE nu nodes
MS_MU_STEPS = ((0.25, 1), (0.5, 2), (1.0, 4))
MS_MU_S_STEP = 2
MS_NU_SIZE = 8


def _steps(n, spec):
    """Node indices 0 .. n-1 (0 and n-1 included) with the steps of ``spec`` ((fraction of
    n below which, step), ...)."""
    k, out = 0, [0]
    while k < n - 1:
        step = next((st for f, st in spec if k < f * n), spec[-1][1])
        k = min(k + step, n - 1)
        out.append(k)
    return np.array(out, dtype=np.int64)


def stored_table_nodes(n_mu, n_ms, mu_steps=MS_MU_STEPS, mu_s_step=MS_MU_S_STEP):
    """The mu and mu_s nodes of the stored table at which :func:`._multiple.
    multiple_scattering_table` integrates (the rest interpolated by
    :func:`._multiple.table_from_coarse`): (mu nodes, mu_s nodes), indices into the full
    axes, ascending, each half of the mu axis with its horizon node and its far end."""
    half = n_mu // 2
    k = _steps(half, mu_steps)            # from the horizon: ground half 0.., sky half n-1..
    mu = np.unique(np.concatenate([k, n_mu - 1 - k]))
    ms = np.unique(np.append(np.arange(0, n_ms, mu_s_step), n_ms - 1)).astype(np.int64)
    return mu, ms


def node_brackets(nodes, n):
    """(cell, fraction) of every index 0 .. n-1 between the ascending ``nodes`` (linear in
    the index): index i lies between nodes[cell[i]] and nodes[cell[i] + 1]."""
    i = np.arange(n, dtype=np.float64)
    cell = np.clip(np.searchsorted(nodes, i, side="right") - 1, 0, nodes.size - 2)
    frac = (i - nodes[cell]) / (nodes[cell + 1] - nodes[cell])
    return cell.astype(np.int64), frac


def stored_multiple_scattering(J_sum, m, sc_idx, col, mu_s_min, n_q, shape, nodes=None,
                               n_nu=MS_NU_SIZE, r_range=None):
    """Step 4: the stored table of orders 2..N, shape ``shape`` (r, mu, mu_s, nu, l), in the
    medium m (:func:`tables_medium`), integrated from the summed density at the nodes of
    :func:`stored_table_nodes` (or ``nodes`` = (mu nodes, mu_s nodes)) on ``n_nu`` nu nodes, and
    interpolated onto the rest in the logarithm (docs/models.md, "precomputed": multiple
    scattering falls off about exponentially with the sun's depression and towards the horizon).
    ``r_range`` = (first, end), every node only: the rows first .. end-1 of the table."""
    from skydome.models.simulated.precomputed import _multiple

    n_r, n_mu, n_ms, n_nu_f, nl = shape
    mu_n, ms_n = stored_table_nodes(n_mu, n_ms) if nodes is None else nodes
    n_nu = min(int(n_nu), n_nu_f)
    full = mu_n.size == n_mu and ms_n.size == n_ms and n_nu == n_nu_f
    r0, r1 = (0, n_r) if r_range is None else (int(r_range[0]), int(r_range[1]))
    if not (0 <= r0 < r1 <= n_r) or (not full and (r0, r1) != (0, n_r)):
        raise ValueError(f"r_range = {r_range} is not valid: 0 <= first < end <= {n_r}, and "
                         "the whole table where it is integrated on a subset of its nodes")
    out = np.empty((r1 - r0,) + tuple(shape[1:]), dtype=np.float32)
    c = out if full else np.empty((n_r, mu_n.size, ms_n.size, n_nu, nl), dtype=np.float32)
    _multiple.multiple_scattering_table(J_sum, m, sc_idx, col, mu_s_min, n_q, QUADRATURE_SCALE_M,
                                        mu_n, n_mu, ms_n, n_ms, r0, n_r, c)
    if full:
        return out
    # log of the computed values (>= 0; a floor of 1e-30 of each wavelength's largest)
    floor = np.maximum(c.max(axis=(0, 1, 2, 3)), 1e-300) * 1e-30
    np.log(np.maximum(c, floor), out=c)
    mc, mf = node_brackets(mu_n, n_mu)
    sc, sf = node_brackets(ms_n, n_ms)
    _multiple.table_from_coarse(c, mu_n, mc, mf, ms_n, sc, sf, m.R, m.Rt, mu_s_min, out)
    return np.exp(out, out=out)


# working memory of one batch of wavelengths of order 2 [bytes] (see precompute)
ORDER_BATCH_BYTES = 400_000_000
# working memory of one batch of wavelengths of the orders >= 3 [bytes]: at the defaults all
# 20 wavelengths are one batch (560 MB, while the single-scattering table of 0.50 GB is not
# held, see precompute): the ray integrals' geometry is the same for every wavelength, and a
# ray integral of 20 wavelengths costs little more than one of 5 (nearly all its time is the
# geometry and the latency of J's gathers), so fewer batches take less time
HIGH_ORDER_BATCH_BYTES = 600_000_000
# the most memory the stored geometry of the orders >= 3's incident rays may take [bytes]
# (higher_orders_summed, _incident.incident_rays: 0.60 GB at the default grids; on larger
# grids the geometry of a share of the rays is stored and the rest computed in each order)
INCIDENT_GEOMETRY_BYTES = 700_000_000


def _batches(per_wl, nl, budget):
    """The fewest batches of equal size whose working arrays (``per_wl`` bytes per
    wavelength) fit ``budget``: wavelengths per batch."""
    n_batch = -(-nl // int(min(nl, max(1, budget // per_wl))))
    return -(-nl // n_batch)


def order_batch_size(p, nl, nsc):
    """Wavelengths per batch of order 2 within ``ORDER_BATCH_BYTES``: its incident radiance
    on the full sphere and the matrix right-hand side (float32) per wavelength, and, where
    the wavelengths take more than one batch, its J on the full outgoing grid (one batch
    of every wavelength writes J straight into the summed density)."""
    n = p["sphere_samples"]
    n_cols = p["scattering_r_size"] * (p["density_mu_s_size"] or p["scattering_mu_s_size"])
    per_wl = 4 * n_cols * (n * n + 10)
    if per_wl * nl <= ORDER_BATCH_BYTES:
        return nl
    return _batches(per_wl + 4 * n_cols * (2 * n + 1) * (n + 1) * nsc, nl, ORDER_BATCH_BYTES)


def high_order_grid(p):
    """(r, mu_s) nodes of the scattering density of orders >= 3: ``high_order_r_size`` x
    ``high_order_mu_s_size`` on the density's own mappings, at most the full grid's
    (None: the full grid)."""
    n_r = p["scattering_r_size"]
    n_ms = p["density_mu_s_size"] or p["scattering_mu_s_size"]
    return (min(p.get("high_order_r_size") or n_r, n_r),
            min(p.get("high_order_mu_s_size") or n_ms, n_ms))


def high_order_batch_size(p, nl, nsc):
    """Wavelengths per batch of the orders >= 3: the order's density (and, on a coarse
    (r, mu_s) grid, the sum of the orders >= 3 there) and the incident radiance on the
    coarse sphere (float32), within ``HIGH_ORDER_BATCH_BYTES``."""
    n = p["sphere_samples"]
    n_o = min(n, max(ORDER_DENSITY_MIN, n // p["order_table_divisor"]))
    n_i = min(p["high_order_sphere_samples"] or n, n)
    n_r, n_ms = high_order_grid(p)
    full = (n_r, n_ms, n_o) == (p["scattering_r_size"],
                                p["density_mu_s_size"] or p["scattering_mu_s_size"], n)
    n_j = 1 if full else 2
    per_wl = 4 * n_r * n_ms * (n_j * (2 * n_o + 1) * (n_o + 1) * nsc + n_i * n_i + 10)
    return _batches(per_wl, nl, HIGH_ORDER_BATCH_BYTES)


# zenith samples of the hemisphere of the ground irradiance of orders >= 2 (see higher_orders)
IRRADIANCE_HIGH_ORDER_SAMPLES = 8


def _hemisphere(n):
    """Midpoint quadrature of the upper hemisphere: n zenith x 2n azimuth nodes over
    [0, pi] (the sky is symmetric about the sun's vertical plane; doubled by the kernel):
    (theta, phi, solid angle per zenith row)."""
    th = (np.arange(n) + 0.5) * (0.5 * np.pi) / n
    ph = (np.arange(2 * n) + 0.5) * np.pi / (2 * n)
    return th, ph, np.sin(th) * (0.5 * np.pi / n) * (np.pi / (2 * n))


def _column_weights(beta_s, n_r, n_ms, nl):
    """Weight of each constituent at every (r, mu_s, l) column of the incident radiance: its
    scattering coefficient at reference density (the density profile is applied exactly
    along each ray: J_k / rho_k is smooth in r, rho_k J_k is not)."""
    return [np.ascontiguousarray(np.broadcast_to(beta_s[k].astype(np.float32),
                                                 (n_r, n_ms, nl)).reshape(-1))
            for k in range(beta_s.shape[0])]


def second_order_batch(ss, col, m, sc_idx, beta_s, pc, pp, pt, mu_s_min, alpha, q2, l0, n_ms_j,
                       J_out, dE_out):
    """Steps 3a-3c of order 2 for one batch of wavelengths (every array and the medium m
    given on the batch's wavelengths, :func:`on_wavelengths`; ``l0`` the index of its
    first table wavelength): the incident radiance from the single-scattering table
    ([Bru17] ComputeScatteringDensity) and the direct sun's ground reflection, J of order 2
    into ``J_out`` (on the full grids of ``q2``), the ground irradiance of order 1 into
    ``dE_out``; returns order 2's source strength per wavelength (:func:`source_total`)."""
    from skydome.models.simulated.precomputed import _density, _irradiance

    nl = ss.shape[-1]
    nsc = sc_idx.size
    n_r = ss.shape[1]
    # irradiance quadrature ([Bru17] ComputeIndirectIrradiance: 16 x 64 over the upper
    # hemisphere; phi on [0, pi] doubled) for the sky of order 1 (table lookups)
    th_i, ph_i, dom_i = _hemisphere(16)
    rhs = None if q2.modes is not None else np.empty((10, n_r * n_ms_j * nl), dtype=np.float32)
    w_col = _column_weights(beta_s, n_r, n_ms_j, nl)
    # 3a. single scattering arriving at each node + ground reflection of the sun
    L_in = np.empty((q2.n_in, n_r, n_ms_j, nl), dtype=np.float32)
    _density.incident_radiance(ss, pc, pp, pt, col, m.extinction, m.albedo, m.R, m.Rt, mu_s_min,
                               alpha, n_r, n_ms_j, q2.th_in, q2.ph_in, L_in)
    # 3c. ground irradiance of order 1 ([BN08] eq. 9), from the same source
    dE = np.empty(dE_out.shape)
    _irradiance.indirect_irradiance(ss, pc, pp, np.ascontiguousarray(pt), m.R, m.Rt, mu_s_min,
                                    th_i, ph_i, dom_i, dE)
    dE_out[...] = dE
    # 3b. scattering density J ([BN08] eq. 7) on the outgoing grid, straight into J_out
    # where it is one block of memory (a batch of all the wavelengths)
    J = (J_out if J_out.flags.c_contiguous else
         np.empty((nsc, q2.th_out.size, q2.ph_out.size, n_r, n_ms_j, nl), dtype=np.float32))
    density_products(q2, L_in, w_col, beta_s, rhs, J, l0)
    del L_in
    if J is not J_out:
        J_out[...] = J
    return source_total(J, q2, m, sc_idx)


def irradiance_of_density(J, m, sc_idx, col, mu_s_min, rule, shape, rows=None):
    """The ground irradiance (table of ``shape`` (r, mu_s, l); its first ``rows`` r rows
    only, all by default) of the radiance whose scattering density is ``J``: a ray integral
    along each direction of the hemisphere (:func:`._irradiance.indirect_irradiance_rays`,
    [BN08] eq. 8 and 9, on IRRADIANCE_HIGH_ORDER_SAMPLES x 4 of them) in the medium m."""
    from skydome.models.simulated.precomputed import _irradiance

    th_h, ph_h, dom_h = _hemisphere(IRRADIANCE_HIGH_ORDER_SAMPLES)
    out = np.empty((shape[0] if rows is None else rows,) + tuple(shape[1:]))
    _irradiance.indirect_irradiance_rays(J, m, sc_idx, col, mu_s_min, *rule, QUADRATURE_SCALE_M,
                                         th_h, ph_h, dom_h, out, shape[0])
    return out


def _ground_row(E0):
    """An irradiance table of two r rows, both the ground's row ``E0`` (mu_s, l): what the
    ground reflection of :func:`._density.incident_radiance_rays` reads (at r = R, the
    first row with weight 1)."""
    return np.ascontiguousarray(np.broadcast_to(E0, (2,) + E0.shape))


def higher_orders_summed(J_sum, dE1, tot2, col, m, sc_idx, beta_s, mu_s_min, q, rule, p,
                         progress=(0, None)):
    """Steps 3a-3b for orders 3..N at every wavelength, and the geometric remainder, with
    no table of one order's density: ``J_sum`` (on the outgoing grid of ``q``, float32)
    holds order 2's density on entry and orders 2..N (+ remainder) on return; ``dE1`` the
    ground irradiance of order 1, ``tot2`` order 2's source strength (:func:`source_total`).

    Every step is linear in the density, so each order's incident radiance is a difference
    of two ray integrals of the running sum: with S_k = J_2 + ... + J_k and G_k the ground
    irradiance of orders 1..k, X_o = rays(S_(o-1)) + ground(G_(o-2)) (the ray integrals of
    :func:`higher_orders` on the rays' geometry stored once for all the orders,
    :mod:`._incident`: the same bits but at the density's sun-at-zenith node, float32
    rounding there), order o's incident radiance is X_o - X_(o-1) (X_2 = 0; for order 3 it
    is X_3 itself), and its density is
    added into ``J_sum`` by the products (``add``). G_(o-1) = G_1 + the irradiance of
    S_(o-1) at the ground's row. The differences lose float32 digits in proportion to an
    order's share of the sum (about 1e-5 relative for order 6 at the defaults); negative
    rounding residues are set to 0. Working memory: two incident-radiance arrays (31 MB at
    the defaults) instead of a second density table (527 MB), so the single-scattering
    table need not be freed and computed again.

    The remainder: J_N f / (1 - f), f the ratio of the last two orders' source strengths
    per wavelength (:func:`higher_orders`), goes in with the last order's products (its
    column weights scaled by 1 + f / (1 - f)): an order's source strength is a linear
    functional of its incident radiance (:class:`_SourceFunctional`), known before its
    products."""
    nl = J_sum.shape[-1]
    n_r, n_ms = J_sum.shape[3], J_sum.shape[4]
    ts = QUADRATURE_SCALE_M
    from skydome.models.simulated.precomputed import _incident

    w_col = _column_weights(beta_s, n_r, n_ms, nl)
    # the incident rays' geometry (nodes, weights of J, cells of J, the ground's
    # transmittance), the same for every order: computed once (_incident; 0.60 GB at the
    # defaults, at most INCIDENT_GEOMETRY_BYTES) instead of in each order's ray integrals
    rays = _incident.incident_rays(J_sum.shape, m, sc_idx, col, mu_s_min, *rule, ts, n_r, n_ms,
                                   q.th_in, q.ph_in, INCIDENT_GEOMETRY_BYTES) \
        if p["orders"] >= 3 else None
    X = np.empty((q.n_in, n_r, n_ms, nl), dtype=np.float32)
    X_prev = np.zeros_like(X)
    ground = _ground_row(dE1[0])                # G_1 at the ground
    strength = _SourceFunctional(q, m, sc_idx, beta_s, n_r, n_ms)
    tot, tot_prev = tot2, None
    for order in range(3, p["orders"] + 1):
        # 3a. X_o: the radiance of orders 2..o-1 arriving at each node from J_sum, + the
        # ground's reflection of orders 1..o-2
        _incident.incident_radiance(J_sum, ground, m, sc_idx, col, mu_s_min, *rule, ts, n_r, n_ms,
                                    q.th_in, q.ph_in, rays, X)
        if order == p["orders"]:
            rays = None                         # (freed before the last products)
        # 3c. the ground irradiance of orders 2..o-1 at the ground's row: G_(o-1)
        G = irradiance_of_density(J_sum, m, sc_idx, col, mu_s_min, rule, dE1.shape, rows=1)
        ground = _ground_row(dE1[0] + G[0])
        # order o's incident radiance X_o - X_(o-1), into X_prev's array; X becomes X_prev
        np.subtract(X, X_prev, out=X_prev)
        np.maximum(X_prev, 0.0, out=X_prev)
        L_in, X_prev, X = X_prev, X, X_prev
        tot_prev, tot = tot, strength(L_in)
        w_o, b_o = w_col, beta_s
        if order == p["orders"] and p["remaining_orders"] == "geometric":
            # the last order's density times 1 + f / (1 - f): with the remainder
            g = (1.0 + _series_factor(tot, tot_prev)).astype(np.float32)
            w_o = [w * np.tile(g, n_r * n_ms) for w in w_col]
            b_o = beta_s * g[None, :]
        # 3b. J of this order added into J_sum ([BN08] eq. 7)
        density_products(q, L_in, w_o, b_o, None, J_sum, 0, add=True)
        report("precomputing tables: scattering orders", progress[0] + order - 2,
               progress[1] or p["orders"])


def higher_orders(J2, dE1, tot2, col, m, sc_idx, beta_s, mu_s_min, q2, q3, hi, rule, p,
                  progress=(0, None), l0=0, sink=None, work=None):
    """Steps 3a-3c for orders 3..N of one batch of wavelengths (the medium m on them,
    :func:`on_wavelengths`), and the geometric remainder:
    ``J2`` the summed density (on the full grids of ``q2``), holding only order 2's on entry
    (the source of order 3), ``dE1`` the ground irradiance of order 1, ``tot2`` order 2's
    source strength. Each order's ground irradiance is computed at the ground's row only
    (its next order's ground reflection reads that row); the irradiance table of orders
    >= 2 is one integral of the summed density afterwards (:func:`irradiance_of_density`).

    No order's radiance is tabulated: the radiance of order k-1 arriving at every node of
    J_k is integrated along each incident ray from J_(k-1)
    (:func:`._density.incident_radiance_rays`, [BN08] eq. 8), and so is the ground
    irradiance (:func:`._irradiance.indirect_irradiance_rays`, [BN08] eq. 9). J of the
    orders >= 3 lives on the grid ``hi`` = (r, mu_s) nodes of the same mappings, on the
    outgoing grid of ``q3``: by default J2's own (r, mu_s) grid, each order's J added
    into ``J2`` once order 3's source is no longer needed; on the opt-in coarser grid
    (``high_order_r_size``, ``high_order_mu_s_size``) the orders >= 3 are summed there
    and that sum (with the remainder) is interpolated into ``J2`` once, at the end.

    ``sink``: instead, a function called with each order's J (and the remainder's) on the
    grid of orders >= 3, which takes their sum (``J2`` then is order 2 alone, read as order
    3's source); ``work``: the array (of that grid's shape) that holds each order's J,
    which may be ``J2`` itself where nothing else reads it (it is read as order 3's source
    before order 3's J is written)."""
    from skydome.models.simulated.precomputed import _density

    nl = J2.shape[-1]
    nsc = sc_idx.size
    n_r, n_ms = hi
    ts = QUADRATURE_SCALE_M
    rhs = np.empty((10, n_r * n_ms * nl), dtype=np.float32)
    w_col = _column_weights(beta_s, n_r, n_ms, nl)
    shape = (nsc, q3.th_out.size, q3.ph_out.size, n_r, n_ms, nl)
    L_in = np.empty((q3.n_in, n_r, n_ms, nl), dtype=np.float32)
    J = np.empty(shape, dtype=np.float32) if work is None else work
    sink_is_own = sink is None
    if sink_is_own:
        # orders 3..N: added straight into J2 on its own grid (J2 is no longer needed as
        # order 3's source once order 3's J is computed), else summed on the coarse grid
        J_hi = J2 if shape == J2.shape else np.zeros(shape, dtype=np.float32)

        def sink(x):
            np.add(J_hi, x, out=J_hi)
    src = J2                                   # J of the order before
    dE = dE1
    tot, tot_prev = tot2, None
    for order in range(3, p["orders"] + 1):
        # 3a. radiance of order-1 arriving at each node, integrated along the incident rays
        # from J of order-1, + ground reflection of the irradiance of order-2
        _density.incident_radiance_rays(src, dE, m, sc_idx, col, mu_s_min, *rule, ts, n_r, n_ms,
                                        q3.th_in, q3.ph_in, L_in)
        # 3c. ground irradiance of order-1 ([BN08] eq. 9) at the ground, from the same source
        dE = _ground_row(irradiance_of_density(src, m, sc_idx, col, mu_s_min, rule, dE1.shape,
                                               rows=1)[0])
        # 3b. J of this order ([BN08] eq. 7); J of order-1 is no longer needed
        density_products(q3, L_in, w_col, beta_s, rhs, J, l0)
        sink(J)
        src = J
        tot_prev, tot = tot, source_total(J, q3, m, sc_idx)
        report("precomputing tables: scattering orders", progress[0] + order - 2,
               progress[1] or p["orders"])
    if p["remaining_orders"] == "geometric" and p["orders"] >= 3:
        # the orders beyond N as a geometric series whose ratio f is that of the last two
        # orders' source strengths, per wavelength (the idea of [Hil20] eq. 10; the
        # radiance of an order is a linear integral of its density): J_N f / (1 - f) added
        # to the summed density. (A per-cell ratio was tried: it is unstable in cells where
        # the ground reflection enters.)
        sink(np.multiply(J, _series_factor(tot, tot_prev).astype(np.float32), out=J))
    del J, L_in
    if p["orders"] >= 3 and sink_is_own and J_hi is not J2:
        add_density(J2, J_hi, q2, q3)


# the interpolant of the orders >= 3's ratio to order 2 in wavelength (_spectral.spread_ratio):
# monotone cubic in log rho against log lambda (True) or linear
SPREAD_CUBIC = True
# ... with the band absorber's part taken out first (_spectral.spread_ratio)
SPREAD_BAND = True


def higher_orders_subset(J_sum, dE1, tot2, l_hi, l_nodes, band, wl, batches, col, m, sc_idx,
                         beta_s, mu_s_min, q2, q3, hi, rule, p, progress=(0, None)):
    """:func:`higher_orders` at the table wavelengths ``l_hi`` only (in the ``batches`` of
    :func:`subset_batches`), spread onto every table wavelength ``wl`` (:mod:`._spectral`):
    ``J_sum`` holds order 2 at every wavelength on entry and orders 2..N (+ remainder) on
    return. The orders >= 3 of J are interpolated as ratios to order 2's J through the
    interpolation nodes ``l_nodes`` (the irradiance table follows from J_sum: see
    :func:`precompute`).

    Working memory: the computed wavelengths that are not nodes (the line-absorbed ones)
    get their orders >= 3 added straight into ``J_sum``; at the nodes only the ratio
    rho = (orders >= 3) / (order 2) is kept, float16, each order's share added to it (one
    rounding of <= 2^-11 of rho per order and for the remainder; docs/models.md,
    "precomputed"), and spread onto the other wavelengths after the last batch. Per batch,
    order 2 at its wavelengths (order 3's source, then each order's J:
    :func:`higher_orders` ``work``)."""
    nl = wl.size
    node_of = {int(l): j for j, l in enumerate(l_nodes)}
    col_of = {int(l): j for j, l in enumerate(l_hi)}
    coarse = (J_sum.shape[0], q3.th_out.size, q3.ph_out.size) + tuple(hi)
    same = coarse == J_sum.shape[:-1]
    dE1_hi = np.ascontiguousarray(dE1[..., l_hi])
    jf = J_sum.reshape(-1, nl)
    rho = np.zeros((l_nodes.size, jf.shape[0]), dtype=np.float16)

    def add(l, h):
        """The orders >= 3 ``h`` (flat, J_sum's grid) of table wavelength l into J_sum, at
        a node into its ratio."""
        _add_order(h[:, None], np.array([l]), node_of, jf, rho)

    for b, ls in enumerate(batches):
        nb = ls.size
        cs = np.array([col_of[int(l)] for l in ls], dtype=np.int64)
        J_b = np.empty(J_sum.shape[:-1] + (nb,), dtype=np.float32)
        np.take(J_sum, ls, axis=-1, out=J_b, mode="clip")     # unbuffered: no temporary
        # the orders >= 3 on a coarser grid than J_sum's: summed there first
        H_b = None if same else np.zeros(coarse + (nb,), dtype=np.float32)

        def sink(Jo, ls=ls, H_b=H_b):
            if H_b is not None:
                H_b += Jo
                return
            _add_order(Jo.reshape(-1, ls.size), ls, node_of, jf, rho)

        higher_orders(J_b, dE1_hi[..., cs], tot2[ls], col, on_wavelengths(m, ls), sc_idx,
                      beta_s[:, ls], mu_s_min, q2, q3, hi, rule, p,
                      (progress[0] + b * (p["orders"] - 2), progress[1]), ls, sink=sink,
                      work=J_b if same else None)
        del J_b, sink
        for i in range(nb if H_b is not None else 0):
            h = np.zeros(J_sum.shape[:-1] + (1,), dtype=np.float32)
            add_density(h, np.ascontiguousarray(H_b[..., i:i + 1]), q2, q3)
            add(int(ls[i]), h.reshape(-1))
        del H_b
    _spread_nodes(jf, rho, l_hi, l_nodes, node_of, band, wl)
    del rho


# rows (nodes of J) per chunk of the float16 ratio's spread
SPREAD_ROWS = 1 << 20
RHO_MAX = np.float32(np.finfo(np.float16).max)


def _spectral_plan(wl, computed, nodes, band):
    from skydome.models.simulated.precomputed import _spectral

    return list(_spectral.spread_plan(wl, computed, nodes, band if SPREAD_BAND else None))


def _add_order(Jf, ls, node_of, jf, rho):
    """One order's J ``Jf`` [row, i] of the table wavelengths ``ls`` (J_sum's grid) into
    ``jf`` (J_sum [row, l]) at the wavelengths that are not nodes, and at the nodes its
    share of order 2 into the float16 ratio ``rho`` [node, row] (the sum in float32,
    rounded once; at most ``RHO_MAX``): one parallel pass of
    :func:`._spectral.add_shares` over the rows."""
    from skydome.models.simulated.precomputed import _spectral

    dst = np.asarray(ls, dtype=np.int64)
    node = np.array([node_of.get(int(l), -1) for l in ls], dtype=np.int64)
    cols = np.arange(dst.size, dtype=np.int64)
    _spectral.add_shares(Jf, cols, dst, node, jf, rho.view(np.uint16), _half_table(), RHO_MAX)


def _half_table():
    """:func:`._spectral.half_table`, made once per process (256 KB)."""
    global _HALF_TABLE
    if _HALF_TABLE is None:
        from skydome.models.simulated.precomputed import _spectral

        _HALF_TABLE = _spectral.half_table()
    return _HALF_TABLE


_HALF_TABLE = None


def _spread_nodes(jf, rho, l_hi, l_nodes, node_of, band, wl):
    """The orders >= 3 of J from their ratio ``rho`` [node, row] at the nodes onto every
    table wavelength of ``jf`` [row, l] (order 2 there on entry) but the computed ones
    that are not nodes (their orders >= 3 are added by their batches); below 1e-12 of
    order 2's largest value at the nodes the orders >= 3 are interpolated directly
    (ratio x order 2)."""
    from skydome.models.simulated.precomputed import _spectral

    plan = _spectral_plan(wl, l_nodes, l_nodes, band)
    plan[0][[int(l) for l in l_hi if int(l) not in node_of]] = -2
    floor = np.float32(1e-12 * max(float(jf[:, int(l)].max(initial=0.0)) for l in l_nodes))
    for a in range(0, jf.shape[0], SPREAD_ROWS):
        e = min(jf.shape[0], a + SPREAD_ROWS)
        rf = np.empty((e - a, rho.shape[0]), dtype=np.float32)
        _spectral.half_rows(rho.view(np.uint16), _half_table(), a, rf)
        _spectral.spread_ratio(jf[a:e], rf, *plan, SPREAD_CUBIC, floor, jf[a:e], True)


# working memory of the orders >= 3 at a subset of the wavelengths [bytes]: one batch and
# the float16 ratio of the nodes computed so far (see subset_batches); at the defaults the 13
# computed wavelengths in one batch (456 MB with the ratio), while the single-scattering
# table (0.50 GB) is not held (see precompute)
HIGH_ORDER_SUBSET_BYTES = 480_000_000


def subset_batches(p, l_hi, l_nodes, nsc):
    """The batches of :func:`higher_orders_subset` (arrays of table indices): the computed
    wavelengths that are not nodes first, then the nodes, each batch as large as fits
    ``HIGH_ORDER_SUBSET_BYTES`` with the float16 ratio of every node up to its end (its
    pages are written as the nodes come); a wavelength costs its J (float32; on a coarser
    grid of the orders >= 3, its sum there and J on the full grid too) and its incident
    radiance; at least one per batch."""
    n = p["sphere_samples"]
    n_o = min(n, max(ORDER_DENSITY_MIN, n // p["order_table_divisor"]))
    n_i = min(p["high_order_sphere_samples"] or n, n)
    n_r, n_ms = high_order_grid(p)
    n_rf, n_msf = p["scattering_r_size"], p["density_mu_s_size"] or p["scattering_mu_s_size"]
    same = (n_r, n_ms, n_o) == (n_rf, n_msf, n)
    j_fine = 4 * nsc * (2 * n + 1) * (n + 1) * n_rf * n_msf
    j_hi = 4 * nsc * (2 * n_o + 1) * (n_o + 1) * n_r * n_ms
    per_wl = (0 if same else j_fine + j_hi) + j_hi + 4 * n_r * n_ms * (n_i * n_i + 10)
    rho = j_fine // 2                      # a node's ratio, float16
    nodes = set(int(l) for l in l_nodes)
    order = ([int(l) for l in l_hi if int(l) not in nodes]
             + [int(l) for l in l_hi if int(l) in nodes])
    out, cur, n_done = [], [], 0
    for l in order:
        n_new = n_done + (l in nodes)
        if cur and per_wl * (len(cur) + 1) + rho * n_new > HIGH_ORDER_SUBSET_BYTES:
            out.append(np.array(cur, dtype=np.int64))
            cur = []
        cur.append(l)
        n_done = n_new
    out.append(np.array(cur, dtype=np.int64))
    return out


# the outgoing grid of the scattering density of orders >= 3 never has fewer zenith
# samples than this (order_table_divisor)
ORDER_DENSITY_MIN = 16


def _cells(n_fine, n_coarse):
    """Interpolation cells (node, fraction) on an axis of ``n_coarse`` nodes of the nodes of
    the same axis with ``n_fine`` nodes (both uniform in the axis' unit coordinate)."""
    x = np.arange(n_fine) * ((n_coarse - 1) / max(n_fine - 1, 1))
    i = np.minimum(x.astype(np.int64), max(n_coarse - 2, 0))
    return i, (x - i).astype(np.float32)


def add_density(J_sum, J, q_sum, q):
    """J_sum += J, J on the outgoing grid of ``q`` and J_sum on that of ``q_sum``
    (:class:`_DensityQuadrature`, both uniform in theta and phi over [0, pi]), and J on its
    own (r, mu_s) nodes of the same mappings (uniform in their unit coordinates, as
    :func:`._multiple.density_acc` interpolates): bilinear in (theta, phi) and in (r, mu_s)
    where the grids differ, one theta row of J_sum at a time (no temporary of the whole
    table)."""
    if J.shape == J_sum.shape:
        J_sum += J
        return
    it, ft = _cells(J_sum.shape[1], J.shape[1])
    ip, fp = _cells(J_sum.shape[2], J.shape[2])
    ir, fr = _cells(J_sum.shape[3], J.shape[3])
    im, fm = _cells(J_sum.shape[4], J.shape[4])
    same_p, same_r, same_m = (J_sum.shape[a] == J.shape[a] for a in (2, 3, 4))
    wp = fp[:, None, None, None]
    wr = fr[None, :, None, None]
    wm = fm[None, None, :, None]
    for a in range(J_sum.shape[1]):
        for k in range(J_sum.shape[0]):
            row = J[k, it[a]] if ft[a] == 0.0 else (1.0 - ft[a]) * J[k, it[a]] + ft[a] * J[k, it[a] + 1]
            if not same_r:      # row: (phi, r, mu_s, l)
                row = (1.0 - wr) * row[:, ir] + wr * row[:, ir + 1]
            if not same_m:
                row = (1.0 - wm) * row[:, :, im] + wm * row[:, :, im + 1]
            if not same_p:
                row = (1.0 - wp) * row[ip] + wp * row[ip + 1]
            J_sum[k, a] += row


# columns (r, mu_s, wavelength) of the incident radiance per block of the azimuthal
# products (the block's coefficient arrays stay in cache)
DENSITY_BLOCK_COLUMNS = 2048
# incident radiances below this are treated as 0 in the azimuthal products (see there)
FLUSH_BELOW = np.float32(1e-30)


def density_products(q, L_in, w_col, beta_s, rhs, J, l0=0, add=False):
    """Step 3b: the scattering density J ([BN08] eq. 7) on the outgoing grid of ``q``
    (:class:`_DensityQuadrature`), laid out [k, theta, phi, r, mu_s, l], from the incident
    radiance ``L_in`` [i, r, mu_s, l] over all (r, mu_s, l) columns, each column weighted
    by the constituent's scattering coefficient ``w_col[k]`` after the product (J = P (L w)
    = (P L) w: no scaled copy of L_in); a tabulated phase function per wavelength (``l0``:
    the table index of J's first wavelength, or the table indices of all of J's
    wavelengths). With the phase matrices in the azimuthal
    Fourier basis (``q.modes``) three float32 matrix products (BLAS) per block of columns:
    the incident radiance's cosine coefficients (shared by the constituents), per mode the
    product with the constituent's theta matrix, the sum over the modes at every outgoing
    azimuth; else one dense product per constituent, factored phase functions through
    their 10-row right-hand side ``rhs``. ``add``: J += the density instead (the azimuthal
    basis only)."""
    nsc, nl = J.shape[0], J.shape[-1]
    # the table index of each of J's wavelengths (``l0`` an int: consecutive from it)
    l_tab = np.arange(nl) + l0 if np.ndim(l0) == 0 else np.asarray(l0)
    if q.modes is not None:
        _azimuthal_products(q, L_in, w_col, beta_s, J, l_tab, add)
        return
    if add:
        raise ValueError("add=True needs the phase matrices in the azimuthal basis")
    lin = L_in.reshape(q.n_in, -1)
    for k in range(nsc):
        Jk = J[k].reshape(q.n_out, -1)
        if q.per_wavelength[k] is not None:
            lin3 = L_in.reshape(q.n_in, -1, nl)
            J3 = J[k].reshape(q.n_out, -1, nl)
            for l in range(nl):
                x = np.ascontiguousarray(lin3[:, :, l]) * np.float32(beta_s[k, l])
                J3[:, :, l] = q.per_wavelength[k][l_tab[l]] @ x
            continue
        left = q.left[:, q.rows[k]:q.rows[k + 1]]
        if q.right[k] is None:
            np.matmul(left, lin, out=Jk)
        else:
            out = rhs[:q.right[k].shape[0]]
            np.matmul(q.right[k], lin, out=out)
            np.matmul(left, out, out=Jk)
        Jk *= w_col[k]


def _modes_to_density(q, G_cls, C, D, out):
    """out[theta, phi, c] = sum_n cos(n phi) sum_a G[n, theta, a] C[a, n, c] per class of
    outgoing azimuths (:class:`_DensityQuadrature`), D the scratch of the per-mode products."""
    for sel, G, S in zip(q.classes, G_cls, q.synthesis):
        n_m = G.shape[0]
        d = D[:n_m, :, :C.shape[2]]
        np.matmul(G, C.transpose(1, 0, 2)[:n_m], out=d)
        np.matmul(S[:, :n_m], d.transpose(1, 0, 2), out=out[:, sel])


def _azimuthal_products(q, L_in, w_col, beta_s, J, l_tab, add=False):
    """:func:`density_products` with the phase matrices in the azimuthal Fourier basis
    (``l_tab``: the table index of each of J's wavelengths; ``add``: J += the density, each
    block computed in a scratch array first). The blocks of columns are
    independent (each writes its own columns of J): they are shared out between
    :func:`product_threads` threads, each with its own scratch arrays and single-threaded
    BLAS (:func:`_blocks_in_threads`)."""
    nsc, nl = J.shape[0], J.shape[-1]
    n_ti, n_pi = q.th_in.size, q.ph_in.size
    n_to, n_po = q.th_out.size, q.ph_out.size
    n_col = L_in[0].size
    L3 = L_in.reshape(n_ti, n_pi, n_col)
    block = nl * max(1, DENSITY_BLOCK_COLUMNS // nl)     # whole wavelengths per block
    n_m = q.analysis.shape[0]
    width = min(block, n_col)
    tab = any(len(m) > 1 for m in q.modes)

    def worker(starts):
        C = np.empty((n_ti, n_m, width), dtype=np.float32)
        Lb = np.empty((n_ti, n_pi, width), dtype=np.float32)
        D = np.empty((n_m, n_to, width), dtype=np.float32)
        T = np.empty((n_to, n_po, width), dtype=np.float32) if add else None
        if tab:
            nb = width // nl
            C1 = np.empty((n_ti, n_m, nb), dtype=np.float32)
            J1 = np.empty((n_to, n_po, nb), dtype=np.float32)
        for c0 in starts:
            c1 = min(n_col, c0 + block)
            c = C[:, :, :c1 - c0]
            # a contiguous copy of the block with radiances below FLUSH_BELOW set to 0: the
            # night side's incident radiance decays to float32 subnormals (< 1.2e-38), and
            # products with subnormal operands run 10-50x slower on x86 (no flush-to-zero in
            # numpy's BLAS); 1e-30 W m^-2 sr^-1 nm^-1 is ~30 orders of magnitude below any
            # radiance the tables resolve, so the density is unchanged to float32 rounding
            lb = Lb[:, :, :c1 - c0]
            lb[...] = L3[:, :, c0:c1]
            lb[lb < FLUSH_BELOW] = 0.0
            np.matmul(q.analysis, lb, out=c)
            for k in range(nsc):
                Jk = J[k].reshape(n_to, n_po, n_col)[:, :, c0:c1]
                dst = T[:, :, :c1 - c0] if add else Jk
                if len(q.modes[k]) == 1:
                    _modes_to_density(q, q.modes[k][0], c, D, dst)
                    dst *= w_col[k][c0:c1]
                else:
                    for l in range(nl):
                        cl = C1[:, :, :(c1 - c0) // nl]
                        cl[...] = c[:, :, l::nl]
                        jl = J1[:, :, :cl.shape[2]]
                        _modes_to_density(q, q.modes[k][l_tab[l]], cl, D, jl)
                        np.multiply(jl, np.float32(beta_s[k, l]), out=dst[:, :, l::nl])
                if add:
                    Jk += dst

    _blocks_in_threads(worker, list(range(0, n_col, block)))


def product_threads():
    """Threads of the scattering density's matrix products: numba's thread count (the
    kernels' own; ``NUMBA_NUM_THREADS``: :func:`skydome._threads.thread_count`)."""
    from skydome._threads import thread_count

    return thread_count()


def _blocks_in_threads(worker, starts):
    """``worker(starts[t::n])`` in n = :func:`product_threads` Python threads (numpy's
    products and ufuncs release the GIL), BLAS limited to one thread meanwhile.

    The products are many small sgemm calls (a few hundred columns each): with BLAS's own
    thread pool order 2's products alone swung between 2.5 and 22 s of CPU from run to run
    (OpenBLAS's threads spin-waiting against numba's between the kernels), and all orders'
    took 4.9-7.7 s wall; with one BLAS thread per Python thread 1.5-2.2 s wall, 2.6-4.3 s
    CPU (2-core EPYC, docs/performance.md)."""
    from threadpoolctl import threadpool_limits

    n = min(product_threads(), len(starts))
    with threadpool_limits(limits=1, user_api="blas"):
        if n <= 1:
            worker(starts)
            return
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(max_workers=n) as pool:
            for f in [pool.submit(worker, starts[t::n]) for t in range(n)]:
                f.result()


def source_total(J, q, m, sc_idx):
    """Per wavelength, sum over J's nodes of sum_k rho_k(r) J_k sin(theta): the scattering
    density of one order times each constituent's number density, over the sphere of
    outgoing directions (theta uniform: sin theta the solid angle per node), the (r, mu_s)
    nodes counted alike; the ratio of two orders' totals is the geometric remainder's
    ratio (comparable across grids of different sizes: divided by the node count of
    the outgoing grid and of the (r, mu_s) grid). The density profiles are those of the
    medium m's constituents sc_idx."""
    from skydome.models.simulated.precomputed._mapping import cell_r
    from skydome.transport._kernels import profile_density

    codes, p0s, p1s, R, Rt = m.profile_code, m.profile_p0, m.profile_p1, m.R, m.Rt
    nsc, n_t, n_p, n_r, n_ms = J.shape[:5]
    nl = J.shape[-1]
    w_t = np.sin(q.th_out) / (n_t * n_p * n_r * n_ms)
    out = np.zeros(nl)
    for k in range(nsc):
        c = int(sc_idx[k])
        rho = np.array([profile_density(int(codes[c]), float(p0s[c]), float(p1s[c]),
                                        cell_r(i, n_r, R, Rt) - R) for i in range(n_r)],
                       dtype=np.float32)
        # the sum over r first, one float32 pass over J (a matrix-vector product per
        # (theta, phi) row: 32 positive terms each), the rest in float64
        s = np.matmul(rho, np.ascontiguousarray(J[k]).reshape(n_t * n_p, n_r, -1))
        out += np.einsum("t,tpml->l", w_t, s.reshape(n_t, n_p, -1, nl), dtype=np.float64)
    return out


class _SourceFunctional:
    """:func:`source_total` of the density that :func:`density_products` makes from an
    incident radiance L (at every table wavelength; phase matrices in the azimuthal basis),
    without making it: the source strength is linear in J, and J_k = P_k L w_k, so
    tot[l] = sum_k beta_k,l sum_(r, mu_s) rho_k(r) sum_i u_k[i] L[i, r, mu_s, l], with
    u_k[i] = sum_(theta, phi) w_t(theta) P_k[(theta, phi), i] computed once from the
    azimuthal modes: the sum over the outgoing azimuths phi of a class picks
    sum_phi cos(n phi) of each mode n (a tabulated phase function: one u per table
    wavelength)."""

    def __init__(self, q, m, sc_idx, beta_s, n_r, n_ms):
        from skydome.models.simulated.precomputed._mapping import cell_r
        from skydome.transport._kernels import profile_density

        codes, p0s, p1s, R, Rt = m.profile_code, m.profile_p0, m.profile_p1, m.R, m.Rt
        n_t, n_p = q.th_out.size, q.ph_out.size
        w_t = np.sin(q.th_out) / (n_t * n_p * n_r * n_ms)
        self.u = []
        for k in range(len(q.modes)):
            sets = []
            for per_cls in q.modes[k]:
                u = np.zeros((q.th_in.size, q.ph_in.size))
                for G, S in zip(per_cls, q.synthesis):
                    n_m = G.shape[0]
                    s_n = S[:, :n_m].astype(np.float64).sum(axis=0)          # sum_phi cos(n phi)
                    g_n = np.einsum("t,nta->na", w_t, G.astype(np.float64))   # sum_theta w_t G
                    u += np.einsum("n,na,nb->ab", s_n, g_n, q.analysis[:n_m].astype(np.float64))
                sets.append(u.reshape(-1))
            self.u.append(sets)
        self.beta_s = beta_s
        self.rho = [np.array([profile_density(int(codes[c]), float(p0s[c]), float(p1s[c]),
                                              cell_r(i, n_r, R, Rt) - R) for i in range(n_r)])
                    for c in (int(x) for x in sc_idx)]

    def __call__(self, L):
        """tot[l] of the density of the incident radiance L [i, r, mu_s, l] (float64)."""
        n_in, n_r, n_ms, nl = L.shape
        out = np.zeros(nl)
        for k, sets in enumerate(self.u):
            if len(sets) == 1:
                a = (sets[0].astype(np.float32) @ L.reshape(n_in, -1)).reshape(n_r, n_ms, nl)
            else:
                a = np.einsum("li,irml->rml", np.array(sets, dtype=np.float32), L)
            out += self.beta_s[k] * np.einsum("r,rml->l", self.rho[k], a, dtype=np.float64)
        return out


def _series_factor(tot, tot_prev):
    """f / (1 - f) of the geometric series with ratio f = tot / tot_prev, clamped to
    [0, 0.9] (0 where the previous order is 0)."""
    ok = tot_prev > 0
    f = np.clip(np.where(ok, tot / np.where(ok, tot_prev, 1.0), 0.0), 0.0, 0.9)
    return f / (1.0 - f)
