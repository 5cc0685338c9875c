"""Twilight (survey 5.2) with the precomputed multiple-scattering sky."""

import numpy as np
import pytest
from typer.testing import CliRunner

from skydome.cli import app
from skydome.apps.twilight import horizon_views
from skydome.effects.twilight import (anti_solar_profile, belt_of_venus, horizontal_illuminance,
                                      twilight_models, zenith_luminance_curve)

# 32 mu_s nodes of the sunset-centred mapping give every twilight band at least the cells of
# the 16 nodes of Bruneton's mapping these tests were written with
SMALL = dict(scattering_r_size=16, scattering_mu_size=64, scattering_mu_s_size=32, orders=3,
             n_wavelengths=10, remaining_orders="none", sphere_samples=16, scattering_nu_size=8)


@pytest.fixture(scope="module")
def skies():
    deps = [0.0, 2.0, 4.0, 6.0, 9.0, 12.0, 15.0, 18.0, 19.0]
    return deps, twilight_models("precomputed", deps, **SMALL)


def test_zenith_luminance_falls_monotonically_by_four_orders(skies):
    """The zenith dims monotonically with depression, by more than 10^4 from 0 to -12 deg;
    below -18 deg the model's night level is 0 (airglow and starlight not modelled)."""
    deps, sk = skies
    wl = np.linspace(400, 700, 10)
    from skydome.spectra import spectrum_to_xyz

    z = np.array([spectrum_to_xyz(s.radiance(np.array([0, 0, 1.0]), wl), wl)[1] for s in sk])
    assert np.all(np.diff(z[:-1]) < 0)
    assert z[deps.index(0.0)] / z[deps.index(12.0)] > 1e4
    assert z[-1] == 0.0


def test_zenith_luminance_curve_orders_of_magnitude():
    """zenith_luminance_curve: at sunset of order 10^2 cd/m^2 (10^2-10^3 is the usual range
    for a clear sky); at -12 deg of order 10^-3 (above the natural night sky's ~2.5e-4
    cd/m^2, V = 21.6 mag/arcsec^2, Patat 2003, A&A 400, 1183, by > 1 magnitude as Patat et
    al. 2006, A&A 455, 385 found between -12 and -18 deg); at -18 deg below that night level."""
    z = zenith_luminance_curve("precomputed", [0.0, 12.0, 18.0], wavelengths_nm=np.linspace(400, 700, 10),
                               **SMALL)
    assert 30.0 < z[0] < 1000.0
    assert 2.5e-4 * 10 ** 0.4 < z[1] < 2e-2
    assert 0.0 < z[2] < 2.5e-4


def test_horizon_views_look_both_ways():
    sun_side, anti = horizon_views(32, 270.0)
    d0, m0 = sun_side.directions()
    d1, m1 = anti.directions()
    c = (8, 16)
    assert d0[c][0] < -0.8 and d1[c][0] > 0.8            # west (sun) and east (anti-sun)
    assert d0[0, 16, 2] > d0[-1, 16, 2]                  # image top towards the zenith
    assert -0.2 < d1[-1, 16, 2] < 0.0                    # horizon just above the bottom edge


def test_illuminance_order_of_magnitude_at_end_of_civil_twilight(skies):
    """Horizontal illuminance at sun -6 deg: of order 1-10 lx (about 3 lx is the usual
    figure for the end of civil twilight); the model gives 5-6 lx with the default tables."""
    deps, sk = skies
    e6 = horizontal_illuminance(sk[deps.index(6.0)], np.linspace(400, 700, 10), n_mu=40, n_phi=24)
    assert 1.0 < e6 < 20.0


@pytest.fixture(scope="module")
def default_skies():
    """The default tables (10 wavelengths) at sun -2 and -4 deg. On the small tables, with
    single scattering integrated at the observer (the default), the multiply scattered
    horizon at sun -4 deg is the reddest part of the anti-solar profile (R/B 0.444 at 2 deg),
    so ``belt_of_venus`` finds no belt there: the belt's test needs the default tables'
    orders >= 2."""
    return [2.0, 4.0], twilight_models("precomputed", [2.0, 4.0], n_wavelengths=10)


