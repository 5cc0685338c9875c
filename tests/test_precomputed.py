"""The ``precomputed`` model (Bruneton 2017 tables, spectral): agreement with the
single-scattering reference, convergence of the scattering orders, conservation of energy,
twilight, persistence, robustness.

References used here: the ``single_scattering`` model (an independent integrator: its own
ray marching and optical-depth quadrature, no 4-D tables); conservation of energy in a
conservative atmosphere over a black ground (what enters at the top leaves at the top or
is absorbed by the ground); Beer-Lambert along a short horizontal path.
"""

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import skydome as sd
from skydome.atmosphere import Atmosphere
from skydome.spectra import solar_irradiance
from skydome.transport._medium import medium_from_properties
from skydome.transport._quadrature import gauss_legendre_unit as gauss_rule
from skydome.transport.geometry import direction_from_angles

SMALL = dict(scattering_r_size=12, scattering_mu_size=48, scattering_mu_s_size=12,
             scattering_nu_size=6, irradiance_mu_s_size=32, irradiance_r_size=8,
             transmittance_mu_size=128, transmittance_r_size=32,
             # the earlier defaults (4 orders, no remainder, Bruneton's sphere quadrature), which
             # these tests were written for
             orders=4, remaining_orders="none", sphere_samples=16)
WL3 = [440.0, 550.0, 680.0]


def sun(elev, az=180.0):
    return sd.Sun(elevation_deg=elev, azimuth_deg=az)


@pytest.fixture(scope="module")
def small():
    """A small 4-order table set shared by the property tests."""
    return sd.model("precomputed", sun=sun(30.0), table_wavelengths_nm=WL3, **SMALL)


def hemisphere(n_el=8, n_az=12, low=2.0):
    el = np.linspace(low, 90.0, n_el)
    az = np.linspace(0.0, 360.0, n_az, endpoint=False)
    E, A = np.meshgrid(el, az, indexing="ij")
    return direction_from_angles(E.ravel(), A.ravel())


def test_registered_and_validated():
    cls = sd.models.get_model_class("precomputed")
    names = {p.name for p in cls.parameters}
    assert {"atmosphere", "turbidity", "observer_altitude_m", "n_wavelengths", "orders",
            "table_wavelengths_nm", "scattering_mu_size"} <= names
    with pytest.raises(ValueError, match="orders"):
        sd.model("precomputed", sun=sun(30.0), orders=0)
    with pytest.raises(ValueError, match="orders"):
        sd.model("precomputed", sun=sun(30.0), orders=21)
    with pytest.raises(ValueError, match="scattering_mu_size"):
        sd.model("precomputed", sun=sun(30.0), scattering_mu_size=33)
    with pytest.raises(ValueError, match="observer_altitude_m"):
        sd.model("precomputed", sun=sun(30.0), observer_altitude_m=200e3)


def test_single_order_matches_single_scattering_reference():
    """orders=1 at Bruneton's default table sizes against the brute-force single-scattering
    integrator (independent quadrature, no 4-D table) over the upper hemisphere, elevations
    2-90 deg, sun at 30 and 10 deg. Measured table-resolution error: <= 0.2 % above 5 deg
    elevation, <= 1.5 % at 2 deg (the horizon, where the mu mapping is steepest)."""
    d = hemisphere()
    el = np.degrees(np.arcsin(d[:, 2]))
    for elev in (30.0, 10.0):
        m = sd.model("precomputed", sun=sun(elev), table_wavelengths_nm=WL3, orders=1,
                     scattering_mu_s_size=32, scattering_nu_size=8)
        ref = sd.model("single_scattering", sun=sun(elev)).radiance(d, WL3)
        rel = np.abs(m.radiance(d, WL3) / ref - 1.0)
        assert rel.max() < 0.02, rel.max()
        assert rel[el >= 5.0].max() < 0.005, rel[el >= 5.0].max()


def test_orders_brighten_monotonically_and_converge():
    """Each added order adds light (all terms are positive) and the increments shrink
    geometrically: in this atmosphere (vertical optical depth ~0.45 at 440 nm, ~0.15 at
    680 nm) each order is less than 0.7 of the one before (measured at most 0.68, for
    order 3 over order 2 near the horizon), and the 6th order adds under 5 % of the sky.
    (Measured: the default 4 orders hold >= 89 % of the 8-order sky at 440 nm, 97.5 % at
    680 nm.)"""
    d = hemisphere(5, 6)
    Ls = []
    for n in (1, 2, 3, 4, 5, 6):
        m = sd.model("precomputed", sun=sun(30.0), table_wavelengths_nm=[440.0, 680.0], **{**SMALL, "orders": n})
        Ls.append(m.radiance(d, [440.0, 680.0]))
    Ls = np.array(Ls)
    inc = np.diff(Ls, axis=0)
    assert np.all(inc > 0.0)
    assert np.all(inc[1:] < 0.7 * inc[:-1])
    assert np.all(inc[-1] / Ls[-1] < 0.05)


