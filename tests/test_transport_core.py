"""The numerical core (skydome.transport._geometry, _quadrature, _tables, _phase, _medium):
named guards, ray/shell geometry against closed forms, Bruneton's mappings as inverse
pairs, Beer-Lambert, normalisation and moments of the phase functions."""

import math

import numpy as np
import pytest
from scipy import integrate

from skydome.transport import _geometry as geo
from skydome.transport import _phase as ph
from skydome.transport import _quadrature as quad
from skydome.transport import _tables as tab
from skydome.transport._medium import Medium, densities, phase_cdf_table

R, RT = 6360e3, 6420e3
H = math.sqrt(RT * RT - R * R)


# -- guards ------------------------------------------------------------------------------------------
def test_safe_sqrt_and_clamp_cosine():
    assert geo.safe_sqrt(-1e-18) == 0.0
    assert geo.safe_sqrt(4.0) == 2.0
    assert geo.clamp_cosine(1.0 + 1e-15) == 1.0
    assert geo.clamp_cosine(-3.0) == -1.0
    assert geo.clamp_cosine(0.25) == 0.25
    assert geo.clamp_radius(R - 1.0, R, RT) == R
    assert geo.clamp_radius(RT + 1.0, R, RT) == RT


# -- geometry against closed forms -------------------------------------------------------------------
@pytest.mark.parametrize("h", [0.0, 1000.0, 30e3])
def test_distances_closed_forms(h):
    """Straight up: Rt - r; straight down: r - R; along the local horizon: sqrt(Rt^2 - r^2)
    (Pythagoras)."""
    r = R + h
    assert geo.distance_to_top(r, 1.0, RT) == pytest.approx(RT - r, rel=1e-12)
    assert geo.distance_to_top(r, 0.0, RT) == pytest.approx(math.sqrt(RT * RT - r * r), rel=1e-12)
    assert geo.distance_to_top(r, -1.0, RT) == pytest.approx(RT + r, rel=1e-12)
    if h > 0:
        assert geo.distance_to_ground(r, -1.0, R) == pytest.approx(h, rel=1e-9)


def test_ground_hit_edge_cases():
    """From the ground: the horizontal ray does not hit (it touches), the slightest downward
    one does. From altitude h: the tangent ray mu_h = -sqrt(1 - (R/r)^2) is the boundary."""
    assert not geo.ray_hits_ground(R, 0.0, R)
    assert geo.ray_hits_ground(R, -1e-9, R)
    assert not geo.ray_hits_ground(R, 1.0, R)
    r = R + 10e3
    mu_h = -math.sqrt(1.0 - (R / r) ** 2)
    assert geo.ray_hits_ground(r, mu_h - 1e-6, R)
    assert not geo.ray_hits_ground(r, mu_h + 1e-6, R)
    assert not geo.ray_hits_ground(r, 0.0, R)


def test_ray_segment_cases():
    # inside, looking up: from 0 to the top
    t0, t1, g = geo.ray_segment(R + 1000.0, 1.0, R, RT)
    assert (t0, g) == (0.0, False) and t1 == pytest.approx(RT - R - 1000.0)
    # inside, looking down: ends at the ground
    t0, t1, g = geo.ray_segment(R + 1000.0, -1.0, R, RT)
    assert g and t1 == pytest.approx(1000.0)
    # transparent planet: through to the far side of the shell
    t0, t1, g = geo.ray_segment(R + 1000.0, -1.0, R, RT, False)
    assert not g and t1 == pytest.approx(RT + R + 1000.0)
    # from space looking down: enters at Rt
    t0, t1, g = geo.ray_segment(RT + 5000.0, -1.0, R, RT)
    assert t0 == pytest.approx(5000.0) and t1 == pytest.approx(RT - R + 5000.0) and g
    # from space looking away: misses
    t0, t1, g = geo.ray_segment(RT + 5000.0, 0.5, R, RT)
    assert t1 < t0
    # observer on the ground looking down sees the ground at its feet
    t0, t1, g = geo.ray_segment(R, -0.5, R, RT)
    assert g and t1 == 0.0


def test_ray_segment_xyz_matches_r_mu():
    p = np.array([3e3, -2e3, R + 500.0])
    d = np.array([0.3, 0.4, -0.2])
    d /= np.linalg.norm(d)
    r = np.linalg.norm(p)
    a = geo.ray_segment_xyz(p[0], p[1], p[2], d[0], d[1], d[2], R, RT)
    b = geo.ray_segment(r, float(p @ d) / r, R, RT)
    assert a[2] == b[2]
    np.testing.assert_allclose(a[:2], b[:2], rtol=1e-9)


