"""Derive skydome's compact tables of one day of the Kider et al. 2014 sky measurements.

Source: Kider, Knowlton, Newlin, Li, Greenberg, "A Framework for the Experimental
Comparison of Solar and Skydome Illumination", ACM TOG 33(6), 2014; data set
"sky-measurements-2014" of the Cornell Program of Computer Graphics (spectralskylight),
Apache License 2.0. Run with a local copy of one day folder of that data set,
``data/YYYY-MM-DD`` (the RADIANCE/*.7z archives and IRRADIANCE/*.txt files; the data set has
2013-05-27 and 2013-09-24), and py7zr installed:

    python tools/derive_kider2014.py PATH/TO/data/2013-05-27 src/skydome/data
    python tools/derive_kider2014.py PATH/TO/data/2013-09-24 src/skydome/data

The day is the folder's name. Writes
* ``kider2014_YYYYMMDD_radiance.csv.gz``: one row per capture and scanner sample: capture
  label (local clock time of the scan start), sample index 0-80, the azimuth and elevation
  written in the file name [deg] (azimuth as the scanner writes it: see
  skydome.validation.kider2014 for its convention), then spectral radiance
  [W m^-2 sr^-1 nm^-1] at 350, 355, ..., 1000 nm, each the mean of the 1 nm samples within
  +-2 nm of the column's wavelength (a 5 nm boxcar; the spectroradiometer's own bandwidth is
  3-10 nm, so nothing resolvable is lost).
* ``kider2014_YYYYMMDD_ghi.csv``: the pyranometer's global horizontal irradiance [W m^-2]
  with its local clock time, every sample of the files that accompany the captures.
"""

from __future__ import annotations

import gzip
import io
import re
import sys
import tempfile
from pathlib import Path

import numpy as np

WAVELENGTHS = np.arange(350, 1001, 5)
NAME = re.compile(r"_-_(\d+)____([0-9.]+)___([0-9.]+)\.asd\.rad\.txt$")
HEADER = """\
# Kider et al. 2014 sky measurements, Cornell (Rhodes Hall roof, 42.443449 N, 76.481962 W),
# day {day}. Source: J. T. Kider Jr., D. Knowlton, J. Newlin, Y. K. Li, D. P. Greenberg,
# "A Framework for the Experimental Comparison of Solar and Skydome Illumination",
# ACM TOG 33(6), 2014; data set sky-measurements-2014 (spectralskylight), Apache License 2.0
# (http://www.apache.org/licenses/LICENSE-2.0); derived by tools/derive_kider2014.py.
"""


def _read_spectrum(text: str) -> tuple[np.ndarray, np.ndarray]:
    rows = [ln.split() for ln in text.splitlines()[1:] if ln.strip()]
    wl = np.array([float(r[0]) for r in rows])
    val = np.array([float(r[1]) for r in rows])
    return wl, val


def derive(day_folder: Path, out_folder: Path) -> None:
    import py7zr

    day = day_folder.name
    if not re.fullmatch(r"\d{4}-\d\d-\d\d", day):
        raise ValueError(f"day_folder must be named YYYY-MM-DD, got {day!r}")
    stem = "kider2014_" + day.replace("-", "")
    header = HEADER.format(day=day)

    rows = []
    for archive in sorted((day_folder / "RADIANCE").glob("*.7z")):
        label = re.search(r"(\d\d)\.(\d\d)\.(\d\d)\.7z$", archive.name)
        capture = f"{label.group(1)}:{label.group(2)}:{label.group(3)}"
        with tempfile.TemporaryDirectory() as tmp:
            with py7zr.SevenZipFile(archive) as z:
                z.extractall(tmp)
            files = {p.name: p.read_text(encoding="ascii") for p in Path(tmp).rglob("*.txt")}
        samples = {}
        for name, text in files.items():
            m = NAME.search(name)
            if not m:
                continue
            wl, val = _read_spectrum(text)
            binned = np.array([val[(wl >= w - 2) & (wl <= w + 2)].mean() for w in WAVELENGTHS])
            samples[int(m.group(1))] = (float(m.group(2)), float(m.group(3)), binned)
        if sorted(samples) != list(range(81)):
            raise ValueError(f"{archive.name}: expected samples 0..80, got {sorted(samples)}")
        for i in range(81):
            az, el, spec = samples[i]
            rows.append(f"{capture},{i},{az:g},{el:g}," + ",".join(f"{v:.5g}" for v in spec))
    out = io.StringIO()
    out.write(header)
    out.write("# columns: capture (local clock time of the scan start), sample, azimuth_file_deg, "
              "elevation_deg, then spectral radiance [W m^-2 sr^-1 nm^-1] at the wavelengths "
              "[nm] in the header row (5 nm boxcar means of the 1 nm data)\n")
    out.write("capture,sample,azimuth_file_deg,elevation_deg,"
              + ",".join(str(w) for w in WAVELENGTHS) + "\n")
    out.write("\n".join(rows) + "\n")
    with gzip.open(out_folder / f"{stem}_radiance.csv.gz", "wt", compresslevel=9) as f:
        f.write(out.getvalue())

    lines = [header.rstrip("\n"),
             "# pyranometer global horizontal irradiance [W m^-2]; time: local clock time",
             "time,ghi_w_m2"]
    for txt in sorted((day_folder / "IRRADIANCE").glob("*.txt")):
        for ln in txt.read_text().splitlines():
            parts = ln.split()
            if len(parts) != 2:
                continue
            value, stamp = parts
            t = stamp.split(".")
            lines.append(f"{t[3]}:{t[4]}:{t[5]},{float(value):g}")
    (out_folder / f"{stem}_ghi.csv").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    derive(Path(sys.argv[1]), Path(sys.argv[2]))
