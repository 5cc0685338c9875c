"""Daylight factor under the CIE standard overcast sky.

The daylight factor of a point is DF = 100 E / E_h [%]: the illuminance E at the point
(sky light reaching it directly, and after reflection by the ground, the room, outside
obstructions) over the illuminance E_h the same sky gives on an unobstructed horizontal
plane outdoors, under the CIE standard overcast sky [CIE94] L = Lz (1 + 2 sin a) / 3 (a the
altitude), which does not depend on the sun's azimuth, so neither does DF.

Two forms:

- :func:`plane_daylight_factor`: an unobstructed plane of any tilt and azimuth outdoors (the
  "sky component" of a plane plus, with a ground reflectance, its externally reflected
  component). The horizontal plane is 100 % by definition; a vertical plane 39.6 % from the
  sky (6/28 + 4/(7 pi), integrated in closed form from the distribution) plus rho / 2 from
  a Lambertian ground of reflectance rho.
- :func:`room_daylight_factor`: sensor points in a Radiance scene (a room with windows), by
  Radiance's ``rtrace -I`` with the overcast sky exported by
  :func:`~skydome.daylighting.scene.write_radiance_sky` and a ground glow of luminance
  rho E_h / pi below the horizon, as the usual Radiance set-up with ``gensky -c`` does.

References
----------
[CIE94] CIE 110-1994, Spatial distribution of daylight - luminance distributions of various
    reference skies; [MS42] P. Moon, D. E. Spencer (1942), Illumination from a non-uniform
    sky, Illuminating Engineering 37, 707-726. G. Ward, Radiance 5.4 manual pages: rtrace
    (-I), oconv, gensky (-c).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

__all__ = ["overcast_sky", "plane_daylight_factor", "room_daylight_factor", "radiance_tool",
           "read_sensors", "check_rtrace_parameters", "RTRACE_PARAMETER_RANGES",
           "DF_SKY_ILLUMINANCE_LX"]

#: Horizontal illuminance of the overcast sky used for the ratio [lx] (DF does not depend on
#: it; 10 klx keeps Radiance's values in a comfortable range).
DF_SKY_ILLUMINANCE_LX = 10000.0
#: Radiance's RGB -> luminance weights and white efficacy [lm W^-1] (color.h).
_RGB_TO_Y = np.array([0.265, 0.670, 0.065])
from skydome.constants import RADIANCE_WHITE_EFFICACY as _WHITE_EFFICACY  # noqa: E402


def overcast_sky(diffuse_horizontal_illuminance: float = DF_SKY_ILLUMINANCE_LX):
    """skydome's CIE 1994 overcast sky scaled to a horizontal illuminance [lx]."""
    import skydome as sd

    return sd.model("cie1994_overcast", sun=sd.Sun(elevation_deg=45.0, azimuth_deg=180.0),
                    diffuse_horizontal_illuminance=diffuse_horizontal_illuminance)


def plane_daylight_factor(tilt_deg=0.0, azimuth_deg=180.0, *, ground_reflectance: float = 0.0):
    """Daylight factor [%] of an unobstructed plane outdoors under the CIE overcast sky.

    Parameters
    ----------
    tilt_deg, azimuth_deg : float or array_like
        Tilt from the horizontal [deg] in [0, 180] and the azimuth the plane faces [deg];
        broadcast together.
    ground_reflectance : float
        Lambertian ground in [0, 1] (default 0: the sky component alone).

    Returns
    -------
    float or numpy.ndarray
        100 (E_sky + E_ground) / E_h, by :func:`skydome.illuminance.illuminance` (the sky
        integrated over the plane's visible hemisphere; the ground seen with view factor
        (1 - cos tilt) / 2).
    """
    from skydome._validate import check_number
    from skydome.illuminance import illuminance, sky_illuminance

    rho = check_number("ground_reflectance", ground_reflectance, 0.0, 1.0)
    sky = overcast_sky()
    e_h = sky_illuminance(sky, 0.0, 180.0)
    pl = illuminance(sky, tilt_deg, azimuth_deg, ground_albedo=rho)
    df = 100.0 * (np.asarray(pl.sky) + np.asarray(pl.ground)) / e_h
    return float(df) if np.ndim(df) == 0 else df


