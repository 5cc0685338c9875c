"""nishita1996: multiple scattering by the sky-sphere method (Nishita et al. 1996).

References used: the project's brute-force `single_scattering` integrator (independent
code: Bruneton-style (r, mu) column table, not the cylindrical table) for order 1; the
optically thin limit (multiple scattering vanishes relative to single scattering as tau);
the physical signatures of [NDKY96] sec. 5 / survey sec. 7.5 (more light and whiter
horizon with multiple scattering)."""

import numpy as np
import pytest

import skydome as sd
from skydome.atmosphere import Atmosphere
from skydome.spectra import spectrum_to_xyz
from skydome.transport.geometry import direction_from_angles

WL = np.array([450.0, 550.0, 650.0])
EL = np.array([89.0, 60.0, 30.0, 10.0, 3.0, 30.0, 10.0, -10.0])
AZ = np.array([0.0, 90.0, 180.0, 180.0, 0.0, 0.0, 270.0, 180.0])
DIRS = direction_from_angles(EL, AZ)
SUN = sd.Sun(elevation_deg=30.0, azimuth_deg=180.0)


@pytest.fixture(scope="module")
def by_order():
    m = sd.model("nishita1996", sun=SUN, orders=6, lattice_size=11, sky_directions=20)
    return m.radiance_by_order(DIRS, WL)


def test_registered():
    cls = sd.models.get_model_class("nishita1996")
    names = {p.name for p in cls.parameters}
    assert {"atmosphere", "turbidity", "observer_altitude_m", "orders"} <= names


def test_order1_matches_single_scattering_reference():
    """Order 1 (cylindrical sun tables) vs the single_scattering reference: within 1 %,
    sky and sunlit ground (same Atmosphere, same ground albedo)."""
    for elev in (30.0, 4.0):
        sun = sd.Sun(elevation_deg=elev, azimuth_deg=120.0)
        a = sd.model("nishita1996", sun=sun, orders=1).radiance(DIRS, WL)
        b = sd.model("single_scattering", sun=sun).radiance(DIRS, WL)
        np.testing.assert_allclose(a, b, rtol=0.01)
        np.testing.assert_allclose(sd.model("nishita1996", sun=sun, orders=1).sun_radiance(WL),
                                   sd.model("single_scattering", sun=sun).sun_radiance(WL),
                                   rtol=0.01)


def test_orders_increase_and_converge(by_order):
    """Every order adds light, each less than the one before (the series converges), and
    the 6th adds < 1 % of the sky's mean luminance."""
    assert np.all(by_order >= 0.0) and np.all(np.isfinite(by_order))
    Y = spectrum_to_xyz(np.moveaxis(by_order, 0, -2), WL)[..., 1]   # (dirs, orders)
    Y = Y.T                                                          # (orders, dirs)
    assert np.all(Y[1:] > 0.0)
    assert np.all(Y[2:] < Y[1:-1])
    cum = np.cumsum(Y, axis=0)
    assert np.all(np.diff(cum, axis=0) > 0)
    share = Y[-1].sum() / cum[-1].sum()
    assert share < 0.01


def test_horizon_whitening(by_order):
    """Multiple scattering brightens the horizon relatively more than the zenith
    ([NDKY96] sec. 5), and the horizon stays less blue than the zenith."""
    single = by_order[0]
    total = by_order.sum(axis=0)
    zen, hor = 0, 4      # 89 deg and 3 deg elevation
    gain = total[..., 1] / single[..., 1]
    assert gain[hor] > 1.3 * gain[zen]
    assert total[hor, 0] / total[hor, 2] < total[zen, 0] / total[zen, 2]


def test_optically_thin_limit():
    """Optically thin air (Rayleigh 1e-9 m^-1, no aerosol, black ground): order 2 / order 1
    is of the order of the optical depth (~1e-5), i.e. multiple scattering vanishes."""
    atm = Atmosphere.custom(rayleigh_scattering=1e-9, mie_scattering=0.0, ground_albedo=0.0)
    m = sd.model("nishita1996", sun=SUN, atmosphere=atm, orders=2, lattice_size=7,
                 sky_directions=12)
    lo = m.radiance_by_order(DIRS[:5], WL)
    assert np.all(lo[1] < 1e-3 * lo[0])


def test_sun_below_horizon_and_ground_no_nan():
    sun = sd.Sun(elevation_deg=-4.0, azimuth_deg=90.0)
    m = sd.model("nishita1996", sun=sun, orders=2, lattice_size=7, sky_directions=12)
    L = m.radiance(DIRS, WL)
    assert np.all(np.isfinite(L)) and np.all(L >= 0.0)
    assert np.all(m.sun_radiance(WL) == 0.0)


@pytest.mark.parametrize("kw", [{"orders": 0}, {"orders": 11}, {"lattice_size": 12},
                                {"observer_altitude_m": 2e5}, {"sky_directions": 3}])
def test_bad_parameters(kw):
    with pytest.raises(ValueError):
        sd.model("nishita1996", sun=SUN, **kw)
