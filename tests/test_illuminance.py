"""skydome.illuminance: analytic skies, the CIE overcast closed forms, Perez's own
normalisation and Radiance's gensky -B as references."""

from __future__ import annotations

import math

import numpy as np
import pytest

import skydome
from skydome import illuminance as il
from skydome.models import SkyModel
from skydome.sun import Sun

from _radiance import radiance_azimuth, sky_function_args


class _Uniform(SkyModel):
    """A sky of constant luminance L [cd m^-2] (and constant spectral radiance L / 683 per
    nm for the spectral variant) above the horizon; no sun."""

    name = "_uniform_test"
    native = "luminance"

    def __init__(self, L, sun=None):
        self.L = float(L)
        self.sun = sun if sun is not None else Sun(30.0, 180.0)

    def luminance(self, directions):
        d = self._directions(directions)
        return np.where(d[..., 2] >= 0.0, self.L, 0.0)


class _UniformSpectral(_Uniform):
    native = "spectral"

    def radiance(self, directions, wavelengths_nm):
        d = self._directions(directions)
        w = np.asarray(wavelengths_nm, dtype=np.float64)
        return np.where(d[..., 2:3] >= 0.0, self.L / 683.0, 0.0) * np.ones(w.size)

    def sun_radiance(self, wavelengths_nm):
        return None


# -- analytic: a uniform sky (view factors) ------------------------------------------------------
def test_uniform_sky_horizontal_and_vertical():
    """Uniform sky of luminance L: E_h = pi L, E_v = pi L / 2 (view factors of a plane)."""
    sky = _Uniform(1000.0)
    assert il.sky_illuminance(sky) == pytest.approx(math.pi * 1000.0, rel=1e-12)
    for az in (0.0, 37.0, 180.0, 271.5):
        assert il.sky_illuminance(sky, 90.0, az) == pytest.approx(math.pi * 500.0, rel=1e-10)


@pytest.mark.parametrize("tilt", [0.0, 10.0, 30.0, 60.0, 90.0, 120.0, 150.0, 180.0])
def test_uniform_sky_tilted_view_factor(tilt):
    """Sky view factor of a tilted plane (1 + cos b) / 2 and ground view factor
    (1 - cos b) / 2 [LJ63]: uniform sky L, Lambertian ground rho lit by pi L."""
    sky = _Uniform(2.0)
    cb = math.cos(math.radians(tilt))
    e = il.illuminance(sky, tilt, 123.0, ground_albedo=0.3)
    assert e.sky == pytest.approx(math.pi * 2.0 * (1 + cb) / 2, rel=1e-9, abs=1e-12)
    assert e.ground == pytest.approx(0.3 * math.pi * 2.0 * (1 - cb) / 2, rel=1e-9, abs=1e-12)
    assert e.sun == 0.0
    # sky and ground of the same luminance: every plane sees pi L
    e1 = il.illuminance(_Uniform(1.0 / math.pi), tilt, 0.0, ground_albedo=1.0)
    assert e1.total == pytest.approx(1.0, rel=1e-9)


def test_uniform_spectral_irradiance():
    """Spectral irradiance of a uniform spectral sky: pi L_lambda on the horizontal,
    pi L_lambda / 2 on a wall; the grey ground adds rho pi L_lambda / 2 on the wall."""
    sky = _UniformSpectral(683.0)
    wl = np.array([400.0, 550.0, 700.0])
    e = il.irradiance(sky, wl, ground_albedo=0.5)
    np.testing.assert_allclose(e.sky, math.pi, rtol=1e-12)
    np.testing.assert_allclose(e.ground, 0.0, atol=0.0)
    v = il.irradiance(sky, wl, 90.0, 270.0, ground_albedo=0.5)
    np.testing.assert_allclose(v.sky, math.pi / 2, rtol=1e-10)
    np.testing.assert_allclose(v.ground, 0.5 * math.pi / 2, rtol=1e-10)
    assert v.unit == "W m^-2 nm^-1" and v.sky.shape == (3,)


