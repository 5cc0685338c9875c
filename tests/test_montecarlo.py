"""The ``montecarlo`` reference sky (issue 5): agreement with single scattering in the thin
limit, energy conservation, 1/sqrt(N) convergence, determinism, polarisation."""

import numpy as np
import pytest

import skydome as sd
from skydome.atmosphere import Atmosphere
from skydome.models.simulated.montecarlo import (angle_of_polarisation, degree_of_polarisation,
                                                 stokes_frame)
from skydome.spectra import solar_irradiance
from skydome.transport.geometry import direction_from_angles

WL = np.array([450.0, 600.0])


def mc(elev, az=180.0, **kw):
    return sd.model("montecarlo", sun=sd.Sun(elevation_deg=elev, azimuth_deg=az), **kw)


def test_registered_with_parameters():
    cls = sd.models.get_model_class("montecarlo")
    names = {p.name for p in cls.parameters}
    assert {"atmosphere", "turbidity", "observer_altitude_m", "samples", "seed", "polarised",
            "max_order"} <= names


@pytest.mark.parametrize("kw, match", [({"samples": 1}, "samples"), ({"seed": -1}, "seed"),
                                       ({"max_order": 0}, "max_order"),
                                       ({"observer_altitude_m": 2e5}, "observer_altitude_m")])
def test_bad_parameters_rejected(kw, match):
    with pytest.raises(ValueError, match=match):
        mc(30.0, **kw)


def test_stokes_needs_polarised():
    with pytest.raises(ValueError, match="polarised"):
        mc(30.0, samples=4).stokes([0.0, 0.0, 1.0], [550.0])


# -- thin limit: the independent single-scattering integrator -------------------------------
THIN = Atmosphere.custom(rayleigh_scattering=lambda wl: 2e-8 * (550.0 / np.asarray(wl)) ** 4,
                         mie_scattering=1e-8, mie_extinction=1.2e-8, mie_phase="henyey_greenstein",
                         mie_g=0.7, ground_albedo=0.0)
THIN_CS = Atmosphere.custom(rayleigh_scattering=2e-8, mie_scattering=1e-8, mie_phase="cornette_shanks",
                            mie_g=0.76, ground_albedo=0.0)
THIN_DIRS = direction_from_angles(np.array([90.0, 40.0, 10.0, 2.0, 25.0, -15.0]),
                                  np.array([0.0, 170.0, 90.0, 300.0, 200.0, 180.0]))


@pytest.mark.parametrize("atm", [THIN, THIN_CS], ids=["hg", "cs"])
@pytest.mark.parametrize("max_order", [1, None])
def test_thin_atmosphere_matches_single_scattering(atm, max_order):
    """Optically thin air (vertical depth ~ 2e-4, black ground, observer at 500 m): the
    orders above the first add ~ 1e-3 x the first (measured: ~0.6 % at depth 2e-3), so the Monte Carlo radiance, with max_order=1 and unbounded, must
    equal the single_scattering model (numerical quadrature, an independent integrator)
    within 3 standard errors (+0.3 % for that model's quadrature error)."""
    sun = sd.Sun(elevation_deg=35.0, azimuth_deg=180.0)
    ref = sd.model("single_scattering", sun=sun, atmosphere=atm,
                   observer_altitude_m=500.0).radiance(THIN_DIRS, WL)
    L, err = sd.model("montecarlo", sun=sun, atmosphere=atm, samples=4000, seed=1,
                      max_order=max_order, observer_altitude_m=500.0).radiance_with_error(THIN_DIRS, WL)
    assert np.all(err > 0) and np.all(err < 0.1 * L)
    assert np.all(np.abs(L - ref) < 3.0 * err + 3e-3 * ref), (L / ref, err / L)


