"""Lorenz-Mie aerosols (skydome.atmosphere.mie) against published values and each other."""

import numpy as np
import pytest

from skydome.atmosphere import Atmosphere
from skydome.atmosphere.mie import MieAerosol, lognormal_nodes, mie_constituent, mie_series
from skydome.atmosphere.profiles import GaussianLayerProfile

# Wiscombe (1979, rev. 1996), NCAR/TN-140+STR, MIEV0 test cases: (m, x, Qext, Qsca, g)
# (m in Wiscombe's convention, absorption negative; None where not needed)
WISCOMBE = [
    (0.75 + 0j, 10.0, None, 2.232265, 0.896473),          # case 7
    (1.33 - 1e-5j, 100.0, None, 2.096594, 0.868959),      # case 10
    (1.5 - 1j, 1.0, 2.336321, 0.6634538, 0.192136),       # case 14
    (1.5 - 1j, 100.0, 2.097502, 1.283697, 0.850252),      # case 15
]


@pytest.mark.parametrize("m,x,qext,qsca,g", WISCOMBE)
def test_own_series_matches_wiscombe_miev0(m, x, qext, qsca, g):
    """The vectorised Bohren-Huffman series written here, against Wiscombe's published
    MIEV0 test output (an independent program)."""
    qe, qs, gg = (v[0] for v in mie_series(m, [x]))
    if qext is not None:
        assert qe == pytest.approx(qext, abs=2e-6)
    assert qs == pytest.approx(qsca, abs=2e-6)
    assert gg == pytest.approx(g, abs=2e-6)


def test_own_series_forward_amplitude_wiscombe_case14():
    """Wiscombe MIEV0 case 14 (x = 1, m = 1.5 - 1i): S1(0) = S2(0) = 0.584080 + 0.190515i
    in his convention (exp(+i omega t)); ours is Bohren & Huffman's, the complex conjugate."""
    *_, s1, s2 = mie_series(1.5 - 1j, [1.0], [1.0])
    assert np.conj(s1[0, 0]) == pytest.approx(0.584080 + 0.190515j, abs=2e-6)
    assert np.conj(s2[0, 0]) == pytest.approx(0.584080 + 0.190515j, abs=2e-6)


def test_bohren_huffman_appendix_a_example():
    """Bohren & Huffman (1983) appendix A, BHMIE example: sphere of radius 0.525 um,
    m = 1.55, lambda = 0.6328 um: Q_ext = Q_sca = 3.10543 (the book's printed output)."""
    x = 2 * np.pi * 0.525 / 0.6328
    qe, qs, _ = (v[0] for v in mie_series(1.55, [x]))
    assert qe == pytest.approx(3.10543, abs=2e-5)
    assert qs == pytest.approx(3.10543, abs=2e-5)


def test_miepython_agrees_with_own_series_over_sizes():
    """miepython (Prahl) and the series written here agree over a size range (two
    independent implementations of the same theory)."""
    import miepython

    x = np.linspace(0.2, 40.0, 60)
    m = 1.5 - 0.001j
    qe, qs, g = mie_series(m, x)
    qe2, qs2, _, g2 = miepython.efficiencies_mx(m, x)
    np.testing.assert_allclose(qe, qe2, rtol=1e-9)
    np.testing.assert_allclose(qs, qs2, rtol=1e-9)
    np.testing.assert_allclose(g, g2, rtol=1e-8, atol=1e-10)


def test_lognormal_nodes_moments():
    """Log-normal moments (Seinfeld & Pandis 2006, eq. 8.39): <r> = r_m exp(ln^2 sg / 2),
    <r^2> = r_m^2 exp(2 ln^2 sg)."""
    r, w = lognormal_nodes(0.5, 1.5, 201)
    s2 = np.log(1.5) ** 2
    assert w.sum() == pytest.approx(1.0)
    assert np.sum(w * r) == pytest.approx(0.5 * np.exp(s2 / 2), rel=2e-4)
    assert np.sum(w * r ** 2) == pytest.approx(0.25 * np.exp(2 * s2), rel=2e-3)


