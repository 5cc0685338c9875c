"""The bake behind the Blender add-on: environment maps, sun lights and exposures.

Blender's bundled Python does not carry skydome's numerical stack, so the add-on runs this
module with skydome's own Python (an add-on preference)::

    PYTHON -m skydome.export.integrations.blender.bake JOB.json

and reads the one line ``RESULT {json}`` it prints (errors: one line on stderr, exit code
2). :func:`bake` does the work and can be called directly.

A job (a JSON object):

* ``model``: a registered model name (default ``hosek_wilkie2012``);
* the sun: ``sun_elevation_deg`` and ``sun_azimuth_deg`` (from north towards east), or
  ``latitude_deg``, ``longitude_deg`` and ``times`` (ISO 8601 with UTC offset; several
  times make a day sequence, one map per time);
* the atmosphere: ``atmosphere`` = ``"earth"`` (default; ``turbidity`` or
  ``aerosol_optical_depth`` at 550 nm, ``albedo``) or ``"blender"``
  (:meth:`skydome.atmosphere.Atmosphere.blender`, Blender 5's own sky). Analytic models
  take ``turbidity`` and ``albedo`` where they have them;
* ``width`` x ``height`` of the lat-long map (default 2048 x 1024), ``half`` (16-bit
  EXR, default true), ``out`` = the map's path (``.exr``, in an existing folder); a
  sequence writes
  ``STEM0001.exr``, ``STEM0002.exr``, ... (Blender's image-sequence numbering);
* ``exposure_compensation_ev`` added to the exposure (default 0).

Each frame of the result gives the map, its ``.sun.json`` (:func:`skydome.export.sun.
sun_light`, convention ``blender``), the sun lamp as Blender takes it (``rotation_euler_deg``
XYZ, ``strength_W_m2``, ``color``, ``angle_deg``), the horizontal illuminance of the sky
(the map integrated over the upper hemisphere with exact pixel solid angles) and of the sun,
and the exposure :func:`exposure_ev`.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np

__all__ = ["bake", "exposure_ev", "sun_rotation_euler_deg", "K_M"]

K_M = 683.0                     # lm/W: the photometric scale of skydome's maps
_Y709 = np.array([0.2126, 0.7152, 0.0722])     # luminance of linear Rec. 709 RGB
_KEYS = {"model", "sun_elevation_deg", "sun_azimuth_deg", "latitude_deg", "longitude_deg",
         "times", "atmosphere", "turbidity", "aerosol_optical_depth", "albedo", "width",
         "height", "half", "out", "exposure_compensation_ev"}


def sun_rotation_euler_deg(elevation_deg: float, azimuth_deg: float) -> list[float]:
    """Blender XYZ Euler angles [deg] that turn a sun lamp (it shines along its local -Z)
    so that its +Z points at the sun (Blender's axes: +X east, +Y north, +Z up).

    With X = 90 - elevation, Y = 0 and Z = 180 - azimuth, R = Rz(Z) Rx(X) takes (0, 0, 1)
    to (sin X sin Z, -sin X cos Z, cos X) = (cos e sin a, cos e cos a, sin e), the
    direction to the sun at elevation e and azimuth a (from north towards east).
    """
    z = (180.0 - float(azimuth_deg) + 180.0) % 360.0 - 180.0
    return [90.0 - float(elevation_deg), 0.0, z]


def exposure_ev(horizontal_illuminance_lx: float, compensation_ev: float = 0.0) -> float:
    """Blender's Film/Color Management exposure [EV] that brings a white Lambertian
    horizontal surface to scene-linear 1.0: its radiance in the maps' units is
    E / (pi x 683), so 2^EV = pi x 683 / E (clamped to Blender's range -32..32).

    The same as an incident-light meter's EV100 = log2(E / 2.5) (ISO 2720 calibration
    constant C = 250 lx s at ISO 100), shifted: EV = log2(pi 683 / 2.5) - EV100 =
    9.745 - EV100.
    """
    e = max(float(horizontal_illuminance_lx), 1e-9)
    return float(np.clip(math.log2(math.pi * K_M / e) + float(compensation_ev), -32.0, 32.0))


def _check_job(job: dict) -> dict:
    """Validated job with defaults; ValueError naming the parameter before any work."""
    from skydome._validate import check_number
    from skydome.models import get_model_class
    from skydome.sun import parse_time

    if not isinstance(job, dict):
        raise ValueError(f"job must be a JSON object, got {type(job).__name__}")
    unknown = sorted(set(job) - _KEYS)
    if unknown:
        raise ValueError(f"unknown job key(s) {', '.join(unknown)}; valid: "
                         f"{', '.join(sorted(_KEYS))}")
    j = dict(job)
    j["model"] = str(j.get("model") or "hosek_wilkie2012")
    get_model_class(j["model"])                            # ValueError naming the model
    atm = j.get("atmosphere") or "earth"
    if atm not in ("earth", "blender"):
        raise ValueError(f"atmosphere must be 'earth' or 'blender', got {atm!r}")
    j["atmosphere"] = atm
    if j.get("turbidity") is not None and j.get("aerosol_optical_depth") is not None:
        raise ValueError("give either turbidity or aerosol_optical_depth, not both")
    if j.get("turbidity") is not None:
        j["turbidity"] = check_number("turbidity", j["turbidity"], 1.0, 32.0)
    if j.get("aerosol_optical_depth") is not None:
        j["aerosol_optical_depth"] = check_number("aerosol_optical_depth",
                                                  j["aerosol_optical_depth"], 0.0, 10.0)
    j["albedo"] = check_number("albedo", j.get("albedo", 0.2), 0.0, 1.0)
    j["width"] = int(check_number("width", j.get("width", 2048), 16, 16384))
    j["height"] = int(check_number("height", j.get("height", j["width"] // 2), 8, 8192))
    if j["width"] != 2 * j["height"]:
        raise ValueError(f"width must be 2 x height for a lat-long map, got "
                         f"{j['width']} x {j['height']}")
    j["half"] = bool(j.get("half", True))
    j["exposure_compensation_ev"] = check_number(
        "exposure_compensation_ev", j.get("exposure_compensation_ev", 0.0), -20.0, 20.0, "EV")
    from skydome._io import check_output_file

    check_output_file(str(j.get("out") or ""), (".exr",), name="out")  # its folder must exist
    names = {p.name for p in get_model_class(j["model"]).parameters}
    if "atmosphere" not in names:
        if atm == "blender":
            raise ValueError(f"atmosphere 'blender' needs a model that takes an atmosphere "
                             f"(e.g. precomputed), not {j['model']!r}")
        if j.get("aerosol_optical_depth") is not None:
            raise ValueError(f"model {j['model']!r} takes no aerosol_optical_depth; give "
                             "turbidity")
    angles = j.get("sun_elevation_deg") is not None or j.get("sun_azimuth_deg") is not None
    place = any(j.get(k) is not None for k in ("latitude_deg", "longitude_deg", "times"))
    if angles == place or (angles and (j.get("sun_elevation_deg") is None
                                       or j.get("sun_azimuth_deg") is None)):
        raise ValueError("give the sun either as sun_elevation_deg and sun_azimuth_deg or as "
                         "latitude_deg, longitude_deg and times")
    if angles:
        j["sun_elevation_deg"] = check_number("sun_elevation_deg",
                                              j.get("sun_elevation_deg"), -90.0, 90.0, "deg")
        j["sun_azimuth_deg"] = check_number("sun_azimuth_deg", j.get("sun_azimuth_deg"),
                                            -360.0, 360.0, "deg")
    else:
        j["latitude_deg"] = check_number("latitude_deg", j.get("latitude_deg"),
                                         -90.0, 90.0, "deg")
        j["longitude_deg"] = check_number("longitude_deg", j.get("longitude_deg"),
                                          -180.0, 180.0, "deg")
        times = j.get("times")
        if isinstance(times, str):
            times = [times]
        if not times or len(times) > 1000:
            raise ValueError(f"times must list 1 to 1000 ISO 8601 times, got {times!r}")
        j["times"] = [str(t) for t in times]
        for t in j["times"]:
            parse_time(t)                                      # ValueError naming time
    return j


def _sky(job: dict, sun):
    import skydome as sd
    from skydome.atmosphere import Atmosphere
    from skydome.models import get_model_class

    names = {p.name for p in get_model_class(job["model"]).parameters}
    params = {}
    if "atmosphere" in names:
        if job["atmosphere"] == "blender":
            params["atmosphere"] = Atmosphere.blender()
        elif job.get("aerosol_optical_depth") is not None:
            params["atmosphere"] = Atmosphere.earth(
                aerosol_optical_depth=job["aerosol_optical_depth"], ground_albedo=job["albedo"])
        else:
            params["atmosphere"] = Atmosphere.earth(turbidity=job.get("turbidity") or 2.5,
                                                    ground_albedo=job["albedo"])
    else:
        if "turbidity" in names and job.get("turbidity") is not None:
            params["turbidity"] = job["turbidity"]
        if "albedo" in names:
            params["albedo"] = job["albedo"]
    return sd.model(job["model"], sun=sun, **params)


def _frame(job: dict, sun, out: Path) -> dict:
    from skydome.export.envmap import render_envmap
    from skydome.export.sun import sun_light, write_sun_json

    sky = _sky(job, sun)
    env = render_envmap(sky, "blender", size=f"{job['width']}x{job['height']}")
    d, w = env.directions()
    L = env.pixels()
    # the sky's horizontal illuminance: 683 x sum Y(L) cos(theta) dOmega, upper hemisphere
    e_sky = float(K_M * ((L @ _Y709) * np.maximum(d[:, 2], 0.0) * w).sum())
    light = sun_light(sky, "blender")
    written = env.write(out, half=job["half"])
    frame = {"map": str(written[0]), "illuminance_sky_lx": e_sky,
             "elevation_deg": float(sun.elevation_deg), "azimuth_deg": float(sun.azimuth_deg),
             "time": sun.time.isoformat() if getattr(sun, "time", None) else None,
             "rotation_euler_deg": sun_rotation_euler_deg(sun.elevation_deg, sun.azimuth_deg)}
    if light is None:
        frame.update(sun_json=None, strength_W_m2=0.0, color=[1.0, 1.0, 1.0],
                     angle_deg=2.0 * float(sun.angular_radius_deg), illuminance_sun_lx=0.0)
    else:
        sj = out.with_name(out.stem + ".sun.json")
        write_sun_json(light, sj)
        b = light["targets"]["blender"]
        frame.update(sun_json=str(sj), strength_W_m2=b["strength_W_m2"], color=b["color"],
                     angle_deg=b["angle_deg"],
                     illuminance_sun_lx=light["illuminance_lx"]
                     * max(light["direction_to_sun_enu"][2], 0.0))
    frame["illuminance_horizontal_lx"] = frame["illuminance_sky_lx"] + frame["illuminance_sun_lx"]
    frame["exposure_ev"] = exposure_ev(frame["illuminance_horizontal_lx"],
                                       job["exposure_compensation_ev"])
    return frame


def bake(job: dict) -> dict:
    """Bake the maps, sun lights and exposures of ``job`` (module docstring); returns
    ``{"frames": [...], "view_transform_note": ...}``. Every input is checked first."""
    import skydome as sd

    j = _check_job(job)
    out = Path(j["out"])
    if j.get("times") is None:
        suns = [sd.Sun(elevation_deg=j["sun_elevation_deg"],
                       azimuth_deg=j["sun_azimuth_deg"] % 360.0)]
    else:
        suns = [sd.Sun.from_location(j["latitude_deg"], j["longitude_deg"], t)
                for t in j["times"]]
    if len(suns) == 1:
        paths = [out]
    else:
        paths = [out.with_name(f"{out.stem}{i + 1:04d}.exr") for i in range(len(suns))]
    frames = [_frame(j, s, p) for s, p in zip(suns, paths)]
    return {"frames": frames, "model": j["model"], "atmosphere": j["atmosphere"],
            "exposure_note": "exposure [EV] = log2(pi x 683 / horizontal illuminance) + "
                             "compensation: a white Lambertian horizontal surface at "
                             "scene-linear 1.0 (AgX, Filmic and Standard alike)"}


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print("usage: python -m skydome.export.integrations.blender.bake JOB.json",
              file=sys.stderr)
        return 2
    try:
        job = json.loads(Path(argv[0]).read_text(encoding="utf-8"))
        result = bake(job)
    except (ValueError, TypeError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print("RESULT " + json.dumps(result))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