# -- conservation of energy ------------------------------------------------------------------
@pytest.mark.parametrize("polarised", [False, True])
def test_conservative_atmosphere_reflects_all_incoming_flux(polarised):
    """No absorption and a white ground (albedo 1): nothing is absorbed, so in steady state
    the upward flux leaving the top of a (nearly) plane-parallel atmosphere equals the
    incoming solar flux mu0 E (planetary albedo 1). Radius 1e8 m and the sun at the zenith
    (subsolar point) make the geometry locally plane-parallel and azimuthally symmetric, so
    F_up = 2 pi int_0^1 L(mu) mu dmu, by 8-node Gauss-Legendre quadrature, from an observer
    10 m below the top. Rayleigh vertical optical depth 0.5: a conservative multiple-
    scattering test (a missing factor in any order breaks it); in polarised mode as well
    (the Mueller matrices redistribute intensity but conserve it)."""
    atm = Atmosphere.custom(rayleigh_scattering=0.5 / 8000.0, mie_scattering=0.0, ground_albedo=1.0,
                            planet_radius_m=1e8, top_altitude_m=100e3)
    x, w = np.polynomial.legendre.leggauss(8)
    mu, w = 0.5 * (x + 1.0), 0.5 * w
    d = np.stack([np.sqrt(1.0 - mu ** 2), 0.0 * mu, -mu], axis=-1)
    m = mc(90.0, 0.0, atmosphere=atm, samples=12000, observer_altitude_m=99_990.0, seed=3,
           polarised=polarised)
    L, e = m.radiance_with_error(d, [550.0])
    E = solar_irradiance(np.array([550.0]))[0]
    F = 2.0 * np.pi * np.sum(w * mu * L[:, 0]) / E
    sF = 2.0 * np.pi * np.sqrt(np.sum((w * mu * e[:, 0]) ** 2)) / E
    assert sF < 0.006
    # 0.2 %: the limb rays (mu < 0.045 miss the ground in the spherical shell)
    assert abs(F - 1.0) < 3.0 * sF + 0.002, (F, sF)


def test_absorbing_ground_loses_flux():
    """The same setup with ground albedo 0.5 must reflect clearly less than the incoming
    flux (a check that the conservation test can tell the difference)."""
    atm = Atmosphere.custom(rayleigh_scattering=0.5 / 8000.0, mie_scattering=0.0, ground_albedo=0.5,
                            planet_radius_m=1e8, top_altitude_m=100e3)
    x, w = np.polynomial.legendre.leggauss(6)
    mu, w = 0.5 * (x + 1.0), 0.5 * w
    d = np.stack([np.sqrt(1.0 - mu ** 2), 0.0 * mu, -mu], axis=-1)
    L = mc(90.0, 0.0, atmosphere=atm, samples=2000, observer_altitude_m=99_990.0).radiance(d, [550.0])
    F = 2.0 * np.pi * np.sum(w * mu * L[:, 0]) / solar_irradiance(np.array([550.0]))[0]
    assert 0.3 < F < 0.8


# -- statistics ------------------------------------------------------------------------------
def test_standard_error_falls_as_inverse_sqrt_n():
    """The standard error of the mean of N independent paths is sigma/sqrt(N): quadrupling
    N halves it (within 15 %), and the spread of 8 independent estimates agrees with it."""
    d = direction_from_angles(np.array([60.0, 20.0]), np.array([90.0, 0.0]))
    e1 = mc(30.0, samples=2000, seed=5).radiance_with_error(d, [550.0])[1]
    e4 = mc(30.0, samples=8000, seed=6).radiance_with_error(d, [550.0])[1]
    ratio = e1 / e4
    assert np.all((ratio > 1.7) & (ratio < 2.3)), ratio
    est = np.array([mc(30.0, samples=500, seed=s).radiance_with_error(d, [550.0])[0] for s in range(8)])
    err = mc(30.0, samples=500, seed=0).radiance_with_error(d, [550.0])[1]
    spread = est.std(axis=0, ddof=1)
    assert np.all((spread > 0.4 * err) & (spread < 2.0 * err)), (spread, err)


def test_same_seed_same_result_different_seed_different():
    d = direction_from_angles(np.array([45.0, 10.0, 80.0]), np.array([0.0, 120.0, 250.0]))
    a = mc(20.0, samples=64, seed=11).radiance(d, WL)
    b = mc(20.0, samples=64, seed=11).radiance(d, WL)
    c = mc(20.0, samples=64, seed=12).radiance(d, WL)
    np.testing.assert_array_equal(a, b)
    assert np.all(a != c)


def test_result_independent_of_thread_count():
    import numba

    d = direction_from_angles(np.array([45.0, 10.0, 80.0, 5.0]), np.array([0.0, 120.0, 250.0, 10.0]))
    a = mc(20.0, samples=64, seed=2).radiance(d, WL)
    old = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        b = mc(20.0, samples=64, seed=2).radiance(d, WL)
    finally:
        numba.set_num_threads(old)
    np.testing.assert_array_equal(a, b)


