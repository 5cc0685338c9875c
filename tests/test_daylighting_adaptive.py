"""The adaptive patch quadrature of the Perez sky matrices against an independent order-16
reference (NumPy, written here from [PSM93] eq. 1 with NumPy's Gauss-Legendre nodes, not the
numba kernel), on the test days of the sample TMY3 year."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skydome.daylighting.patches import AdaptiveRule, patches
from skydome.daylighting.skymatrix import perez_sky_matrix_from_weather
from skydome.daylighting.weather import read_weather, sample_weather_path


@pytest.fixture(scope="module")
def days():
    from _daylighting import TEST_DAYS

    w = read_weather(sample_weather_path())
    return w.select(np.isin(w.day_of_year, TEST_DAYS))


def _gl16_patch_means(ps, s, coef, q=16):
    """Mean of the Perez relative luminance over every sky patch and the horizontal integral
    of lv cos(zeta) over the sky, by a q x q Gauss-Legendre rule in (sin a, azimuth) on each
    ring patch and q x 6q (periodic trapezoid in azimuth) on the zenith cap."""
    a, b, c, d, e = coef
    x, wx = np.polynomial.legendre.leggauss(q)
    u, wu = 0.5 * (x + 1.0), 0.5 * wx
    slo = np.sin(ps.altitude_low_rad[1:])
    shi = np.sin(ps.altitude_high_rad[1:])
    ring = slice(0, ps.n_sky - 1)
    sz = slo[ring, None] + (shi - slo)[ring, None] * u  # (p, q) sin(altitude)
    ws = (shi - slo)[ring, None] * wu
    h = ps.azimuth_half_width_rad[1:][ring]
    phi = ps.azimuth_centre_rad[1:][ring, None] + h[:, None] * x  # (p, q)
    wp = h[:, None] * wx
    sz_c = slo[-1] + (shi[-1] - slo[-1]) * u
    ws_c = (shi[-1] - slo[-1]) * wu
    phi_c = 2.0 * math.pi * (np.arange(6 * q) + 0.5) / (6 * q)

    def lv(z, azi):
        r = np.sqrt(1.0 - z * z)
        cg = np.clip(r * np.sin(azi) * s[0] + r * np.cos(azi) * s[1] + z * s[2], -1.0, 1.0)
        grad = 1.0 + a * np.exp(b / np.maximum(z, 0.01))  # [PSM93] eq. 1, zenith clamp
        v = grad * (1.0 + c * np.exp(d * np.arccos(cg)) + e * cg * cg)
        return np.maximum(v, 0.0)

    f = lv(sz[:, :, None], phi[:, None, :])  # (p, q alt, q az)
    w = ws[:, :, None] * wp[:, None, :]
    fc = lv(sz_c[:, None], phi_c[None, :])
    wc = ws_c[:, None] * np.full(6 * q, 2.0 * math.pi / (6 * q))
    means = np.concatenate([(f * w).sum((1, 2)) / w.sum((1, 2)), [(fc * wc).sum() / wc.sum()]])
    horiz = (f * w * sz[:, :, None]).sum() + (fc * wc * sz_c[:, None]).sum()
    return means, horiz


def _reference(days, ps):
    """Sky-only luminance matrix [cd m^-2] (hours, sky patches), order 16, normalised as
    gendaymtx does (the sky's horizontal illuminance equals the diffuse horizontal one)."""
    from skydome.models.analytic.perez1993 import (perez1993_coefficients_many,
                                                    perez1993_sky_parameters)

    sd = days.spa_sun_directions()
    zen = np.degrees(np.arccos(np.clip(sd[:, 2], -1.0, 1.0)))
    td = np.where(np.isfinite(days.dew_point_c), days.dew_point_c, 11.0)
    par = perez1993_sky_parameters(days.dni, days.dhi, zen, days.day_of_year, td)
    zc = np.radians(par.sun_zenith_deg)
    azi = np.arctan2(sd[:, 0], sd[:, 1])
    s = np.stack([np.sin(zc) * np.sin(azi), np.sin(zc) * np.cos(azi), np.cos(zc)], axis=-1)
    coef = perez1993_coefficients_many(zc, par.epsilon, par.delta)
    lit = (days.dni + days.dhi) > 1e-4
    ref = np.zeros((len(days), ps.n_sky))
    for h in np.flatnonzero(lit):
        means, horiz = _gl16_patch_means(ps, s[h], coef[h])
        ref[h] = means * max(par.diffuse_illuminance[h], 0.0) / horiz
    return ref, lit


@pytest.mark.parametrize("spec", ["tregenza", "reinhart:4"])
def test_adaptive_within_0p1_percent_of_order_16(days, spec):
    """Every lit patch-hour of the default (adaptive) rule within 0.1 % of the order-16
    patch mean (the figure the rule was chosen for; docs/daylighting.md, section 2), and
    closer than order 4 (today's former default) in the worst patch-hour."""
    ps = patches(spec)
    ref, lit = _reference(days, ps)
    kw = dict(patches=ps, sun="none", components="luminance")
    ad = perez_sky_matrix_from_weather(days, **kw).sky[:, 1:, 0]
    o4 = perez_sky_matrix_from_weather(days, order=4, **kw).sky[:, 1:, 0]
    assert np.count_nonzero(lit) > 40 and ref[lit].min() > 0.0
    err_ad = np.abs(ad[lit] - ref[lit]) / ref[lit]
    err_o4 = np.abs(o4[lit] - ref[lit]) / ref[lit]
    assert err_ad.max() <= 1e-3
    assert err_ad.max() < err_o4.max()
    assert np.all(ad[~lit] == 0.0)


def test_adaptive_rule_spends_fewer_nodes_at_mf4(days):
    """At MF:4 the default rule evaluates, over the lit hours of the test days, fewer than
    half the nodes of order 4 (its point: the cost of the default path)."""
    from skydome.daylighting.skymatrix import quadrature_rule

    ps = patches("reinhart:4")
    nodes, _, offsets, cos_tier = quadrature_rule(ps, "adaptive")
    sd = days.spa_sun_directions()[(days.dni + days.dhi) > 1e-4]
    dots = sd @ ps.centres[1:].T
    tier = np.full(dots.shape, offsets.shape[0] - 1)
    for t in range(offsets.shape[0] - 2, -1, -1):
        tier = np.where(dots > cos_tier[t][None, :], t, tier)
    counts = np.diff(offsets, axis=1)[tier, np.arange(ps.n_sky)[None, :]].sum(axis=1)
    assert counts.mean() < 0.5 * ps.nodes(4)[0].shape[0]
    assert np.all(counts > ps.n_sky)  # never below one node a patch


def test_tiers_of_one_order_are_that_order_bit_for_bit(days):
    """A tiered rule whose three tiers are all order q computes, node for node, what order
    q computes: the same bits (the tier choice changes which copy of the nodes is read)."""
    from skydome.daylighting import _kernels as DK

    ps = patches("reinhart:2")
    perez_sky_matrix_from_weather(days, patches=ps, order=2, backend="numba")
    n_sig = len(DK.fill_perez_sky.signatures)
    for q in (1, 3):
        rule = AdaptiveRule(near_order=q, mid_order=q, far_order=q, far_az_order=q,
                            horizon_order=1)
        a = perez_sky_matrix_from_weather(days, patches=ps, order=rule, backend="numba")
        b = perez_sky_matrix_from_weather(days, patches=ps, order=q, backend="numba")
        assert np.array_equal(a.sky, b.sky)
    assert len(DK.fill_perez_sky.signatures) == n_sig  # one compiled kernel for every rule


@pytest.mark.parametrize("kw, message", [
    (dict(near_order=0), "near_order"),
    (dict(far_az_order=17), "far_az_order"),
    (dict(mid_angle_deg=-1.0), "mid_angle_deg"),
    (dict(horizon_deg=float("nan")), "horizon_deg"),
])
def test_bad_rules(kw, message):
    with pytest.raises(ValueError, match=message):
        AdaptiveRule(**kw)


def test_bad_order_string(days):
    with pytest.raises(ValueError, match="order = 'fine'"):
        perez_sky_matrix_from_weather(days, order="fine")