@pytest.mark.parametrize("beta", [1.2e-5, 3.3e-5])
def test_energy_conservation_conservative_rayleigh(beta):
    """Conservative Rayleigh atmosphere (vertical optical depth 0.096 and 0.26), black
    ground, 12 orders: the solar flux entering at the top, E0 mu_s, equals the flux leaving
    at the top (integral of the upward radiance seen from the top) plus the direct and
    diffuse flux absorbed by the ground (conservation of energy). Measured: 0.2 % and 0.5 %
    short (spherical geometry and table resolution); required within 1.5 %."""
    atm = Atmosphere.custom(rayleigh_scattering=beta, mie_scattering=0.0, ground_albedo=0.0)
    m = sd.model("precomputed", sun=sun(60.0), atmosphere=atm, table_wavelengths_nm=[550.0],
                 orders=12, scattering_r_size=16, scattering_mu_size=64, scattering_mu_s_size=16,
                 remaining_orders="none", sphere_samples=16, scattering_nu_size=8)
    top = m.with_sun(observer_altitude_m=atm.top_altitude_m - 1.0)
    x, w = np.polynomial.legendre.leggauss(64)
    mu, wmu = -(x + 1.0) / 2.0, w / 2.0
    phi = (np.arange(64) + 0.5) * 2.0 * np.pi / 64
    M, P = np.meshgrid(mu, phi, indexing="ij")
    s = np.sqrt(1.0 - M ** 2)
    d = np.stack([s * np.sin(P), s * np.cos(P), M], axis=-1)
    L = top.radiance_table(d)[..., 0]
    f_up = np.sum(L * (-M) * wmu[:, None]) * 2.0 * np.pi / 64
    e0 = solar_irradiance([550.0])[0]
    direct, diffuse = m.irradiance_components([550.0])
    f_in = np.sin(np.radians(60.0))
    assert (f_up + direct[0] / e0 + diffuse[0] / e0) == pytest.approx(f_in, rel=0.015)
    assert diffuse[0] > 0.0 and f_up > 0.0


def test_ground_irradiance_direct_and_diffuse(small):
    """Direct irradiance = sun radiance x disc solid angle x cos(zenith), with the sun's
    transmittance from the single-scattering model's own quadrature (independent path);
    the diffuse part equals the cosine-weighted hemisphere integral of the model's own sky
    (the irradiance table holds orders 1..N and the remainder, as the sky does) within 3 %."""
    wl = np.array(WL3)
    direct, diffuse = small.irradiance_components(wl)
    ss = sd.model("single_scattering", sun=small.sun)
    expect = ss.sun_radiance(wl) * small.sun.solid_angle_sr * np.sin(np.radians(30.0))
    np.testing.assert_allclose(direct, expect, rtol=0.01)
    x, w = np.polynomial.legendre.leggauss(48)
    mu, wmu = (x + 1.0) / 2.0, w / 2.0
    phi = (np.arange(64) + 0.5) * 2.0 * np.pi / 64
    M, P = np.meshgrid(mu, phi, indexing="ij")
    s = np.sqrt(1.0 - M ** 2)
    d = np.stack([s * np.sin(P), s * np.cos(P), M], axis=-1)
    L = small.radiance(d, wl)
    hemi = np.einsum("ijl,ij,i->l", L, M, wmu) * 2.0 * np.pi / 64
    np.testing.assert_allclose(diffuse, hemi, rtol=0.03)
    np.testing.assert_allclose(small.ground_irradiance(wl), direct + diffuse)


def test_twilight_sky_finite_positive(small):
    """Sun 4 deg below the horizon: the sky is finite, positive, darker than by day, and
    brightest towards the sun's azimuth near the horizon (the twilight arch)."""
    tw = small.with_sun(sun(-4.0, 180.0))
    d = hemisphere(10, 12)
    L = tw.radiance(d, WL3)
    assert np.all(np.isfinite(L)) and np.all(L > 0.0)
    day = small.radiance(d, WL3)
    assert np.all(L.sum(-1) < day.sum(-1))
    near = direction_from_angles(np.array([3.0, 3.0]), np.array([180.0, 0.0]))
    Ln = tw.radiance(near, WL3)
    assert Ln[0, 1] > 2.0 * Ln[1, 1]
    assert np.all(tw.sun_radiance(WL3) == 0.0)


def test_night_below_table_range_is_zero(small):
    night = small.with_sun(sun(-25.0))
    assert np.all(night.radiance(hemisphere(3, 4), WL3) == 0.0)


def test_save_load_round_trip_exact(small, tmp_path):
    p = tmp_path / "tables.npz"
    small.save(p)
    loaded = sd.models.get_model_class("precomputed").load(p)
    d = np.concatenate([hemisphere(4, 5), -hemisphere(2, 3)])
    assert np.array_equal(loaded.radiance(d, WL3), small.radiance(d, WL3))
    assert np.array_equal(loaded.sun_radiance(WL3), small.sun_radiance(WL3))
    assert np.array_equal(loaded.ground_irradiance(WL3), small.ground_irradiance(WL3))
    assert loaded.describe()["parameters"]["orders"] == 4
    other = loaded.load(p, sun=sun(10.0))
    assert other.sun.elevation_deg == 10.0


def test_export_textures(small, tmp_path):
    files = small.export_textures(tmp_path)
    desc = json.loads((tmp_path / "textures.json").read_text())
    ms = np.load(tmp_path / "multiple_scattering.npy")
    assert ms.dtype == np.float32
    assert list(ms.shape) == desc["textures"]["multiple_scattering"]["shape"] == [12, 48, 12, 6, 3]
    assert desc["textures"]["single_scattering"]["axes"][0] == "constituent"
    assert (tmp_path / "textures.md").exists() and len(files) >= 6
    tr = np.load(tmp_path / "transmittance.npy")
    assert np.all((tr > 0) & (tr <= 1))


