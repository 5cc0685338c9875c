"""precomputed: the orders >= 3 at a subset of the table wavelengths (``high_order_wavelengths``)."""

import numpy as np
import pytest

import skydome as sd
from skydome.atmosphere import Atmosphere
from skydome.models.simulated.precomputed import _precompute as PC
from skydome.models.simulated.precomputed import _spectral as S

# small tables (a few seconds each); 20 table wavelengths, Atmosphere.earth (ozone, water
# vapour, oxygen)
SMALL = dict(scattering_r_size=8, scattering_mu_size=32, scattering_mu_s_size=16,
             scattering_nu_size=8, irradiance_mu_s_size=16, irradiance_r_size=8,
             transmittance_mu_size=32, transmittance_r_size=16, sphere_samples=8,
             high_order_sphere_samples=8, cache=False)


def _props_and_columns(wl):
    props = Atmosphere.earth().optical_properties(wl, fold=True)
    p = sd.models.simulated.precomputed.PrecomputedSky._validate_params({})
    from skydome.transport._medium import medium_from_properties

    col = PC.transmittance_columns(medium_from_properties(props), p)
    return props, col[:, 0, 0]


def test_subset_has_both_ends_and_computes_the_gas_bands():
    """The 20 table wavelengths 380-780 nm: every one in a water-vapour or oxygen band is
    computed and none of them is an interpolation node: the table wavelengths 590 (water
    vapour), 675 and 696 (oxygen B band, 687 nm, and water vapour), 717 and 738 (water
    vapour) and 759 nm (oxygen A band, 760 nm): band positions as in HITRAN (Rothman et al.
    2013); the Chappuis band of ozone, broad, is interpolated."""
    wl = np.linspace(380.0, 780.0, 20)
    props, column = _props_and_columns(wl)
    band = {10, 14, 15, 16, 17, 18}
    for k in (4, 5, 7):
        computed, nodes = S.subset_indices(20, k, props.extinction - props.scattering, column)
        assert nodes.size == k and nodes[0] == 0 and nodes[-1] == 19
        assert band <= set(computed.tolist())
        assert not band & set(nodes.tolist())
        assert set(computed.tolist()) == band | set(nodes.tolist())
    every = np.arange(20)
    for k in (None, 14, 40):
        computed, nodes = S.subset_indices(20, k, props.extinction - props.scattering, column)
        assert np.array_equal(computed, every) and np.array_equal(nodes, every)


def test_pchip_slopes_match_scipy():
    """The monotone cubic's node slopes against scipy's PchipInterpolator (an independent
    implementation of Fritsch & Carlson 1980 with the same end conditions)."""
    from scipy.interpolate import PchipInterpolator

    rng = np.random.default_rng(3)
    for k in (2, 3, 4, 7):
        for _ in range(20):
            x = np.sort(rng.uniform(5.9, 6.7, k))
            y = rng.normal(size=k) if rng.uniform() < 0.5 else np.cumsum(rng.uniform(0.0, 1.0, k))
            d = np.zeros(k)
            S.pchip_slopes(x, y, d)
            np.testing.assert_allclose(d, PchipInterpolator(x, y).derivative()(x), rtol=1e-9,
                                       atol=1e-12)


