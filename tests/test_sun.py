"""Tests of skydome.sun: time parsing, solar position, Earth-sun distance, irradiance.

Oracles:
- Reda & Andreas 2004 (NREL/TP-560-34302), the SPA paper's worked example (table A5.1).
- Astronomy: the noon elevation at the June solstice is 90 - |lat - eps| with eps the
  obliquity of the ecliptic of date, 23.4358 deg (IAU 2006 mean obliquity for 2026.47)
  + 0.0023 deg (IAU 1980 nutation in obliquity, 9.2" cos(Omega), Omega = -27 deg).
- IMCCE (Paris Observatory) apsides: perihelion 4 January 2006 15 h UTC at
  0.983326979 au; aphelion 6 July 2007 23:52 UTC at 1.01670594 au.
- pvlib's SPA (an independent program) for the Preetham 1999 formula over a whole year,
  for SPA's refraction increment and for SPA's radius vector.
"""

from __future__ import annotations

import subprocess
import sys
from datetime import datetime, timedelta, timezone

import numpy as np
import pytest

from skydome.sun import (SOLAR_CONSTANT_W_M2, Sun, earth_sun_distance,
                         extraterrestrial_irradiance, parse_time, solar_position)

pvlib = pytest.importorskip("pvlib")

UTC = timezone.utc


# -- parse_time ------------------------------------------------------------------------------
@pytest.mark.parametrize("text", ["2026-06-21T20:45+02:00", "2026-06-21T18:45Z",
                                  "2026-06-21 20:45+02:00", " 2026-06-21T13:45:00-05:00 ",
                                  "2026-06-21T18:45:00.000+00:00"])
def test_parse_time_good(text):
    t = parse_time(text)
    assert t.tzinfo is not None
    assert t == datetime(2026, 6, 21, 18, 45, tzinfo=UTC)


def test_parse_time_keeps_offset_and_accepts_aware_datetimes():
    t = parse_time("2026-06-21T20:45+02:00")
    assert t.utcoffset() == timedelta(hours=2)
    aware = datetime(2026, 1, 1, 12, tzinfo=timezone(timedelta(hours=-8)))
    assert parse_time(aware) == aware
    pd = pytest.importorskip("pandas")
    ts = pd.Timestamp("2026-06-21T18:45Z")
    assert parse_time(ts) == datetime(2026, 6, 21, 18, 45, tzinfo=UTC)


@pytest.mark.parametrize("text", ["yesterday noon", "2026-13-01T00:00Z", "", "21/06/2026 12:00",
                                  "2026-06-21T25:00Z"])
def test_parse_time_bad_strings(text):
    with pytest.raises(ValueError) as err:
        parse_time(text)
    msg = str(err.value)
    assert msg.startswith(f"time = {text!r} is not an ISO 8601 time")
    assert "2026-06-21T20:45+02:00" in msg  # gives an example


@pytest.mark.parametrize("value", ["2026-06-21T12:00", "2026-06-21", datetime(2026, 6, 21, 12)])
def test_parse_time_refuses_naive_times(value):
    with pytest.raises(ValueError, match=r"^time = .* has no UTC offset"):
        parse_time(value)


@pytest.mark.parametrize("value", [12, 1.5, None])
def test_parse_time_bad_types(value):
    with pytest.raises(TypeError, match="time must be"):
        parse_time(value)


# -- validation ------------------------------------------------------------------------------
@pytest.mark.parametrize("kw, match", [
    (dict(lat_deg=91.0), r"lat_deg = 91 deg is out of range \[-90, 90\]"),
    (dict(lat_deg=-90.5), r"lat_deg = -90.5 deg is out of range"),
    (dict(lon_deg=181.0), r"lon_deg = 181 deg is out of range \[-180, 180\]"),
    (dict(lon_deg=float("nan")), r"lon_deg = nan is not a finite number"),
    (dict(method="meeus"), r"method = 'meeus' is not one of 'spa', 'preetham1999'"),
    (dict(pressure_pa=-1.0), r"pressure_pa = -1 Pa is out of range"),
    (dict(time="noonish"), r"^time = 'noonish' is not an ISO 8601 time"),
])
def test_solar_position_validation(kw, match):
    args = dict(lat_deg=48.0, lon_deg=16.0, time="2026-06-21T12:00Z")
    args.update(kw)
    with pytest.raises(ValueError, match=match):
        solar_position(**args)


