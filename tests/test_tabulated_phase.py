"""Tabulated phase functions (skydome.atmosphere.TabulatedPhase, Lorenz-Mie tables) reach
the physically based models through the kernels' medium record."""

import math

import numpy as np
import pytest

import skydome as sd
from skydome.atmosphere import Atmosphere, Constituent, TabulatedPhase
from skydome.atmosphere.mie import MieAerosol, mie_constituent
from skydome.atmosphere.profiles import ExponentialProfile
from skydome.transport.geometry import angle_between, direction_from_angles

WL = np.array([450.0, 550.0, 650.0])
SUN = sd.Sun(elevation_deg=35.0, azimuth_deg=180.0)


def hg(g, c):
    """Henyey-Greenstein phase [sr^-1] written out here (Henyey & Greenstein 1941)."""
    return (1 - g * g) / (1 + g * g - 2 * g * c) ** 1.5 / (4 * math.pi)


def _single(atm, dirs):
    return sd.model("single_scattering", sun=SUN, atmosphere=atm).radiance(dirs, WL)


def _dirs():
    el = np.array([35.0, 38.0, 50.0, 70.0, 20.0, 5.0, 60.0])
    az = np.array([185.0, 180.0, 200.0, 300.0, 20.0, 90.0, 0.0])
    return direction_from_angles(el, az)


def test_mie_phase_reaches_single_scattering():
    """A thin layer of uniform 0.8 um spheres (m = 1.5, tau = 1e-4): with the tabulated
    Lorenz-Mie phase the single-scattered radiance is 4 pi P(theta) times the radiance
    with an isotropic phase (single scattering factors per constituent), with P from
    miepython (i_unpolarized, norm='one'), an independent Lorenz-Mie code."""
    import miepython

    aero = MieAerosol(0.8, 1.0, 1.5 + 0.0j)
    prof = ExponentialProfile(1200.0)
    mie = mie_constituent(aero, prof, optical_depth_550=1e-4, name="mie")
    assert mie.phase == "tabulated"
    iso = Constituent("mie", scattering=mie.scattering, absorption=mie.absorption, profile=prof,
                      phase="isotropic")
    atm_mie = Atmosphere((mie,), ground_albedo=0.0)
    atm_iso = Atmosphere((iso,), ground_albedo=0.0)
    d = _dirs()
    L_mie = _single(atm_mie, d)
    L_iso = _single(atm_iso, d)
    cos_t = np.cos(angle_between(d, SUN.direction))
    for j, wl in enumerate(WL):
        x = 2 * math.pi * 0.8e3 / wl
        p = miepython.i_unpolarized(1.5, x, cos_t, norm="one")
        np.testing.assert_allclose(L_mie[:, j], 4 * math.pi * p * L_iso[:, j], rtol=2e-3)


def test_tabulated_hg_table_reproduces_analytic_hg_model():
    """The Earth atmosphere with its aerosol phase given as an HG table at 1441 angles
    reproduces the analytic HG aerosol in the single-scattering model to 1e-3."""
    g = 0.76
    base = Atmosphere.earth(turbidity=4.0, aerosol_phase="henyey_greenstein", aerosol_g=g)
    theta = np.linspace(0.0, 180.0, 1441)
    table = TabulatedPhase(theta, hg(g, np.cos(np.radians(theta))), normalise=False,
                           description="HG g=0.76")
    cons = tuple(Constituent(c.name, c.scattering, c.absorption, c.profile, "tabulated", g,
                             phase_table=table) if c.name == "aerosol" else c
                 for c in base.constituents)
    tab_atm = Atmosphere(cons, ground_albedo=0.1)
    d = _dirs()
    np.testing.assert_allclose(_single(tab_atm, d), _single(base, d), rtol=1e-3)


def test_measured_table_is_normalised_and_interpolated():
    """A table of relative values at 1 deg (5 x HG, two wavelengths) is normalised to 1 over
    the sphere and follows HG on the kernels' grid within the 1 deg interpolation error;
    between the measured wavelengths it is interpolated linearly."""
    theta = np.linspace(0.0, 180.0, 181)
    c = np.cos(np.radians(theta))
    vals = np.stack([5 * hg(0.5, c), 5 * hg(0.7, c)], axis=-1)
    t = TabulatedPhase(theta, vals, [400.0, 800.0])
    grid = t.on_grid([400.0, 600.0, 800.0])
    th = np.radians(np.linspace(0.0, 180.0, grid.shape[0]))
    norm = 2 * math.pi * np.trapezoid(grid * np.sin(th)[:, None], th, axis=0)
    np.testing.assert_allclose(norm, 1.0, rtol=1e-12)
    np.testing.assert_allclose(grid[:, 0], hg(0.5, np.cos(th)), rtol=2e-2)
    np.testing.assert_allclose(grid[:, 2], hg(0.7, np.cos(th)), rtol=2e-2)
    raw = np.interp(np.degrees(th), theta, 0.5 * (vals[:, 0] + vals[:, 1]))
    np.testing.assert_allclose(grid[:, 1], raw / (2 * math.pi * np.trapezoid(raw * np.sin(th), th)),
                               rtol=1e-12)


def test_mie_table_normalised_over_the_sphere():
    """The Lorenz-Mie phase table integrates to 1 over the sphere ([BH83] eq. 3.16)."""
    aero = MieAerosol(0.5, 1.3, 1.5 - 0.001j, n_radii=15)
    theta, p = aero.phase_table([450.0, 650.0])
    th = np.radians(theta)
    np.testing.assert_allclose(2 * math.pi * np.trapezoid(p * np.sin(th)[:, None], th, axis=0),
                               1.0, rtol=2e-3)


def test_tabulated_phase_errors():
    theta = np.linspace(0.0, 180.0, 19)
    with pytest.raises(ValueError, match="theta_deg"):
        TabulatedPhase(np.linspace(0.0, 170.0, 19), np.ones(19))
    with pytest.raises(ValueError, match="non-negative"):
        TabulatedPhase(theta, -np.ones(19))
    with pytest.raises(ValueError, match="wavelengths_nm"):
        TabulatedPhase(theta, np.ones((19, 2)))
    with pytest.raises(ValueError, match="does not match"):
        TabulatedPhase(theta, np.ones(18))
    with pytest.raises(ValueError, match="phase_table"):
        Constituent("dust", scattering=1e-5, phase="tabulated")
    with pytest.raises(TypeError, match="phase_table"):
        Constituent("dust", scattering=1e-5, phase="tabulated", phase_table=np.ones(19))