@pytest.mark.parametrize("cubic", [False, True])
@pytest.mark.parametrize("with_band", [False, True])
def test_spread_ratio_power_law_exact_zero_base_safe(cubic, with_band):
    """A ratio that is a power law of the wavelength (log rho linear in log lambda), times
    exp(-dL x the band absorber's optical depth) with a band present, is reproduced exactly
    by both interpolants (the least-squares dL is exact when the rest is linear); computed
    wavelengths keep their values; where the base vanishes, the orders >= 3 are
    interpolated directly (finite, non-negative)."""
    wl = np.linspace(380.0, 780.0, 20)
    computed = np.array([0, 5, 10, 12, 19])
    nodes = np.array([0, 5, 12, 19])
    # a Chappuis-like bump (peak near 600 nm), optical depth up to 0.04
    band = 0.04 * np.exp(-0.5 * ((wl - 600.0) / 60.0) ** 2) if with_band else np.zeros(20)
    plan = S.spread_plan(wl, computed, nodes, band)
    base = np.stack([(wl / 550.0) ** -4.0, np.full(20, 2.0), np.zeros(20)]).astype(np.float64)
    rho = 0.4 * (wl / 550.0) ** -2.5 * np.exp(-3.0 * band)
    hi = (base * rho)[:, computed].copy()
    hi[1, 2] = 7.0            # a computed, not a node, wavelength keeps its own value
    hi[2] = [1.0, 2.0, 0.0, 3.0, 4.0]
    out = np.zeros_like(base)
    S.spread_ratio(base, hi, *plan, cubic, 0.0, out)
    exact = base * rho
    exact[1, 10] = 7.0
    np.testing.assert_allclose(out[:2], exact[:2], rtol=1e-10)
    assert np.all(np.isfinite(out[2])) and np.all(out[2] >= 0.0)
    np.testing.assert_allclose(out[2, computed], hi[2], rtol=1e-12)
    f = np.log(wl[3] / wl[0]) / np.log(wl[5] / wl[0])      # linear in log lambda
    np.testing.assert_allclose(out[2, 3], 1.0 + f * (2.0 - 1.0), rtol=1e-9)
    # out may be the base itself (the values of a node read before any is written)
    b2 = base.copy()
    S.spread_ratio(b2, hi, *plan, cubic, 0.0, b2)
    np.testing.assert_allclose(b2, base + out, rtol=1e-12)


def test_band_depth_is_ozone_alone():
    """Of Atmosphere.earth's absorbers only ozone counts as a band absorber (water vapour
    and the oxygen bands are line-like): its vertical optical depth at 600 nm is
    0.0375 +- 10 %, after the Chappuis band's 5.2e-21 cm^2 per molecule at 300 DU
    (8.06e18 cm^-2): tau = 0.042 at 602 nm (Serdyuchenko et al. 2014)."""
    wl = np.linspace(380.0, 780.0, 20)
    props, column = _props_and_columns(wl)
    b = S.band_depth(props.extinction - props.scattering, column, props.scattering)
    i = int(np.argmax(b))
    assert 580.0 <= wl[i] <= 620.0
    assert 0.03 < b[i] < 0.046
    assert b[0] < 1e-3 * b[i]


def _sky(m, elev):
    return m.with_sun(sd.Sun(elevation_deg=elev, azimuth_deg=180.0))


def _exact_and_fast(elev, **kw):
    """(all wavelengths (the default), the subset of 7 nodes, the computed line-absorbed
    wavelengths, the nodes, the 20 table wavelengths) on the small tables ``SMALL`` updated
    by ``kw``; the computed wavelengths as the model picks them (nodes evenly in log
    lambda)."""
    wl = np.linspace(380.0, 780.0, 20)
    sun = sd.Sun(elevation_deg=elev, azimuth_deg=180.0)
    exact = sd.model("precomputed", sun=sun, **dict(SMALL, **kw))
    fast = sd.model("precomputed", sun=sun, **dict(SMALL, high_order_wavelengths=7, **kw))
    props, column = _props_and_columns(wl)
    computed, nodes = S.subset_indices(20, 7, props.extinction - props.scattering, column, wl)
    return exact, fast, np.setdiff1d(computed, nodes), nodes, wl


def _assert_computed_match(a, b, lines, nodes):
    """The subset's radiance ``b`` against every wavelength's ``a`` at the computed
    wavelengths: float32 rounding at the line-absorbed ones (the irradiance table's nodes in
    twilight, 1e-9 to 1e-5 of its day values, differ between the two paths by up to 2.7e-5
    relative, and the sky at sun -4 deg next to the horizon takes it on through the
    ground's reflection: measured 2.9e-5; 7e-7 at sun 10 deg); at the nodes the ratio
    (orders >= 3) / (order 2) is kept in float16, so the orders >= 3 are rounded to within
    2^-11 of their value (per order; well within 2^-11 of the radiance in practice)."""
    np.testing.assert_allclose(b[:, lines], a[:, lines], rtol=5e-5)
    np.testing.assert_allclose(b[:, nodes], a[:, nodes], rtol=2.0 ** -11)