def test_aerial_perspective_limits(small):
    """Distance 0: T = 1, nothing in-scattered; distance beyond the top: the sky itself.
    A 1 km horizontal path at the ground: T = exp(-sum beta_e d) (Beer-Lambert with the
    sea-level coefficients; curvature and the 1 m altitude gain are negligible)."""
    d = direction_from_angles(np.array([20.0, 45.0, 0.0]), np.array([0.0, 90.0, 90.0]))
    T0, S0 = small.aerial_perspective(d, 0.0, WL3)
    np.testing.assert_allclose(T0, 1.0, atol=1e-6)
    np.testing.assert_allclose(S0, 0.0, atol=1e-9)
    _, Sinf = small.aerial_perspective(d[:2], 1e7, WL3)
    np.testing.assert_allclose(Sinf, small.radiance(d[:2], WL3), rtol=1e-6)
    h = np.array([1.0, 0.0, 0.0])
    T, S = small.aerial_perspective(h, 1000.0, WL3)
    props = small.atmosphere.optical_properties(WL3)
    np.testing.assert_allclose(T, np.exp(-props.extinction.sum(0) * 1000.0), rtol=0.01)
    assert np.all(S > 0.0)


def test_spectral_interpolation_between_table_wavelengths(small):
    """Off-grid wavelengths: the radiance per unit solar irradiance is interpolated
    linearly between table wavelengths (so it lies between its neighbours' values), then
    multiplied by the solar spectrum on the requested grid; on the table grid it is the
    table value times the solar spectrum."""
    d = hemisphere(3, 4)
    wl = np.array([440.0, 500.0, 550.0])
    ratio = small.radiance(d, wl) / (solar_irradiance(wl) * small.sun.irradiance_scale)
    lo = np.minimum(ratio[:, 0], ratio[:, 2])
    hi = np.maximum(ratio[:, 0], ratio[:, 2])
    assert np.all((ratio[:, 1] >= lo * (1 - 1e-12)) & (ratio[:, 1] <= hi * (1 + 1e-12)))
    np.testing.assert_allclose(ratio[:, 1], ratio[:, 0] + (ratio[:, 2] - ratio[:, 0]) * 60 / 110,
                               rtol=1e-12)
    np.testing.assert_allclose(small.radiance(d, WL3),
                               small.radiance_table(d) * solar_irradiance(WL3), rtol=1e-12)


@settings(max_examples=40, deadline=None)
@given(elev=st.floats(-18.0, 90.0), az=st.floats(0.0, 360.0),
       dz=st.floats(-1.0, 1.0), dphi=st.floats(0.0, 2 * np.pi),
       alt=st.sampled_from([0.0, 1500.0, 30e3]))
def test_no_nan_no_negative(small, elev, az, dz, dphi, alt):
    m = small.with_sun(sun(elev, az), observer_altitude_m=alt)
    s = np.sqrt(max(1.0 - dz * dz, 0.0))
    d = np.array([[s * np.cos(dphi), s * np.sin(dphi), dz], [0, 0, 1.0], [0, 0, -1.0],
                  [1.0, 0.0, 0.0]])
    L = m.radiance(d, [400.0, 550.0, 700.0])
    assert np.all(np.isfinite(L)) and np.all(L >= 0.0)
    T, S = m.aerial_perspective(d, 5000.0, [550.0])
    assert np.all(np.isfinite(S)) and np.all(S >= 0.0) and np.all((T >= 0) & (T <= 1))
    assert np.all(m.ground_irradiance([550.0]) >= 0.0)


def test_geometric_remaining_orders_approximates_more_orders():
    """The geometric estimate of the orders beyond N brings 3 orders closer to 8 computed
    orders (small tables, turbidity 4: within 10 % where 3 orders alone are up to 37 % low)."""
    import skydome as sd
    from skydome.transport.geometry import direction_from_angles

    small = dict(scattering_r_size=8, scattering_mu_size=32, scattering_mu_s_size=8, n_wavelengths=4,
                 turbidity=4.0, sphere_samples=16, scattering_nu_size=8)
    sun = sd.Sun(elevation_deg=20.0, azimuth_deg=180.0)
    d = direction_from_angles(np.array([80.0, 30.0, 5.0, 5.0]), np.array([0.0, 90.0, 0.0, 180.0]))
    wl = np.array([450.0, 600.0])
    ref = sd.model("precomputed", sun=sun, orders=8, remaining_orders="none", **small).radiance(d, wl)
    plain = sd.model("precomputed", sun=sun, orders=3, remaining_orders="none", **small).radiance(d, wl)
    geo = sd.model("precomputed", sun=sun, orders=3, remaining_orders="geometric", **small).radiance(d, wl)
    assert np.all(geo >= plain)
    assert np.max(np.abs(geo / ref - 1)) < 0.1
    assert np.max(np.abs(geo / ref - 1)) < 0.5 * np.max(np.abs(plain / ref - 1))


def _error_vs_monte_carlo(aod, sun_elevation, elevations, azimuths, samples, seed, max_noise,
                          **model_kw):
    """|precomputed / montecarlo - 1| at 550 nm in the given directions (sun at azimuth 180),
    after checking that the reference's relative standard error is below ``max_noise``;
    the model uses 6 orders + the geometric remainder and ``model_kw``."""
    atm = Atmosphere.earth(aerosol_optical_depth=aod)
    s = sun(sun_elevation)
    wl = [550.0]
    d = direction_from_angles(np.array(elevations), np.array(azimuths))
    ref, err = sd.model("montecarlo", sun=s, atmosphere=atm, samples=samples,
                        seed=seed).radiance_with_error(d, wl)
    assert np.all(err / ref < max_noise)
    # the earlier defaults of the settings a test does not give (sphere quadrature, nu and
    # mu_s nodes), so that each test keeps the settings it was written for
    kw = {"orders": 6, "remaining_orders": "geometric", "sphere_samples": 16,
          "scattering_nu_size": 8, "scattering_mu_s_size": 32, **model_kw}
    m = sd.model("precomputed", sun=s, atmosphere=atm, table_wavelengths_nm=wl, **kw)
    return np.abs(m.radiance(d, wl) / ref - 1.0)[:, 0]


