"""Hourly weather files (EPW, TMY3) for daylighting: irradiances, illuminances, sun positions.

Files are parsed by pvlib.iotools (``read_epw``, ``read_tmy3``); this module checks what they
hold, marks the files' missing-value codes as missing, and adds the sun position of every
record.

Time convention: both formats label a record with the END of the hour it integrates over
(TMY3 ``01:00`` and EPW hour 1 cover 00:00-01:00 local standard time). The sun is placed at
the hour's MIDPOINT (00:30), as Radiance's epw2wea/gendaymtx do (a .wea file written by
epw2wea holds hour 0.5 for that record). Sun positions are pvlib's NREL SPA [RA04], true
(geometric) zenith without refraction, as Radiance's sun.c.

References
----------
.. [RA04] I. Reda, A. Andreas, "Solar position algorithm for solar radiation applications",
   Solar Energy 76(5) 577-589 (2004).
.. [WM08] S. Wilcox, W. Marion, "Users manual for TMY3 data sets", NREL/TP-581-43156 (2008).
.. [EPW] U.S. DOE, "EnergyPlus Auxiliary Programs", chapter "Weather Converter Program",
   EnergyPlus weather file (EPW) data dictionary.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["Site", "Weather", "read_weather", "sample_weather_path", "write_wea", "radiance_sun_directions",
           "WEATHER_LIMITS"]

#: Plausible ranges of the quantities read [unit]; values outside them mean a unit mix-up
#: (e.g. illuminance in an irradiance column) or a corrupt record. Irradiance limits: the
#: solar constant 1361-1367 W m^-2 [WM08]; DHI above 1000 W m^-2 does not occur.
WEATHER_LIMITS = {
    "dni": (0.0, 1400.0, "W/m^2"),
    "dhi": (0.0, 1000.0, "W/m^2"),
    "ghi": (0.0, 1500.0, "W/m^2"),
    "dni_illuminance": (0.0, 140000.0, "lx"),
    "dhi_illuminance": (0.0, 150000.0, "lx"),
    "ghi_illuminance": (0.0, 160000.0, "lx"),
    "dew_point_c": (-70.0, 40.0, "degC"),
}

# pvlib column names -> ours, per format.
_TMY3_COLUMNS = {"dni": "dni", "dhi": "dhi", "ghi": "ghi", "DN illum (lx)": "dni_illuminance",
                 "DH illum (lx)": "dhi_illuminance", "GH illum (lx)": "ghi_illuminance",
                 "temp_dew": "dew_point_c", "albedo": "albedo",
                 "precipitable_water": "precipitable_water_cm", "AOD (unitless)": "aod"}
_EPW_COLUMNS = {"dni": "dni", "dhi": "dhi", "ghi": "ghi", "direct_normal_illuminance":
                "dni_illuminance", "diffuse_horizontal_illuminance": "dhi_illuminance",
                "global_horizontal_illuminance": "ghi_illuminance", "temp_dew": "dew_point_c",
                "albedo": "albedo", "precipitable_water": "precipitable_water_cm",
                "aerosol_optical_depth": "aod"}
# EPW missing-value codes [EPW data dictionary]: a value >= the code is missing.
_EPW_MISSING = {"dni": 9999.0, "dhi": 9999.0, "ghi": 9999.0, "dni_illuminance": 999900.0,
                "dhi_illuminance": 999900.0, "ghi_illuminance": 999900.0,
                "dew_point_c": 99.9, "albedo": 999.0, "precipitable_water_cm": 999.0,
                "aod": 0.999}
_REQUIRED = ("dni", "dhi")


@dataclass(frozen=True)
class Site:
    """Where the weather was recorded: name, latitude [deg N], longitude [deg E],
    UTC offset of local standard time [h], elevation [m]."""

    name: str
    latitude_deg: float
    longitude_deg: float
    utc_offset_h: float
    elevation_m: float


@dataclass(frozen=True)
class Weather:
    """An hourly weather record with the sun position at each hour's midpoint.

    Attributes
    ----------
    site : Site
    path : str
        File it came from; ``format`` is "epw" or "tmy3".
    time : numpy.ndarray of datetime64[s]
        Hour midpoints in local standard time (n,).
    month, day : numpy.ndarray of int
        Calendar month and day of each record; ``hour`` is the midpoint in hours since local
        standard midnight (0.5 .. 23.5), as a .wea file holds it.
    day_of_year : numpy.ndarray of int
        1..365 (366 in a leap year).
    dni, dhi, ghi : numpy.ndarray
        Direct normal, diffuse horizontal and global horizontal irradiance [W m^-2].
    dni_illuminance, dhi_illuminance, ghi_illuminance : numpy.ndarray or None
        The same as illuminances [lx] where the file holds them (None otherwise).
    dew_point_c : numpy.ndarray or None
        Surface dew point [deg C].
    albedo, aod, precipitable_water_cm : numpy.ndarray or None
        Ground albedo [-], aerosol optical depth (broadband, as the file defines it) [-] and
        precipitable water [cm]; missing entries are nan, the whole field None if the file
        holds none.
    sun_zenith_deg, sun_azimuth_deg : numpy.ndarray
        True (unrefracted) solar zenith angle and azimuth from north towards east [deg]
        at the hour's midpoint, by ``sun_model``.
    sun_model : str
        "spa" (pvlib's NREL SPA [RA04], the default) or "radiance" (Radiance's short series,
        :func:`radiance_sun_directions`; read with ``read_weather(..., sun_position=
        "radiance")`` to reproduce gendaymtx without computing SPA).
    """

    site: Site
    path: str
    format: str
    time: np.ndarray
    month: np.ndarray
    day: np.ndarray
    hour: np.ndarray
    day_of_year: np.ndarray
    dni: np.ndarray
    dhi: np.ndarray
    ghi: np.ndarray
    dni_illuminance: np.ndarray | None
    dhi_illuminance: np.ndarray | None
    ghi_illuminance: np.ndarray | None
    dew_point_c: np.ndarray | None
    albedo: np.ndarray | None
    aod: np.ndarray | None
    precipitable_water_cm: np.ndarray | None
    sun_zenith_deg: np.ndarray
    sun_azimuth_deg: np.ndarray
    sun_model: str = "spa"

    def __len__(self) -> int:
        return int(self.dni.shape[0])

    @property
    def sun_directions(self) -> np.ndarray:
        """Unit vectors towards the sun (n, 3), East-North-Up, by ``sun_model``."""
        z = np.radians(self.sun_zenith_deg)
        a = np.radians(self.sun_azimuth_deg)
        return np.stack([np.sin(z) * np.sin(a), np.sin(z) * np.cos(a), np.cos(z)], axis=-1)

    def spa_sun_directions(self) -> np.ndarray:
        """Unit vectors towards the sun (n, 3) by NREL SPA [RA04] whatever ``sun_model``."""
        if self.sun_model == "spa":
            return self.sun_directions
        zen, azi = _spa_zenith_azimuth(self.site, self.time)
        z, a = np.radians(zen), np.radians(azi)
        return np.stack([np.sin(z) * np.sin(a), np.sin(z) * np.cos(a), np.cos(z)], axis=-1)

    def radiance_sun_directions(self) -> np.ndarray:
        """Unit vectors towards the sun (n, 3) from Radiance's approximate solar position, as
        gendaymtx computes them (for reproducing gendaymtx; see
        :func:`radiance_sun_directions`)."""
        s = self.site
        return radiance_sun_directions(s.latitude_deg, s.longitude_deg, s.utc_offset_h,
                                       self.day_of_year, self.hour)

    def select(self, mask) -> "Weather":
        """The records where ``mask`` (bool or index array) selects, as a new Weather."""
        import dataclasses

        idx = np.arange(len(self))[mask]
        fields = {}
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            fields[f.name] = v[idx] if isinstance(v, np.ndarray) else v
        return Weather(**fields)

    def summary(self) -> dict:
        """What the file holds: site, period, which quantities, daylight hours, sums."""
        held = [k for k in ("dni", "dhi", "ghi", "dni_illuminance", "dhi_illuminance",
                            "ghi_illuminance", "dew_point_c", "albedo", "aod",
                            "precipitable_water_cm")
                if getattr(self, k) is not None and np.any(np.isfinite(getattr(self, k)))]
        return {
            "site": self.site.name, "latitude_deg": self.site.latitude_deg,
            "longitude_deg": self.site.longitude_deg, "utc_offset_h": self.site.utc_offset_h,
            "elevation_m": self.site.elevation_m, "format": self.format,
            "records": len(self), "first": str(self.time[0]), "last": str(self.time[-1]),
            "step": "1 h (sun at the hour's midpoint)",
            "quantities": held,
            "daylight_hours": int(np.sum(self.sun_zenith_deg < 90.0)),
            "annual_ghi_kwh_m2": float(np.nansum(self.ghi) / 1000.0),
            "annual_dni_kwh_m2": float(np.nansum(self.dni) / 1000.0),
            "annual_dhi_kwh_m2": float(np.nansum(self.dhi) / 1000.0),
        }


def radiance_sun_directions(latitude_deg, longitude_deg, utc_offset_h, day_of_year,
                            hour) -> np.ndarray:
    """Sun unit vectors (ENU) by the short series Radiance's gensky/gendaymtx use.

    Declination delta = 0.4093 sin(2 pi (J - 81) / 365); solar time t = T + 0.170 sin(4 pi
    (J - 80) / 373) - 0.129 sin(2 pi (J - 8) / 355) + 12 (L_meridian - L) / pi (longitudes
    west, T local standard time [h], J the day of the year); altitude asin(sin phi sin delta -
    cos phi cos delta cos(pi t / 12)) and the matching azimuth [RS87] (Radiance 5.4 sun.c;
    its declination period was corrected from 368 to 365 days in 2019). It differs from
    NREL SPA by up to 0.9 deg (Greensboro, sample year); skydome's default is SPA.

    References
    ----------
    .. [RS87] G. Ward, Radiance ``sun.c`` "solar calculations" (1987, revised 2019),
       functions sdec, stadj, salt, sazi.
    """
    lat = np.radians(np.asarray(latitude_deg, dtype=np.float64))
    lon_w = np.radians(-np.asarray(longitude_deg, dtype=np.float64))
    mer_w = np.radians(-15.0 * np.asarray(utc_offset_h, dtype=np.float64))
    jd = np.asarray(day_of_year, dtype=np.float64)
    decl = 0.4093 * np.sin((2.0 * np.pi / 365.0) * (jd - 81.0))
    t = (np.asarray(hour, dtype=np.float64) + 0.170 * np.sin((4.0 * np.pi / 373.0) * (jd - 80.0))
         - 0.129 * np.sin((2.0 * np.pi / 355.0) * (jd - 8.0)) + 12.0 * (mer_w - lon_w) / np.pi)
    w = t * np.pi / 12.0
    alt = np.arcsin(np.sin(lat) * np.sin(decl) - np.cos(lat) * np.cos(decl) * np.cos(w))
    # azimuth from south towards west, turned to from north towards east (+ pi)
    az = np.pi - np.arctan2(np.cos(decl) * np.sin(w),
                            -np.cos(lat) * np.sin(decl) - np.sin(lat) * np.cos(decl) * np.cos(w))
    return np.stack([np.cos(alt) * np.sin(az), np.cos(alt) * np.cos(az), np.sin(alt)], axis=-1)


def sample_weather_path() -> Path:
    """The TMY3 file of Greensboro, NC (USAF 723170) that pvlib ships in its data folder.

    Source: NREL National Solar Radiation Database 1991-2005 update, TMY3 [WM08], public
    domain (U.S. Government work), distributed with pvlib-python (BSD-3-Clause) as
    ``pvlib/data/723170TYA.CSV``.
    """
    import pvlib

    p = Path(pvlib.__file__).resolve().parent / "data" / "723170TYA.CSV"
    if not p.exists():  # pragma: no cover - pvlib always ships it
        raise FileNotFoundError(f"pvlib's sample TMY3 file is missing ({p.name})")
    return p


def _detect_format(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix == ".epw":
        return "epw"
    if suffix == ".wea":
        return "wea"
    with path.open("r", errors="replace") as f:
        first = f.readline()
    if first.upper().startswith("LOCATION,"):
        return "epw"
    if suffix == ".csv" or first.split(",")[0].strip().isdigit():
        return "tmy3"
    raise ValueError(f"weather = {str(path)!r}: not an EPW or TMY3 file "
                     "(expected a .epw or a TMY3 .csv)")


def _check_records(path: Path, fmt: str) -> None:
    """Every data line must have the format's number of fields (TMY3: as many as its column
    header [WM08]; EPW: at least the 35 of its data dictionary); a short last line is a
    truncated file."""
    skip = 2 if fmt == "tmy3" else 8
    with path.open("r", errors="replace") as f:
        lines = f.read().splitlines()
    if len(lines) <= skip:
        raise ValueError(f"weather = {str(path)!r}: truncated, no data records")
    need = len(lines[1].split(",")) if fmt == "tmy3" else 35
    for k, ln in enumerate(lines[skip:], start=skip + 1):
        if not ln.strip():
            continue
        n = len(ln.split(","))
        if n < need:
            where = "last" if k == len(lines) else f"line {k}"
            raise ValueError(f"weather = {str(path)!r}: truncated record ({where}: {n} of "
                             f"{need} fields)")


def read_weather(path, *, year: int = 2021, sun_position: str = "spa") -> Weather:
    """Read an hourly EPW, TMY3 or Radiance .wea weather file and compute the sun at each
    hour's midpoint.

    Parameters
    ----------
    path : str or Path
        ``.epw`` (EnergyPlus) or TMY3 ``.csv`` [WM08], read by pvlib.iotools; or a Radiance
        ``.wea`` file (gendaymtx's input, as epw2wea and :func:`write_wea` write it: a
        six-line header, then ``month day hour DNI DHI`` with the hour's midpoint and
        ``weather_data_file_units 1``, W m^-2). A .wea holds no dew point, albedo or GHI
        (GHI is DHI + DNI cos(zenith)).
    year : int
        Calendar year the typical months are placed in (TMY files mix years); a non-leap year
        keeps 8760 hours (default 2021).
    sun_position : {"spa", "radiance"}
        Sun at the midpoints by NREL SPA (default; pvlib) or by Radiance's short series (what
        gendaymtx uses; needs neither pvlib nor SPA's 0.1 s for a year).

    Returns
    -------
    Weather

    Raises
    ------
    FileNotFoundError
        No such file.
    ValueError
        Not an EPW/TMY3 file, truncated (a full typical year has 8760 records; a partial
        file must still step by exactly one hour), missing DNI/DHI values, values outside
        :data:`WEATHER_LIMITS` (e.g. illuminances in irradiance columns), or a time step
        other than one hour. The message names the file, the field and the first bad record.
    """
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"weather = {str(path)!r}: no such file")
    if not p.is_file():
        raise ValueError(f"weather = {str(path)!r} is not a file")
    from skydome._validate import check_choice

    check_choice("sun_position", sun_position, ("spa", "radiance"))
    fmt = _detect_format(p)
    if fmt == "wea":
        return _read_wea(p, year, sun_position)
    _check_records(p, fmt)
    import warnings

    from pvlib import iotools

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if fmt == "epw":
                data, meta = iotools.read_epw(str(p))
                names = _EPW_COLUMNS
                site = Site(str(meta.get("city", "")).strip(), float(meta["latitude"]),
                            float(meta["longitude"]), float(meta["TZ"]),
                            float(meta["altitude"]))
            else:
                data, meta = iotools.read_tmy3(str(p), map_variables=True)
                names = _TMY3_COLUMNS
                site = Site(str(meta.get("Name", "")).strip().strip('"'),
                            float(meta["latitude"]), float(meta["longitude"]),
                            float(meta["TZ"]), float(meta["altitude"]))
    except (ValueError, KeyError, IndexError, TypeError) as exc:
        raise ValueError(f"weather = {str(path)!r}: cannot be read as {fmt.upper()} "
                         f"({type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''})"
                         ) from None
    except Exception as exc:  # pandas' parser errors
        raise ValueError(f"weather = {str(path)!r}: cannot be read as {fmt.upper()} "
                         f"({type(exc).__name__})") from None
    n = len(data)
    if n == 0:
        raise ValueError(f"weather = {str(path)!r}: no records")
    if not (-90.0 <= site.latitude_deg <= 90.0) or not (-180.0 <= site.longitude_deg <= 180.0):
        raise ValueError(f"weather = {str(path)!r}: latitude {site.latitude_deg:g} / longitude "
                         f"{site.longitude_deg:g} deg out of range")

    # -- time: the end of each record's hour from its own date and hour fields (TMY3 "MM/DD",
    # "HH:00" with HH 1..24 [WM08]; EPW month, day, hour 1..24 [EPW]), placed in ``year``;
    # records must step by exactly one hour.
    try:
        if fmt == "tmy3":
            md = [str(v).split("/") for v in data["Date (MM/DD/YYYY)"]]
            months = np.array([int(x[0]) for x in md])
            days = np.array([int(x[1]) for x in md])
            hours = np.array([int(str(v).split(":")[0]) for v in data["Time (HH:MM)"]])
        else:
            months = np.asarray(data["month"], dtype=np.int64)
            days = np.asarray(data["day"], dtype=np.int64)
            hours = np.asarray(data["hour"], dtype=np.int64)
        day0 = np.array([np.datetime64(f"{year:04d}-{m:02d}-{d:02d}") for m, d in zip(months, days)])
    except (ValueError, KeyError, IndexError):
        raise ValueError(f"weather = {str(path)!r}: bad date or hour field") from None
    if np.any(hours < 1) or np.any(hours > 24):
        k = int(np.argmax((hours < 1) | (hours > 24)))
        raise ValueError(f"weather = {str(path)!r}: hour {hours[k]} of record {k + 1} is out of "
                         "range [1, 24]")
    t_end = day0.astype("datetime64[s]") + hours.astype("timedelta64[h]")
    step = np.diff(t_end).astype(np.int64)
    if np.any(step != 3600):
        k = int(np.argmax(step != 3600))
        raise ValueError(f"weather = {str(path)!r}: time step {step[k] / 3600:g} h between "
                         f"records {k + 1} and {k + 2} ({t_end[k]} -> {t_end[k + 1]}); "
                         "only hourly files are supported")
    if n != 8760 and n != 8784:
        # A partial year is allowed only if it is whole days; anything else is truncated.
        if n % 24 != 0:
            raise ValueError(f"weather = {str(path)!r}: truncated, {n} hourly records "
                             "(a year has 8760; a partial file must hold whole days)")
    t_mid = t_end - np.timedelta64(1800, "s")  # the hour's midpoint

    # -- quantities ----------------------------------------------------------------------------
    values: dict[str, np.ndarray | None] = {}
    for src, dst in names.items():
        if src not in data.columns:
            values[dst] = None
            continue
        v = np.asarray(data[src], dtype=np.float64).copy()
        if fmt == "epw" and dst in _EPW_MISSING:
            v[v >= _EPW_MISSING[dst]] = np.nan
        values[dst] = v
    for key in ("albedo", "aod", "precipitable_water_cm"):
        v = values.get(key)
        if v is not None:
            # TMY3 writes 0 with source '?' where a value is missing; EPW uses codes (above).
            v[~(v > 0.0)] = np.nan
            if not np.any(np.isfinite(v)):
                values[key] = None
    for key in _REQUIRED:
        v = values.get(key)
        if v is None:
            raise ValueError(f"weather = {str(path)!r}: no {key} column")
        bad = ~np.isfinite(v)
        if np.any(bad):
            k = int(np.argmax(bad))
            raise ValueError(f"weather = {str(path)!r}: missing {key} value at record {k + 1} "
                             f"({t_end[k]})")
    for key, (lo, hi, unit) in WEATHER_LIMITS.items():
        v = values.get(key)
        if v is None:
            continue
        bad = np.isfinite(v) & ((v < lo) | (v > hi))
        if np.any(bad):
            k = int(np.argmax(bad))
            raise ValueError(f"weather = {str(path)!r}: {key} = {v[k]:g} at record {k + 1} "
                             f"({t_end[k]}) is out of range [{lo:g}, {hi:g}] {unit} "
                             "(wrong units?)")

    # -- the sun at the hour's midpoint (true zenith) -----------------------------------------
    month, day, hour, doy = _calendar(t_mid)
    zen, azi = _sun_zenith_azimuth(site, t_mid, doy, hour, sun_position)
    return Weather(
        site=site, path=str(p), format=fmt, time=t_mid, month=month, day=day, hour=hour,
        day_of_year=doy, dni=values["dni"], dhi=values["dhi"],
        ghi=values["ghi"] if values.get("ghi") is not None else np.full(n, np.nan),
        dni_illuminance=values.get("dni_illuminance"),
        dhi_illuminance=values.get("dhi_illuminance"),
        ghi_illuminance=values.get("ghi_illuminance"),
        dew_point_c=values.get("dew_point_c"), albedo=values.get("albedo"),
        aod=values.get("aod"), precipitable_water_cm=values.get("precipitable_water_cm"),
        sun_zenith_deg=zen, sun_azimuth_deg=azi, sun_model=sun_position,
    )


def _calendar(t_mid):
    """Month, day, hour of day (float) and day of the year of datetime64 instants."""
    t = np.asarray(t_mid, dtype="datetime64[s]")
    days = t.astype("datetime64[D]")
    months = days.astype("datetime64[M]")
    years = days.astype("datetime64[Y]")
    month = (months - years.astype("datetime64[M]")).astype(np.int64) + 1
    day = (days - months.astype("datetime64[D]")).astype(np.int64) + 1
    doy = (days - years.astype("datetime64[D]")).astype(np.int64) + 1
    hour = (t - days.astype("datetime64[s]")).astype(np.int64) / 3600.0
    return month, day, hour, doy


def _spa_zenith_azimuth(site: Site, t_mid):
    """True zenith and azimuth [deg] by pvlib's NREL SPA [RA04] at local-standard instants."""
    import datetime

    import pandas as pd
    from pvlib import solarposition

    tz = datetime.timezone(datetime.timedelta(hours=site.utc_offset_h))
    idx = pd.DatetimeIndex(t_mid).tz_localize(tz)
    sp = solarposition.get_solarposition(idx, site.latitude_deg, site.longitude_deg,
                                         altitude=site.elevation_m, method="nrel_numpy")
    return (np.asarray(sp["zenith"], dtype=np.float64),
            np.asarray(sp["azimuth"], dtype=np.float64))


