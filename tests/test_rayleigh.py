"""Rayleigh physics against the survey (Kment, Rauter & Zotti 2006), eqs. 3-8 and Table 1."""

import numpy as np
import pytest

from skydome.atmosphere.rayleigh import (king_factor, rayleigh_k, rayleigh_phase,
                                         rayleigh_phase_normalised,
                                         rayleigh_scattering_coefficient, refractive_index_air)

# Survey Table 1: wavelength [nm], beta [m^-1], 1/beta [km] as printed.
TABLE1 = [
    (700, 4.184e-6, 239.0),
    (570, 9.517e-6, 105.0),
    (540, 1.181e-5, 84.6),
    (470, 2.059e-5, 48.5),
    (400, 3.924e-5, 25.5),
]


@pytest.mark.parametrize("wl, beta, inv_km", TABLE1)
def test_table1_attenuation(wl, beta, inv_km):
    """beta from eq. 8 with n = 1.000278 (eq. 6) and N_s = 2.545e25 (eq. 5), to the 4
    significant figures printed in Table 1."""
    b = float(rayleigh_scattering_coefficient(wl))
    assert float(f"{b:.4g}") == pytest.approx(beta, rel=0, abs=0)
    # 1/beta is printed with 3 significant figures; the 470 nm entry (48.5 km) truncates
    # 1/2.059e-5 m = 48.57 km, so compare within 0.1 km.
    assert 1e-3 / b == pytest.approx(inv_km, abs=0.1)


def test_beta_equals_4_pi_k_over_lambda4():
    """Eq. 8: beta = 8 pi^3 (n^2-1)^2 / (3 N_s lambda^4) = 4 pi K / lambda^4, K from eq. 4."""
    n, ns, lam = 1.000278, 2.545e25, 550e-9
    direct = 8 * np.pi**3 * (n * n - 1) ** 2 / (3 * ns * lam**4)
    assert rayleigh_scattering_coefficient(550.0) == pytest.approx(direct, rel=1e-12)
    assert 4 * np.pi * rayleigh_k(n, ns) / lam**4 == pytest.approx(direct, rel=1e-12)


def test_lambda_minus_four_law():
    b = rayleigh_scattering_coefficient(np.array([400.0, 800.0]))
    assert b[0] / b[1] == pytest.approx(16.0, rel=1e-12)


def test_refractive_index_formulas_published_values():
    # Peck & Reeves 1972, Table 3 (standard air): (n-1) 1e8 = 27785.7 at 0.5 um? -- use
    # Ciddor 1996 Table 1 / NIST "Engineering metrology toolbox": standard air at 633 nm,
    # 15 degC, 101325 Pa, 450 ppm: n - 1 = 2.7653e-4 (Ciddor eq. 1).
    n_c = refractive_index_air(632.99, "ciddor1996")
    assert (n_c - 1.0) == pytest.approx(2.7653e-4, rel=2e-4)
    n_p = refractive_index_air(632.99, "peck_reeves1972")
    assert (n_p - 1.0) == pytest.approx(2.7653e-4, rel=1e-3)
    # dispersion: shorter wavelengths have larger n
    n = refractive_index_air(np.array([400.0, 700.0]), "peck_reeves1972")
    assert n[0] > n[1]
    # survey constant
    assert refractive_index_air(550.0) == pytest.approx(1.000278)


def test_survey_constant_close_to_dispersion_formula_in_visible():
    wl = np.linspace(400, 700, 31)
    n = refractive_index_air(wl, "peck_reeves1972")
    assert np.all(np.abs(n - 1.000278) < 6e-6)


def test_phase_normalised_integrates_to_one():
    mu = np.linspace(-1, 1, 200001)
    for rho in (0.0, 0.0279, 0.1):
        integral = 2 * np.pi * np.trapezoid(rayleigh_phase_normalised(mu, rho), mu)
        assert integral == pytest.approx(1.0, rel=1e-9)
    # eq. 3 itself has mean 1 over the sphere (normalisation constant 4 pi)
    assert 2 * np.pi * np.trapezoid(rayleigh_phase(mu), mu) == pytest.approx(4 * np.pi, rel=1e-9)


def test_phase_forward_backward_symmetry_and_ratio():
    assert rayleigh_phase(1.0) == pytest.approx(rayleigh_phase(-1.0))
    assert rayleigh_phase(1.0) / rayleigh_phase(0.0) == pytest.approx(2.0)


def test_depolarised_phase_shape_hansen_travis():
    """With depolarisation rho the phase function is P11 = 3 / (4 (1 + 2 g)) ((1 + 3 g) +
    (1 - g) cos^2) / (4 pi), g = rho / (2 - rho) (Hansen & Travis 1974, eq. 2.15): the
    side-scattering ratio P(90)/P(0) is (1 + 3 g) / (2 (1 + g)), 0.5140 for rho = 0.0279."""
    g = 0.0279 / (2 - 0.0279)
    p = rayleigh_phase_normalised(np.array([1.0, 0.0]), 0.0279)
    assert p[1] / p[0] == pytest.approx((1 + 3 * g) / (2 * (1 + g)), rel=1e-12)
    assert p[1] / p[0] == pytest.approx(0.5140, abs=1e-4)
    # the kernel's phase function is the same function
    from skydome.transport._kernels import phase_value

    for c in (-0.7, 0.0, 0.4, 1.0):
        assert phase_value(0, g, c) == pytest.approx(float(rayleigh_phase_normalised(c, 0.0279)), rel=1e-12)


def test_king_factor_value():
    # Bates 1984: rho = 0.0279 gives F_K = 1.0480
    assert king_factor(0.0279) == pytest.approx(1.0480, abs=2e-4)
    assert king_factor(0.0) == 1.0


@pytest.mark.parametrize("kwargs, match", [
    ({"refractive_index": "bogus"}, "method"),
    ({"depolarisation": 0.9}, "depolarisation"),
    ({"number_density_m3": -1.0}, "number_density_m3"),
])
def test_bad_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        rayleigh_scattering_coefficient(550.0, **kwargs)


def test_bad_wavelength():
    with pytest.raises(ValueError, match="wavelengths_nm"):
        rayleigh_scattering_coefficient(np.nan)
    with pytest.raises(ValueError, match="out of range"):
        rayleigh_scattering_coefficient(-5.0)