def test_planes_broadcast():
    """Arrays of planes give arrays, equal to the one-plane calls."""
    sky = skydome.model("cie2003", sun=Sun(35.0, 200.0), sky_type=12)
    tilts = np.array([[0.0, 45.0], [90.0, 90.0]])
    azs = np.array([0.0, 180.0])
    e = il.sky_illuminance(sky, tilts, azs)
    assert e.shape == (2, 2)
    for i in range(2):
        for j in range(2):
            assert e[i, j] == pytest.approx(il.sky_illuminance(sky, tilts[i, j], azs[j]),
                                            rel=1e-14)


# -- analytic: the CIE overcast sky ---------------------------------------------------------------
def test_cie_overcast_closed_forms():
    """L = Lz (1 + 2 cos theta) / 3 (survey eq. 13). Horizontal: E_h = 7 pi Lz / 9.
    Vertical, by hand: E_v = 2 int_0^{pi/2} L sin^2 theta d theta = Lz (pi / 6 + 4 / 9),
    whatever the wall's azimuth."""
    sky = skydome.model("cie1994_overcast", sun=Sun(40.0, 180.0), zenith_luminance=1000.0)
    assert il.sky_illuminance(sky) == pytest.approx(7 * math.pi / 9 * 1000.0, rel=1e-10)
    for az in (0.0, 90.0, 200.0):
        assert il.sky_illuminance(sky, 90.0, az) == pytest.approx(
            1000.0 * (math.pi / 6 + 4 / 9), rel=1e-5)
    assert il.sun_illuminance(sky) == 0.0


def test_cie2003_type15_converges():
    """The sharpest CIE sky (type 15, circumsolar peak): the defaults agree with a grid
    8x finer in each direction within 1e-4, on a horizontal and a sun-facing wall."""
    sky = skydome.model("cie2003", sun=Sun(25.0, 180.0), sky_type=15)
    for tilt, az in ((0.0, 0.0), (90.0, 180.0), (45.0, 150.0)):
        fine = il.sky_illuminance(sky, tilt, az, n_mu=512, n_phi=1024)
        assert il.sky_illuminance(sky, tilt, az) == pytest.approx(fine, rel=1e-4)


# -- Radiance: gensky -B -------------------------------------------------------------------------
@pytest.mark.parametrize("el,az", [(15, 135), (35, 225), (55, 300), (80, 20)])
def test_cie_clear_horizontal_against_gensky_B(el, az):
    """Reference: Radiance gensky +s -B E: the zenith brightness it writes for a horizontal
    diffuse irradiance E comes from its fit normsc() of the hemisphere integral (about
    0.3 %); the sky with that zenith luminance must give E on the horizontal."""
    e_h = 100.0
    args = ["gensky", "-ang", str(el), str(radiance_azimuth(az)), "+s", "-B", str(e_h)]
    lz = sky_function_args(args)[1]   # printed with 4 digits
    sky = skydome.model("cie1994_clear", sun=Sun(el, az), zenith_luminance=lz)
    assert il.sky_illuminance(sky) == pytest.approx(e_h, rel=3.5e-3)


# -- the sun and luminance-only models -----------------------------------------------------------
def test_perez_inputs_come_back():
    """Perez 1993 scaled to given illuminances ([PSM93]: the sky integrates to the diffuse
    horizontal illuminance, the sun is the direct normal illuminance): the API returns the
    inputs, E_sun,h = E_n sin(h), and E_n on a plane facing the sun."""
    sun = Sun(32.0, 150.0)
    sky = skydome.model("perez1993", sun=sun, dni_illuminance=60000.0,
                        dhi_illuminance=18000.0)
    e = il.horizontal_illuminance(sky)
    assert e.sky == pytest.approx(18000.0, rel=2e-3)
    assert e.sun == pytest.approx(60000.0 * math.sin(math.radians(32.0)), rel=1e-12)
    facing = il.sun_illuminance(sky, 90.0 - 32.0, 150.0)
    assert facing == pytest.approx(60000.0, rel=1e-12)
    assert il.sun_illuminance(sky, 90.0, 330.0) == 0.0          # wall turned away
    assert sky.direct_normal_illuminance() == pytest.approx(60000.0, rel=1e-12)