def test_phase_table_normalised_and_consistent_with_g():
    """The tabulated phase integrates to 1 over the sphere and its mean cosine equals the
    asymmetry parameter from miepython's efficiencies (independent routes)."""
    a = MieAerosol(0.5, 1.2, 1.5 - 0.001j, n_radii=21)
    th, p = a.phase_table([450.0, 650.0])
    t = np.radians(th)
    w = 2 * np.pi * np.sin(t)
    norm = np.trapezoid(p * w[:, None], t, axis=0)
    gtab = np.trapezoid(p * (np.cos(t) * w)[:, None], t, axis=0)
    np.testing.assert_allclose(norm, 1.0, atol=2e-4)
    np.testing.assert_allclose(gtab, a.optics([450.0, 650.0]).g, atol=1e-3)


def test_rayleigh_limit_of_small_spheres():
    """Small non-absorbing spheres (x << 1): Q_sca = 8/3 x^4 |(m^2-1)/(m^2+2)|^2 (Bohren &
    Huffman eq. 5.8) and the phase function tends to 3/(16 pi)(1 + cos^2)."""
    a = MieAerosol(0.005, 1.0, 1.5 + 0j)
    o = a.optics([500.0])
    x = 2 * np.pi * 5.0 / 500.0
    q = 8 / 3 * x ** 4 * abs((1.5 ** 2 - 1) / (1.5 ** 2 + 2)) ** 2
    assert o.c_sca_m2[0] / (np.pi * (5e-9) ** 2) == pytest.approx(q, rel=1e-3)
    c = np.array([1.0, 0.0, -1.0])
    np.testing.assert_allclose(a.phase_function(c, [500.0])[:, 0], 3 / (16 * np.pi) * (1 + c * c), rtol=2e-3)


def test_absorption_gives_albedo_below_one():
    ash = MieAerosol(0.45, 1.15, 1.5 - 0.001j, n_radii=21).optics([550.0])
    soot = MieAerosol(0.1, 1.5, 1.75 - 0.44j, n_radii=21).optics([550.0])
    assert 0.95 < ash.single_scattering_albedo[0] < 1.0
    assert soot.single_scattering_albedo[0] < 0.5


def test_constituent_optical_depth_is_honoured():
    a = MieAerosol(0.45, 1.15, 1.5 - 0.001j, n_radii=21)
    prof = GaussianLayerProfile(20e3, 3e3)
    c = mie_constituent(a, prof, optical_depth_550=0.7)
    tau = prof.column(100e3) * (c.scattering([550.0]) + c.absorption([550.0]))
    assert tau[0] == pytest.approx(0.7, rel=1e-9)
    assert c.g == pytest.approx(a.optics([550.0]).g[0])


def _sun_transmittance(atm, wl, elevation_deg=30.0):
    tau = sum(atm.vertical_optical_depth(wl).values())
    return np.exp(-tau / np.sin(np.radians(elevation_deg)))


def test_volcanic_ash_blue_sun():
    """Survey section 5.6: narrow ash (~0.7-1 um particles) scatters out red: the sun seen
    through the layer is blue, T(450 nm) > T(650 nm); the layer alone also."""
    atm = Atmosphere.volcanic_ash(1.0)
    ext = atm.vertical_optical_depth([450.0, 650.0])["volcanic_ash"]
    assert ext[0] < ext[1]
    t = _sun_transmittance(atm, np.array([450.0, 650.0]), 60.0)
    assert t[0] > t[1]


def test_forest_fire_smoke_extinction_minimum_in_blue():
    """Wilson (MNRAS 111, 1951), the blue sun of 1950 September 26 (Alberta fires):
    the layer's extinction had a minimum near 435 nm, rising ('blueing') from there to
    630 nm. The preset (uniform 0.5 um oily droplets) puts it within 400-470 nm."""
    wl = np.arange(380.0, 640.0, 10.0)
    atm = Atmosphere.forest_fire_smoke(1.0)
    ext = atm.vertical_optical_depth(wl)["forest_fire_smoke"]
    assert 400.0 <= wl[np.argmin(ext)] <= 470.0
    i450, i630 = np.searchsorted(wl, 450.0), np.searchsorted(wl, 630.0)
    assert np.all(np.diff(ext[i450:i630 + 1]) > 0)


def test_errors_name_parameter():
    with pytest.raises(ValueError, match="median_radius_um"):
        MieAerosol(-1.0)
    with pytest.raises(ValueError, match="geometric_std"):
        MieAerosol(0.5, 0.5)
    with pytest.raises(ValueError, match="refractive_index"):
        MieAerosol(0.5, 1.1, 0.5 + 0j)
    with pytest.raises(ValueError, match="exactly one"):
        mie_constituent(MieAerosol(0.5), GaussianLayerProfile(1e3, 1e3))
