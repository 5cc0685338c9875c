"""The Kider et al. 2014 spectral sky scans of 2013-05-27 and 2013-09-24 (Cornell, Ithaca NY).

:func:`load_captures` reads the compact derived tables shipped in ``skydome/data``
(``kider2014_YYYYMMDD_radiance.csv.gz``, ``kider2014_YYYYMMDD_ghi.csv``, one pair per day
of :data:`DAYS`; derived by
``tools/derive_kider2014.py`` from the data set ``sky-measurements-2014``, Apache-2.0) and
returns one :class:`Capture` per scan: the 81 directions in skydome's East-North-Up frame,
the time of every sample, the sun (NREL SPA through :func:`skydome.sun.solar_position`) at
the capture's mean time and at every sample, the measured spectral radiance
[W m^-2 sr^-1 nm^-1] at 350-1000 nm (5 nm) and the pyranometer's global horizontal
irradiance [W m^-2] averaged over the scan.

Conventions (established from the data by :func:`fit_conventions`, tested in
tests/validation/test_kider2014.py):

* **Azimuth.** The azimuth written in the scanner's file names runs counter-clockwise
  from north (as Bruneton's reader, ebruneton/clear-sky-models
  ``atmosphere/measurement/measured_atmosphere.cc``, notes): skydome's azimuth (from north
  towards east) is ``(360 - azimuth_file) mod 360``.
* **Time.** Capture labels are local clock times, Eastern Daylight Time (UTC-4) on that
  day. A scan lasts about 343 s (the pyranometer files of a capture run 09:30:00-09:35:43),
  so sample i is taken near ``start + (i + 0.5) * 343 s / 81``.

* **Clock.** With the labels read as EDT, the sun seen in the data of 2013-05-27 lies
  7-12 deg from the SPA sun at every capture, always towards where the sun was earlier
  that morning. Two estimators measure the shift. The centre of the circumsolar peak
  (:func:`sun_from_data`, :func:`fit_clock_offset`) matches the SPA sun of about 40
  minutes before the label (:data:`PEAK_CLOCK_OFFSET_MIN`), but the 20 deg gaps between
  the scanner's rings leave that centre poorly determined. The whole sky's shape
  (:func:`skydome.validation.compare.clock_scan`: hillaire2020 with the AERONET aerosol,
  the RMS of ln(model / measured) about its mean, sun at the label plus -70 ... +20 min,
  the best offset of each capture the vertex of a parabola through the best grid offset
  and its neighbours) puts it at the label minus 19-40 min; the loader takes the median of
  those per-capture best offsets of the point model over the 15 captures, as
  ``tools/validation_measured.py OUT --clock --day 2013-05-27`` prints it, rounded to
  the minute: :data:`CLOCK_OFFSET_MIN` (tests/test_validation_kider2014.py reruns a
  cheaper scan and fails if the two drift apart). One shift fixing elevation and azimuth
  together points to the scanner's clock rather than to its azimuth alignment (an
  azimuth offset would leave the elevation error); modelling the scanner's motion (each
  sample the mean along its move) does not remove it (docs/validation_measured.md,
  "Scanner motion and clock"). Bruneton's reader notes the same mismatch and estimates
  the sun azimuth from the symmetry axis instead. 2013-09-24's scans fit best at their
  labels (:data:`CLOCK_OFFSETS_MIN`: 0 for that day). ``load_captures(clock_offset_min=0)``
  gives the labels as they are.

With the file azimuth read clockwise, or with UTC-5, the data do not fit at any shift near
zero (see :func:`fit_conventions`).
"""

from __future__ import annotations

import gzip
from dataclasses import dataclass
from datetime import datetime, timedelta, timezone
from functools import lru_cache

import numpy as np

__all__ = ["DAYS", "DEFAULT_DAY", "CLOCK_OFFSETS_MIN", "CLOCK_OFFSET_MIN",
           "PEAK_CLOCK_OFFSET_MIN",
           "fit_clock_offset", "SITE_LATITUDE_DEG", "SITE_LONGITUDE_DEG", "SITE_ALTITUDE_M",
           "SCAN_DURATION_S", "Capture", "load_captures", "capture_labels",
           "fit_conventions", "sun_from_data"]

