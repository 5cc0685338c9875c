"""Aerial perspective / airlight over an image with depth (survey 5.3)."""

import numpy as np
import pytest
from typer.testing import CliRunner

import skydome as sd
from skydome.cli import app
from skydome.effects.airlight import apply_airlight

SUN = sd.Sun(elevation_deg=20.0, azimuth_deg=120.0)
DIST = np.array([[1e3, 3e3, 10e3, 30e3]])
GREY = np.full((1, 4, 3), 0.1)
# small precomputed tables (and the earlier default orders and quadrature) keep the file fast
SMALL = dict(scattering_r_size=16, scattering_mu_size=64, scattering_mu_s_size=16, orders=3, n_wavelengths=10,
             remaining_orders="none", sphere_samples=16, scattering_nu_size=8)


def _mp(method):
    return SMALL if method == "precomputed" else None


@pytest.mark.parametrize("method", ["precomputed", "preetham1999", "hillaire2020"])
def test_distant_objects_bluer_and_brighter_in_clear_air(method):
    out = apply_airlight(GREY, DIST, SUN, method=method, turbidity=2.0, fov_deg=10, model_params=_mp(method))
    br = out[0, :, 2] / out[0, :, 0]
    assert np.all(np.diff(br[:3]) > 0) and br[-1] > br[0]   # bluer with distance
    # (Preetham's airlight reddens again beyond ~10 km: its B/R at 30 km is below that at 10 km)
    assert out[0, -1].sum() > out[0, 0].sum()         # brighter with distance


@pytest.mark.parametrize("method", ["precomputed", "preetham1999", "hillaire2020"])
def test_haze_is_less_blue_than_clear_air(method):
    """Clear air: the airlight alone is bluest over short paths (Rayleigh in-scattering,
    lambda^-4: B/R > 1) and its B/R falls with distance as the blue saturates first. In
    haze (turbidity 8, wavelength-flat aerosol scattering) the distant scene loses its blue."""
    kw = dict(fov_deg=10, model_params=_mp(method), return_parts=True)
    clear, _, lc = apply_airlight(GREY, DIST, SUN, method=method, turbidity=2.0, **kw)
    hazy, _, lh = apply_airlight(GREY, DIST, SUN, method=method, turbidity=8.0, **kw)
    air_br = lc[0, :, 2] / lc[0, :, 0]
    assert np.all(air_br > 1.0) and np.all(np.diff(air_br) < 0)
    assert hazy[0, -1, 2] / hazy[0, -1, 0] < 0.7 * clear[0, -1, 2] / clear[0, -1, 0]
    assert lh[0, 0, 2] / lh[0, 0, 0] < 0.7 * air_br[0]


def test_zero_distance_and_sky_unchanged():
    img = np.random.default_rng(0).uniform(0, 1, (2, 3, 3))
    dep = np.array([[np.inf, np.inf, 0.0], [np.inf, 0.0, np.inf]])
    out = apply_airlight(img, dep, SUN, method="hoffman_preetham2002", turbidity=3.0)
    np.testing.assert_array_equal(out, img)


@pytest.mark.parametrize("method", ["precomputed", "preetham1999", "hoffman_preetham2002", "hillaire2020"])
def test_vanishing_distance_changes_nothing(method):
    """At 1 m (white balance on the sun: output in the input's units) the image is unchanged
    to 1e-3 (+ 0.3 % for the interpolated precomputed tables): Beer-Lambert T = exp(-beta s)
    with beta ~ 1e-5 m^-1 at sea level, airlight ~ beta s."""
    img = np.random.default_rng(1).uniform(0.05, 1, (2, 2, 3))
    out = apply_airlight(img, np.full((2, 2), 1.0), SUN, method=method, turbidity=3.0,
                         white_balance="sun", model_params=_mp(method))
    np.testing.assert_allclose(out, img, rtol=3e-3, atol=1e-3)


def test_white_balance_on_sun_needs_the_sun_up():
    with pytest.raises(ValueError, match="elevation_deg = -2"):
        apply_airlight(GREY, DIST, sd.Sun(elevation_deg=-2.0, azimuth_deg=120.0), method="precomputed",
                       white_balance="sun")
    with pytest.raises(ValueError, match="white_balance"):
        apply_airlight(GREY, DIST, SUN, white_balance="camera")


def test_short_distance_methods_agree_on_transmittance():
    """At 200 m every method is near Beer-Lambert with sea-level extinction: the
    transmittances lie within 0.94-1 and agree within 4 % (hillaire2020's froxel volume,
    4 km per slice, gives the highest: 0.98-0.99 against 0.95-0.975)."""
    ts = []
    for m in ("precomputed", "preetham1999", "hoffman_preetham2002", "hillaire2020"):
        _, t, _ = apply_airlight(GREY[:, :1], np.array([[200.0]]), SUN, method=m, turbidity=3.0,
                                 return_parts=True, model_params=_mp(m))
        ts.append(t[0, 0])
    ts = np.array(ts)
    assert np.all(ts > 0.94) and np.ptp(ts, axis=0).max() < 0.04