@pytest.mark.parametrize("depression", [2.0, 4.0])
def test_belt_of_venus_above_earth_shadow(default_skies, depression):
    """Sun 2 and 4 deg below the horizon: opposite the sun, a redder band (the Belt of Venus,
    maximum R/B) lies above a bluer, darker band on the horizon (the earth's shadow), as
    measured by hyperspectral imaging of clear civil twilights (R. L. Lee, "Measuring and
    modeling twilight's Belt of Venus", Appl. Opt. 54(4), B194-B203, 2015: a reddish band
    above the antisolar horizon over the bluish-grey, darker earth's shadow). Measured
    with the default tables: belt 8.5 and 18.5 deg, R/B contrast 0.29 and 0.12, shadow top
    5.5 and 11.5 deg."""
    deps, sk = default_skies
    el = np.arange(0.5, 30.0, 0.5)
    lum, rb = anti_solar_profile(sk[deps.index(depression)], el, np.linspace(400, 700, 10))
    b = belt_of_venus(el, rb, lum)
    assert b["found"] and 3.0 < b["belt_deg"] < 20.0
    assert b["contrast"] > 0.1                                   # belt redder than the shadow
    assert 0.5 < b["shadow_top_deg"] < b["belt_deg"]             # shadow under the belt
    assert b["shadow_luminance"] < 0.8 * b["belt_luminance"]     # and darker


def test_no_belt_in_a_uniform_profile():
    """A profile with constant colour has no Belt of Venus (found is False)."""
    el = np.arange(0.5, 30.0, 0.5)
    assert not belt_of_venus(el, np.full(el.shape, 0.6))["found"]


def test_no_belt_where_the_redness_still_rises_at_the_top():
    """A profile bluer near the horizon whose R/B rises to the top of the profile (as the
    default sky's at sun -6 deg: 0.14 at the shadow, 0.23 at 39 deg) has no band: its maximum
    is the profile's end, so no belt is found; the same profile with a maximum inside it and
    falling above (a band) is one."""
    el = np.arange(0.5, 40.1, 0.5)
    rising = 0.14 + 0.09 * (el / 40.0)
    assert not belt_of_venus(el, rising)["found"]
    band = 0.14 + 0.09 * np.exp(-((el - 12.0) / 6.0) ** 2)
    b = belt_of_venus(el, band)
    assert b["found"] and b["belt_deg"] == 12.0


def test_belt_of_venus_rejects_profile_without_data():
    with pytest.raises(ValueError, match="elevations_deg"):
        belt_of_venus([0.5, 1.0], [1.0, 1.0])


def test_cli_twilight(tmp_path):
    out = tmp_path / "tw"
    res = CliRunner().invoke(app, ["twilight", "--step", "9", "--size", "24", "--wavelengths", "6",
                                   "--scattering-r-size", "8", "--scattering-mu-size", "32",
                                   "--scattering-mu-s-size", "8", "--orders", "2", "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert (out / "twilight.csv").exists() and (out / "contact_sheet.png").exists()
    assert (out / "horizon_sheet.png").exists() and (out / "horizon_sun_minus_090.png").exists()
    assert "sun  -9.00 deg" in res.output
    head = (out / "twilight.csv").read_text().splitlines()
    assert head[0].startswith("sun_elevation_deg,zenith_luminance_cd_m2") and len(head) == 4
    res = CliRunner().invoke(app, ["twilight", "--step", "20", "--out", str(tmp_path / "x")])
    assert res.exit_code == 2 and "step = 20" in res.output
    res = CliRunner().invoke(app, ["twilight", "--exposure", "fixed", "--out", str(tmp_path / "y")])
    assert res.exit_code == 2 and "exposure = 'fixed'" in res.output


@pytest.mark.parametrize("exposure", ["one", "ramp"])
def test_twilight_frames_darken_frame_by_frame(tmp_path, exposure):
    # one exposure (or the 80 % ramp) for the whole sequence: the sky's luminance falls
    # with the sun's depression, so every frame is darker than the one before
    from PIL import Image

    from skydome.apps.twilight import run_twilight
    from skydome.spectra import srgb_decode

    run_twilight(tmp_path / "tw", step_deg=3.0, size=24, wavelengths=6, exposure=exposure,
                 scattering_r_size=8, scattering_mu_size=32, scattering_mu_s_size=8, orders=2)
    frames = sorted((tmp_path / "tw").glob("frame_sun_minus_*.png"))
    assert len(frames) >= 4
    lin = [srgb_decode(np.asarray(Image.open(f), dtype=float) / 255.0) for f in frames]
    mean = [a.mean() for a in lin]
    if exposure == "ramp":
        # the ramp follows the log-average luminance (the automatic exposure's statistic):
        # the frames' log-average display value falls frame by frame
        logavg = [np.exp(np.mean(np.log(a[a > 0] + 1e-6))) for a in lin]
        assert np.all(np.diff(logavg) < 0), logavg
        assert np.all(np.diff(mean)[:3] < 0), mean
    else:  # deep twilight may round to black at the first frame's exposure
        assert np.all(np.diff(mean) <= 0) and np.all(np.diff(mean)[:3] < 0), mean