#: Rhodes Hall roof, Cornell University (Kider et al. 2014, sec. 4)
SITE_LATITUDE_DEG = 42.443449
SITE_LONGITUDE_DEG = -76.481962
#: Approximate height of the site above sea level [m] (Ithaca's Cornell campus ~ 250 m;
#: not given by the data set; the models place the observer at sea level, see
#: docs/validation_measured.md)
SITE_ALTITUDE_M = 250.0
#: Duration of one 81-sample scan [s] (first to last pyranometer record of a capture)
SCAN_DURATION_S = 343.0
#: Eastern Daylight Time, the time zone of the capture labels
EDT = timezone(timedelta(hours=-4), "EDT")
#: Correction added to 2013-05-27's capture labels [min]: the median over its 15 captures of
#: the best clock offset of the whole sky's shape (point model;
#: :func:`skydome.validation.compare.clock_scan`, printed by ``tools/validation_measured.py
#: OUT --clock --day 2013-05-27`` as "median of the per-capture best offsets": -23.0 min)
CLOCK_OFFSET_MIN = -23.0
#: The shift the circumsolar peak alone gives (:func:`fit_clock_offset`, median over the
#: captures; the loader's default before the whole-sky scan, kept for that comparison)
PEAK_CLOCK_OFFSET_MIN = -40.0
#: The days of the data set (its every day), the first the default
DAYS = ("2013-05-27", "2013-09-24")
DEFAULT_DAY = DAYS[0]
#: Clock correction per day [min]: 2013-05-27 the whole-sky scan's :data:`CLOCK_OFFSET_MIN`,
#: 2013-09-24 none (its scans fit best within 6 min of the labels;
#: docs/validation_measured.md)
CLOCK_OFFSETS_MIN = {"2013-05-27": CLOCK_OFFSET_MIN, "2013-09-24": 0.0}
DATE = (2013, 5, 27)


def _check_day(day: str) -> str:
    if day not in DAYS:
        raise ValueError(f"day must be one of {', '.join(DAYS)}, got {day!r}")
    return day


def _date(day: str) -> tuple[int, int, int]:
    y, m, d = (int(x) for x in _check_day(day).split("-"))
    return y, m, d


def _stem(day: str) -> str:
    return "kider2014_" + _check_day(day).replace("-", "")


@lru_cache(maxsize=4)
def _read_radiance(day: str = DEFAULT_DAY):
    from skydome.data import DATA_DIR

    with gzip.open(DATA_DIR / f"{_stem(day)}_radiance.csv.gz", "rt", encoding="utf-8") as f:
        lines = [ln for ln in f if ln.strip() and not ln.startswith("#")]
    header = lines[0].strip().split(",")
    wl = np.array([float(h) for h in header[4:]])
    labels, rest = [], []
    for ln in lines[1:]:
        parts = ln.strip().split(",")
        labels.append(parts[0])
        rest.append([float(x) for x in parts[1:]])
    arr = np.array(rest)
    arr.setflags(write=False)
    wl.setflags(write=False)
    return tuple(labels), arr, wl


@lru_cache(maxsize=4)
def _read_ghi(day: str = DEFAULT_DAY):
    from skydome.data import DATA_DIR

    times, vals = [], []
    with (DATA_DIR / f"{_stem(day)}_ghi.csv").open(encoding="utf-8") as f:
        for ln in f:
            if ln.startswith("#") or ln.startswith("time") or not ln.strip():
                continue
            t, v = ln.strip().split(",")
            h, m, s = (int(x) for x in t.split(":"))
            times.append(h * 3600 + m * 60 + s)
            vals.append(float(v))
    return np.array(times, dtype=np.float64), np.array(vals)


def capture_labels(day: str = DEFAULT_DAY) -> tuple[str, ...]:
    """The capture labels of ``day`` (local clock time of the scan start, "HH:MM:SS"):
    15 on 2013-05-27, 5 on 2013-09-24."""
    labels, _, _ = _read_radiance(_check_day(day))
    return tuple(dict.fromkeys(labels))