def test_hazy_sky_against_monte_carlo():
    """AOD 0.2 (Cornette-Shanks aerosol, g = 0.76), sun at 60 deg, 550 nm, 6 orders plus the
    geometric remainder on a 64-node mu_s axis, against the independent ``montecarlo`` model
    (all orders, 20 000 paths per direction: relative standard error 0.4-0.7 %). Directions:
    zenith (30 deg from the sun), 90 deg from the sun, 5 deg from the sun, the side, and the
    horizon towards the sun. Before the scattering density was kept in the sun's frame and the
    observer's orders 2..N integrated at the sun's own mu_s, the zenith sky at AOD 0.5 was 16 %
    too bright (confirmed by a brute-force second-order integral); measured now with these
    (reduced) tables: within 1.6 % above 10 deg elevation and 3.6 % at 5 deg. Required: 3 %
    above 10 deg, 6 % at 5 deg (the measured error plus three MC standard errors)."""
    rel = _error_vs_monte_carlo(0.2, 60.0, [89.9, 30.0, 65.0, 20.0, 5.0],
                                [0.0, 0.0, 180.0, 270.0, 180.0],
                                samples=20000, seed=11, max_noise=0.01,
                                scattering_mu_s_size=64, scattering_r_size=16,
                                scattering_mu_size=64, transmittance_mu_size=128,
                                transmittance_r_size=32)
    assert np.all(rel[:4] < 0.03), rel
    assert rel[4] < 0.06, rel


def test_very_hazy_low_sun_against_monte_carlo():
    """AOD 0.5, sun 10 deg up, 550 nm, the hazy-air settings of docs/validation.md (6 orders +
    geometric remainder, sphere_samples 32, scattering_nu_size 16), against ``montecarlo``
    (150 000 paths per direction: relative standard error 0.4-0.8 %). Directions 20-40 deg
    from the sun near the horizon (where the multiply scattered aureole is) and 20 deg from
    the zenith towards and away from the sun. With Bruneton's default sphere quadrature
    (16) and nu nodes (8), and the observer's orders 2..N on the table's (mu, nu) mapping,
    these were 16-22 % too bright near the horizon and -7 / +8 % off at 70 deg elevation;
    measured now: within 3 %. Required: 5 % (the measured error plus three standard errors)."""
    rel = _error_vs_monte_carlo(0.5, 10.0, [3.0, 10.0, 25.0, 70.0, 70.0, 89.9],
                                [150.0, 150.0, 120.0, 180.0, 0.0, 0.0],
                                samples=150000, seed=12, max_noise=0.01,
                                sphere_samples=32, scattering_nu_size=16)
    assert np.all(rel < 0.05), rel


def test_high_sun_horizon_against_monte_carlo():
    """AOD 0.05, sun 60 deg up, 550 nm, the validated settings (docs/validation.md: 6 orders
    + geometric remainder, sphere_samples 32, scattering_nu_size 16, density_mu_s_size 64)
    against ``montecarlo`` (150 000 paths: relative standard error 0.13-0.18 %). The horizon
    towards the sun and 25-45 deg up away from it: with the scattering density on the
    table's 32 mu_s nodes these were -6.2 / -5.2 / +2.5 / +3.3 % off (in the sun's frame the
    local horizon moves with mu_s, and the aerosol's forward peak picks it up); measured now
    -1.3, -0.7, +0.2, +0.4, +0.01 %. Required: 2 % (the measured error plus three standard
    errors)."""
    rel = _error_vs_monte_carlo(0.05, 60.0, [3.0, 3.0, 25.0, 45.0, 89.9],
                                [180.0, 150.0, 0.0, 0.0, 0.0],
                                samples=150000, seed=13, max_noise=0.003,
                                sphere_samples=32, scattering_nu_size=16, density_mu_s_size=64)
    assert np.all(rel < 0.02), rel


def test_density_mu_s_size_is_validated():
    with pytest.raises(ValueError, match="density_mu_s_size"):
        sd.model("precomputed", sun=sun(30.0), density_mu_s_size=1)


def test_twilight_against_monte_carlo():
    """Sun 4 deg below the horizon, AOD 0.2, 550 nm, the validated settings (with
    scattering_mu_s_size 64), against ``montecarlo`` (400 000 paths: relative standard error
    1.3-2.9 %). Horizon and 10 deg up towards the anti-sun side (the twilight arch is
    towards the sun, azimuth 180), 45 deg up at the side, zenith. With the table's default
    32 mu_s nodes these were 13-34 % too bright (in twilight the sky changes quickly with
    the sun's depression); measured now 2.8-10.5 % (mean 6.7 %). Required: every direction
    within 16 % and the mean within 10 % (the measured error plus about two standard
    errors)."""
    rel = _error_vs_monte_carlo(0.2, -4.0, [2.0, 10.0, 10.0, 45.0, 89.9],
                                [0.0, 0.0, 45.0, 90.0, 0.0],
                                samples=400000, seed=14, max_noise=0.035,
                                sphere_samples=32, scattering_nu_size=16,
                                scattering_mu_s_size=64, density_mu_s_size=64)
    assert np.all(rel < 0.16) and rel.mean() < 0.10, rel


