"""Hourly weather files (EPW, TMY3) for daylighting: irradiances, illuminances, sun positions.

Files are read line by line with bounded line lengths, field counts and record counts (so a
damaged or hostile file is refused in well under a second, whatever its size), checked
field by field (every refusal names the file, the record, its line and the field), the
files' missing-value codes marked as missing, and the sun position of every record added.
Text may be UTF-8 or Latin-1, with or without a UTF-8 byte-order mark, in all three formats.

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

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["Site", "Weather", "read_weather", "sample_weather_path", "write_wea",
           "radiance_sun_directions", "WEATHER_LIMITS", "MAX_LINE_BYTES", "MAX_FIELDS",
           "MAX_RECORDS"]

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


# -- reading: bounded, line by line ---------------------------------------------------------
#: Longest line read [bytes]. EPW records are about 150 bytes, TMY3 records about 200, their
#: headers (EPW DESIGN CONDITIONS, TMY3 column names) under 2 kB; a longer line is not a
#: weather record and is refused before it is read whole.
MAX_LINE_BYTES = 16384
#: Most fields a data record may hold (EPW 35, TMY3 71, .wea 5).
MAX_FIELDS = 128
#: Most data records a file may hold: one leap year of hours. Files with more (sub-hourly or
#: several years, or not weather at all) are refused at the first record past it.
MAX_RECORDS = 8784
_BOM = b"\xef\xbb\xbf"


def _decode(raw: bytes) -> str:
    """UTF-8, else Latin-1 (which decodes any byte): real EPW/TMY3 site names come in both."""
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return raw.decode("latin-1")


def bounded_lines(path: Path, label: str, max_bytes: int, what: str):
    """(line number, raw bytes) of each line of the file ``path``, read one at a time with at
    most ``max_bytes`` a line: a longer one is refused without reading it whole (ValueError
    "``label``: line k is longer than ``max_bytes`` bytes (not ``what``)"); a UTF-8
    byte-order mark at the start of the file is dropped. Line ends are kept."""
    with path.open("rb") as f:
        k = 0
        while True:
            raw = f.readline(max_bytes + 1)
            if not raw:
                return
            k += 1
            if len(raw) > max_bytes and not raw.endswith(b"\n"):
                raise ValueError(f"{label}: line {k} is longer than {max_bytes} bytes "
                                 f"(not {what})")
            if k == 1 and raw.startswith(_BOM):
                raw = raw[len(_BOM):]
            yield k, raw


def _iter_lines(path: Path, name: str):
    """(line number, text) of each line (:func:`bounded_lines`, at most MAX_LINE_BYTES a
    line), decoded (:func:`_decode`), line ends (LF, CRLF) stripped."""
    for k, raw in bounded_lines(path, f"weather = {name!r}", MAX_LINE_BYTES,
                                "a weather record"):
        yield k, _decode(raw).rstrip("\r\n")


def _first_line(path: Path) -> str:
    for _, text in _iter_lines(path, str(path)):
        return text
    return ""


def _where(name: str, rec: int, line: int) -> str:
    return f"weather = {name!r}: record {rec} (line {line})"


def _number(text: str, name: str, rec: int, line: int, field: str) -> float:
    """A numeric field; empty means missing (nan). Anything else that is not a finite
    number is refused naming the file, the record, its line and the field."""
    s = text.strip()
    if not s:
        return float("nan")
    try:
        v = float(s)
    except ValueError:
        v = None
    if v is None or not np.isfinite(v):
        raise ValueError(f"{_where(name, rec, line)}, field {field} = {s[:40]!r} is not a "
                         "number")
    return v


def _integer(text: str, name: str, rec: int, line: int, field: str) -> int:
    s = text.strip()
    try:
        return int(s)
    except ValueError:
        pass
    v = _number(s, name, rec, line, field) if s else float("nan")
    if not np.isfinite(v) or v != int(v):
        raise ValueError(f"{_where(name, rec, line)}, field {field} = {s[:40]!r} is not a "
                         "whole number")
    return int(v)


def _column(texts, line_of, name: str, field: str, integer: bool = False) -> np.ndarray:
    """One field of every record as floats (numpy's conversion of the strings); where that
    fails or meets a value that is not finite, the records are checked one by one so that
    the refusal names the first bad record, its line and the field (an empty field is
    missing: nan)."""
    try:
        v = np.array(texts, dtype=np.float64)
        ok = bool(np.all(np.isfinite(v)))
        if ok and integer:
            ok = bool(np.all(v == np.round(v)))
    except ValueError:
        ok = False
    if ok:
        return v
    one = _integer if integer else _number
    return np.array([one(t, name, j + 1, int(line_of[j]), field) for j, t in enumerate(texts)],
                    dtype=np.float64)


def _header_number(text: str, name: str, line: int, field: str) -> float:
    s = text.strip().strip('"')
    try:
        v = float(s)
    except ValueError:
        v = float("nan")
    if not np.isfinite(v):
        raise ValueError(f"weather = {name!r}: line {line} (site header), field {field} = "
                         f"{s[:40]!r} is not a number")
    return v


#: Where the site header (line 1) of each format holds latitude, longitude, time zone and
#: elevation: (field index, the format's name for it) [EPW, TMY3]; the site's name is field 1.
_EPW_SITE = ((6, "latitude"), (7, "longitude"), (8, "time zone"), (9, "elevation"))
_TMY3_SITE = ((4, "latitude"), (5, "longitude"), (3, "TZ"), (6, "altitude"))


def _header_site(f: list[str], name: str, fields) -> "Site":
    """The Site of the header fields ``f`` laid out as ``fields`` (``_EPW_SITE``,
    ``_TMY3_SITE``)."""
    return Site(f[1].strip(), *(_header_number(f[i], name, 1, label) for i, label in fields))


def _split_record(text: str, sep, name: str, rec: int, line: int, need: int) -> list[str]:
    if len(text) > MAX_FIELDS * 64 and text.count(sep or " ") > MAX_FIELDS:
        raise ValueError(f"{_where(name, rec, line)} has more than {MAX_FIELDS} fields")
    f = text.split(sep)
    if len(f) > MAX_FIELDS:
        raise ValueError(f"{_where(name, rec, line)} has {len(f)} fields; a record has at "
                         f"most {MAX_FIELDS}")
    if len(f) < need:
        raise ValueError(f"weather = {name!r}: truncated record (record {rec}, line {line}: "
                         f"{len(f)} of {need} fields)")
    return f


def _too_many(name: str, line: int) -> ValueError:
    return ValueError(f"weather = {name!r}: more than {MAX_RECORDS} records (line {line}); "
                      f"an hourly year has 8760 or 8784, only hourly files of at most one year "
                      "are supported")


# EPW data dictionary [EPW]: 0-based field index of each quantity in a data record.
_EPW_FIELDS = {"dew_point_c": 7, "ghi": 13, "dni": 14, "dhi": 15, "ghi_illuminance": 16,
               "dni_illuminance": 17, "dhi_illuminance": 18, "precipitable_water_cm": 28,
               "aod": 29, "albedo": 32}
# TMY3 column names [WM08] of each quantity.
_TMY3_FIELDS = {"dni": "DNI (W/m^2)", "dhi": "DHI (W/m^2)", "ghi": "GHI (W/m^2)",
                "dni_illuminance": "DN illum (lx)", "dhi_illuminance": "DH illum (lx)",
                "ghi_illuminance": "GH illum (lx)", "dew_point_c": "Dew-point (C)",
                "albedo": "Alb (unitless)", "precipitable_water_cm": "Pwat (cm)",
                "aod": "AOD (unitless)"}
# Field names used in messages.
_LABELS = {"dni": "DNI", "dhi": "DHI", "ghi": "GHI", "dni_illuminance": "DNI illuminance",
           "dhi_illuminance": "DHI illuminance", "ghi_illuminance": "GHI illuminance",
           "dew_point_c": "dew point", "albedo": "albedo",
           "precipitable_water_cm": "precipitable water", "aod": "AOD"}


def _record_columns(rows, lines, name: str, time_labels, keys):
    """The records ``rows`` (month, day, hour, then one text field per key of ``keys``) read
    at line numbers ``lines`` as columns: the line numbers (int array), the month, day and
    hour as int arrays (``time_labels`` name them in errors) and the quantities by key
    (:func:`_column` each)."""
    line_of = np.array(lines, dtype=np.int64)
    cols = list(zip(*rows))
    ints = [_column(cols[j], line_of, name, lab, integer=True).astype(np.int64)
            for j, lab in enumerate(time_labels)]
    values = {key: _column(cols[3 + j], line_of, name, _LABELS[key]) for j, key in enumerate(keys)}
    return line_of, ints, values


def _parse_epw(p: Path, name: str):
    """Site, (month, day, hour) arrays, quantity arrays and line numbers of an EPW file."""
    site = None
    want = (1, 2, 3, *_EPW_FIELDS.values())  # month, day, hour, then the quantities
    rows: list[list[str]] = []
    lines: list[int] = []
    rec = 0
    for k, text in _iter_lines(p, name):
        if k == 1:
            f = text.split(",", 12)
            if f[0].strip().upper() != "LOCATION" or len(f) < 10:
                raise ValueError(f"weather = {name!r}: line 1 is not an EPW LOCATION header "
                                 "(LOCATION,city,state,country,source,WMO,lat,lon,TZ,elev)")
            site = _header_site(f, name, _EPW_SITE)
            continue
        if k <= 8 or not text.strip():
            continue  # the other seven header lines [EPW]
        rec += 1
        if rec > MAX_RECORDS:
            raise _too_many(name, k)
        f = _split_record(text, ",", name, rec, k, 35)
        rows.append([f[i] for i in want])
        lines.append(k)
    if site is None:
        raise ValueError(f"weather = {name!r}: empty file")
    if rec == 0:
        raise ValueError(f"weather = {name!r}: truncated, no data records")
    line_of, ints, values = _record_columns(rows, lines, name, ("month", "day", "hour"),
                                            _EPW_FIELDS)
    for key, v in values.items():
        if key in _EPW_MISSING:
            v[v >= _EPW_MISSING[key]] = np.nan
    values["precipitable_water_cm"] = values["precipitable_water_cm"] / 10.0  # EPW: mm
    return site, *ints, values, line_of


def _parse_tmy3(p: Path, name: str):
    """Site, (month, day, hour) arrays, quantity arrays and line numbers of a TMY3 file."""
    import csv

    site = None
    index: dict[str, int] = {}
    need = i_date = i_time = 0
    keys: list[str] = []
    want: list[int] = []
    rows: list[list[str]] = []
    lines: list[int] = []
    rec = 0
    for k, text in _iter_lines(p, name):
        if k == 1:
            f = next(csv.reader([text]), [])
            if len(f) < 7:
                raise ValueError(f"weather = {name!r}: line 1 is not a TMY3 site header "
                                 "(USAF,Name,State,TZ,latitude,longitude,altitude)")
            site = _header_site(f, name, _TMY3_SITE)
            continue
        if k == 2:
            heads = text.split(",")
            if len(heads) > MAX_FIELDS:
                raise ValueError(f"weather = {name!r}: line 2 has {len(heads)} column names; "
                                 f"a TMY3 file has 71 (at most {MAX_FIELDS} are read)")
            index = {h.strip(): i for i, h in enumerate(heads)}
            need = len(heads)
            for col in ("Date (MM/DD/YYYY)", "Time (HH:MM)"):
                if col not in index:
                    raise ValueError(f"weather = {name!r}: line 2 has no {col!r} column")
            i_date, i_time = index["Date (MM/DD/YYYY)"], index["Time (HH:MM)"]
            keys = [key for key, col in _TMY3_FIELDS.items() if col in index]
            want = [index[_TMY3_FIELDS[key]] for key in keys]
            continue
        if not text.strip():
            continue
        rec += 1
        if rec > MAX_RECORDS:
            raise _too_many(name, k)
        f = _split_record(text, ",", name, rec, k, need)
        d = f[i_date].strip().split("/")
        t = f[i_time].strip().split(":")
        if len(d) < 2:
            raise ValueError(f"{_where(name, rec, k)}, field date = {f[i_date][:20]!r} is not "
                             "MM/DD/YYYY")
        rows.append([d[0], d[1], t[0], *(f[i] for i in want)])
        lines.append(k)
    if site is None or not index:
        raise ValueError(f"weather = {name!r}: truncated, no TMY3 header")
    if rec == 0:
        raise ValueError(f"weather = {name!r}: truncated, no data records")
    line_of, ints, got = _record_columns(
        rows, lines, name, ("date (month)", "date (day)", "time (hour)"), keys)
    values = {key: got.get(key) for key in _TMY3_FIELDS}
    return site, *ints, values, line_of


def _detect_format(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix == ".epw":
        return "epw"
    if suffix == ".wea":
        return "wea"
    first = _first_line(path)
    if first.upper().startswith("LOCATION,"):
        return "epw"
    if suffix == ".csv" or first.split(",")[0].strip().isdigit():
        return "tmy3"
    raise ValueError(f"weather = {str(path)!r}: not an EPW or TMY3 file "
                     "(expected a .epw or a TMY3 .csv)")


def read_weather(path, *, year: int = 2021, sun_position: str = "spa") -> Weather:
    """Read an hourly EPW, TMY3 or Radiance .wea weather file and compute the sun at each
    hour's midpoint.

    Parameters
    ----------
    path : str or Path
        ``.epw`` (EnergyPlus [EPW]) or TMY3 ``.csv`` [WM08]; or a Radiance ``.wea`` file
        (gendaymtx's input, as epw2wea and :func:`write_wea` write it: a six-line header,
        then ``month day hour DNI DHI`` with the hour's midpoint and
        ``weather_data_file_units 1``, W m^-2). A .wea holds no dew point, albedo or GHI
        (GHI is DHI + DNI cos(zenith)). Text in UTF-8 or Latin-1, with or without a UTF-8
        byte-order mark.
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
        Not an EPW/TMY3/.wea file; a line longer than :data:`MAX_LINE_BYTES`, a record with
        more than :data:`MAX_FIELDS` fields or more than :data:`MAX_RECORDS` records (each
        refused as soon as it is read, so that neither time nor memory grows with such a
        file); truncated (a full typical year has 8760 records; a partial file must still
        step by exactly one hour); a field that is not a number; missing DNI/DHI values,
        values outside :data:`WEATHER_LIMITS` (e.g. illuminances in irradiance columns), or
        a time step other than one hour. The message names the file, the record and its
        line, and the field.
    """
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"weather = {str(path)!r}: no such file")
    if not p.is_file():
        raise ValueError(f"weather = {str(path)!r} is not a file")
    from skydome._validate import check_choice, check_int

    check_choice("sun_position", sun_position, ("spa", "radiance"))
    check_int("year", year, 1, 9999)
    fmt = _detect_format(p)
    if fmt == "wea":
        return _read_wea(p, year, sun_position)
    name = str(path)
    parse = _parse_epw if fmt == "epw" else _parse_tmy3
    site, months, days, hours, values, line_of = parse(p, name)
    n = len(months)
    if not (-90.0 <= site.latitude_deg <= 90.0) or not (-180.0 <= site.longitude_deg <= 180.0):
        raise ValueError(f"weather = {name!r}: latitude {site.latitude_deg:g} / longitude "
                         f"{site.longitude_deg:g} deg out of range")
    if not -12.0 <= site.utc_offset_h <= 14.0:
        raise ValueError(f"weather = {name!r}: time zone {site.utc_offset_h:g} h is out of "
                         "range [-12, 14] h")

    def at(k: int) -> str:
        return f"record {k + 1} (line {line_of[k]})"

    # -- time: the end of each record's hour from its own date and hour fields (TMY3 "MM/DD",
    # "HH:00" with HH 1..24 [WM08]; EPW month, day, hour 1..24 [EPW]), placed in ``year``;
    # records must step by exactly one hour.
    bad = (months < 1) | (months > 12) | (days < 1) | (days > 31)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise ValueError(f"weather = {name!r}: {at(k)}, month/day {months[k]}/{days[k]} is "
                         "not a date")
    y0 = np.datetime64(f"{year:04d}-01", "M")
    day0 = (y0 + (months - 1)).astype("datetime64[D]") + (days - 1)
    bad = (day0.astype("datetime64[M]") - y0).astype(np.int64) != months - 1  # e.g. 02/30
    if np.any(bad):
        k = int(np.argmax(bad))
        raise ValueError(f"weather = {name!r}: {at(k)}, month/day {months[k]}/{days[k]} is "
                         f"not a date in {year}")
    if np.any(hours < 1) or np.any(hours > 24):
        k = int(np.argmax((hours < 1) | (hours > 24)))
        raise ValueError(f"weather = {name!r}: hour {hours[k]} of {at(k)} is out of "
                         "range [1, 24]")
    t_end = day0.astype("datetime64[s]") + hours.astype("timedelta64[h]")
    step = np.diff(t_end).astype(np.int64)
    if np.any(step != 3600):
        k = int(np.argmax(step != 3600))
        raise ValueError(f"weather = {name!r}: time step {step[k] / 3600:g} h between "
                         f"{at(k)} and {at(k + 1)} ({t_end[k]} -> {t_end[k + 1]}); "
                         "only hourly files are supported")
    if n != 8760 and n != 8784:
        # A partial year is allowed only if it is whole days; anything else is truncated.
        if n % 24 != 0:
            raise ValueError(f"weather = {name!r}: truncated, {n} hourly records "
                             "(a year has 8760; a partial file must hold whole days)")
    t_mid = t_end - np.timedelta64(1800, "s")  # the hour's midpoint

    # -- quantities ----------------------------------------------------------------------------
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
            raise ValueError(f"weather = {name!r}: no {key} column")
        bad = ~np.isfinite(v)
        if np.any(bad):
            k = int(np.argmax(bad))
            raise ValueError(f"weather = {name!r}: missing {key} value at {at(k)} "
                             f"({t_end[k]}), field {_LABELS[key]}")
    for key, (lo, hi, unit) in WEATHER_LIMITS.items():
        v = values.get(key)
        if v is None:
            continue
        bad = np.isfinite(v) & ((v < lo) | (v > hi))
        if np.any(bad):
            k = int(np.argmax(bad))
            raise ValueError(f"weather = {name!r}: {key} = {v[k]:g} at {at(k)} "
                             f"({t_end[k]}), field {_LABELS[key]}, is out of range "
                             f"[{lo:g}, {hi:g}] {unit} (wrong units?)")

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


def _pvlib_spa():
    """pvlib's ``spa`` module (its numpy NREL SPA [RA04]) without importing the ``pvlib``
    package: ``pvlib/__init__`` imports every subpackage (SciPy's integrate and optimize,
    pandas; 0.8-1.1 s of CPU on a 2-core EPYC), while ``spa.py`` needs numpy alone. None
    when pvlib's SPA would be numba-compiled (PVLIB_USE_NUMBA set; pvlib then reloads it for
    its numpy path, which :func:`_spa_zenith_azimuth` takes through pvlib instead)."""
    import os
    import sys

    if os.getenv("PVLIB_USE_NUMBA", "0") != "0":
        return None
    mod = sys.modules.get("pvlib.spa")
    if mod is not None:
        return None if mod.USE_NUMBA else mod
    import importlib.util

    spec = importlib.util.find_spec("pvlib")  # finds the package; runs nothing of it
    if spec is None or not spec.submodule_search_locations:
        return None
    path = Path(next(iter(spec.submodule_search_locations))) / "spa.py"
    sub = importlib.util.spec_from_file_location("pvlib.spa", path)
    if sub is None or sub.loader is None:
        return None
    mod = importlib.util.module_from_spec(sub)
    sub.loader.exec_module(mod)  # not put in sys.modules: a later ``import pvlib`` is whole
    return None if mod.USE_NUMBA else mod


def _spa_zenith_azimuth(site: Site, t_mid):
    """True zenith and azimuth [deg] by pvlib's NREL SPA [RA04] at local-standard instants.

    The arguments are those of pvlib's ``get_solarposition(..., altitude=elevation,
    method="nrel_numpy")``, passed to its ``spa.solar_position_numpy`` directly (the same
    numbers, bit for bit: tests/test_daylighting_weather.py), without pandas or the pvlib
    package's imports: instants as Unix seconds (UTC nanoseconds / 1e9, as pvlib's
    ``_datetime_to_unixtime``), pressure from the site's elevation by pvlib's ``alt2pres``
    (hPa; it moves only the apparent, refracted position, which is not used), 12 degC,
    delta T 67 s, refraction 0.5667 deg (pvlib's defaults)."""
    spa = _pvlib_spa()
    if spa is None:
        return _spa_zenith_azimuth_pvlib(site, t_mid)
    t = np.asarray(t_mid, dtype="datetime64[ns]")
    offset_us = round(site.utc_offset_h * 3_600_000_000)  # datetime.timedelta(hours=...)
    ns = t.astype(np.int64) - offset_us * 1000
    unixtime = ns / np.int64(1_000_000_000)
    alt = float(site.elevation_m)
    pressure = 100 * ((44331.514 - alt) / 11880.516) ** (1 / 0.1902632)  # pvlib alt2pres
    res = spa.solar_position_numpy(unixtime, site.latitude_deg, site.longitude_deg, alt,
                                   pressure / 100, 12.0, 67.0, 0.5667, 4)
    return (np.asarray(res[1], dtype=np.float64), np.asarray(res[4], dtype=np.float64))


def _spa_zenith_azimuth_pvlib(site: Site, t_mid):
    """:func:`_spa_zenith_azimuth` through pvlib's ``get_solarposition`` (with pandas)."""
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
    head: dict = {}
    keys = ("place", "latitude", "longitude", "time_zone", "site_elevation",
            "weather_data_file_units")
    rows: list[list[float]] = []
    line_of: list[int] = []
    labels = ("month", "day", "hour", "DNI", "DHI")
    in_head = True
    for k, text in _iter_lines(p, name):
        if in_head and text.split(" ", 1)[0] in keys:
            key, _, val = text.partition(" ")
            head[key] = val.strip()
            continue
        if in_head:
            in_head = False
            for key in keys[1:]:
                if key not in head:
                    raise ValueError(f"weather = {name!r}: .wea header lacks {key!r}")
        if not text.strip():
            continue
        j = len(rows) + 1
        if j > MAX_RECORDS:
            raise _too_many(name, k)
        f = text.split(None, MAX_FIELDS)
        if len(f) != 5:
            raise ValueError(f"weather = {name!r}: truncated record (record {j}: "
                             f"{len(f) if len(f) <= MAX_FIELDS else 'too many'} of 5 fields, "
                             f"line {k})")
        try:  # the common case: five finite numbers (no per-field messages needed)
            r = [float(v) for v in f]
        except ValueError:
            r = None
        if r is None or not all(map(math.isfinite, r)):
            try:
                r = [_number(v, name, j, k, lab) for v, lab in zip(f, labels)]
            except ValueError as exc:
                raise ValueError(f"{exc} (a record that is not numeric)") from None
            if any(np.isnan(r)):
                raise ValueError(f"{_where(name, j, k)} is not numeric")
        rows.append(r)
        line_of.append(k)
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
    if not all(np.isfinite([site.latitude_deg, site.longitude_deg, site.utc_offset_h,
                            site.elevation_m])):
        raise ValueError(f"weather = {name!r}: bad .wea header value (not finite)")
    if not (-90.0 <= site.latitude_deg <= 90.0) or not (-180.0 <= site.longitude_deg <= 180.0):
        raise ValueError(f"weather = {name!r}: latitude {site.latitude_deg:g} / longitude "
                         f"{site.longitude_deg:g} deg out of range")
    if not rows:
        raise ValueError(f"weather = {name!r}: truncated, no data records")
    data = np.array(rows, dtype=np.float64)
    lines = np.array(line_of, dtype=np.int64)
    n = data.shape[0]

    def at(j: int) -> str:
        return f"record {j + 1} (line {lines[j]})"

    bad = ((data[:, 0] != np.round(data[:, 0])) | (data[:, 1] != np.round(data[:, 1]))
           | (data[:, 0] < 1) | (data[:, 0] > 12) | (data[:, 1] < 1) | (data[:, 1] > 31)
           | (data[:, 2] < 0.0) | (data[:, 2] > 24.0))
    if np.any(bad):
        j = int(np.argmax(bad))
        raise ValueError(f"weather = {name!r}: {at(j)}, month/day/hour "
                         f"{data[j, 0]:g}/{data[j, 1]:g} {data[j, 2]:g} is not a date and hour")
    mo, da = data[:, 0].astype(np.int64), data[:, 1].astype(np.int64)
    y0 = np.datetime64(f"{year:04d}-01", "M")
    t_day = (y0 + (mo - 1)).astype("datetime64[D]") + (da - 1)
    t_mid = t_day.astype("datetime64[s]") + np.round(data[:, 2] * 3600.0).astype(
        "timedelta64[s]")
    step = np.diff(t_mid).astype(np.int64)
    if np.any(step != 3600):
        j = int(np.argmax(step != 3600))
        raise ValueError(f"weather = {name!r}: time step {step[j] / 3600:g} h between "
                         f"{at(j)} and {at(j + 1)}; only hourly files are supported")
    if n not in (8760, 8784) and n % 24 != 0:
        raise ValueError(f"weather = {name!r}: truncated, {n} hourly records "
                         "(a year has 8760; a partial file must hold whole days)")
    dni, dhi = data[:, 3].copy(), data[:, 4].copy()
    for key, v in (("dni", dni), ("dhi", dhi)):
        lo, hi, unit = WEATHER_LIMITS[key]
        bad = ~np.isfinite(v) | (v < lo) | (v > hi)
        if np.any(bad):
            j = int(np.argmax(bad))
            raise ValueError(f"weather = {name!r}: {key} = {v[j]:g} at {at(j)}, field "
                             f"{_LABELS[key]}, is out of range [{lo:g}, {hi:g}] {unit} "
                             "(wrong units?)")
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