def _seconds(label: str) -> int:
    h, m, s = (int(x) for x in label.split(":"))
    return h * 3600 + m * 60 + s


@dataclass(frozen=True, eq=False)
class Capture:
    """One scan of the sky: 81 directions, their times, the sun and the spectra.

    Attributes
    ----------
    label : str
        Local clock time of the scan start (EDT), "HH:MM:SS", as the data set labels it.
    day : str
        The day, "YYYY-MM-DD" (one of :data:`DAYS`).
    start : datetime
        Scan start, timezone-aware: the label plus the clock correction.
    sample_times : ndarray of datetime (81,)
        Estimated time of each sample, ``start + (i + 0.5) * duration / 81``.
    mean_time : datetime
        Mean time of the scan.
    azimuth_file_deg, elevation_deg : ndarray (81,)
        The angles of the file names [deg] (file azimuth counter-clockwise from north).
    azimuth_deg : ndarray (81,)
        Azimuth from north towards east [deg] (skydome's convention).
    directions : ndarray (81, 3)
        Unit vectors in the ENU frame.
    wavelengths_nm : ndarray (nw,)
        350, 355, ..., 1000 nm.
    radiance : ndarray (81, nw)
        Measured spectral radiance [W m^-2 sr^-1 nm^-1].
    sun : skydome.Sun
        The sun at ``mean_time`` (SPA, geometric elevation, no refraction).
    sample_sun_elevation_deg, sample_sun_azimuth_deg : ndarray (81,)
        The sun at each sample's time [deg].
    ghi_w_m2 : float
        Pyranometer global horizontal irradiance averaged over the scan [W m^-2].
    """

    label: str
    day: str
    start: datetime
    sample_times: np.ndarray
    mean_time: datetime
    azimuth_file_deg: np.ndarray
    elevation_deg: np.ndarray
    azimuth_deg: np.ndarray
    directions: np.ndarray
    wavelengths_nm: np.ndarray
    radiance: np.ndarray
    sun: object
    sample_sun_elevation_deg: np.ndarray
    sample_sun_azimuth_deg: np.ndarray
    ghi_w_m2: float

    @property
    def sun_angle_deg(self) -> np.ndarray:
        """Angle between each sample direction and the sun at the mean time [deg]."""
        c = np.clip(self.directions @ self.sun.direction, -1.0, 1.0)
        return np.degrees(np.arccos(c))


def _enu(azimuth_deg, elevation_deg):
    az, el = np.radians(azimuth_deg), np.radians(elevation_deg)
    return np.stack([np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)], axis=-1)


def _azimuth_from_file(azimuth_file_deg, convention: str = "ccw"):
    if convention == "ccw":
        return np.mod(360.0 - np.asarray(azimuth_file_deg), 360.0)
    if convention == "cw":
        return np.mod(np.asarray(azimuth_file_deg), 360.0)
    raise ValueError(f"convention must be 'ccw' or 'cw', got {convention!r}")