def test_default_settings_against_monte_carlo():
    """The default settings (6 orders + geometric remainder, sphere_samples 32, nu 16, 48 mu_s
    nodes on the sunset-centred mapping) at 550 nm, AOD 0.2 with the sun at 30 deg, against
    ``montecarlo`` (40 000 paths per direction: relative standard error below 1 %). Same
    directions and tolerances as ``test_hazy_sky_against_monte_carlo``: 3 % above 10 deg
    elevation, 6 % at 5 deg."""
    atm = Atmosphere.earth(aerosol_optical_depth=0.2)
    s = sun(30.0)
    wl = [550.0]
    d = direction_from_angles(np.array([89.9, 30.0, 65.0, 20.0, 5.0]),
                              np.array([0.0, 0.0, 180.0, 270.0, 180.0]))
    ref, err = sd.model("montecarlo", sun=s, atmosphere=atm, samples=40000,
                        seed=15).radiance_with_error(d, wl)
    assert np.all(err / ref < 0.01)
    m = sd.model("precomputed", sun=s, atmosphere=atm, table_wavelengths_nm=wl)
    rel = np.abs(m.radiance(d, wl) / ref - 1.0)[:, 0]
    assert np.all(rel[:4] < 0.03), rel
    assert rel[4] < 0.06, rel


TWILIGHT_REFERENCE = Path(__file__).parent / "data" / "twilight_montecarlo_550nm.npz"


@pytest.mark.parametrize("elevation, bounds", [
    (-4.0, [0.03, 0.16, 0.06, 0.09, 0.06]),
    (-6.0, [0.10, 0.19, 0.09, 0.13, 0.04]),
])
def test_default_twilight_against_stored_monte_carlo(elevation, bounds):
    """The default settings in twilight (AOD 0.2, 550 nm, the same tables as
    ``test_default_settings_against_monte_carlo``) against a stored ``montecarlo`` reference:
    tests/data/twilight_montecarlo_550nm.npz, 10 000 000 paths per direction at sun -4 and
    -6 deg (seed 11; the file's ``command`` and ``provenance`` say how it was made;
    relative standard error 0.2-0.5 % at -4 deg, 0.6-1.9 % at -6 deg). Directions: 10 deg up
    towards the sun (the twilight arch) and opposite it (the earth's shadow), 30 deg up at
    90 deg from the sun, 50 deg up opposite it, the zenith. Measured (code of 3634802):
    +1.9 / +13.3 / +4.3 / +7.4 / +3.9 % at -4 deg, -8.0 / +12.1 / +5.2 / +9.0 / -0.2 % at
    -6 deg (too bright opposite the sun: the sun-zenith resolution of the tables, see
    docs/performance.md, "Twilight accuracy of the default"). Required: each direction within
    its measured error plus three standard errors and about 1 %, so that a change that
    makes twilight worse fails (Bruneton's 32-node mu_s axis was 13-34 % off at -4 deg:
    ``test_twilight_against_monte_carlo``)."""
    ref = np.load(TWILIGHT_REFERENCE)
    d, wl = ref["directions"], ref["wavelengths_nm"]
    k = f"{elevation:g}"
    mc, err = ref[k][:, 0], ref[k + "_err"][:, 0]
    assert np.all(err / mc < 0.02)
    m = sd.model("precomputed", sun=sun(elevation), table_wavelengths_nm=list(wl),
                 atmosphere=Atmosphere.earth(aerosol_optical_depth=0.2))
    rel = m.radiance(d, wl)[:, 0] / mc - 1.0
    assert np.all(np.abs(rel) < np.array(bounds)), rel


def test_coarse_density_of_higher_orders_is_interpolated_bilinearly():
    """The scattering density of orders >= 3 lives on an outgoing grid twice as coarse and
    is added into the summed density bilinearly in (theta, phi): a density that is linear in
    theta and phi (a, b, c chosen here) must come out exactly, a + b theta + c phi, on every
    node of the fine grid."""
    from skydome.models.simulated.precomputed import _precompute as PC

    class Grid:
        def __init__(self, n):
            self.th_out = np.linspace(0.0, np.pi, 2 * n + 1)
            self.ph_out = np.linspace(0.0, np.pi, n + 1)

    fine, coarse = Grid(8), Grid(4)
    a, b, c = 0.5, 2.0, -0.25

    def linear(g):
        T, P = np.meshgrid(g.th_out, g.ph_out, indexing="ij")
        v = (a + b * T + c * P).astype(np.float32)
        return np.ascontiguousarray(np.broadcast_to(v[None, :, :, None, None, None],
                                                    (2,) + v.shape + (3, 4, 5)))

    J_sum = np.zeros_like(linear(fine))
    PC.add_density(J_sum, linear(coarse), fine, coarse)
    np.testing.assert_allclose(J_sum, linear(fine), rtol=1e-6, atol=1e-6)
    # the same grid: a plain sum
    PC.add_density(J_sum, linear(fine), fine, fine)
    np.testing.assert_allclose(J_sum, 2 * linear(fine), rtol=1e-6, atol=1e-6)


def test_coarse_density_grid_of_higher_orders_is_interpolated_in_r_and_mu_s():
    """The scattering density of orders >= 3 on its coarse (r, mu_s) grid is added into the
    summed density on the full grid bilinearly in the unit coordinates of both axes (the
    interpolation of ``_multiple.density_acc``): a density linear in them (a, b, c chosen
    here) must come out exactly on every full-grid node, with and without a coarser
    outgoing grid."""
    from skydome.models.simulated.precomputed import _precompute as PC

    class Grid:
        def __init__(self, n):
            self.th_out = np.linspace(0.0, np.pi, 2 * n + 1)
            self.ph_out = np.linspace(0.0, np.pi, n + 1)

    a, b, c, d = 0.5, 2.0, -0.25, 0.75

    def linear(g, n_r, n_ms):
        T, P, X, Y = np.meshgrid(g.th_out, g.ph_out, np.linspace(0, 1, n_r),
                                 np.linspace(0, 1, n_ms), indexing="ij")
        v = (a + b * X + c * Y + d * T - c * P).astype(np.float32)
        return np.ascontiguousarray(np.broadcast_to(v[None, ..., None], (2,) + v.shape + (3,)))

    fine, coarse = Grid(8), Grid(4)
    for q in (fine, coarse):
        J_sum = np.zeros_like(linear(fine, 32, 48))
        PC.add_density(J_sum, linear(q, 16, 24), fine, q)
        np.testing.assert_allclose(J_sum, linear(fine, 32, 48), rtol=1e-5, atol=1e-5)