# -- polarisation ----------------------------------------------------------------------------
@pytest.mark.parametrize("rho, expect", [(0.0, 1.0), (0.0279, 0.9457)])
def test_rayleigh_single_scattering_dop_at_90_degrees(rho, expect):
    """Single Rayleigh scattering at 90 deg from the sun is polarised to (1 - rho)/(1 + rho)
    (Hansen & Travis 1974 eq. 2.15; Chandrasekhar 1950): 1 for rho = 0 and 0.9457 for
    rho = 0.0279 (Young 1980's depolarisation of air). Sun at 30 deg elevation, view at 60 deg
    elevation in the opposite azimuth: scattering angle 90 deg. The polarisation is
    perpendicular to the scattering plane, which here is the meridian plane: Q < 0, U = 0."""
    atm = Atmosphere.custom(rayleigh_scattering=1.2e-5, mie_scattering=0.0, depolarisation=rho,
                            ground_albedo=0.3)
    m = mc(30.0, 180.0, atmosphere=atm, samples=300, polarised=True, max_order=1)
    d = direction_from_angles(60.0, 0.0)
    S = m.stokes(d, [550.0])[0]
    assert degree_of_polarisation(S) == pytest.approx(expect, abs=5e-4)
    assert S[1] < 0 and abs(S[2]) < 1e-3 * S[0]
    assert abs(abs(angle_of_polarisation(S)) - 90.0) < 0.1


def test_polarised_and_scalar_radiance_agree():
    """First order: the polarised intensity equals the scalar one (same random streams).
    All orders, Earth atmosphere, 4000 paths (standard errors ~2-3 %): the two agree within
    3 combined standard errors plus 2 %. (The neglect of polarisation itself changes the
    radiance by up to ~10 % in Rayleigh atmospheres, Mishchenko, Lacis & Travis 1994; with
    40 000 paths we measure up to 3 % at 550 nm and 6 % at 450 nm, 90 deg from the sun.)"""
    d = direction_from_angles(np.array([80.0, 30.0, 10.0, -10.0]), np.array([0.0, 90.0, 200.0, 0.0]))
    s1 = mc(25.0, samples=200, max_order=1).radiance(d, WL)
    p1 = mc(25.0, samples=200, max_order=1, polarised=True).radiance(d, WL)
    np.testing.assert_allclose(p1, s1, rtol=1e-9)
    s, es = mc(25.0, samples=4000, seed=1).radiance_with_error(d, WL)
    p, ep = mc(25.0, samples=4000, seed=2, polarised=True).radiance_with_error(d, WL)
    assert np.all(np.abs(p - s) < 3.0 * np.hypot(es, ep) + 0.02 * s), (p / s, es / s)