def test_from_location_validation():
    with pytest.raises(ValueError, match="lat_deg = 95"):
        Sun.from_location(95.0, 0.0, "2026-06-21T12:00Z")
    with pytest.raises(ValueError, match="method = 'nrel'"):
        Sun.from_location(45.0, 0.0, "2026-06-21T12:00Z", method="nrel")
    with pytest.raises(TypeError, match="unexpected keyword"):
        Sun.from_location(45.0, 0.0, "2026-06-21T12:00Z", altitude=3.0)


def test_sun_constructor_still_works():
    s = Sun(30.0, 180.0)
    assert (s.elevation_deg, s.azimuth_deg, s.distance_au) == (30.0, 180.0, 1.0)
    assert s.latitude_deg is None and s.time is None
    s2 = Sun(10.0, -90.0, 0.3, 1.01)
    assert s2.azimuth_deg == 270.0 and s2.angular_radius_deg == 0.3
    assert s2.irradiance_scale == pytest.approx(1.0 / 1.01**2, rel=1e-15)


def test_import_does_not_load_pvlib_or_pandas():
    code = "import sys, skydome.sun; print(sorted(m for m in ('pvlib', 'pandas') if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


# -- SPA -------------------------------------------------------------------------------------
def test_spa_reda_andreas_2004_example():
    # Reda & Andreas 2004, appendix A.5: 17 October 2003, 12:30:30 local time (UTC-7),
    # lat 39.742476, lon -105.1786, elevation 1830.14 m, 820 mbar, 11 C, delta_t 67 s,
    # atmos_refract 0.5667 deg -> topocentric zenith 50.11162 deg, azimuth 194.34024 deg.
    elev, az = solar_position(39.742476, -105.1786, "2003-10-17T12:30:30-07:00", method="spa",
                              altitude_m=1830.14, pressure_pa=82000.0, temperature_c=11.0,
                              refraction=True, delta_t_s=67.0)
    assert 90.0 - elev == pytest.approx(50.11162, abs=1e-4)
    assert az == pytest.approx(194.34024, abs=1e-4)
    s = Sun.from_location(39.742476, -105.1786, "2003-10-17T12:30:30-07:00", altitude_m=1830.14,
                          pressure_pa=82000.0, temperature_c=11.0, refraction=True, delta_t_s=67.0)
    assert s.zenith_deg == pytest.approx(50.11162, abs=1e-4)
    assert s.azimuth_deg == pytest.approx(194.34024, abs=1e-4)
    assert s.latitude_deg == 39.742476 and s.longitude_deg == -105.1786
    assert s.time == datetime(2003, 10, 17, 19, 30, 30, tzinfo=UTC)
    # Reda & Andreas 2004 table A5.1: Earth radius vector R = 0.9965422974 au
    assert s.distance_au == pytest.approx(0.9965422974, abs=1e-6)


OBLIQUITY_2026_DEG = 23.4358 + 0.0023  # see the module docstring


def _noon_scan(lat, method):
    """Highest elevation on 2026-06-21 at lon 0, sampling 11:40-12:20 UTC every 15 s."""
    t0 = datetime(2026, 6, 21, 11, 40, tzinfo=UTC)
    times = [t0 + timedelta(seconds=15 * i) for i in range(161)]
    elev, _ = solar_position(lat, 0.0, times, method=method)
    return elev.max()