def test_cli_synthetic_and_files(tmp_path):
    r = CliRunner()
    out = tmp_path / "a.png"
    res = r.invoke(app, ["airlight", "--synthetic", "--method", "hoffman_preetham2002", "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert out.exists()
    img = np.full((4, 5, 3), 0.2)
    np.save(tmp_path / "i.npy", img)
    np.save(tmp_path / "d.npy", np.full((4, 5), 5e3))
    res = r.invoke(app, ["airlight", "--image", str(tmp_path / "i.npy"), "--depth", str(tmp_path / "d.npy"),
                         "--method", "preetham1999", "--turbidity", "3", "--out", str(tmp_path / "o.npy")])
    assert res.exit_code == 0, res.output
    assert np.load(tmp_path / "o.npy").shape == (4, 5, 3)
    res = r.invoke(app, ["airlight", "--image", str(tmp_path / "i.npy"), "--depth", str(tmp_path / "d.npy"),
                         "--method", "fog", "--out", str(tmp_path / "p.npy")])
    assert res.exit_code == 2 and "method = 'fog'" in res.output and not (tmp_path / "p.npy").exists()


# Rayleigh volume scattering coefficient of dry air at 550 nm, 288.15 K, 1013.25 hPa:
# 1.149e-5 m^-1 (Bucholtz 1995, Appl. Opt. 34, 2765; the same value follows from
# sigma = 24 pi^3 (n^2-1)^2 / (lambda^4 N^2 (n^2+2)^2) F_K with Peck & Reeder's n - 1 =
# 2.7775e-4, N = 2.547e25 m^-3 and F_K = 1.048).
BETA_R_550 = 1.149e-5


def _ext_550(method, turbidity, s):
    from skydome.transport.geometry import direction_from_angles

    kw = _mp(method) or {}
    m = sd.model(method, sun=SUN, turbidity=turbidity, **kw)
    d = np.repeat(np.asarray(direction_from_angles(0.0, 0.0))[None], len(s), axis=0)
    extra = {"use_volume": False} if method == "hillaire2020" else {}
    t, _ = m.aerial_perspective(d, np.array(s, dtype=float), np.array([550.0]), **extra)
    return -np.log(t[:, 0]) / np.asarray(s)


def test_pure_rayleigh_extinction_matches_bucholtz():
    """precomputed with turbidity 1 (no aerosol): the horizontal extinction at the ground
    is the Rayleigh coefficient of Bucholtz (1995) to 2 %, and Beer-Lambert holds
    (-ln T / s the same at 10 m and 1 km to 1 %)."""
    k = _ext_550("precomputed", 1.0, [10.0, 1000.0])
    np.testing.assert_allclose(k, BETA_R_550, rtol=0.02)
    assert abs(k[1] / k[0] - 1.0) < 0.01


@pytest.mark.parametrize("method", ["precomputed", "preetham1999", "hoffman_preetham2002", "hillaire2020"])
def test_short_paths_follow_beer_lambert_with_more_than_rayleigh(method):
    """Turbidity 2, horizontal paths of 10 m and 1 km: -ln T / s at 550 nm is constant
    (Beer-Lambert in a horizontal homogeneous layer) to 4 % (measured: 2.7 % for the small
    precomputed tables, their interpolation; < 0.5 % for the others), exceeds the Rayleigh
    coefficient of Bucholtz (1995) (aerosol adds extinction) and lies within 8 % of
    9.2e-5 m^-1, the methods' common value (measured spread 9.15-9.49e-5 m^-1)."""
    k = _ext_550(method, 2.0, [10.0, 1000.0])
    assert abs(k[1] / k[0] - 1.0) < 0.04
    assert k[0] > 1.5 * BETA_R_550
    assert abs(k[0] / 9.2e-5 - 1.0) < 0.08


def test_fill_sky_puts_the_models_sky_in_the_sky_pixels():
    """fill_sky: sky pixels get the model's sky along their rays, on the output's scale; a
    clear noon-side sky seen 2-10 deg up (precomputed tables) is blue (B/R > 1) and, on the
    fixed scale (1 = white surface under the extraterrestrial sun, E0/pi ~ 4e4 cd/m^2), the
    clear sky near the horizon is a fraction of it (~5-10 kcd/m^2 -> 0.1-0.4)."""
    img = np.full((2, 3, 3), 0.2)
    dep = np.array([[np.inf, np.inf, np.inf], [5e3, 5e3, 5e3]])
    out = apply_airlight(img, dep, SUN, method="preetham1999", turbidity=2.0, fov_deg=20,
                         view_elevation_deg=5.0, fill_sky=True)
    sky = out[0]
    assert np.all(sky[:, 2] > sky[:, 0])
    y = sky @ np.array([0.2126, 0.7152, 0.0722])
    assert np.all((y > 0.05) & (y < 0.6))
    kept = apply_airlight(img, dep, SUN, method="preetham1999", turbidity=2.0, fov_deg=20,
                          view_elevation_deg=5.0)
    np.testing.assert_array_equal(kept[0], img[0])
    np.testing.assert_array_equal(kept[1], out[1])          # objects are unaffected
    with pytest.raises(ValueError, match="fill_sky"):
        apply_airlight(img, dep, SUN, method="dobashi2002", fill_sky=True)