def radiance_tool(name: str) -> tuple[str, dict]:
    """(path, environment) of a Radiance program: the build pyradiance ships, else PATH.

    Raises RuntimeError when neither has it."""
    env = dict(os.environ)
    try:
        import importlib.util

        spec = importlib.util.find_spec("pyradiance")
    except (ImportError, ValueError):
        spec = None
    if spec is not None and spec.submodule_search_locations:
        root = Path(list(spec.submodule_search_locations)[0])
        exe = root / "bin" / name
        if exe.exists():
            env["RAYPATH"] = os.pathsep.join([".", str(root / "lib")])
            env["PATH"] = os.pathsep.join([str(root / "bin"), env.get("PATH", "")])
            return str(exe), env
    found = shutil.which(name)
    if found is None:
        raise RuntimeError(f"Radiance's {name} was not found (install pyradiance or Radiance)")
    return found, env


#: Longest line of a sensor points file read [bytes] (six numbers need under 200).
MAX_SENSOR_LINE_BYTES = 4096


def read_sensors(path) -> np.ndarray:
    """Sensor points of a Radiance points file: one ``x y z dx dy dz`` per line -> (n, 6).

    Read line by line (at most MAX_SENSOR_LINE_BYTES a line); a binary file, a line that is
    not text or not six numbers is refused naming the file and the line."""
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"sensors = {str(path)!r}: no such file")
    from skydome.daylighting.weather import bounded_lines

    rows = []
    for k, raw in bounded_lines(p, f"sensors = {str(path)!r}", MAX_SENSOR_LINE_BYTES,
                                "a points file"):
        try:
            ln = raw.decode("ascii")
        except UnicodeDecodeError:
            ln = None
        if ln is None or "\x00" in ln:
            raise ValueError(f"sensors = {str(path)!r}: line {k} is not text (a binary "
                             "file?); expected one 'x y z dx dy dz' a line")
        if not ln.strip() or ln.lstrip().startswith("#"):
            continue
        try:
            v = [float(x) for x in ln.split()]
        except ValueError:
            v = []
        if len(v) != 6 or not np.all(np.isfinite(v)):
            raise ValueError(f"sensors = {str(path)!r}: line {k} must be 6 numbers "
                             "(x y z dx dy dz)")
        rows.append(v)
    if not rows:
        raise ValueError(f"sensors = {str(path)!r} holds no points")
    return _check_sensors(np.array(rows))


def _check_sensors(sensors) -> np.ndarray:
    s = np.asarray(sensors, dtype=np.float64)
    if s.ndim != 2 or s.shape[1] != 6 or s.shape[0] < 1:
        raise ValueError(f"sensors has shape {s.shape}; expected (n, 6): x y z dx dy dz")
    if not np.all(np.isfinite(s)):
        raise ValueError("sensors holds non-finite values")
    if np.any(np.linalg.norm(s[:, 3:], axis=1) < 1e-9):
        raise ValueError("sensors: a direction (dx dy dz) is zero")
    return s


#: rtrace's ambient parameters as this module bounds them: name -> (low, high) inclusive
#: (integers up to C's INT_MAX, as rtrace reads them).
RTRACE_PARAMETER_RANGES = {"ab": (0, 16), "ad": (1, 2**31 - 1), "as_": (0, 2**31 - 1),
                           "aa": (0.0, 1.0), "ar": (0, 2**31 - 1), "lw": (0.0, 1.0)}


def check_rtrace_parameters(ab: int = 5, ad: int = 2048, as_: int = 512, aa: float = 0.1,
                            ar: int = 256, lw: float = 1e-4) -> dict:
    """rtrace's ambient parameters checked against :data:`RTRACE_PARAMETER_RANGES`; returns
    them as a dict, or raises ValueError (TypeError for a non-number) naming the parameter,
    its value and its range. :func:`room_daylight_factor` calls it before any work; a
    command line can call it before reading any file."""
    from skydome._validate import check_int, check_number

    out = {}
    for name, v in (("ab", ab), ("ad", ad), ("as_", as_), ("aa", aa), ("ar", ar), ("lw", lw)):
        lo, hi = RTRACE_PARAMETER_RANGES[name]
        out[name] = (check_int(name, v, lo, hi) if isinstance(lo, int)
                     else check_number(name, v, lo, hi))
    return out