@pytest.mark.parametrize("lat", [-60.0, -30.0, 0.0, 10.0, 48.0, 60.0, 80.0])
def test_solstice_noon_elevation_spa(lat):
    expected = 90.0 - abs(lat - OBLIQUITY_2026_DEG)
    # SPA is topocentric: parallax lowers the sun by up to 8.8" = 0.0024 deg.
    assert _noon_scan(lat, "spa") == pytest.approx(expected, abs=0.006)


@pytest.mark.parametrize("lat", [-60.0, 0.0, 48.0, 80.0])
def test_solstice_noon_elevation_preetham(lat):
    expected = 90.0 - abs(lat - OBLIQUITY_2026_DEG)
    assert _noon_scan(lat, "preetham1999") == pytest.approx(expected, abs=0.02)


def test_refraction_raises_sun_and_matches_spa_increment():
    t = "2026-03-20T08:00+01:00"  # morning sun about 20 deg up in Vienna
    g_spa = solar_position(48.21, 16.37, t, "spa")[0]
    a_spa = solar_position(48.21, 16.37, t, "spa", refraction=True)[0]
    g_pr = solar_position(48.21, 16.37, t, "preetham1999")[0]
    a_pr = solar_position(48.21, 16.37, t, "preetham1999", refraction=True)[0]
    assert 0.03 < a_spa - g_spa < 0.06   # about 2.7' at 19 deg (Saemundsson 1986)
    assert a_pr - g_pr == pytest.approx(a_spa - g_spa, abs=2e-3)


# -- Preetham 1999 against SPA over a year ---------------------------------------------------
def _unit(elev_deg, az_deg):
    e = np.radians(elev_deg)
    a = np.radians(az_deg)
    return np.stack([np.cos(e) * np.sin(a), np.cos(e) * np.cos(a), np.sin(e)], axis=-1)


# Bounds measured over 2026 (docs/sections/sun.md): elevation 1.04 deg, angle 1.08 deg.
MAX_ELEVATION_DIFF_DEG = 1.1
MAX_ANGLE_DIFF_DEG = 1.15


def test_preetham_against_spa_whole_year():
    worst_e = worst_a = 0.0
    # (longitude, UTC offset of the local standard time): San Francisco, Vienna, Tokyo
    places = [(-122.42, -8), (16.37, 1), (139.69, 9)]
    for lat in (-60.0, -30.0, 0.0, 30.0, 48.0, 60.0):
        for lon, off in places:
            tz = timezone(timedelta(hours=off))
            t0 = datetime(2026, 1, 1, tzinfo=tz)
            times = [t0 + timedelta(hours=3 * i) for i in range(365 * 8)]
            e_p, a_p = solar_position(lat, lon, times, method="preetham1999")
            e_s, a_s = solar_position(lat, lon, times, method="spa")
            de = np.abs(e_p - e_s)
            cosang = np.clip(np.sum(_unit(e_p, a_p) * _unit(e_s, a_s), axis=-1), -1.0, 1.0)
            ang = np.degrees(np.arccos(cosang))
            worst_e = max(worst_e, de.max())
            worst_a = max(worst_a, ang.max())
            # the azimuth is in the right quadrant whenever the sun is up and away from the
            # zenith (near the zenith a small angular error is a large azimuth error)
            up = (e_s > 5.0) & (e_s < 75.0)
            daz = (a_p[up] - a_s[up] + 180.0) % 360.0 - 180.0
            assert np.all(np.abs(daz) < 2.0)  # measured 1.5 deg
    assert worst_e < MAX_ELEVATION_DIFF_DEG
    assert worst_a < MAX_ANGLE_DIFF_DEG
    assert worst_e > 0.3  # the approximation is visibly coarser than SPA (not SPA by mistake)