def _capture(label: str, utc_offset_h: float = -4.0, azimuth_convention: str = "ccw",
             clock_offset_min: float = CLOCK_OFFSET_MIN, day: str = DEFAULT_DAY) -> Capture:
    from skydome.sun import Sun, solar_position

    labels, arr, wl = _read_radiance(day)
    rows = np.array([lab == label for lab in labels])
    if not rows.any():
        raise ValueError(f"capture must be one of {', '.join(capture_labels(day))}, got {label!r}")
    block = arr[rows]
    order = np.argsort(block[:, 0])
    block = block[order]
    tz = timezone(timedelta(hours=utc_offset_h))
    h, m, s = (int(x) for x in label.split(":"))
    start = datetime(*_date(day), h, m, s, tzinfo=tz) + timedelta(minutes=clock_offset_min)
    n = block.shape[0]
    dt = SCAN_DURATION_S / n
    times = np.array([start + timedelta(seconds=(i + 0.5) * dt) for i in range(n)], dtype=object)
    mean_time = start + timedelta(seconds=SCAN_DURATION_S / 2.0)
    az_file, el = block[:, 1].copy(), block[:, 2].copy()
    az = _azimuth_from_file(az_file, azimuth_convention)
    sun = Sun.from_location(SITE_LATITUDE_DEG, SITE_LONGITUDE_DEG, mean_time)
    s_el, s_az = solar_position(SITE_LATITUDE_DEG, SITE_LONGITUDE_DEG, list(times))
    gt, gv = _read_ghi(day)
    t0 = _seconds(label)
    sel = (gt >= t0) & (gt <= t0 + SCAN_DURATION_S)
    ghi = float(np.mean(gv[sel])) if sel.any() else float("nan")
    return Capture(label=label, day=day, start=start, sample_times=times, mean_time=mean_time,
                   azimuth_file_deg=az_file, elevation_deg=el, azimuth_deg=az,
                   directions=_enu(az, el), wavelengths_nm=np.array(wl),
                   radiance=block[:, 3:].copy(), sun=sun,
                   sample_sun_elevation_deg=np.asarray(s_el, dtype=float),
                   sample_sun_azimuth_deg=np.asarray(s_az, dtype=float), ghi_w_m2=ghi)


def load_captures(labels=None, clock_offset_min: float | None = None,
                  day: str = DEFAULT_DAY) -> list[Capture]:
    """The captures of ``day`` (one of :data:`DAYS`; all of them, or those named in
    ``labels``), with the conventions of the module docstring; ``clock_offset_min`` [min] in
    [-120, 120] is added to the labels (default: the day's :data:`CLOCK_OFFSETS_MIN`). The
    pyranometer GHI is averaged over the labelled scan window."""
    from skydome._validate import check_number

    _check_day(day)
    if clock_offset_min is None:
        clock_offset_min = CLOCK_OFFSETS_MIN[day]
    off = check_number("clock_offset_min", clock_offset_min, -120.0, 120.0, "min")
    if labels is None:
        labels = capture_labels(day)
    elif isinstance(labels, str):
        labels = [labels]
    valid = capture_labels(day)
    for lab in labels:
        if lab not in valid:
            raise ValueError(f"capture must be one of {', '.join(valid)}, got {lab!r}")
    return [_capture(lab, clock_offset_min=off, day=day) for lab in labels]


# -- the conventions, from the data ----------------------------------------------------------
def _band_radiance(radiance, wavelengths_nm, lo=400.0, hi=700.0):
    sel = (wavelengths_nm >= lo) & (wavelengths_nm <= hi)
    return radiance[:, sel].mean(axis=1)


def sun_from_data(azimuth_deg, elevation_deg, radiance, exclude=(0,)):
    """Estimate the sun's direction from one scan [deg]: (elevation, azimuth).

    The 400-700 nm mean radiance of the samples within 40 deg of the brightest one is fitted
    by ``ln L = a + b gamma + c gamma^2`` with gamma the angle to an unknown centre (least
    squares over the centre and a, b, c); the centre is the estimate. Samples in ``exclude``
    (sample 0 by default: Bruneton notes it seems systematically wrong) are left out.
    """
    from scipy.optimize import least_squares

    az = np.asarray(azimuth_deg, float)
    el = np.asarray(elevation_deg, float)
    L = np.asarray(radiance, float)
    keep = np.ones(L.size, bool)
    keep[list(exclude)] = False
    d = _enu(az, el)
    i0 = np.flatnonzero(keep)[np.argmax(L[keep])]
    near = keep & (np.degrees(np.arccos(np.clip(d @ d[i0], -1, 1))) < 40.0)
    dn, y = d[near], np.log(L[near])

    def resid(p):
        c = _enu(p[1], p[0])
        g = np.arccos(np.clip(dn @ c, -1, 1))
        return p[2] + p[3] * g + p[4] * g * g - y

    best = None
    for del_ in (-8.0, 0.0, 8.0):
        for daz in (-10.0, 0.0, 10.0):
            p0 = [el[i0] + del_, az[i0] + daz, y.max(), -2.0, 1.0]
            r = least_squares(resid, p0)
            if best is None or r.cost < best.cost:
                best = r
    return float(best.x[0]), float(np.mod(best.x[1], 360.0))