def test_high_order_wavelengths_against_all_wavelengths_small_tables():
    """The approximation against the all-wavelength computation on a small table set
    (Atmosphere.earth, 20 table wavelengths, 6 orders + remainder), ground observer: at the
    computed wavelengths the same radiance (float32 rounding; at the interpolation nodes
    float16 rounding of the orders >= 3, see below), elsewhere within the errors
    measured for this table set with the default 7 interpolation nodes (per-wavelength
    RMS / max at sun 60, 10, -4 deg: 0.01 / 0.02, 0.05 / 0.08, 0.07 / 0.12 %; bounds
    generous against those), and the ground irradiance likewise."""
    exact, fast, lines, nodes, wl = _exact_and_fast(30.0)
    el, az = np.meshgrid([1.0, 5.0, 15.0, 40.0, 89.0], np.arange(0.0, 181.0, 30.0))
    d = sd.direction_from_angles(el.ravel(), az.ravel() + 180.0)
    for elev, (rms_b, max_b) in ((60.0, (0.0005, 0.001)), (10.0, (0.0015, 0.0025)),
                                 (-4.0, (0.002, 0.004))):
        a, b = _sky(exact, elev).radiance(d, wl), _sky(fast, elev).radiance(d, wl)
        assert np.all(np.isfinite(b)) and np.all(b >= 0.0)
        r = b / a - 1.0
        _assert_computed_match(a, b, lines, nodes)
        assert np.sqrt(np.mean(r * r, axis=0)).max() < rms_b, elev
        assert np.abs(r).max() < max_b, elev
    Ea, Eb = exact._t.irradiance, fast._t.irradiance
    rel = np.abs(Eb - Ea) / Ea.max(axis=(0, 1))
    assert rel.max() < 2e-3
    assert fast.high_order_wavelengths == 7 and exact.high_order_wavelengths is None


def test_subset_on_the_coarse_high_order_grid_matches_all_wavelengths():
    """With the orders >= 3 on the opt-in coarse (r, mu_s) grid, the subset path (their sum
    per wavelength interpolated onto the full grid) gives at the computed wavelengths the
    sky of the all-wavelength path on the same grid (the interpolation is linear in J, so
    the same up to float32 rounding at the line-absorbed wavelengths, and the float16 ratio's
    rounding, at most 2^-11 of the radiance, at the nodes)."""
    exact, fast, lines, nodes, wl = _exact_and_fast(10.0, high_order_r_size=4,
                                                    high_order_mu_s_size=8)
    d = sd.direction_from_angles([1.0, 5.0, 30.0, 89.0], [180.0, 0.0, 90.0, 0.0])
    _assert_computed_match(exact.radiance(d, wl), fast.radiance(d, wl), lines, nodes)


def test_float16_ratio_sum_within_its_rounding_bound():
    """PC._add_order (each order's J into the summed density at the line-absorbed
    wavelengths, at the nodes its share of order 2 into the float16 ratio) against the
    float64 sums of the same orders: 5 orders (4 and the remainder) exact to float32 at
    the line wavelength; at the nodes each addition rounds to float16 (at most 2^-11 of the
    partial sum), so within 5 x 2^-11 of rho; 0 where order 2 is 0; clipped at float16's
    largest value."""
    rng = np.random.default_rng(7)
    n, nl = 3000, 4
    jf = rng.uniform(1e-3, 1.0, (n, nl)).astype(np.float32)
    jf[:10, 1] = 0.0
    j2 = jf.copy()
    node_of = {1: 0, 3: 1}                   # table wavelengths 1 and 3 are nodes, 2 is not
    ls = np.array([1, 2, 3])
    orders = [(rng.uniform(0.0, 2.0, (n, 3)) * j2[:, ls] * 0.5 ** k).astype(np.float32)
              for k in range(5)]
    orders[0][10, 0] = 1e6 * j2[10, 1]        # a ratio beyond float16's range
    rho = np.zeros((2, n), dtype=np.float16)
    for Jo in orders:
        PC._add_order(Jo, ls, node_of, jf, rho)
    total = sum(Jo.astype(np.float64) for Jo in orders)
    np.testing.assert_allclose(jf[:, 2], j2[:, 2] + total[:, 1], rtol=1e-6)
    np.testing.assert_array_equal(jf[:, [0, 1, 3]], j2[:, [0, 1, 3]])   # nodes: order 2 kept
    ok = j2[:, 1] > 0
    assert np.all(rho[0, ~ok] == 0.0)
    assert rho[0, 10] == np.finfo(np.float16).max
    for k, l in ((0, 1), (1, 3)):
        m = ok.copy() if k == 0 else np.ones(n, dtype=bool)
        m[10] = False
        exact = total[m, l - 1] / j2[m, l]
        np.testing.assert_allclose(rho[k, m].astype(np.float64), exact, rtol=5 * 2.0 ** -11)
        assert np.abs(rho[k, m] / exact - 1.0).max() > 2.0 ** -14   # float16 rounding is there