def room_daylight_factor(scene, sensors, *, ground_reflectance: float = 0.2, ab: int = 5,
                         ad: int = 2048, as_: int = 512, aa: float = 0.1, ar: int = 256,
                         lw: float = 1e-4, sky: str | None = None,
                         allow_commands: bool = False) -> np.ndarray:
    """Daylight factor [%] of sensor points in a Radiance scene under the CIE overcast sky.

    Parameters
    ----------
    scene : str, Path or sequence of them
        Radiance scene files (the room, its windows, obstructions) for ``oconv``.
    sensors : array_like (n, 6) or str / Path
        Points and the directions their illuminance is taken for (``x y z dx dy dz``), or a
        points file with one sensor a line.
    ground_reflectance : float
        Reflectance of the ground below the horizon, in [0, 1] (default 0.2, gensky's).
    ab, ad, as_, aa, ar, lw :
        rtrace's ambient parameters (-ab bounces, -ad divisions, -as super-samples, -aa
        accuracy, -ar resolution, -lw weight limit); the defaults suit a single room.
    sky : str, optional
        Radiance text of another sky to use instead of skydome's (e.g. ``gensky -c``'s
        output followed by its skyfunc glows); its horizontal illuminance must be
        DF_SKY_ILLUMINANCE_LX. For comparisons.
    allow_commands : bool
        Let the scene files (and ``sky``) hold command lines (``!command``), which Radiance's
        oconv runs as shell commands when it reads them (default False: such a file is
        refused before any work, naming the file and the line; see
        :func:`~skydome.daylighting.scene.check_scene_files`).

    Returns
    -------
    numpy.ndarray (n,)
        100 E / E_h with E = 179 (0.265 R + 0.670 G + 0.065 B) of ``rtrace -I``.
    """
    from skydome._validate import check_number
    from skydome.daylighting.scene import (check_scene_files, find_scene_command,
                                           write_radiance_sky)

    rt = check_rtrace_parameters(ab=ab, ad=ad, as_=as_, aa=aa, ar=ar, lw=lw)
    ab, ad, as_, aa, ar, lw = (rt[k] for k in ("ab", "ad", "as_", "aa", "ar", "lw"))
    rho = check_number("ground_reflectance", ground_reflectance, 0.0, 1.0)
    files = check_scene_files(scene, allow_commands=allow_commands)
    if sky is not None:
        if not isinstance(sky, str):
            raise TypeError(f"sky must be Radiance scene text (str), got {type(sky).__name__}")
        hit = None if allow_commands else find_scene_command(sky)
        if hit is not None:
            raise ValueError(f"sky: line {hit[0]} is a command line ({hit[1]!r}), which "
                             "Radiance runs as a shell command; refused unless "
                             "allow_commands=True")
    s = read_sensors(sensors) if isinstance(sensors, (str, Path)) else _check_sensors(sensors)
    oconv, env = radiance_tool("oconv")
    rtrace, _ = radiance_tool("rtrace")
    e_h = DF_SKY_ILLUMINANCE_LX
    with tempfile.TemporaryDirectory(prefix="skydome-df-") as tmp:
        tmp = Path(tmp)
        if sky is None:
            write_radiance_sky(overcast_sky(e_h), tmp / "sky.rad")
            g = rho * e_h / np.pi / _WHITE_EFFICACY  # ground radiance, Radiance units
            with (tmp / "sky.rad").open("a") as f:
                f.write(f"\nvoid glow ground_glow\n0\n0\n4 {g:.7g} {g:.7g} {g:.7g} 0\n\n"
                        "ground_glow source ground\n0\n0\n4 0 0 -1 180\n")
        else:
            (tmp / "sky.rad").write_text(sky)
        with (tmp / "scene.oct").open("wb") as f:
            r = subprocess.run([oconv, "sky.rad", *map(str, files)], stdout=f,
                               stderr=subprocess.PIPE, env=env, cwd=tmp, timeout=600)
        if r.returncode != 0:
            raise RuntimeError(f"oconv failed: {r.stderr.decode(errors='replace').strip()}")
        pts = "".join(" ".join(f"{v:.9g}" for v in row) + "\n" for row in s)
        r = subprocess.run([rtrace, "-h", "-I", "-ab", str(ab), "-ad", str(ad), "-as",
                            str(as_), "-aa", str(aa), "-ar", str(ar), "-lw", str(lw),
                            "scene.oct"],
                           input=pts.encode(), capture_output=True, env=env, cwd=tmp,
                           timeout=3600)
        if r.returncode != 0:
            raise RuntimeError(f"rtrace failed: {r.stderr.decode(errors='replace').strip()}")
        vals = np.array(r.stdout.split(), dtype=np.float64).reshape(-1, 3)
    if vals.shape[0] != s.shape[0]:
        raise RuntimeError(f"rtrace returned {vals.shape[0]} values for {s.shape[0]} sensors")
    e = _WHITE_EFFICACY * (vals @ _RGB_TO_Y)
    return 100.0 * np.maximum(e, 0.0) / e_h