def _angle_deg(el1, az1, el2, az2):
    return float(np.degrees(np.arccos(np.clip(_enu(az1, el1) @ _enu(az2, el2), -1, 1))))


def fit_conventions(labels=None, day: str = DEFAULT_DAY) -> dict:
    """Compare the sun seen in the data with SPA under each reading of the files.

    For each capture the sun is estimated from the radiance (:func:`sun_from_data`) with the
    file azimuth read counter-clockwise ("ccw") and clockwise ("cw") from north, and SPA
    gives the sun at the scan's mean time for the labels read as UTC-4 (EDT) and UTC-5
    (EST). Returns ``{(convention, utc_offset_h): angles}``: the angle [deg] between the
    estimated and the SPA sun per capture (an array), for the four combinations.
    """
    from skydome.sun import solar_position

    labels = capture_labels(day) if labels is None else labels
    labs, arr, wl = _read_radiance(_check_day(day))
    out = {}
    for conv in ("ccw", "cw"):
        for off in (-4.0, -5.0):
            angles = []
            for lab in labels:
                rows = np.array([x == lab for x in labs])
                block = arr[rows][np.argsort(arr[rows][:, 0])]
                az = _azimuth_from_file(block[:, 1], conv)
                el = block[:, 2]
                L = _band_radiance(block[:, 3:], wl)
                e_el, e_az = sun_from_data(az, el, L)
                h, m, s = (int(x) for x in lab.split(":"))
                t = datetime(*_date(day), h, m, s, tzinfo=timezone(timedelta(hours=off))) \
                    + timedelta(seconds=SCAN_DURATION_S / 2.0)
                s_el, s_az = solar_position(SITE_LATITUDE_DEG, SITE_LONGITUDE_DEG, t)
                angles.append(_angle_deg(e_el, e_az, float(s_el), float(s_az)))
            out[(conv, off)] = np.array(angles)
    return out


def fit_clock_offset(labels=None, offsets_min=np.arange(-90.0, 31.0, 1.0),
                     day: str = DEFAULT_DAY) -> dict:
    """The clock correction that brings the SPA sun onto the sun seen in the data.

    For each capture (labels read as EDT, file azimuth counter-clockwise) the angle between
    :func:`sun_from_data` and the SPA sun at the scan's mean time plus each offset [min] is
    computed. Returns ``{"offsets_min", "angles_deg" (captures, offsets), "best_min"
    (per capture), "median_best_min", "labels"}``.
    """
    from skydome.sun import solar_position

    labels = capture_labels(day) if labels is None else tuple(labels)
    offs = np.asarray(offsets_min, dtype=np.float64)
    angles = np.empty((len(labels), offs.size))
    for k, c in enumerate(load_captures(labels, clock_offset_min=0.0, day=day)):
        e_el, e_az = sun_from_data(c.azimuth_deg, c.elevation_deg,
                                   _band_radiance(c.radiance, c.wavelengths_nm))
        ts = [c.mean_time + timedelta(minutes=float(o)) for o in offs]
        s_el, s_az = solar_position(SITE_LATITUDE_DEG, SITE_LONGITUDE_DEG, ts)
        angles[k] = [_angle_deg(e_el, e_az, float(a), float(b)) for a, b in zip(s_el, s_az)]
    best = offs[np.argmin(angles, axis=1)]
    return {"offsets_min": offs, "angles_deg": angles, "best_min": best,
            "median_best_min": float(np.median(best)), "labels": labels}


#: Samples left out of the statistics: sample 0 (north, low, the first of each scan) reads
#: 25-42 % below the mean of its two ring neighbours in every capture from 10:00 on, more
#: than 10 % below any other sample of the ring by that measure (bar its neighbours)
#: (tests/test_validation_kider2014.py); Bruneton notes it seems systematically wrong
#: (clear-sky-models, measured_atmosphere.cc).
EXCLUDED_SAMPLES = (0,)
