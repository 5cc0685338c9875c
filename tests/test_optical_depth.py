"""Optical depth along rays (survey eq. 12): quadrature, closed forms, Chapman, the table."""

import numpy as np
import pytest

from skydome.atmosphere import Atmosphere
from skydome.atmosphere.profiles import ExponentialProfile, TentProfile, UniformProfile
from skydome.transport.optical_depth import (ColumnTable, chapman, chapman_column, column_density,
                                             optical_depth)

R, RT = 6360e3, 6460e3
MU = np.array([1.0, 0.7, 0.3, 0.1, 0.02, 0.0, -0.01])


def chord(h, mu, radius=RT):
    """Closed form: distance from radius R + h along mu to the sphere of given radius."""
    r = R + h
    return -r * mu + np.sqrt(r * r * (mu * mu - 1.0) + radius * radius)


@pytest.mark.parametrize("h", [0.0, 5000.0, 60e3])
def test_uniform_shell_equals_closed_form(h):
    """A uniform density filling the whole shell: the quadrature converges to the
    geometric path length (ray-sphere intersection; midpoint rule in v = ln(1 + u/ts),
    relative error (ln(1 + L/ts)/n)^2/24 < 1e-5 at n = 1024); rays below the horizon from altitude pass a lowest
    point and climb again (or hit the ground, where the column ends)."""
    u = UniformProfile(RT - R)
    mu = MU[MU >= 0] if h == 0 else MU
    col = column_density(u, h, mu, R, RT, samples=1024)
    r = R + h
    hits = (mu < 0) & (r * r * (mu * mu - 1) + R * R >= 0)
    expect = np.where(hits, -r * mu - np.sqrt(np.maximum(r * r * (mu * mu - 1) + R * R, 0)), chord(h, mu))
    np.testing.assert_allclose(col, expect, rtol=1e-5)
    coarse = column_density(u, h, mu, R, RT, samples=64)
    np.testing.assert_allclose(coarse, expect, rtol=2e-3)


def test_exponential_vertical_column_closed_form():
    """Straight up, the column of exp(-h/H) to the top Ht is H (1 - exp(-Ht/H)) exactly."""
    for H in (1200.0, 7994.0):
        col = column_density(ExponentialProfile(H), 0.0, 1.0, R, RT, samples=64)
        assert col == pytest.approx(H * (1 - np.exp(-(RT - R) / H)), rel=1e-4)
        col = column_density(ExponentialProfile(H), 0.0, 1.0, R, RT, samples=1024)
        assert col == pytest.approx(H * (1 - np.exp(-(RT - R) / H)), rel=1e-6)


def test_plane_parallel_limit():
    """Near the zenith the curvature correction is small: column ~ H / mu, and the
    spherical column is always below the flat one (0.13 % below at mu = 0.7)."""
    H = 8000.0
    mu = np.array([1.0, 0.9, 0.7])
    col = column_density(ExponentialProfile(H), 0.0, mu, R, RT, samples=128)
    np.testing.assert_allclose(col, H / mu, rtol=2e-3)
    wide = np.array([0.5, 0.3, 0.1])
    assert np.all(column_density(ExponentialProfile(H), 0.0, wide, R, RT, samples=128) < H / wide)


def test_quadrature_converges():
    p = ExponentialProfile(7994.0)
    a = column_density(p, 0.0, MU[MU >= 0], R, RT, samples=64)
    b = column_density(p, 0.0, MU[MU >= 0], R, RT, samples=4096)
    np.testing.assert_allclose(a, b, rtol=2e-5)


@pytest.mark.parametrize("H", [1200.0, 7994.0])
@pytest.mark.parametrize("h", [0.0, 2000.0])
def test_chapman_against_quadrature(H, h):
    """The Chapman approximation (asymptotic erfcx form) agrees with quadrature within
    0.15 % for rays above the horizon (its error is -1/x, x = r/H, at the zenith), with
    the top far above the layer (the approximation's top is at infinity)."""
    top = R + 40 * H + h
    mu = np.array([1.0, 0.5, 0.2, 0.05, 0.0])
    q = column_density(ExponentialProfile(H), h, mu, R, top, samples=2048)
    c = chapman_column(H, h, mu, R)
    np.testing.assert_allclose(c, q, rtol=1.5e-3)


def test_chapman_below_horizon_from_altitude():
    """Rays dipping below the horizon that miss the ground (the grazing branch)."""
    H, h = 7994.0, 20e3
    r = R + h
    mu_h = -np.sqrt(1 - (R / r) ** 2)
    mu = np.array([0.5 * mu_h, 0.9 * mu_h])
    q = column_density(ExponentialProfile(H), h, mu, R, R + 400e3, samples=4096)
    c = chapman_column(H, h, mu, R)
    np.testing.assert_allclose(c, q, rtol=5e-3)
    assert np.isinf(chapman_column(H, h, np.array([1.1 * mu_h]), R)).all()


def test_chapman_flat_limit():
    """x -> infinity: Ch -> 1 / cos(chi)."""
    np.testing.assert_allclose(chapman(1e12, np.array([1.0, 0.5, 0.25])), [1, 2, 4], rtol=1e-5)


def test_column_table_matches_quadrature():
    """The interpolated table gives the optical depth of every constituent at 400 nm within
    1e-3 absolute of direct quadrature (transmittance within 0.1 %), from the ground to
    12 km and from the zenith to grazing incidence; rays into the ground are infinite
    (earth shadow)."""
    atm = Atmosphere.earth(turbidity=3.0)
    props = atm.optical_properties([400.0])
    tab = ColumnTable(props)
    for h in (0.0, 300.0, 1500.0, 5000.0, 12e3):
        for mu in (1.0, 0.4, 0.05, 0.01, 0.0):
            got = tab.lookup(h, mu)
            for k, c in enumerate(atm.constituents):
                ref = column_density(c.profile, h, mu, R, RT, samples=4096)
                ext = props.extinction[k, 0]
                assert abs(got[k] - ref) * ext < 1e-3, (c.name, h, mu, got[k], ref)
    assert np.isinf(tab.lookup(1000.0, -0.5)).all()


def test_optical_depth_methods_agree():
    atm = Atmosphere.earth(turbidity=2.0)
    wl = np.array([400.0, 550.0, 700.0])
    q = optical_depth(atm, 0.0, np.array([1.0, 0.3]), wl)
    c = optical_depth(atm, 0.0, np.array([1.0, 0.3]), wl, method="chapman")
    np.testing.assert_allclose(c, q, rtol=2e-3)
    # vertical optical depth equals the atmosphere's own column sums
    vod = sum(atm.vertical_optical_depth(wl).values())
    np.testing.assert_allclose(q[0], vod, rtol=1e-4)


@pytest.mark.parametrize("kw, frag", [
    (dict(altitude_m=-1.0, cos_zenith=1.0), "altitude_m = -1"),
    (dict(altitude_m=0.0, cos_zenith=1.5), "cos_zenith = 1.5"),
    (dict(altitude_m=200e3, cos_zenith=1.0), "altitude_m = 200000"),
])
def test_bad_rays(kw, frag):
    with pytest.raises(ValueError, match=frag):
        column_density(ExponentialProfile(8000.0), planet_radius_m=R, top_radius_m=RT, **kw)


def test_tent_profile_column():
    """Ozone tent (10-25-40 km): the vertical column is the triangle's area, 15 km."""
    t = TentProfile(25e3, 15e3)
    assert column_density(t, 0.0, 1.0, R, RT, samples=2048) == pytest.approx(15e3, rel=1e-4)