def test_array_and_scalar_agree():
    times = ["2026-06-21T06:00+02:00", "2026-06-21T13:00+02:00", "2026-12-21T12:00+01:00"]
    for method in ("spa", "preetham1999"):
        e, a = solar_position(48.21, 16.37, times, method=method)
        assert e.shape == a.shape == (3,)
        for i, t in enumerate(times):
            assert (e[i], a[i]) == pytest.approx(solar_position(48.21, 16.37, t, method=method),
                                                 abs=1e-9)


# -- distance and irradiance -----------------------------------------------------------------
def test_distance_perihelion_and_aphelion_spa():
    # IMCCE: perihelion 2006-01-04 15 h UTC 0.983326979 au, aphelion 2007-07-06 23:52 UTC
    # 1.01670594 au
    peri = Sun.from_location(0.0, 0.0, "2006-01-04T15:00Z")
    aph = Sun.from_location(0.0, 0.0, "2007-07-06T23:52Z")
    assert peri.distance_au == pytest.approx(0.983326979, abs=1e-5)
    assert aph.distance_au == pytest.approx(1.01670594, abs=1e-5)


def test_distance_perihelion_and_aphelion_spencer():
    # Spencer's series departs from SPA by up to 5.6e-4 au over a year (measured, docs).
    peri = Sun.from_location(0.0, 0.0, "2006-01-04T15:00Z", method="preetham1999")
    aph = Sun.from_location(0.0, 0.0, "2007-07-06T23:52Z", method="preetham1999")
    assert peri.distance_au == pytest.approx(0.983326979, abs=6e-4)
    assert aph.distance_au == pytest.approx(1.01670594, abs=6e-4)
    days = np.arange(1.0, 366.0, 0.25)
    d = earth_sun_distance([datetime(2026, 1, 1, tzinfo=UTC) + timedelta(days=x - 1) for x in days],
                           method="preetham1999")
    assert days[np.argmin(d)] == pytest.approx(3.7, abs=2.0)     # perihelion early January
    assert days[np.argmax(d)] == pytest.approx(187.7, abs=3.0)   # aphelion early July


def test_extraterrestrial_irradiance():
    assert SOLAR_CONSTANT_W_M2 == 1361.1  # Gueymard 2018
    # time -> SPA distance; IMCCE apsides (module docstring)
    e_peri = extraterrestrial_irradiance("2006-01-04T15:00Z")
    assert e_peri == pytest.approx(1361.1 / 0.983326979**2, rel=2e-5)
    e_aph = extraterrestrial_irradiance(datetime(2007, 7, 6, 23, 52, tzinfo=UTC))
    assert e_aph == pytest.approx(1361.1 / 1.01670594**2, rel=2e-5)
    # day of year -> Spencer; yearly mean of (r0/r)^2 is 1/sqrt(1 - e^2) = 1.00014 (e = 0.0167)
    days = np.arange(1.0, 366.0, 0.5)
    e_days = extraterrestrial_irradiance(days)
    assert e_days.mean() / 1361.1 == pytest.approx(1.00014, abs=5e-5)
    assert extraterrestrial_irradiance(4.6) == pytest.approx(1361.1 / 0.983326979**2, rel=1.5e-3)
    s = Sun.from_location(0.0, 0.0, "2006-01-04T15:00Z")
    assert s.extraterrestrial_irradiance == pytest.approx(e_peri, rel=1e-12)
    assert s.irradiance_scale == pytest.approx(1.0 / s.distance_au**2, rel=1e-15)
    with pytest.raises(ValueError, match="time_or_day_of_year = 0"):
        extraterrestrial_irradiance(0)
    with pytest.raises(ValueError, match="not an ISO 8601 time"):
        extraterrestrial_irradiance("Jan 3")
    with pytest.raises(TypeError):
        extraterrestrial_irradiance(True)


def test_sun_below_horizon_at_night():
    s = Sun.from_location(48.21, 16.37, "2026-12-21T00:00+01:00")
    assert s.elevation_deg < -60.0   # local midnight in winter: about -65 deg
    assert 0.0 <= s.azimuth_deg < 360.0