def test_float16_bits_in_the_kernels_are_numpys_cast():
    """The kernels' binary16 (numba has no float16 on the CPU): the decoding table is the
    value of every bit pattern as numpy reads it, and ``half_bits`` rounds float32 values
    to the same bits as numpy's cast (IEEE 754 round to nearest, ties to even): at every
    binary16 value in [0, 65504], at the float32 values next to it and at every midpoint
    between neighbours (the ties), and at 200 000 random float32 values (and their 2^-30 multiples, deep in the
    subnormal range) spread over the
    subnormal and normal ranges."""
    from numba import njit

    table = S.half_table()
    h = np.arange(1 << 16, dtype=np.uint32).astype(np.uint16)
    np.testing.assert_array_equal(table.view(np.uint32),
                                  h.view(np.float16).astype(np.float32).view(np.uint32))

    @njit
    def bits(u, out):
        for i in range(u.size):
            out[i] = S.half_bits(u[i])

    v = table[:0x7C00].astype(np.float64)            # 0 .. 65504, every finite value >= 0
    mid = 0.5 * (v[1:] + v[:-1])                      # exact ties (in float32 too)
    x = np.concatenate([v, mid, np.nextafter(mid, 0.0), np.nextafter(mid, 1e6),
                        np.exp(np.random.default_rng(3).uniform(np.log(1e-9), np.log(65504.0),
                                                                200_000))]).astype(np.float32)
    x = np.concatenate([x, x * np.float32(2.0 ** -30)])
    x = x[x <= 65504.0]
    out = np.empty(x.size, dtype=np.uint16)
    bits(x.view(np.uint32), out)
    np.testing.assert_array_equal(out, x.astype(np.float16).view(np.uint16))


def test_subset_batches_cover_the_computed_wavelengths_within_the_budget():
    """With 7 interpolation nodes each computed wavelength is in exactly one batch, the
    line-absorbed ones first, then the nodes, and every batch with the float16 ratio of the
    nodes done by its end (2 bytes per node of J) stays within HIGH_ORDER_SUBSET_BYTES: J at
    the default sizes is 2 x 65 x 33 x 32 x 48 float32 (26.4 MB) per wavelength."""
    p = sd.models.simulated.precomputed.PrecomputedSky._validate_params({})
    wl = np.linspace(380.0, 780.0, 20)
    props, column = _props_and_columns(wl)
    computed, nodes = S.subset_indices(20, 7,
                                       props.extinction - props.scattering, column, wl)
    batches = PC.subset_batches(p, computed, nodes, 2)
    flat = np.concatenate(batches)
    assert sorted(flat.tolist()) == computed.tolist()
    is_node = np.isin(flat, nodes)
    assert not np.any(is_node[:np.argmax(is_node)]) and np.all(is_node[np.argmax(is_node):])
    j = 2 * 65 * 33 * 32 * 48 * 4
    l_in = 16 * 16 * 32 * 48 * 4
    done = 0
    for b in batches:
        done += int(np.isin(b, nodes).sum())
        assert b.size * (j + l_in) + done * j // 2 <= PC.HIGH_ORDER_SUBSET_BYTES
    assert len(batches) == 1          # the 13 computed wavelengths in one batch


def test_default_orders_above_two_in_one_batch():
    """At the default settings the orders >= 3 are computed at every table wavelength
    (``high_order_wavelengths`` None), by default summed into the summed density (no
    batches, see test_summed_orders_give_the_per_order_tables); with one order's density
    at a time (``SUMMED_ORDERS`` off), the 20 of the default grid are one batch within
    HIGH_ORDER_BATCH_BYTES: J (2 x 65 x 33 x 32 x 48 float32, 26.4 MB per wavelength) and
    the incident radiance on 16 x 16 directions with its 10 columns of matrix right-hand
    side (1.6 MB per wavelength)."""
    p = sd.models.simulated.precomputed.PrecomputedSky._validate_params({})
    assert p["high_order_wavelengths"] is None
    assert PC.high_order_batch_size(p, 20, 2) == 20
    per_wl = 4 * 32 * 48 * (2 * 65 * 33 + 16 * 16 + 10)
    assert 20 * per_wl <= PC.HIGH_ORDER_BATCH_BYTES