def _sun_zenith_azimuth(site: Site, t_mid, doy, hour, sun_position: str):
    if sun_position == "spa":
        return _spa_zenith_azimuth(site, t_mid)
    d = radiance_sun_directions(site.latitude_deg, site.longitude_deg, site.utc_offset_h, doy,
                                hour)
    zen = np.degrees(np.arccos(np.clip(d[:, 2], -1.0, 1.0)))
    azi = np.degrees(np.arctan2(d[:, 0], d[:, 1])) % 360.0
    return zen, azi


def _read_wea(p: Path, year: int, sun_position: str) -> Weather:
    """A Radiance .wea file (gendaymtx's input format; see :func:`write_wea`)."""
    name = str(p)
    with p.open("r", errors="replace") as f:
        lines = f.read().splitlines()
    head: dict = {}
    k = 0
    keys = ("place", "latitude", "longitude", "time_zone", "site_elevation",
            "weather_data_file_units")
    while k < len(lines) and lines[k].split(" ", 1)[0] in keys:
        key, _, val = lines[k].partition(" ")
        head[key] = val.strip()
        k += 1
    for key in keys[1:]:
        if key not in head:
            raise ValueError(f"weather = {name!r}: .wea header lacks {key!r}")
    if head["weather_data_file_units"] != "1":
        raise ValueError(f"weather = {name!r}: weather_data_file_units = "
                         f"{head['weather_data_file_units']!r}; only 1 (DNI and DHI in W/m^2) "
                         "is supported")
    try:
        # Radiance's signs: longitude and time_zone (standard meridian) in degrees WEST.
        site = Site(head.get("place", "").replace("_", " "), float(head["latitude"]),
                    -float(head["longitude"]), -float(head["time_zone"]) / 15.0,
                    float(head["site_elevation"]))
    except ValueError:
        raise ValueError(f"weather = {name!r}: bad .wea header value") from None
    if not (-90.0 <= site.latitude_deg <= 90.0) or not (-180.0 <= site.longitude_deg <= 180.0):
        raise ValueError(f"weather = {name!r}: latitude {site.latitude_deg:g} / longitude "
                         f"{site.longitude_deg:g} deg out of range")
    body = [ln for ln in lines[k:] if ln.strip()]
    if not body:
        raise ValueError(f"weather = {name!r}: truncated, no data records")
    fields = " ".join(body).split()
    if len(fields) != 5 * len(body):  # find the record that has not 5 fields
        for j, ln in enumerate(body):
            if len(ln.split()) != 5:
                raise ValueError(f"weather = {name!r}: truncated record (record {j + 1}: "
                                 f"{len(ln.split())} of 5 fields)")
    try:
        # Python's float per field, then one array: numpy's conversion of a year's 43 800
        # strings alone took 0.017 s; the whole read is now 0.017 s against 0.035 s
        data = np.array(list(map(float, fields)), dtype=np.float64).reshape(-1, 5)
    except ValueError:
        raise ValueError(f"weather = {name!r}: a record is not numeric") from None
    n = data.shape[0]
    mo, da = data[:, 0].astype(np.int64), data[:, 1].astype(np.int64)
    if np.any((mo < 1) | (mo > 12) | (da < 1) | (da > 31)):
        raise ValueError(f"weather = {name!r}: bad month or day field")
    y0 = np.datetime64(f"{year:04d}-01", "M")
    t_day = (y0 + (mo - 1)).astype("datetime64[D]") + (da - 1)
    t_mid = t_day.astype("datetime64[s]") + np.round(data[:, 2] * 3600.0).astype(
        "timedelta64[s]")
    step = np.diff(t_mid).astype(np.int64)
    if np.any(step != 3600):
        j = int(np.argmax(step != 3600))
        raise ValueError(f"weather = {name!r}: time step {step[j] / 3600:g} h between "
                         f"records {j + 1} and {j + 2}; only hourly files are supported")
    if n not in (8760, 8784) and n % 24 != 0:
        raise ValueError(f"weather = {name!r}: truncated, {n} hourly records "
                         "(a year has 8760; a partial file must hold whole days)")
    dni, dhi = data[:, 3].copy(), data[:, 4].copy()
    for key, v in (("dni", dni), ("dhi", dhi)):
        lo, hi, unit = WEATHER_LIMITS[key]
        bad = ~np.isfinite(v) | (v < lo) | (v > hi)
        if np.any(bad):
            j = int(np.argmax(bad))
            raise ValueError(f"weather = {name!r}: {key} = {v[j]:g} at record {j + 1} is out "
                             f"of range [{lo:g}, {hi:g}] {unit} (wrong units?)")
    month, day, hour, doy = _calendar(t_mid)
    zen, azi = _sun_zenith_azimuth(site, t_mid, doy, hour, sun_position)
    ghi = dhi + dni * np.maximum(np.cos(np.radians(zen)), 0.0)
    return Weather(site=site, path=name, format="wea", time=t_mid, month=month, day=day,
                   hour=hour, day_of_year=doy, dni=dni, dhi=dhi, ghi=ghi,
                   dni_illuminance=None, dhi_illuminance=None, ghi_illuminance=None,
                   dew_point_c=None, albedo=None, aod=None, precipitable_water_cm=None,
                   sun_zenith_deg=zen, sun_azimuth_deg=azi, sun_model=sun_position)


def write_wea(weather: Weather, path) -> None:
    """Write ``weather`` as a Radiance .wea file (irradiances, hour midpoints), atomically.

    Header: place, latitude (deg N), longitude (deg WEST, Radiance's sign), time_zone
    (standard meridian, deg WEST = -15 x UTC offset), site_elevation [m],
    weather_data_file_units 1 (DNI and DHI in W m^-2); then ``month day hour dni dhi``.
    """
    from skydome.daylighting.radiance_io import atomic_write_bytes

    s = weather.site
    lines = [f"place {s.name.replace(' ', '_') or 'site'}", f"latitude {s.latitude_deg:.4f}",
             f"longitude {-s.longitude_deg:.4f}", f"time_zone {-15.0 * s.utc_offset_h:.1f}",
             f"site_elevation {s.elevation_m:.1f}", "weather_data_file_units 1"]
    for mo, da, hr, dn, dh in zip(weather.month, weather.day, weather.hour, weather.dni,
                                  weather.dhi):
        lines.append(f"{mo} {da} {hr:.3f} {dn:.1f} {dh:.1f}")
    atomic_write_bytes(path, ("\n".join(lines) + "\n").encode())