def test_irradiance_rays_share_geometry_exactly():
    """``indirect_irradiance_rays`` shares each hemisphere ray's nodes, columns and
    exponentials between the sun positions and azimuths: it must equal the plain sum of one
    ``_multiple.ray_integral`` per ray (computed here in Python, ray by ray) on a small
    random density."""
    from skydome.models.simulated.precomputed import _irradiance, _multiple, _precompute as PC
    from skydome.models.simulated.precomputed._mapping import mu_s_frame, mu_s_from_unit

    props = Atmosphere.earth(aerosol_optical_depth=0.3).optical_properties(np.array(WL3), fold=True)
    R, Rt = float(props.planet_radius_m), float(props.top_radius_m)
    p = dict(transmittance_r_size=16, transmittance_mu_size=64)
    m = medium_from_properties(props)
    col = PC.transmittance_columns(m, p)
    sc = np.array([0, 1], dtype=np.int64)
    rng = np.random.default_rng(3)
    J = rng.uniform(0.5, 1.5, (2, 9, 5, 6, 7, 3)).astype(np.float32)
    rule = gauss_rule(5)
    mu_s_min = float(np.cos(np.radians(108.0)))
    th, ph, dom = PC._hemisphere(3)
    args = (m, sc, col)
    out = np.empty((3, 5, 3))
    _irradiance.indirect_irradiance_rays(J, *args, mu_s_min, *rule, 500.0, th, ph, dom, out, 3)
    # the ground's row alone (as the precomputation's orders ask for it): the same values
    row0 = np.empty((1, 5, 3))
    _irradiance.indirect_irradiance_rays(J, *args, mu_s_min, *rule, 500.0, th, ph, dom, row0,
                                         3)
    np.testing.assert_array_equal(row0[0], out[0])
    ref = np.zeros_like(out)
    frame = mu_s_frame(mu_s_min)
    for ir in range(3):
        r = R + (Rt - R) * ir / 2.0
        for im in range(5):
            mu_s = mu_s_from_unit(im / 4.0, mu_s_min)    # the table's node (the sun mapping)
            for a in range(th.size):
                for b in range(ph.size):
                    nu = np.clip(np.sqrt(1 - mu_s ** 2) * np.sin(th[a]) * np.cos(ph[b])
                                 + mu_s * np.cos(th[a]), -1, 1)
                    one = np.zeros(3)
                    sc_ = _multiple.ray_scratch(5, col.shape[0], 2, 3, np.empty((10, 2, 3)))
                    _multiple.ray_integral(J, *args, frame, r, np.cos(th[a]), mu_s, nu, False,
                                           *rule, 500.0, sc_, one)
                    ref[ir, im] += 2 * np.cos(th[a]) * dom[a] * one
    # equal to rounding: 1e-12 relative at the inner mu_s nodes, within 1e-5 at the end
    # nodes (the sun at mu_s_min, and at the zenith, where the azimuth about the sun is
    # singular), and at the top (r = Rt)
    # the rays have no length (values of 1e-15)
    np.testing.assert_allclose(out, ref, rtol=1e-5, atol=1e-12 * ref.max())
    np.testing.assert_allclose(out[:, 1:-1], ref[:, 1:-1], rtol=1e-12, atol=1e-12 * ref.max())



def test_incident_radiance_rays_against_one_ray_integral_per_ray():
    """``incident_radiance_rays`` (float32 sums, work items ordered by the angle from the
    sun) against one float64 ``_multiple.ray_integral`` per incident ray, computed here in
    Python, on a small random density (rays to the top and to the ground; a black ground, so
    no reflected term): equal within float32 rounding."""
    from skydome.models.simulated.precomputed import _density, _multiple, _precompute as PC
    from skydome.models.simulated.precomputed._mapping import mu_s_frame

    props = Atmosphere.earth(aerosol_optical_depth=0.3).optical_properties(np.array(WL3), fold=True)
    R, Rt = float(props.planet_radius_m), float(props.top_radius_m)
    p = dict(transmittance_r_size=16, transmittance_mu_size=64)
    m = medium_from_properties(props)._replace(albedo=np.zeros(3))      # a black ground
    col = PC.transmittance_columns(m, p)
    sc = np.array([0, 1], dtype=np.int64)
    J = np.random.default_rng(5).uniform(0.5, 1.5, (2, 9, 5, 6, 7, 3)).astype(np.float32)
    rule = gauss_rule(5)
    mu_s_min = float(np.cos(np.radians(108.0)))
    n_r, n_ms, n_th = 3, 4, 4
    th_in = (np.arange(n_th) + 0.5) * np.pi / n_th
    args = (m, sc, col)
    out = np.empty((n_th * n_th, n_r, n_ms, 3), dtype=np.float32)
    dE = np.zeros((4, 8, 3))
    _density.incident_radiance_rays(J, dE, *args, mu_s_min, *rule, 500.0, n_r, n_ms, th_in,
                                    th_in, out)
    frame = mu_s_frame(mu_s_min)
    ref = np.empty(out.shape)
    n_ground = 0
    for ir in range(n_r):
        for ims in range(n_ms):
            r, mu_s, sin_s = _density.density_node(ir, ims, n_r, n_ms, R, Rt, mu_s_min)
            for a in range(n_th):
                for b in range(n_th):
                    nu, ct, ground = _density.incident_direction(th_in[a], th_in[b], r, mu_s,
                                                                 sin_s, R)
                    n_ground += ground
                    one = np.zeros(3)
                    sc_ = _multiple.ray_scratch(5, col.shape[0], 2, 3, np.empty((10, 2, 3)))
                    _multiple.ray_integral(J, *args, frame, r, ct, mu_s, nu, ground,
                                           *rule, 500.0, sc_, one)
                    ref[a * n_th + b, ir, ims] = one
    assert 0 < n_ground < ref.size // 3
    np.testing.assert_allclose(out, ref, rtol=2e-6, atol=1e-6 * ref.max())