def test_sun_below_horizon_gives_no_direct_light():
    sky = skydome.model("cie1994_overcast", sun=Sun(-3.0, 180.0), zenith_luminance=10.0)
    assert il.sun_illuminance(sky, 90.0, 180.0) == 0.0


def test_spectral_model_sun_irradiance_matches_sun_radiance():
    """Preetham 1999: the direct spectral irradiance on a plane facing the sun is
    sun_radiance x solid angle (definition of the disc's mean radiance)."""
    sun = Sun(45.0, 180.0)
    sky = skydome.model("preetham1999", sun=sun, turbidity=3.0)
    wl = np.array([450.0, 550.0, 650.0])
    e = il.sun_irradiance(sky, wl, 45.0, 180.0)
    np.testing.assert_allclose(e, sky.sun_radiance(wl) * sun.solid_angle_sr, rtol=1e-12)


# -- bad input ------------------------------------------------------------------------------------
def test_bad_input_names_the_parameter():
    sky = _Uniform(1.0)
    with pytest.raises(ValueError, match="tilt_deg"):
        il.sky_illuminance(sky, 181.0)
    with pytest.raises(ValueError, match="azimuth_deg"):
        il.sky_illuminance(sky, 0.0, float("nan"))
    with pytest.raises(ValueError, match="ground_albedo"):
        il.illuminance(sky, ground_albedo=1.5)
    with pytest.raises(ValueError, match="n_mu"):
        il.sky_illuminance(sky, n_mu=1)
    with pytest.raises(TypeError, match="sky"):
        il.sky_illuminance("cie2003")
    with pytest.raises(TypeError, match="luminance-only"):
        il.irradiance(sky, [550.0])
    with pytest.raises(ValueError, match="wavelengths_nm"):
        il.irradiance(_UniformSpectral(1.0), [np.nan])


def test_cie_sky_with_a_sun():
    """A CIE sky given dni_illuminance carries that sun: E_sun on the horizontal is
    E_n sin(h), and without it the model has no sun."""
    sun = Sun(35.0, 200.0)
    sky = skydome.model("cie2003", sun=sun, sky_type=12, dni_illuminance=70000.0)
    assert sky.sun_luminance() == pytest.approx(70000.0 / sun.solid_angle_sr, rel=1e-12)
    assert il.sun_illuminance(sky) == pytest.approx(70000.0 * math.sin(math.radians(35.0)),
                                                    rel=1e-12)
    bare = skydome.model("cie2003", sun=sun, sky_type=12)
    assert bare.sun_luminance() is None and il.sun_illuminance(bare) == 0.0


def test_asrc_cie_sun_from_dni_matches_perez():
    """ASRC-CIE given dni/dhi converts dni with the Perez et al. 1990 direct efficacy, as
    perez1993 does from the same irradiances (their air mass formulas differ: Kasten 1966
    against Kasten & Young 1989, hence 1 %)."""
    sun = Sun(40.0, 180.0)
    asrc = skydome.model("asrc_cie", sun=sun, dni=600.0, dhi=120.0)
    perez = skydome.model("perez1993", sun=sun, dni=600.0, dhi=120.0)
    assert asrc.direct_normal_illuminance() == pytest.approx(perez.direct_illuminance, rel=1e-2)


@pytest.mark.parametrize("n", [7, 64, 256, 512])
def test_gauss_rule_on_one_blas_thread(n):
    """The quadrature's Gauss-Legendre rule is computed on one BLAS thread: the same bits as
    numpy's leggauss run with the process's threads, exact for polynomials of degree 2n - 1
    (int_0^1 x^k dx = 1 / (k + 1)), and the caller's BLAS thread count left as it was."""
    from threadpoolctl import threadpool_info

    from skydome.illuminance import _gauss_01

    _gauss_01.cache_clear()
    before = [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]
    x, w = _gauss_01(n)
    after = [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]
    assert after == before
    xr, wr = np.polynomial.legendre.leggauss(n)
    assert np.array_equal(x, 0.5 * (xr + 1.0)) and np.array_equal(w, 0.5 * wr)
    for k in (0, 1, 2 * n - 1):
        assert np.sum(w * x ** k) == pytest.approx(1.0 / (k + 1), rel=1e-12)
