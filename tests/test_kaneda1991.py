"""kaneda1991: spherical earth, exponential air and aerosols, single scattering, fog
(Kaneda et al. 1991; survey section 7.2)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import skydome as sd
from skydome.models.simulated import kaneda1991 as kn
from skydome.spectra import spectrum_to_xyz, xyz_to_xy
from skydome.transport.geometry import direction_from_angles

WL = np.array([400.0, 450.0, 500.0, 550.0, 600.0, 650.0, 700.0])


def _sky(elev=30.0, az=135.0, **kw):
    return sd.model("kaneda1991", sun=sd.Sun(elevation_deg=elev, azimuth_deg=az), **kw)


def _directions(n=60, seed=7):
    """n upper-hemisphere directions, uniform in solid angle, plus near-horizon ones."""
    rng = np.random.default_rng(seed)
    el = np.degrees(np.arcsin(rng.uniform(0.0, 1.0, n)))
    az = rng.uniform(0.0, 360.0, n)
    el[:5] = [0.0, 0.5, 2.0, 89.5, 45.0]
    return direction_from_angles(el, az)


def test_registered():
    assert "kaneda1991" in sd.models.available()


@pytest.mark.parametrize("elev", [5.0, 30.0, 60.0])
def test_without_fog_agrees_with_single_scattering(elev):
    """Kaneda 1991 without fog agrees with the single_scattering reference within 1 %
    (same Atmosphere, same sun): per wavelength and in luminance, 60 directions over the
    upper hemisphere. The reference is the project's brute-force integrator with its own
    sample placement (an independent quadrature of the same integral)."""
    atm = sd.Atmosphere.earth(turbidity=3.0)
    sun = sd.Sun(elevation_deg=elev, azimuth_deg=135.0)
    d = _directions()
    k = sd.model("kaneda1991", sun=sun, atmosphere=atm)
    ref = sd.model("single_scattering", sun=sun, atmosphere=atm)
    lk, lr = k.radiance(d, WL), ref.radiance(d, WL)
    assert np.max(np.abs(lk / lr - 1.0)) < 0.01
    yk, yr = k.luminance(d), ref.luminance(d)
    assert np.max(np.abs(yk / yr - 1.0)) < 0.01
    np.testing.assert_allclose(k.sun_radiance(WL), ref.sun_radiance(WL), rtol=1e-3)


def test_uniform_fog_transmittance_is_beer_lambert():
    """A horizontal path of d metres inside a uniform fog layer of extinction sigma
    multiplies the clear-air transmittance by exp(-sigma d) (constant density: closed
    form). The ray rises d^2/(2R) < 0.1 m over 1 km, well inside a 50 m layer."""
    clear = _sky()
    foggy = _sky(fog_density=0.004, fog_height_m=50.0, fog_profile="uniform")
    v = [0.0, 1.0, 0.0]
    for d in (10.0, 300.0, 1000.0):
        t0, _ = clear.aerial_perspective(v, d, WL)
        t1, _ = foggy.aerial_perspective(v, d, WL)
        np.testing.assert_allclose(t1 / t0, math.exp(-0.004 * d), rtol=1e-6)


def test_uniform_fog_dims_the_sun_by_its_chord():
    """Sun disc through a uniform fog layer of thickness H on a sphere of radius R: extra
    factor exp(-sigma s), s = sqrt((R+H)^2 - R^2 cos^2 e) - R sin e (ray-sphere chord)."""
    e = 20.0
    clear = _sky(elev=e)
    foggy = _sky(elev=e, fog_density=0.002, fog_height_m=200.0, fog_profile="uniform")
    R = clear.atmosphere.planet_radius_m
    se = math.sin(math.radians(e))
    s = math.sqrt((R + 200.0) ** 2 - R * R * (1 - se * se)) - R * se
    np.testing.assert_allclose(foggy.sun_radiance(WL) / clear.sun_radiance(WL),
                               math.exp(-0.002 * s), rtol=1e-9)


def test_exponential_fog_dims_the_sun_by_the_chapman_column():
    """Exponential fog: extra factor exp(-sigma C), C the column of exp(-h/H) towards
    the sun, from the transport engine's Chapman-function column (scipy erfcx), and for
    a high sun close to the flat-earth H / sin(e)."""
    from skydome.transport.optical_depth import chapman_column

    for e in (2.0, 20.0, 70.0):
        clear = _sky(elev=e)
        foggy = _sky(elev=e, fog_density=0.003, fog_height_m=150.0)
        R = clear.atmosphere.planet_radius_m
        col = float(chapman_column(150.0, 0.0, math.sin(math.radians(e)), R))
        np.testing.assert_allclose(foggy.sun_radiance(WL) / clear.sun_radiance(WL),
                                   math.exp(-0.003 * col), rtol=1e-9)
    assert col == pytest.approx(150.0 / math.sin(math.radians(70.0)), rel=1e-3)


def test_fog_makes_the_horizon_whiter():
    """Grey fog scatters the sunlight it receives without colouring it: the horizon
    moves towards the chromaticity of the direct sunlight (the illuminant), away from
    the clear sky's blue, and its blue/red radiance ratio falls."""
    wl = np.linspace(380.0, 780.0, 41)
    d = direction_from_angles(np.array([1.0]), np.array([315.0]))
    clear = _sky()
    foggy = _sky(fog_density=0.005, fog_height_m=150.0)
    xy_sun = xyz_to_xy(spectrum_to_xyz(clear.sun_radiance(wl), wl))
    l0, l1 = clear.radiance(d, wl)[0], foggy.radiance(d, wl)[0]
    xy0 = xyz_to_xy(spectrum_to_xyz(l0, wl))
    xy1 = xyz_to_xy(spectrum_to_xyz(l1, wl))
    assert np.hypot(*(xy1 - xy_sun)) < 0.5 * np.hypot(*(xy0 - xy_sun))
    i450, i650 = 7, 27
    assert l1[i450] / l1[i650] < l0[i450] / l0[i650]
    # and the fog's in-scattering saturates with distance at a grey-ish level
    t, lin = foggy.aerial_perspective([0.0, 1.0, 0.0], np.array([10.0, 100.0, 2000.0]), WL)
    assert np.all(np.diff(t[:, 3]) < 0) and np.all(np.diff(lin[:, 3]) > 0)