def test_point_along_law_of_cosines():
    """The radius and cosines at distance t agree with explicit vectors."""
    r, mu, t = R + 2000.0, 0.3, 45e3
    p = np.array([0.0, 0.0, r])
    d = np.array([math.sqrt(1 - mu * mu), 0.0, mu])
    q = p + t * d
    rq = np.linalg.norm(q)
    assert geo.radius_along(r, mu, t) == pytest.approx(rq, rel=1e-12)
    assert geo.mu_along(r, mu, t, rq) == pytest.approx(q @ d / rq, rel=1e-12)
    s = np.array([0.6, 0.0, 0.8])
    assert geo.mu_s_along(r, 0.8, float(d @ s), t, rq) == pytest.approx(q @ s / rq, rel=1e-12)


def test_shadow_crossings_on_the_cylinder():
    """Both crossings lie on the shadow cylinder |p - (p.s)s| = R on the night side."""
    sz = -0.2
    s = np.array([math.sqrt(1 - sz * sz), 0.0, sz])
    d = np.array([-0.9, 0.1, 0.3])
    d /= np.linalg.norm(d)
    n, t1, t2 = geo.shadow_crossings(R, d[2], sz, float(d @ s), R)
    assert n >= 1
    for t in (t1, t2)[:n]:
        p = np.array([0.0, 0.0, R]) + t * d
        assert np.linalg.norm(p - (p @ s) * s) == pytest.approx(R, rel=1e-9)
        assert p @ s < 0


# -- mappings as inverse pairs ------------------------------------------------------------------------
@pytest.mark.parametrize("x_r", [0.0, 0.1, 0.5, 0.93, 1.0])
def test_transmittance_mapping_round_trip(x_r):
    for x_mu in (0.0, 0.2, 0.5, 0.77, 1.0):
        r, mu = tab.r_mu_from_transmittance_unit(x_r, x_mu, R, RT)
        a, b = tab.transmittance_unit_from_r_mu(r, mu, R, RT)
        assert a == pytest.approx(x_r, abs=1e-9)
        if x_r < 1.0:   # at the top every mu maps to d = 0 except the exact coordinate
            assert b == pytest.approx(x_mu, abs=1e-7)


def test_transmittance_mapping_ends():
    """x_mu = 0 is the zenith, x_mu = 1 the horizon from the ground (Bruneton 2017)."""
    assert tab.transmittance_unit_from_r_mu(R, 1.0, R, RT) == pytest.approx((0.0, 0.0))
    assert tab.transmittance_unit_from_r_mu(R, 0.0, R, RT) == pytest.approx((0.0, 1.0))


@pytest.mark.parametrize("h", [0.0, 3000.0, 40e3])
def test_irradiance_mapping_round_trip(h):
    r = R + h
    for mu_s in (-1.0, 0.0, 0.4):
        xr, xm = tab.irradiance_unit_from_r_mu_s(r, mu_s, R, RT)
        assert tab.r_mu_s_from_irradiance_unit(xr, xm, R, RT) == pytest.approx((r, mu_s))


def test_cells_and_bilinear_lookup_reproduce_a_bilinear_function():
    """A function bilinear in the unit coordinates is interpolated exactly."""
    n_r, n_mu = 9, 17
    xr = np.arange(n_r) / (n_r - 1)
    xm = np.arange(n_mu) / (n_mu - 1)
    f2 = 2.0 + 3.0 * xr[:, None] - xm[None, :] + 0.5 * xr[:, None] * xm[None, :]
    table = np.stack([f2, 2 * f2])
    table_l = np.stack([f2, -f2, f2 * 0.5], axis=-1)
    assert tab.cell(1.0, 5) == (3, 1.0)
    assert tab.cell(-0.5, 5) == (0, 0.0)
    out = np.zeros(2)
    out_l = np.zeros(3)
    for r, mu in ((R + 500.0, 0.9), (R + 20e3, 0.05), (R + 59e3, 0.5)):
        a, b = tab.transmittance_unit_from_r_mu(r, mu, R, RT)
        expect = 2.0 + 3.0 * a - b + 0.5 * a * b
        tab.lookup_columns(table, r, mu, R, RT, out)
        np.testing.assert_allclose(out, [expect, 2 * expect], rtol=1e-12)
        assert tab.lookup_column(table, 1, r, mu, R, RT) == pytest.approx(2 * expect, rel=1e-12)
        tab.lookup_rmu(table_l, r, mu, R, RT, 2.0, out_l)
        np.testing.assert_allclose(out_l, [2 * expect, -2 * expect, expect], rtol=1e-12)


