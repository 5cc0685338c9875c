"""Radiance scene export of one sky: the sky distribution as a data pattern, the sun as a source.

``write_radiance_sky(model, path)`` writes three files beside each other:

- ``NAME.rad``: ``void brightdata skyfunc`` reading ``NAME.dat`` through ``NAME.cal``, a
  ``glow`` modified by it over the upper hemisphere (``source`` of 180 deg), and, if the
  model has a sun, ``void light solar`` + ``solar source sun`` (0.533 deg, Radiance's disc);
- ``NAME.dat``: the sky's radiance in Radiance units (luminance / 179 lm W^-1, grey) on a
  grid of zenith angle (0..90 deg) x azimuth (0..360 deg from north towards east), linearly
  interpolated by brightdata;
- ``NAME.cal``: the direction -> (zenith angle, azimuth) mapping, 0 below the horizon.

The sky is any skydome model's ``luminance(directions)`` (spectral models through their
luminance: the export is achromatic). The sun's light is the direct normal illuminance
(``direct_normal_illuminance()``) spread over a
0.533 deg disc, as gendaylit and gendaymtx -D do.

Scene files given to Radiance (``room_daylight_factor``'s ``scene``) may hold command lines:
a line whose first character (after blanks) is ``!`` makes oconv run the rest of the line
as a shell command and read its output as scene text (Radiance's own feature, e.g.
``!xform -t 1 0 0 chair.rad``). A scene file from elsewhere can so run any program with the
user's rights. :func:`check_scene_files` refuses such lines unless the caller passes
``allow_commands=True``.

Reference: G. Ward, Radiance 5.4 reference manual: ``brightdata``, data file format,
``glow``, ``source``, ``light``; scene description format ("!command" inline commands).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

__all__ = ["write_radiance_sky", "sun_direct_illuminance", "check_scene_files",
           "find_scene_command"]

from skydome.constants import RADIANCE_SUN_ANGLE_DEG as SUN_ANGLE_DEG
from skydome.constants import RADIANCE_WHITE_EFFICACY as WHITE_EFFICACY

_CAL = """{{ skydome sky export: direction -> zenith angle and azimuth [deg] }}
sd_z = if(Dz - 1, 1, if(-1 - Dz, -1, Dz));
sd_zen = 180 / PI * acos(sd_z);
sd_a = 180 / PI * atan2(Dx, Dy);
sd_azi = if(-sd_a, sd_a + 360, sd_a);
sd_sky(v) = if(Dz, if(v, v, 0), 0);
"""


_BLANK = b" \t\r\f\v"


def find_scene_command(data) -> tuple[int, str] | None:
    """(line number, line) of the first command line (``!`` first after blanks) in Radiance
    scene text ``data`` (bytes or str, or a binary file object read in 1 MiB pieces), or
    None. Lines of any length are scanned without holding them whole."""
    import re

    if isinstance(data, str):
        data = data.encode("utf-8", "surrogateescape")
    if isinstance(data, (bytes, bytearray)):
        import io

        data = io.BytesIO(bytes(data))
    pat = re.compile(rb"\n[ \t\r\f\v]*!")
    line0 = 1          # line number at the start of the piece
    at_start = True    # only blanks seen since the last line break (or the file's start)
    while True:
        piece = data.read(1 << 20)
        if not piece:
            return None
        hit = None
        if at_start:
            s = piece.lstrip(_BLANK)
            if s[:1] == b"!":
                hit = len(piece) - len(s) - 1  # treat as a match ending at the "!"
        if hit is None:
            m = pat.search(piece)
            if m is not None:
                hit = m.start()
                line0 += piece.count(b"\n", 0, m.start()) + 1
                return line0, _line_text(piece, m.end() - 1)
        else:
            return line0, _line_text(piece, hit + 1)
        nl = piece.rfind(b"\n")
        if nl >= 0:
            at_start = not piece[nl + 1:].strip(_BLANK)
        else:
            at_start = at_start and not piece.strip(_BLANK)
        line0 += piece.count(b"\n")


def _line_text(piece: bytes, k: int) -> str:
    end = piece.find(b"\n", k)
    text = piece[k:end if end >= 0 else len(piece)][:80]
    return text.decode("utf-8", "replace").strip()


def check_scene_files(files, *, allow_commands: bool = False) -> list[Path]:
    """The scene files as resolved paths, each checked to exist; unless ``allow_commands``,
    a file holding a command line (``!command``, which Radiance runs as a shell command when
    it reads the scene) is refused with a ValueError naming the file, the line and the
    command. ``files``: a path or a sequence of them."""
    if not isinstance(allow_commands, bool):
        raise TypeError(f"allow_commands must be True or False, got {allow_commands!r}")
    items = [files] if isinstance(files, (str, Path)) else list(files)
    if not items:
        raise ValueError("scene: give at least one Radiance scene file")
    out = []
    for f in items:
        p = Path(f).resolve()
        if not p.is_file():
            raise ValueError(f"scene = {str(f)!r}: no such file")
        if not allow_commands:
            with p.open("rb") as fh:
                hit = find_scene_command(fh)
            if hit is not None:
                raise ValueError(
                    f"scene = {str(f)!r}: line {hit[0]} is a command line ({hit[1]!r}), "
                    "which Radiance runs as a shell command when it reads the scene; "
                    "refused unless allow_commands=True (--allow-commands)")
        out.append(p)
    return out


def sun_direct_illuminance(model) -> float:
    """Direct normal illuminance of the model's sun [lx] (0 if it has none or it is below
    the horizon): :meth:`SkyModel.direct_normal_illuminance`."""
    if getattr(model, "sun", None) is None or model.sun.elevation_deg <= 0.0:
        return 0.0
    return max(float(model.direct_normal_illuminance()), 0.0)


def write_radiance_sky(model, path, *, zenith_step_deg: float = 0.25,
                       azimuth_step_deg: float = 0.5, overwrite: bool = False) -> list[Path]:
    """Write ``path`` (.rad) with its .dat and .cal for ``model``; returns the three paths.

    The grid steps set brightdata's interpolation error: with the defaults (0.25 x 0.5 deg,
    361 x 721 values) a Perez sky is reproduced within 0.2 % away from the sun's disc.
    """
    from skydome._validate import check_number
    from skydome.daylighting.radiance_io import atomic_write_bytes

    dz = check_number("zenith_step_deg", zenith_step_deg, 0.01, 10.0)
    da = check_number("azimuth_step_deg", azimuth_step_deg, 0.01, 30.0)
    rad = Path(path)
    if rad.suffix != ".rad":
        raise ValueError(f"out = {str(path)!r} must end in .rad")
    dat, cal = rad.with_suffix(".dat"), rad.with_suffix(".cal")
    for p in (rad, dat, cal):
        if p.exists() and not overwrite:
            raise ValueError(f"out = {str(p)!r} exists (use --overwrite)")
    if not rad.parent.is_dir():
        raise ValueError(f"out = {str(path)!r}: folder {str(rad.parent)!r} does not exist")
    nz = int(round(90.0 / dz)) + 1
    na = int(round(360.0 / da)) + 1
    zen = np.radians(np.linspace(0.0, 90.0, nz))
    azi = np.radians(np.linspace(0.0, 360.0, na))
    st = np.sin(zen)[:, None]
    d = np.stack(np.broadcast_arrays(st * np.sin(azi)[None, :], st * np.cos(azi)[None, :],
                                     np.cos(zen)[:, None]), axis=-1)
    # the horizon row is sampled a hair above it (models return 0 below z = 0)
    d[-1, :, 2] = 1e-9
    lum = np.asarray(model.luminance(d), dtype=np.float64)
    if not np.all(np.isfinite(lum)) or np.any(lum < 0.0):
        raise ValueError(f"model {model.name!r} returned a negative or non-finite luminance")
    vals = lum / WHITE_EFFICACY
    head = f"2\n0 90 {nz}\n0 360 {na}\n"
    body = "\n".join(" ".join(f"{v:.7g}" for v in row) for row in vals)
    e_sun = sun_direct_illuminance(model)
    lines = [f"# skydome sky: model {model.name}, sun elevation {model.sun.elevation_deg:.4f} "
             f"deg, azimuth {model.sun.azimuth_deg:.4f} deg (from north towards east)",
             f"# radiance units: luminance / {WHITE_EFFICACY:g} lm/W; direct normal "
             f"illuminance {e_sun:.6g} lx", ""]
    if e_sun > 0.0:
        s = model.sun.direction
        omega = math.pi * math.radians(SUN_ANGLE_DEG / 2.0) ** 2
        r = e_sun / WHITE_EFFICACY / omega
        lines += [f"void light solar\n0\n0\n3 {r:.7g} {r:.7g} {r:.7g}\n",
                  f"solar source sun\n0\n0\n4 {s[0]:.9f} {s[1]:.9f} {s[2]:.9f} "
                  f"{SUN_ANGLE_DEG}\n"]
    lines += [f"void brightdata skyfunc\n5 sd_sky {dat.name} {cal.name} sd_zen sd_azi\n0\n0\n",
              "skyfunc glow sky_glow\n0\n0\n4 1 1 1 0\n",
              "sky_glow source sky\n0\n0\n4 0 0 1 180\n"]
    written = []
    try:
        for p, text in ((dat, head + body + "\n"), (cal, _CAL), (rad, "\n".join(lines))):
            atomic_write_bytes(p, text.encode())
            written.append(p)
    except BaseException:
        for p in written:
            p.unlink(missing_ok=True)
        raise
    return [rad, dat, cal]