def test_fog_object_radiance_and_long_path_limit():
    """L = L0 T + L_in, and an endless path gives the sky radiance."""
    sky = _sky(fog_density=0.001)
    d = np.array([0.2, 0.4, 0.6])
    _, lin = sky.aerial_perspective(d, 1e9, WL)
    np.testing.assert_allclose(lin, sky.radiance(d, WL), rtol=1e-12)
    L0 = np.full(WL.size, 0.1)
    t, tot = sky.aerial_perspective(d, 500.0, WL, object_radiance=L0)
    _, lin5 = sky.aerial_perspective(d, 500.0, WL)
    np.testing.assert_allclose(tot, L0 * t + lin5)


@pytest.mark.parametrize("phase", [kn.phase_hazy, kn.phase_murky])
def test_nishita_phase_functions_are_normalised(phase):
    """The hazy/murky approximations integrate to 1 over the sphere (Gauss-Legendre)."""
    x, w = np.polynomial.legendre.leggauss(200)
    assert 2.0 * math.pi * np.sum(w * phase(x)) == pytest.approx(1.0, rel=1e-10)


def test_mie_phase_choice_murky_is_more_forward_than_hazy():
    """[NMN87]: murky (exponent 32) is more forward-peaked than hazy (exponent 8): the
    ratio of the radiance 5 deg from the sun to that 90 deg away is larger."""
    d = direction_from_angles(np.array([35.0, 30.0]), np.array([135.0, 315.0]))
    h = _sky(mie_phase="hazy").radiance(d, WL)
    m = _sky(mie_phase="murky").radiance(d, WL)
    assert m[0, 3] / m[1, 3] > h[0, 3] / h[1, 3]
    assert np.all(np.isfinite(m)) and np.all(m > 0)


def test_validation():
    with pytest.raises(ValueError, match=r"fog_density = 1 m\^-1 is out of range"):
        _sky(fog_density=1.0)
    with pytest.raises(ValueError, match="fog_profile"):
        _sky(fog_profile="cubic")
    with pytest.raises(ValueError, match="either atmosphere or turbidity"):
        _sky(atmosphere=sd.Atmosphere.earth(), turbidity=3.0)
    with pytest.raises(TypeError):
        _sky(atmosphere="air")


@settings(max_examples=25, deadline=None)
@given(elev=st.floats(-20.0, 90.0), az=st.floats(0.0, 360.0), fog=st.floats(0.0, 0.05),
       fh=st.floats(1.0, 2000.0), prof=st.sampled_from(["exponential", "uniform"]),
       x=st.floats(-1, 1), y=st.floats(-1, 1), z=st.floats(-1, 1))
def test_no_nan_or_negative(elev, az, fog, fh, prof, x, y, z):
    if x * x + y * y + z * z < 1e-6:
        z = 1.0
    sky = _sky(elev, az, fog_density=fog, fog_height_m=fh, fog_profile=prof)
    L = sky.radiance([[x, y, z], [0, 0, 1], [1, 0, 0], [0, 0, -1]], WL[::3])
    assert np.all(np.isfinite(L)) and np.all(L >= 0)
    s = sky.sun_radiance(WL[::3])
    assert np.all(np.isfinite(s)) and np.all(s >= 0)
    t, lin = sky.aerial_perspective([x, y, z], np.array([0.0, 50.0, 1e4]), WL[::3])
    assert np.all(np.isfinite(t)) and np.all((t >= 0) & (t <= 1))
    assert np.all(np.isfinite(lin)) and np.all(lin >= 0)