# -- quadrature ---------------------------------------------------------------------------------------
def test_geometric_nodes_integrate_a_constant():
    """sum of w over the nodes is L up to (ln(1 + L/ts)/n)^2/24 relative (midpoint rule in v)."""
    L, ts = 150e3, 500.0
    for n in (16, 64, 256):
        dv = quad.geometric_step(L, n, ts)
        total = sum(quad.geometric_node(k, dv, ts)[1] for k in range(n))
        bound = (math.log1p(L / ts) / n) ** 2 / 24.0
        assert abs(total / L - 1.0) <= 1.05 * bound
        assert quad.geometric_edge(n, dv, ts) == pytest.approx(L, rel=1e-12)


def test_beer_lambert_uniform_and_exponential_columns():
    """Uniform density: the column is the geometric path (Beer-Lambert with tau = beta L);
    exponential straight up: H (1 - exp(-(Rt - R)/H))."""
    m = _medium(codes=[2, 0], p0=[RT - R, 8000.0])
    out = np.zeros(2)
    for mu in (1.0, 0.5, 0.1, 0.0):
        quad.medium_columns(m, R, mu, 2048, 500.0, True, out)
        assert out[0] == pytest.approx(geo.distance_to_top(R, mu, RT), rel=1e-5)
    quad.medium_columns(m, R, 1.0, 256, 500.0, True, out)
    assert out[1] == pytest.approx(8000.0 * -math.expm1(-(RT - R) / 8000.0), rel=1e-5)


def test_simpson_is_exact_for_cubics():
    f = lambda x: 1.0 + 2.0 * x - 3.0 * x ** 2 + x ** 3   # noqa: E731
    assert quad.simpson(f(0.0), f(1.0), f(2.0), 2.0) == pytest.approx(2.0 + 4.0 - 8.0 + 4.0)


def test_sphere_nodes_weights_and_moments():
    n_mu, n_phi = 64, 32
    nodes = np.array([quad.sphere_node(k, n_mu, n_phi) for k in range(n_mu * n_phi)])
    assert nodes[:, 3].sum() == pytest.approx(4 * math.pi, rel=1e-12)
    np.testing.assert_allclose(np.linalg.norm(nodes[:, :3], axis=1), 1.0, rtol=1e-12)
    # integral of z^2 over the sphere is 4 pi / 3
    assert (nodes[:, 3] * nodes[:, 2] ** 2).sum() == pytest.approx(4 * math.pi / 3, rel=1e-3)


# -- phase functions ----------------------------------------------------------------------------------
def _sphere_integral(f, points=()):
    """2 pi integral over c in [-1, 1] of f(c) (scipy adaptive quadrature)."""
    return 2 * math.pi * integrate.quad(f, -1.0, 1.0, points=points, limit=400, epsabs=1e-12)[0]


@pytest.mark.parametrize("rho", [0.0, 0.0279, 0.5])
def test_rayleigh_normalised_and_hansen_travis_form(rho):
    """Normalised; equals 3/(8 pi) ((1 + rho) + (1 - rho) c^2) / (2 + rho) (Hansen & Travis
    1974 eq. 2.15); at rho = 0 it is 3/(16 pi) (1 + c^2) ([KRZ06] eq. 3)."""
    gamma = ph.rayleigh_gamma(rho)
    assert ph.rayleigh_rho(gamma) == pytest.approx(rho)
    assert _sphere_integral(lambda c: ph.rayleigh_phase(gamma, c)) == pytest.approx(1.0, rel=1e-10)
    for c in (-1.0, -0.3, 0.0, 0.6, 1.0):
        ht = 3 / (8 * math.pi) * ((1 + rho) + (1 - rho) * c * c) / (2 + rho)
        assert ph.rayleigh_phase(gamma, c) == pytest.approx(ht, rel=1e-12)
    if rho == 0.0:
        assert ph.rayleigh_phase(0.0, 0.5) == pytest.approx(3 / (16 * math.pi) * 1.25)


