"""The sun: its position (given, or from place and time) and its disc.

``Sun(elevation_deg, azimuth_deg)`` places the sun directly; ``Sun.from_location(lat, lon,
time)`` computes its position with NREL's SPA (Reda & Andreas 2004, through pvlib) or with
the Preetham et al. 1999 appendix formula. Azimuth is measured from north towards east.

Importing this module does not import pvlib or pandas: they are imported inside the
functions that need them (method ``"spa"``).

References
----------
.. [RA04] I. Reda, A. Andreas, "Solar position algorithm for solar radiation
   applications", Solar Energy 76(5), 577-589 (2004); NREL/TP-560-34302 (rev. 2008).
.. [PSS99] A. J. Preetham, P. Shirley, B. Smits, "A practical analytic model for
   daylight", SIGGRAPH 99, 91-100 (1999), appendix A.6.
.. [Spe71] J. W. Spencer, "Fourier series representation of the position of the sun",
   Search 2(5), 172 (1971).
.. [Gue18] C. A. Gueymard, "A reevaluation of the solar constant based on a 42-year total
   solar irradiance time series and a reconciliation of spaceborne observations",
   Solar Energy 168, 2-9 (2018).
.. [KL11] G. Kopp, J. L. Lean, "A new, lower value of total solar irradiance: evidence
   and climate significance", Geophys. Res. Lett. 38, L01706 (2011).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import date, datetime, timezone
from typing import Any

import numpy as np

from skydome._validate import check_choice, check_number
from skydome.constants import SOLAR_CONSTANT_GUEYMARD2018, SPA_SUN_RADIUS_DEG, SUN_ANGULAR_RADIUS_DEG

__all__ = [
    "Sun",
    "parse_time",
    "solar_position",
    "earth_sun_distance",
    "extraterrestrial_irradiance",
    "SOLAR_POSITION_METHODS",
    "SOLAR_CONSTANT_W_M2",
    "eccentricity_correction_spencer1971",
    "sun_from_options",
]

#: Solar position algorithms understood by :func:`solar_position`.
SOLAR_POSITION_METHODS = ("spa", "preetham1999")

#: Total solar irradiance at 1 au [W/m^2]: 1361.1 +- 0.5 W/m^2 [Gue18], consistent with
#: the 1360.8 +- 0.5 W/m^2 of SORCE/TIM at solar minimum [KL11].
SOLAR_CONSTANT_W_M2 = SOLAR_CONSTANT_GUEYMARD2018

_TIME_EXAMPLE = "e.g. '2026-06-21T20:45+02:00' or '2026-06-21T18:45Z'"


# -- time ------------------------------------------------------------------------------------
def parse_time(value: Any, name: str = "time") -> datetime:
    """Return a timezone-aware :class:`datetime.datetime` for an ISO 8601 time.

    Parameters
    ----------
    value : str or datetime.datetime
        An ISO 8601 date and time with a UTC offset or ``Z``, e.g.
        ``"2026-06-21T20:45+02:00"``, ``"2026-06-21T18:45Z"`` or
        ``"2026-06-21 20:45+02:00"`` (a space may replace the ``T``), or a timezone-aware
        ``datetime`` (pandas ``Timestamp`` included).
    name : str
        Parameter name used in error messages.

    Returns
    -------
    datetime.datetime
        The same instant, with its UTC offset kept (local clock time is what the
        Preetham formula needs).

    Raises
    ------
    ValueError
        If the string is not an ISO 8601 time, or the time has no UTC offset (a naive
        time is ambiguous by up to a day of solar position).
    TypeError
        For any other type.
    """
    if isinstance(value, str):
        text = value.strip()
        try:
            t = datetime.fromisoformat(text)
        except ValueError:
            raise ValueError(f"{name} = {value!r} is not an ISO 8601 time; give a date, time "
                             f"and UTC offset, {_TIME_EXAMPLE}") from None
        if t.tzinfo is None or t.utcoffset() is None:
            raise ValueError(f"{name} = {value!r} has no UTC offset; add one, {_TIME_EXAMPLE}")
        return t
    if isinstance(value, datetime):
        to_py = getattr(value, "to_pydatetime", None)  # pandas.Timestamp
        t = to_py() if callable(to_py) else value
        if t.tzinfo is None or t.utcoffset() is None:
            raise ValueError(f"{name} = {value} has no UTC offset; give a timezone-aware "
                             f"datetime or an ISO 8601 string, {_TIME_EXAMPLE}")
        return t
    if isinstance(value, date):
        raise ValueError(f"{name} = {value} has no time of day and no UTC offset; "
                         f"{_TIME_EXAMPLE}")
    raise TypeError(f"{name} must be an ISO 8601 string or a timezone-aware datetime, got "
                    f"{value!r} ({type(value).__name__})")


def _parse_times(time: Any, name: str = "time") -> tuple[list[datetime], bool]:
    """Parse one time or a sequence of times; return (list of datetimes, is_scalar)."""
    if isinstance(time, (str, datetime, date)):
        return [parse_time(time, name)], True
    try:
        items = list(time)
    except TypeError:
        parse_time(time, name)  # raises TypeError naming the parameter
        raise
    if not items:
        raise ValueError(f"{name} is an empty sequence")
    return [parse_time(t, f"{name}[{i}]") for i, t in enumerate(items)], False


def _utc_index(times: list[datetime]):
    import pandas as pd

    return pd.DatetimeIndex([t.astimezone(timezone.utc) for t in times])


# -- position --------------------------------------------------------------------------------
def solar_position(lat_deg: float, lon_deg: float, time: Any, method: str = "spa",
                   altitude_m: float = 0.0, pressure_pa: float = 101325.0,
                   temperature_c: float = 12.0, refraction: bool = False,
                   delta_t_s: float | None = None):
    """Elevation and azimuth of the sun's centre for a place and time.

    Parameters
    ----------
    lat_deg : float
        Geodetic latitude [deg], north positive, in [-90, 90].
    lon_deg : float
        Longitude [deg], east positive, in [-180, 180].
    time : str, datetime or sequence of them
        ISO 8601 time(s) with UTC offset, or timezone-aware datetime(s); see
        :func:`parse_time`. A sequence gives arrays.
    method : {"spa", "preetham1999"}
        ``"spa"``: NREL Solar Position Algorithm [RA04] through
        ``pvlib.solarposition.spa_python`` (uncertainty +-0.0003 deg, years -2000 to
        6000); topocentric, i.e. it includes the parallax of the observer.
        ``"preetham1999"``: the closed-form approximation of [PSS99] appendix A.6
        (declination and equation of time from short sine series; see the Notes).
    altitude_m : float
        Observer height above sea level [m], in [-1000, 100000] (``"spa"`` only; the
        Preetham formula ignores it).
    pressure_pa : float
        Air pressure at the observer [Pa], in [0, 500000]; used by the refraction
        correction only.
    temperature_c : float
        Air temperature at the observer [deg C], in [-100, 100]; refraction only.
    refraction : bool
        False (default): geometric (true) elevation, the one sky models use.
        True: apparent elevation, raised by atmospheric refraction ([RA04] eq. 42 with
        ``atmos_refract = 0.5667`` deg; the same formula is applied to the Preetham
        elevation).
    delta_t_s : float or None
        TT - UT1 [s], in [-8000, 8000] (``"spa"`` only). None: pvlib's estimate for the
        year and month (Espenak & Meeus polynomials), about 69 s in 2026.

    Returns
    -------
    elevation_deg, azimuth_deg : float or ndarray
        Elevation above the horizon [deg] (negative below it) and azimuth from north
        towards east [deg] in [0, 360).

    Notes
    -----
    Preetham et al. write longitude ``L`` and standard meridian ``SM`` positive towards
    the west, in radians; this function converts the user's east-positive longitude
    and the time's UTC offset (hours east of Greenwich): ``L = -lon``,
    ``SM = -15 deg x offset``. ``t_s`` is the local clock time of the given time in
    decimal hours and ``J`` its local day of the year (1..366). The printed azimuth
    formula has a sign error and loses the quadrant (``atan``); we use the form of the
    implementations of the same appendix (Utah rtrt ``SunSky``, Mitsuba 0.x: ``atan2``
    with the sign fixed), which is standard spherical trigonometry, and turn its
    south-based angle into an azimuth from north towards east.

    References
    ----------
    [RA04], [PSS99] appendix A.6.
    """
    lat = check_number("lat_deg", lat_deg, -90.0, 90.0, "deg")
    lon = check_number("lon_deg", lon_deg, -180.0, 180.0, "deg")
    check_choice("method", method, SOLAR_POSITION_METHODS)
    alt = check_number("altitude_m", altitude_m, -1000.0, 100000.0, "m")
    p = check_number("pressure_pa", pressure_pa, 0.0, 500000.0, "Pa")
    temp = check_number("temperature_c", temperature_c, -100.0, 100.0, "deg C")
    if not isinstance(refraction, (bool, np.bool_)):
        raise TypeError(f"refraction must be True or False, got {refraction!r}")
    if delta_t_s is not None:
        delta_t_s = check_number("delta_t_s", delta_t_s, -8000.0, 8000.0, "s")
    times, scalar = _parse_times(time)

    if method == "spa":
        for i, t in enumerate(times):
            if t.astimezone(timezone.utc).year > 6000:
                raise ValueError(f"time = {t.isoformat()} is out of SPA's range of years "
                                 f"[-2000, 6000]")
        elev, az = _spa_position(lat, lon, times, alt, p, temp, bool(refraction), delta_t_s)
    else:
        elev, az = _preetham_position(lat, lon, times)
        if refraction:
            elev = elev + _refraction_deg(elev, p, temp)
    if scalar:
        return float(elev[0]), float(az[0])
    return elev, az


def _spa_position(lat, lon, times, altitude_m, pressure_pa, temperature_c, refraction,
                  delta_t_s):
    from pvlib.solarposition import spa_python  # lazy: pvlib and pandas are heavy

    df = spa_python(_utc_index(times), lat, lon, altitude=altitude_m, pressure=pressure_pa,
                    temperature=temperature_c, delta_t=delta_t_s, atmos_refract=0.5667,
                    how="numpy")
    key = "apparent_elevation" if refraction else "elevation"
    elev = np.asarray(df[key], dtype=np.float64)
    az = np.asarray(df["azimuth"], dtype=np.float64) % 360.0  # [RA04] eq. 46: from north, east
    return elev, az


def _local_time_parts(times: list[datetime]):
    """Local decimal hour t_s, day of year J and UTC offset [h] of each time."""
    n = len(times)
    ts = np.empty(n)
    day = np.empty(n)
    off = np.empty(n)
    for i, t in enumerate(times):
        ts[i] = t.hour + t.minute / 60.0 + (t.second + t.microsecond * 1e-6) / 3600.0
        day[i] = t.timetuple().tm_yday
        off[i] = t.utcoffset().total_seconds() / 3600.0
    return ts, day, off


def _preetham_position(lat_deg, lon_deg, times):
    ts, J, offset_h = _local_time_parts(times)
    # [PSS99] A.6 writes longitude and standard meridian west-positive, in radians.
    L = np.radians(-lon_deg)                # longitude, west positive
    SM = np.radians(-15.0 * offset_h)       # standard meridian of the clock time, west positive
    l = np.radians(lat_deg)                 # latitude
    # [PSS99] A.6: solar time [h]
    t = (ts + 0.170 * np.sin(4.0 * np.pi * (J - 80.0) / 373.0)
         - 0.129 * np.sin(2.0 * np.pi * (J - 8.0) / 355.0) + 12.0 * (SM - L) / np.pi)
    # [PSS99] A.6: solar declination [rad]
    d = 0.4093 * np.sin(2.0 * np.pi * (J - 81.0) / 368.0)
    w = np.pi * t / 12.0
    sin_e = np.sin(l) * np.sin(d) - np.cos(l) * np.cos(d) * np.cos(w)
    # [PSS99] A.6: theta_s = pi/2 - asin(sin l sin d - cos l cos d cos(pi t/12))
    elev = np.degrees(np.arcsin(np.clip(sin_e, -1.0, 1.0)))
    # [PSS99] A.6: phi_s = atan(-cos d sin(pi t/12) / (cos l sin d - sin l cos d cos(pi t/12)))
    # as printed has a sign error and loses the quadrant. Implementations of the appendix
    # (Utah rtrt SunSky, Mitsuba 0.x sun/sky) use
    # atan2(-cos d sin(pi t/12), -(cos l sin d + sin l cos d cos(pi t/12))), an angle from
    # south measured towards west, which is the spherical-trigonometry result. We use it.
    opp = -np.cos(d) * np.sin(w)
    adj = -(np.cos(l) * np.sin(d) + np.sin(l) * np.cos(d) * np.cos(w))
    from_south_west = np.degrees(np.arctan2(opp, adj))
    az = (180.0 + from_south_west) % 360.0   # from north towards east
    return elev, az


def _refraction_deg(elev_deg, pressure_pa, temperature_c, atmos_refract=0.5667):
    """Atmospheric refraction [deg] to add to a true elevation ([RA04] eq. 42).

    Zero when the sun is below -(0.26667 + atmos_refract) deg, as in SPA.
    """
    e0 = np.asarray(elev_deg, dtype=np.float64)
    p_mbar = pressure_pa / 100.0
    with np.errstate(invalid="ignore", divide="ignore"):
        de = (p_mbar / 1010.0) * (283.0 / (273.0 + temperature_c)) * 1.02 / (
            60.0 * np.tan(np.radians(e0 + 10.3 / (e0 + 5.11))))
    return np.where(e0 >= -(SPA_SUN_RADIUS_DEG + atmos_refract), de, 0.0)


# -- distance and irradiance -----------------------------------------------------------------
def eccentricity_correction_spencer1971(day_of_year) -> np.ndarray:
    """Earth-sun distance factor E0 = (r0 / r)^2 [-] from Spencer's Fourier series [Spe71].

    ``day_of_year`` 1..366 (day 0 gives the value of day 365: the series is periodic).
    The one home of this series; Perez 1993 and the extraterrestrial irradiance use it."""
    g = 2.0 * np.pi * (np.asarray(day_of_year, dtype=np.float64) - 1.0) / 365.0  # day angle
    return (1.000110 + 0.034221 * np.cos(g) + 0.001280 * np.sin(g)
            + 0.000719 * np.cos(2.0 * g) + 0.000077 * np.sin(2.0 * g))  # [Spe71]


_spencer_inverse_square = eccentricity_correction_spencer1971


def earth_sun_distance(time: Any, method: str = "spa", delta_t_s: float | None = None):
    """Earth-sun distance [au] at a time.

    Parameters
    ----------
    time : str, datetime or sequence of them
        See :func:`parse_time`.
    method : {"spa", "preetham1999"}
        ``"spa"``: SPA's heliocentric radius vector [RA04] (VSOP87 terms, through
        ``pvlib.solarposition.nrel_earthsun_distance``). ``"preetham1999"`` (the paper
        has no distance): Spencer's Fourier series for (r0/r)^2 [Spe71] on the UTC day
        of the year, accurate to about 1e-4 au, without pvlib.
    delta_t_s : float or None
        TT - UT1 [s] for ``"spa"``; None: pvlib's estimate.

    Returns
    -------
    float or ndarray
        Distance [au].
    """
    check_choice("method", method, SOLAR_POSITION_METHODS)
    if delta_t_s is not None:
        delta_t_s = check_number("delta_t_s", delta_t_s, -8000.0, 8000.0, "s")
    times, scalar = _parse_times(time)
    if method == "spa":
        from pvlib.solarposition import nrel_earthsun_distance

        d = np.asarray(nrel_earthsun_distance(_utc_index(times), how="numpy",
                                              delta_t=delta_t_s), dtype=np.float64)
    else:
        day = np.array([_fractional_day_of_year(t) for t in times])
        d = 1.0 / np.sqrt(_spencer_inverse_square(day))
    return float(d[0]) if scalar else d


def _fractional_day_of_year(t: datetime) -> float:
    u = t.astimezone(timezone.utc)
    return (u.timetuple().tm_yday
            + (u.hour + u.minute / 60.0 + (u.second + u.microsecond * 1e-6) / 3600.0) / 24.0)


def extraterrestrial_irradiance(time_or_day_of_year: Any):
    """Total solar irradiance at the top of the atmosphere [W/m^2].

    ``SOLAR_CONSTANT_W_M2`` (1361.1 W/m^2 at 1 au [Gue18]) times (r0/r)^2.

    Parameters
    ----------
    time_or_day_of_year : str, datetime, float or array of floats
        A time (see :func:`parse_time`): the distance is SPA's radius vector (pvlib).
        A day of the year in [1, 367) (1 = 1 January 00:00, fractions allowed):
        Spencer's series [Spe71], no pvlib.

    Returns
    -------
    float or ndarray
        Irradiance on a surface normal to the sun's rays [W/m^2].
    """
    x = time_or_day_of_year
    if isinstance(x, (str, datetime, date)):
        d = earth_sun_distance(x, method="spa")
        return SOLAR_CONSTANT_W_M2 / (d * d)
    if isinstance(x, (bool, np.bool_)):
        raise TypeError(f"time_or_day_of_year must be a time or a day number, got {x!r}")
    if isinstance(x, (int, float, np.integer, np.floating)):
        day = check_number("time_or_day_of_year", x, 1.0, 367.0, "", high_open=True)
        return float(SOLAR_CONSTANT_W_M2 * _spencer_inverse_square(day))
    try:
        day = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError("time_or_day_of_year must be a time, a day number or an array of "
                        f"day numbers, got {x!r}") from None
    if not np.all(np.isfinite(day)) or day.size == 0 or day.min() < 1.0 or day.max() >= 367.0:
        raise ValueError("time_or_day_of_year = array out of range [1, 367) (day of year)")
    return SOLAR_CONSTANT_W_M2 * _spencer_inverse_square(day)


# -- the sun ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class Sun:
    """The sun as seen by the observer.

    Parameters
    ----------
    elevation_deg : float
        Elevation above the horizon [deg], in [-90, 90]. Negative values put the sun
        below the horizon (twilight, night); models state what they do there.
    azimuth_deg : float
        Azimuth from north towards east [deg], any finite value (wrapped to [0, 360)).
    angular_radius_deg : float
        Apparent angular radius of the disc [deg], in (0, 5]; default 0.2665.
    distance_au : float
        Earth-sun distance [au], in [0.95, 1.05]; the extraterrestrial irradiance is
        scaled by 1/distance_au^2.
    latitude_deg, longitude_deg : float or None
        Observer's latitude and east-positive longitude [deg] when the sun was placed
        with :meth:`from_location`; None otherwise.
    time : datetime or None
        The timezone-aware time given to :meth:`from_location`; None otherwise.
    """

    elevation_deg: float
    azimuth_deg: float
    angular_radius_deg: float = SUN_ANGULAR_RADIUS_DEG
    distance_au: float = 1.0
    latitude_deg: float | None = None
    longitude_deg: float | None = None
    time: datetime | None = None

    def __post_init__(self):
        object.__setattr__(self, "elevation_deg",
                           check_number("elevation_deg", self.elevation_deg, -90.0, 90.0, "deg"))
        az = check_number("azimuth_deg", self.azimuth_deg, unit="deg")
        object.__setattr__(self, "azimuth_deg", az % 360.0)
        object.__setattr__(self, "angular_radius_deg",
                           check_number("angular_radius_deg", self.angular_radius_deg, 0.0, 5.0,
                                        "deg", low_open=True))
        object.__setattr__(self, "distance_au",
                           check_number("distance_au", self.distance_au, 0.95, 1.05, "au"))
        if self.latitude_deg is not None:
            object.__setattr__(self, "latitude_deg", check_number(
                "latitude_deg", self.latitude_deg, -90.0, 90.0, "deg"))
        if self.longitude_deg is not None:
            object.__setattr__(self, "longitude_deg", check_number(
                "longitude_deg", self.longitude_deg, -180.0, 180.0, "deg"))
        if self.time is not None:
            object.__setattr__(self, "time", parse_time(self.time))

    @classmethod
    def from_location(cls, lat_deg: float, lon_deg: float, time: Any, method: str = "spa",
                      **kw) -> "Sun":
        """The sun seen from a place at a time.

        Parameters
        ----------
        lat_deg, lon_deg : float
            Latitude [deg] in [-90, 90] (north positive) and longitude [deg] in
            [-180, 180] (east positive).
        time : str or datetime
            ISO 8601 time with UTC offset or a timezone-aware datetime.
        method : {"spa", "preetham1999"}
            Position algorithm (see :func:`solar_position`). The distance comes from
            SPA's radius vector for ``"spa"`` and from Spencer's series for
            ``"preetham1999"`` (see :func:`earth_sun_distance`).
        **kw
            ``altitude_m``, ``pressure_pa``, ``temperature_c``, ``refraction``,
            ``delta_t_s`` for :func:`solar_position`, and ``angular_radius_deg`` for the
            disc (default 0.2665 deg, the mean at 1 au; it is not scaled with distance).

        Returns
        -------
        Sun
        """
        radius = kw.pop("angular_radius_deg", SUN_ANGULAR_RADIUS_DEG)
        allowed = {"altitude_m", "pressure_pa", "temperature_c", "refraction", "delta_t_s"}
        unknown = sorted(set(kw) - allowed)
        if unknown:
            raise TypeError(f"Sun.from_location() got unexpected keyword(s) {', '.join(unknown)}; "
                            f"valid: angular_radius_deg, {', '.join(sorted(allowed))}")
        t = parse_time(time)
        elev, az = solar_position(lat_deg, lon_deg, t, method=method, **kw)
        dist = earth_sun_distance(t, method=method, delta_t_s=kw.get("delta_t_s"))
        return cls(elevation_deg=elev, azimuth_deg=az, angular_radius_deg=radius,
                   distance_au=dist, latitude_deg=float(lat_deg), longitude_deg=float(lon_deg),
                   time=t)

    @property
    def zenith_deg(self) -> float:
        """Zenith angle [deg]."""
        return 90.0 - self.elevation_deg

    @property
    def direction(self) -> np.ndarray:
        """Unit vector towards the sun, shape (3,), East-North-Up."""
        from skydome.transport.geometry import direction_from_angles

        return direction_from_angles(self.elevation_deg, self.azimuth_deg)

    @property
    def solid_angle_sr(self) -> float:
        """Solid angle of the disc [sr]: 2 pi (1 - cos r)."""
        return 2.0 * np.pi * (1.0 - np.cos(np.radians(self.angular_radius_deg)))

    @property
    def irradiance_scale(self) -> float:
        """Factor 1/d^2 applied to the 1 au extraterrestrial irradiance."""
        return 1.0 / (self.distance_au * self.distance_au)

    @property
    def extraterrestrial_irradiance(self) -> float:
        """Total solar irradiance at the top of the atmosphere [W/m^2]: 1361.1 / d^2."""
        return SOLAR_CONSTANT_W_M2 * self.irradiance_scale


def sun_from_options(sun_elevation=None, sun_azimuth=None, lat=None, lon=None, time=None,
                     method: str = "spa", *, option_prefix: str = "") -> "Sun":
    """The :class:`Sun` of a command line or an API request: by angles [deg] or by place
    and ISO 8601 time, not both (default: 30 deg high in the south).

    Every value is checked before any work, with a message naming it as
    ``option_prefix + name`` (``"--"`` on the command line, where the names are
    ``--sun-elevation`` ...; ``""`` in the viewer's API). Raises ValueError.
    """
    def name(key: str) -> str:
        return option_prefix + (key.replace("_", "-") if option_prefix else key)

    if sun_elevation is not None:
        check_number("sun_elevation", sun_elevation, -90.0, 90.0, "deg")
    if sun_azimuth is not None:
        check_number("sun_azimuth", sun_azimuth, -360.0, 360.0, "deg")
    if lat is not None:
        check_number("lat", lat, -90.0, 90.0, "deg")
    if lon is not None:
        check_number("lon", lon, -180.0, 180.0, "deg")
    by_angles = sun_elevation is not None or sun_azimuth is not None
    by_place = any(v is not None for v in (lat, lon, time))
    if by_angles and by_place:
        raise ValueError(f"give either {name('sun_elevation')}/{name('sun_azimuth')} or "
                         f"{name('lat')}/{name('lon')}/{name('time')}, not both")
    if by_place:
        missing = [name(n) for n, v in (("lat", lat), ("lon", lon), ("time", time)) if v is None]
        if missing:
            raise ValueError(f"{', '.join(missing)} missing: {name('lat')}, {name('lon')} and "
                             f"{name('time')} go together")
        check_choice("sun_method", method, SOLAR_POSITION_METHODS)
        return Sun.from_location(lat, lon, parse_time(time, "time"), method=method)
    return Sun(elevation_deg=30.0 if sun_elevation is None else sun_elevation,
               azimuth_deg=180.0 if sun_azimuth is None else sun_azimuth)