def _assert_same_tables(t_ref, t, rtol):
    """``t``'s tables equal ``t_ref``'s: the single-scattering table to 1e-12 relative (the
    same computation twice: bit for bit on some CPUs, but where the compiled loops' vector
    blocking follows the arrays' alignment in memory the sums round differently, measured up
    to 9.5e-13), the summed scattering density and the irradiance table within ``rtol``
    (and 1e-4 / 1e-9 of their largest values absolute: the density's float32 products
    round by the blocking of the BLAS kernel, which differs between CPUs; measured up to
    1.1e-5 of the largest value, at values 1e-2 of it, on one AMD EPYC machine, 7.7e-5 at
    two values 0.42 of it (1.8e-4 relative) on another, and below 1e-6 on others; a
    wavelength's table computed from another's inputs would be off by tens of %)."""
    np.testing.assert_allclose(t.single_scattering, t_ref.single_scattering, rtol=1e-12,
                               atol=1e-15 * float(np.max(t_ref.single_scattering)))
    np.testing.assert_allclose(t.scattering_density, t_ref.scattering_density, rtol=rtol,
                               atol=1e-4 * float(np.max(t_ref.scattering_density)))
    np.testing.assert_allclose(t.irradiance, t_ref.irradiance, rtol=rtol,
                               atol=1e-9 * float(np.max(t_ref.irradiance)))


def test_subset_batches_of_one_wavelength_give_the_one_batch_tables(monkeypatch):
    """The orders >= 3 of the subset path in one batch (the default's plan) and in a batch
    per computed wavelength (``HIGH_ORDER_SUBSET_BYTES`` too small for two) compute the same
    numbers per wavelength in another grouping: the summed density and the irradiance agree
    to float32 rounding (each value is computed from its own wavelength's inputs only;
    the batches change only the blocking of the products), and the single-scattering table
    freed during the orders >= 3 and computed again is bit-identical."""
    wl = np.linspace(380.0, 780.0, 20)
    atm = Atmosphere.earth(aerosol_optical_depth=0.3)
    sun = sd.Sun(elevation_deg=20.0, azimuth_deg=180.0)
    kw = dict(SMALL, high_order_wavelengths=7)
    one = sd.model("precomputed", sun=sun, atmosphere=atm, table_wavelengths_nm=wl, **kw)
    monkeypatch.setattr(PC, "HIGH_ORDER_SUBSET_BYTES", 1)
    many = sd.model("precomputed", sun=sun, atmosphere=atm, table_wavelengths_nm=wl, **kw)
    _assert_same_tables(one._t, many._t, rtol=2e-6)


def test_summed_orders_give_the_per_order_tables(monkeypatch):
    """The default path of the orders >= 3 (``higher_orders_summed``: each order's incident
    radiance the difference of two ray integrals of the running sum, its density added into
    the summed density, the single-scattering table kept) against one order's density at a
    time (``higher_orders``, ``SUMMED_ORDERS`` off; the single-scattering table freed and
    computed again): the same summed density and irradiance table within float32
    rounding of the differences (order 5 is a few % of the sum), the same single-scattering
    table, which the summed path computes once."""
    from skydome.models.simulated.precomputed import _single

    wl = np.linspace(380.0, 780.0, 6)
    atm = Atmosphere.earth(aerosol_optical_depth=0.3)
    sun = sd.Sun(elevation_deg=20.0, azimuth_deg=180.0)
    kw = dict(SMALL, orders=5)
    calls = []
    table = _single.single_scattering_table

    def counted(*a):
        calls.append(1)
        return table(*a)

    monkeypatch.setattr(_single, "single_scattering_table", counted)
    summed = sd.model("precomputed", sun=sun, atmosphere=atm, table_wavelengths_nm=wl, **kw)
    n_summed = len(calls)
    monkeypatch.setattr(PC, "SUMMED_ORDERS", False)
    per_order = sd.model("precomputed", sun=sun, atmosphere=atm, table_wavelengths_nm=wl, **kw)
    assert (n_summed, len(calls) - n_summed) == (1, 2)
    _assert_same_tables(per_order._t, summed._t, rtol=2e-5)
    assert np.all(summed._t.scattering_density >= 0.0)