@pytest.mark.parametrize("g", [-0.5, 0.0, 0.76, 0.9])
def test_hg_and_cs_normalised_with_known_mean_cosine(g):
    """Both integrate to 1; <cos> is g for HG (its definition) and 3 g (4 + g^2) /
    (5 (2 + g^2)) for Cornette-Shanks (Cornette & Shanks 1992, Appl. Opt. 31, eq. 9)."""
    pts = (0.9, 0.99, 0.999)
    assert _sphere_integral(lambda c: ph.henyey_greenstein(g, c), pts) == pytest.approx(1.0, rel=1e-8)
    assert _sphere_integral(lambda c: ph.cornette_shanks(g, c), pts) == pytest.approx(1.0, rel=1e-8)
    assert _sphere_integral(lambda c: c * ph.henyey_greenstein(g, c), pts) == pytest.approx(g, abs=1e-8)
    cs_mean = 3 * g * (4 + g * g) / (5 * (2 + g * g))
    assert _sphere_integral(lambda c: c * ph.cornette_shanks(g, c), pts) == pytest.approx(cs_mean, abs=1e-8)
    assert ph.phase_value(ph.ISOTROPIC, 0.0, 0.3) == pytest.approx(1 / (4 * math.pi))


def _hg_table(g_values, na=1441):
    theta = np.linspace(0.0, math.pi, na)
    return np.stack([np.array([ph.henyey_greenstein(g, math.cos(t)) for t in theta])
                     for g in g_values], axis=-1)[None]          # (1, na, nl)


def test_tabulated_hg_reproduces_analytic():
    """An HG table at 1441 angles (0.125 deg) reproduces the analytic HG to 1e-3."""
    gs = [0.3, 0.76, 0.85]
    table = _hg_table(gs)
    for l, g in enumerate(gs):
        for c in np.cos(np.radians([0.0, 0.07, 1.3, 10.0, 45.0, 90.0, 133.3, 180.0])):
            assert ph.tabulated_phase(table, 0, l, c) == pytest.approx(ph.henyey_greenstein(g, c), rel=1e-3)


def test_medium_record_and_spectral_phase():
    """The record passes to numba as one argument; phase_of/phase_fill dispatch per code."""
    gs = [0.3, 0.76]
    table = np.concatenate([np.zeros((1, 1441, 2)), _hg_table(gs)])
    m = _medium(codes=[0, 0], p0=[8000.0, 1200.0], phase_code=[ph.RAYLEIGH, ph.TABULATED],
                phase_param=[0.0, 0.0], table=table, nl=2)
    rho = np.zeros(2)
    densities(m, 1200.0, rho)
    np.testing.assert_allclose(rho, [math.exp(-0.15), math.exp(-1.0)], rtol=1e-12)
    out = np.zeros(2)
    ph.phase_fill(m, 1, 0.5, out)
    np.testing.assert_allclose(out, [ph.henyey_greenstein(g, 0.5) for g in gs], rtol=1e-3)
    assert ph.phase_of(m, 0, 1, 0.5) == pytest.approx(ph.rayleigh_phase(0.0, 0.5))
    assert ph.phase_is_spectral(m, 1) and not ph.phase_is_spectral(m, 0)
    both = np.zeros((2, 2))
    ph.phase_matrix_fill(m, 0.5, both)
    np.testing.assert_allclose(both[1], out)


def test_sampling_hg_and_tabulated_mean_cosine():
    """Sampled cosines have the mean g (HG inversion and the inverted tabulated CDF)."""
    g = 0.76
    u = (np.arange(20000) + 0.5) / 20000
    c_hg = np.array([ph.sample_henyey_greenstein(g, x) for x in u])
    assert c_hg.mean() == pytest.approx(g, abs=2e-3)
    cdf = phase_cdf_table(_hg_table([g]))
    assert cdf[0, 0, 0] == 0.0 and cdf[0, -1, 0] == pytest.approx(1.0)
    c_tab = np.array([ph.sample_tabulated(cdf, 0, 0, x) for x in u])
    assert c_tab.mean() == pytest.approx(g, abs=2e-3)
    assert np.all(np.abs(c_tab) <= 1.0)


def _medium(codes, p0, p1=None, phase_code=None, phase_param=None, table=None, nl=1):
    nc = len(codes)
    p1 = np.zeros(nc) if p1 is None else np.asarray(p1, float)
    table = np.zeros((nc, 2, nl)) if table is None else table
    return Medium(R, RT, np.asarray(codes, np.int64), np.asarray(p0, float), p1,
                  np.ones((nc, nl)), np.ones((nc, nl)),
                  np.asarray(phase_code if phase_code is not None else [0] * nc, np.int64),
                  np.asarray(phase_param if phase_param is not None else [0.0] * nc, float),
                  table, phase_cdf_table(table), np.zeros(nl))
