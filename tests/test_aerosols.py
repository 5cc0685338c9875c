"""Mie phase-function approximations (survey eqs. 10-11) and aerosol optical depth."""

import numpy as np
import pytest

from skydome.atmosphere.aerosols import (aerosol_optical_depth, angstrom_beta_from_turbidity,
                                         cornette_shanks, cornette_shanks_survey,
                                         henyey_greenstein, henyey_greenstein_survey)

G_VALUES = np.round(np.linspace(-0.95, 0.95, 39), 3)


def _sphere_integral(f, g):
    # Integrate over mu in [-1, 1] with a substitution that resolves the forward peak:
    # Gauss-Legendre on many sub-intervals clustered towards mu = 1 (and -1 for g < 0).
    x, w = np.polynomial.legendre.leggauss(64)
    edges = 1.0 - np.geomspace(2.0, 1e-9, 400)
    edges = np.concatenate([[-1.0], edges[edges > -1.0], [1.0]])
    if g < 0:
        edges = -edges[::-1]
    a, b = edges[:-1, None], edges[1:, None]
    mu = 0.5 * (b - a) * x + 0.5 * (b + a)
    return float(2 * np.pi * np.sum(0.5 * (b - a) * w * f(mu, g)))


@pytest.mark.parametrize("g", G_VALUES)
def test_henyey_greenstein_normalised(g):
    assert _sphere_integral(henyey_greenstein, g) == pytest.approx(1.0, rel=1e-8)


@pytest.mark.parametrize("g", G_VALUES)
def test_cornette_shanks_normalised(g):
    assert _sphere_integral(cornette_shanks, g) == pytest.approx(1.0, rel=1e-8)


def test_survey_forms_have_normalisation_constant_4pi():
    for g in (-0.5, 0.0, 0.76):
        assert _sphere_integral(henyey_greenstein_survey, g) == pytest.approx(4 * np.pi, rel=1e-8)
        assert _sphere_integral(cornette_shanks_survey, g) == pytest.approx(4 * np.pi, rel=1e-8)


def test_henyey_greenstein_mean_cosine_is_g():
    # <cos theta> of HG equals g by construction [HG41]
    for g in (-0.6, 0.2, 0.8):
        assert _sphere_integral(lambda mu, gg: mu * henyey_greenstein(mu, gg), g) == pytest.approx(g, rel=1e-7)


def test_cornette_shanks_g0_is_rayleigh():
    mu = np.linspace(-1, 1, 11)
    assert np.allclose(cornette_shanks_survey(mu, 0.0), 0.75 * (1 + mu**2))


def test_henyey_greenstein_isotropic_at_g0():
    mu = np.linspace(-1, 1, 11)
    assert np.allclose(henyey_greenstein(mu, 0.0), 1 / (4 * np.pi))


def test_turbidity_to_angstrom_beta_preetham():
    # Preetham et al. 1999, A.2: beta = 0.04608 T - 0.04586
    assert angstrom_beta_from_turbidity(2.0) == pytest.approx(0.0463)
    assert angstrom_beta_from_turbidity(10.0) == pytest.approx(0.41494)


def test_angstrom_law():
    tau = aerosol_optical_depth(np.array([500.0, 1000.0]), 0.1, 1.3)
    assert tau[1] == pytest.approx(0.1)
    assert tau[0] == pytest.approx(0.1 * 0.5**-1.3)


@pytest.mark.parametrize("g", [1.0, -1.0, 1.5, np.nan])
def test_bad_g(g):
    with pytest.raises(ValueError, match="g"):
        henyey_greenstein(0.5, g)


def test_bad_turbidity():
    with pytest.raises(ValueError, match=r"turbidity = -1 is out of range \[1, 32\]"):
        angstrom_beta_from_turbidity(-1)