def test_stored_table_nodes_keep_the_horizon_and_both_ends():
    """The stored multiple-scattering table is integrated on a subset of its nodes: each half
    of the mu axis keeps its horizon node, the next quarter of the half at every node, and
    its far end (zenith, nadir); every second mu_s node plus the last; the brackets of
    every full-grid node are the computed nodes on either side, with fraction 0 on them."""
    from skydome.models.simulated.precomputed import _precompute as PC

    mu, ms = PC.stored_table_nodes(128, 48)
    assert {0, 63, 64, 127} <= set(mu.tolist())
    assert set(range(0, 16)) <= set(mu.tolist()) and set(range(112, 128)) <= set(mu.tolist())
    assert ms.tolist() == list(range(0, 48, 2)) + [47]
    cell, frac = PC.node_brackets(mu, 128)
    assert np.all(mu[cell] <= np.arange(128)) and np.all(np.arange(128) <= mu[cell + 1])
    assert np.all(frac[mu[:-1]] == 0.0) and frac[mu[-1]] == 1.0
    # no node is interpolated across the split between the halves (nodes 63 | 64)
    assert not np.any((mu[cell] <= 63) & (mu[cell + 1] >= 64) & (frac > 0.0))


def test_table_from_coarse_identity_and_exact_for_exponentials():
    """:func:`table_from_coarse` returns the computed nodes as they are (all nodes computed:
    the table itself) and, given the logarithm, reproduces a table that is
    exponential in the mu and mu_s node indices and constant in nu exactly (the model's
    multiple scattering falls off about exponentially with the sun's depression)."""
    from skydome.models.simulated.precomputed import _multiple, _precompute as PC

    R, Rt, mu_s_min = 6.36e6, 6.42e6, float(np.cos(np.radians(108.0)))
    shape = (3, 16, 12, 6, 2)
    i_mu = np.arange(16)[None, :, None, None, None]
    i_ms = np.arange(12)[None, None, :, None, None]
    full = np.exp(-0.3 * np.minimum(i_mu, 15 - i_mu) - 0.7 * i_ms
                  + np.array([0.0, 1.0])).astype(np.float32) * np.ones(shape, np.float32)
    out = np.empty(shape, np.float32)
    all_nodes = np.arange(16), np.arange(12)
    mc, mf = PC.node_brackets(all_nodes[0], 16)
    sc, sf = PC.node_brackets(all_nodes[1], 12)
    _multiple.table_from_coarse(full, all_nodes[0], mc, mf, all_nodes[1], sc, sf, R, Rt,
                                mu_s_min, out)
    np.testing.assert_array_equal(out, full)
    mu_n, ms_n = PC.stored_table_nodes(16, 12, ((0.5, 2), (1.0, 3)), 3)
    coarse = np.log(np.ascontiguousarray(full[:, mu_n][:, :, ms_n][:, :, :, :3]))
    mc, mf = PC.node_brackets(mu_n, 16)
    sc, sf = PC.node_brackets(ms_n, 12)
    _multiple.table_from_coarse(coarse, mu_n, mc, mf, ms_n, sc, sf, R, Rt, mu_s_min, out)
    np.testing.assert_allclose(np.exp(out), full, rtol=2e-5)


@pytest.fixture(scope="module")
def default_550():
    """The default settings at 550 nm, AOD 0.2, sun 30 deg (the tables of
    ``test_default_settings_against_monte_carlo``)."""
    atm = Atmosphere.earth(aerosol_optical_depth=0.2)
    return sd.model("precomputed", sun=sun(30.0), atmosphere=atm, table_wavelengths_nm=[550.0])