def test_stokes_frame_is_meridian():
    d = direction_from_angles(np.array([30.0, 90.0]), np.array([90.0, 0.0]))
    a, b = stokes_frame(d)
    np.testing.assert_allclose(np.sum(a * d, -1), 0.0, atol=1e-12)
    np.testing.assert_allclose(a[0], [-0.5, 0.0, np.sqrt(3) / 2], atol=1e-12)   # east, 30 deg up
    np.testing.assert_allclose(a[1], [0.0, -1.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(np.cross(-d, a), b)


def test_sun_below_horizon_and_ground_no_nan():
    """Twilight (sun at -6 deg) and directions below the horizon: finite, non-negative;
    the twilight sky is far darker than the day sky; the sun's disc is hidden."""
    d = direction_from_angles(np.array([90.0, 5.0, -30.0]), np.array([0.0, 0.0, 180.0]))
    m = mc(-6.0, 0.0, samples=200, polarised=True)
    L = m.radiance(d, WL)
    S = m.stokes(d, WL)
    assert np.all(np.isfinite(S)) and np.all(L >= 0)
    assert np.all(m.sun_radiance(WL) == 0.0)
    day = mc(30.0, 0.0, samples=200).radiance(d, WL)
    assert np.all(L[:2] < 0.05 * day[:2])
    assert np.all((degree_of_polarisation(S) >= 0) & (degree_of_polarisation(S) <= 1))


def test_sun_radiance_excluded_from_sky():
    """Looking straight at the sun, radiance holds only the aureole (the scattered light);
    sun_radiance holds the disc, E/Omega x T, orders of magnitude brighter."""
    m = mc(40.0, 180.0, samples=200)
    L = m.radiance(m.sun.direction, [550.0])
    Ls = m.sun_radiance([550.0])
    assert 0 < L[0] < 1e-3 * Ls[0]


def test_single_scattering_polarisation_perpendicular_to_scattering_plane():
    """Single Rayleigh scattering polarises the light perpendicular to the scattering plane
    (the plane through the sun and the view direction; Chandrasekhar 1950): the angle of
    polarisation in the meridian frame equals the angle of the unit vector s x d, for views
    off the sun's vertical (this checks the frame rotations and their handedness)."""
    atm = Atmosphere.custom(rayleigh_scattering=1.2e-5, mie_scattering=0.0, ground_albedo=0.0)
    m = mc(25.0, 150.0, atmosphere=atm, samples=200, polarised=True, max_order=1)
    d = direction_from_angles(np.array([50.0, 20.0, 75.0, 35.0]), np.array([40.0, 250.0, 100.0, 200.0]))
    aop = angle_of_polarisation(m.stokes(d, [550.0])[:, 0])
    e = np.cross(m.sun.direction, d)
    e /= np.linalg.norm(e, axis=-1, keepdims=True)
    a, b = stokes_frame(d)
    expect = np.degrees(np.arctan2(np.sum(e * b, -1), np.sum(e * a, -1)))
    diff = (aop - expect + 90.0) % 180.0 - 90.0
    assert np.all(np.abs(diff) < 0.2), (aop, expect)


@pytest.mark.parametrize("code, g, rho", [(0, 0.0, 0.0), (0, 0.0, 0.0279), (1, 0.76, 0.0),
                                          (1, -0.3, 0.0), (2, 0.76, 0.0), (2, 0.5, 0.0), (3, 0.0, 0.0)])
def test_phase_samplers_reproduce_their_phase_functions(code, g, rho):
    """The direction samplers draw cos(theta) with the pdf 2 pi P(cos): the first two moments
    of 400 000 draws match the analytic ones within 5 standard errors, and a 20-bin histogram
    matches the integrated phase function (chi-square, 19 dof, < 50). Analytic moments:
    HG <c> = g, <c^2> = (1 + 2 g^2)/3 (Henyey & Greenstein 1941); Cornette-Shanks
    <c> = 3 g (4 + g^2) / (5 (2 + g^2)) (Cornette & Shanks 1992); Rayleigh with
    depolarisation <c> = 0, <c^2> = ((1 + rho)/3 + (1 - rho)/5) / ((1 + rho) + (1 - rho)/3)."""
    from skydome.models.simulated import _kernels_montecarlo as K

    n = 400_000
    c = K.sample_cos_many(code, g, rho, n, 7)
    if code == 0:
        m1, m2 = 0.0, ((1 + rho) / 3 + (1 - rho) / 5) / ((1 + rho) + (1 - rho) / 3)
    elif code == 1:
        m1, m2 = g, (1 + 2 * g * g) / 3
    elif code == 2:
        m1, m2 = 3 * g * (4 + g * g) / (5 * (2 + g * g)), None
    else:
        m1, m2 = 0.0, 1.0 / 3.0
    assert abs(c.mean() - m1) < 5 * c.std() / np.sqrt(n)
    if m2 is not None:
        assert abs((c ** 2).mean() - m2) < 5 * (c ** 2).std() / np.sqrt(n)
    edges = np.linspace(-1, 1, 21)
    fine = np.linspace(-1, 1, 20001)
    pdf = np.array([2 * np.pi * K.phase(code, g, rho, x) for x in fine])
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (pdf[1:] + pdf[:-1]) * np.diff(fine))])
    expect = n * np.diff(np.interp(edges, fine, cdf))
    counts = np.histogram(c, edges)[0]
    chi2 = np.sum((counts - expect) ** 2 / expect)
    assert chi2 < 50, chi2


def test_arago_and_babinet_neutral_points():
    """Multiple scattering in a Rayleigh atmosphere creates the Arago and Babinet neutral
    points, about 20 deg above the antisolar point and above the sun (Arago 1809, Babinet
    1840; Coulson 1988, Polarization and Intensity of Light in the Atmosphere, ch. 5):
    between them and the antisun/sun the polarisation is parallel to the scattering plane
    (Q > 0 in the meridian frame of the sun's vertical), beyond them perpendicular (Q < 0).
    Single scattering alone gives Q < 0 everywhere, so this checks the multiple-scattering
    Stokes bookkeeping. (Measured with 20 000 paths at 450 nm, sun at 5 deg: Q changes sign
    22 deg above the antisolar point and 20 deg above the sun.)"""
    atm = Atmosphere.earth(aerosol_optical_depth=0.0, ozone_du=0.0, ground_albedo=0.0)
    m = mc(5.0, 180.0, atmosphere=atm, samples=3000, polarised=True, seed=4)
    d = direction_from_angles(np.array([1.0, 30.0, 10.0, 45.0]), np.array([0.0, 0.0, 180.0, 180.0]))
    S, e = m.stokes_with_error(d, [450.0])
    q, eq = S[:, 0, 1], e[:, 0, 1]
    assert q[0] > 4 * eq[0] and q[2] > 4 * eq[2]          # 6 deg from antisun, 5 deg from sun
    assert q[1] < -4 * eq[1] and q[3] < -4 * eq[3]        # 35 deg from antisun, 40 deg from sun
    # single scattering: perpendicular everywhere
    s1 = mc(5.0, 180.0, atmosphere=atm, samples=300, polarised=True, max_order=1).stokes(d, [450.0])
    assert np.all(s1[:, 0, 1] < 0)