def test_stored_multiple_scattering_against_the_full_grid_integration(default_550):
    """The stored table of orders 2..N, integrated at a subset of its nodes and interpolated
    (``stored_table="subset"``, opt-in), against the reference: the same integral of the same summed density at
    every node of the full grid (128 mu x 48 mu_s x 16 nu). Tolerances from the
    measurement (docs/models.md, "precomputed", "The stored table on a subset of its
    nodes"): relative table error (floor 1e-3 of the largest value) mean 0.58 %, 99th
    percentile 5.6 % at 20 wavelengths; and where the table is read, the in-scattered
    radiance of aerial perspective over 1-100 km from the ground and from 10 km with the
    sun at 60, 10, 2 and -4 deg: RMS up to 3.0 % in luminance at 20 wavelengths, 3.2 %
    here at 550 nm (10 km, sun -4 deg, 1 km); 3.9 % there since the descending rays'
    first piece is integrated on two halves (cache format 14: both tables change), bound
    4.5 %."""
    import dataclasses

    from skydome.models.simulated.precomputed import _precompute as PC

    m = default_550
    t = m._t
    n_q = max(4, (m.integration_samples + 1) // 2)
    shape = t.multiple_scattering.shape
    full = t.multiple_scattering          # the default: integrated at every node
    sub = PC.stored_multiple_scattering(
        t.scattering_density, PC.tables_medium(t), t.scattering_index, t.columns, t.mu_s_min,
        n_q, shape)
    assert m.stored_table == "full"
    rel = np.abs(sub - full) / np.maximum(full, 1e-3 * full.max())
    assert rel.mean() < 0.01, rel.mean()
    assert np.percentile(rel, 99) < 0.08, np.percentile(rel, 99)
    m_full = m
    m = m.with_sun()
    m._t = dataclasses.replace(t, multiple_scattering=sub)
    el = np.array([0.0, 1.0, 3.0, 10.0, 30.0, 60.0, 89.0, -1.0, -3.0, -10.0])
    az = np.linspace(0.0, 180.0, 7)
    E, A = np.meshgrid(el, az, indexing="ij")
    d = direction_from_angles(E.ravel(), A.ravel())
    wl = [550.0]
    for alt in (0.0, 10000.0):
        sky = d[:49] if alt == 0.0 else d      # a ground observer's ground rays have no path
        for elev in (60.0, 10.0, 2.0, -4.0):
            a = m.with_sun(sun(elev), observer_altitude_m=alt)
            b = m_full.with_sun(sun(elev), observer_altitude_m=alt)
            for dist in (1e3, 1e4, 1e5):
                x = a.aerial_perspective(sky, dist, wl)[1][:, 0]
                y = b.aerial_perspective(sky, dist, wl)[1][:, 0]
                e = (x - y) / np.maximum(y, 0.01 * np.median(y))
                assert np.sqrt(np.mean(e ** 2)) < 0.045, (alt, elev, dist, e)


def test_precompute_runs_without_numpy_hugepage_advice_and_restores_it(monkeypatch):
    """The precomputation runs with numpy's transparent-huge-page advice off (its tables on
    small pages: docs/performance.md, "The weights of a whole ray; the tables on small
    pages") and leaves numpy's setting as it found it, also when the precomputation fails."""
    multiarray = pytest.importorskip("numpy._core.multiarray")
    switch = getattr(multiarray, "_set_madvise_hugepage", None)
    if switch is None:
        pytest.skip("this numpy has no huge-page switch")
    from skydome.models.simulated.precomputed import _precompute as PC

    seen = []

    def during(props, wl, p):
        state = switch(False)       # the setting in force, put back at once
        switch(state)
        seen.append(state)
        raise RuntimeError("stop here")

    monkeypatch.setattr(PC, "_precompute_tables", during)
    original = switch(True)
    try:
        for start in (True, False):
            switch(start)
            with pytest.raises(RuntimeError, match="stop here"):
                PC.precompute(None, None, None)
            assert switch(start) == start
    finally:
        switch(original)
    assert seen == [False, False]


def test_gauss_rule_in_v_integrates_length_and_density_profiles():
    """``transport._quadrature.ray_nodes_rule`` with ``gauss_legendre_unit`` against closed
    forms: the length of
    a ray (a constant integrand) and the column of an exponential profile of scale height
    H along a vertical ray, H (1 - exp(-L / H)), for the Rayleigh (8 km) and aerosol (1.2 km)
    scale heights. The midpoint rule of ``ray_nodes`` in v = ln(1 + u / ts) is short on the
    length by about V^2 / (24 n^2), V = ln(1 + L / ts) (the Jacobian e^v is convex): the
    reason the precomputation's ray integrals use the Gauss rule."""
    from skydome.transport import _quadrature as G

    R = 6.36e6
    ts = 500.0
    for L in (2e4, 1e5, 1.2e6):
        t = np.empty(40)
        w = np.empty(40)
        rx, rw = G.gauss_legendre_unit(7)
        n = G.ray_nodes_rule(R, 1.0, L, rx, rw, ts, t, w)     # upward: one piece
        assert n == 7
        assert abs(w[:n].sum() / L - 1.0) < 1e-7        # e^v to degree 13
        for H in (8000.0, 1200.0) if L <= 1e5 else ():    # vertical rays: <= 100 km
            exact = H * (1.0 - np.exp(-L / H))
            assert abs(np.sum(w[:n] * np.exp(-t[:n] / H)) / exact - 1.0) < 2e-3
        n = G.ray_nodes(R, 1.0, L, 10, ts, t, w)
        V = np.log1p(L / ts)
        short = 1.0 - w[:n].sum() / L
        assert 0.5 * V ** 2 / (24 * 100) < short < 1.5 * V ** 2 / (24 * 100)


@pytest.mark.parametrize("elevation, altitude", [(30.0, 0.0), (2.0, 3000.0), (-3.0, 0.0),
                                                 (-20.0, 0.0)])
def test_xyz_is_the_integrated_spectrum(elevation, altitude):
    """PrecomputedSky.xyz (one product of the table values with the wavelength
    interpolation, the solar spectrum and the CIE 1931 integration weights) equals the
    protocol's definition: radiance on the default wavelengths integrated by
    spectrum_to_xyz (skydome.spectra, checked against the CIE tables in test_spectra), over
    the whole sphere (the ground below the horizon included) and at night (all zero)."""
    from skydome.spectra import default_wavelengths, spectrum_to_xyz

    sky = sd.model("precomputed", sun=sd.Sun(elevation_deg=elevation, azimuth_deg=200.0),
                   observer_altitude_m=altitude)
    d = np.random.default_rng(4).normal(size=(3, 700, 3))
    wl = default_wavelengths()
    want = spectrum_to_xyz(sky.radiance(d, wl), wl)
    got = sky.xyz(d)
    assert got.shape == (3, 700, 3)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * max(want.max(), 1.0))
    np.testing.assert_allclose(sky.luminance(d), want[..., 1], rtol=1e-12,
                               atol=1e-12 * max(want.max(), 1.0))
    if elevation < -18.0:
        assert not got.any()
