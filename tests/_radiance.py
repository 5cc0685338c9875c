"""Run Radiance's sky generators (shipped with pyradiance) as an independent reference.

``radiance_sky_luminance(gen_args, directions)`` runs a generator (gensky, gendaylit),
builds an octree with its sky as a glow source, traces one ray from the origin in each
direction with rtrace and returns the luminance the way Radiance reports it,
179 lm/W x (0.265 R + 0.670 G + 0.065 B). ``radiance_cal(...)`` evaluates an expression
of a .cal file directly with rcalc, e.g. a sky function without gensky's horizon/ground
blend.

Directions are East-North-Up unit vectors (x east, y north, z up), the same frame as
Radiance's (X east, Y north, Z up). Radiance's generators take the solar azimuth from
SOUTH towards WEST: ``radiance_azimuth(az_enu)`` converts skydome's azimuth (from north
towards east).

Every helper calls ``pytest.skip`` when pyradiance or its binaries are missing.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import pytest

#: Radiance's luminous efficacy of its RGB "white" [lm/W] (color.h WHTEFFICACY).
WHTEFFICACY = 179.0
#: Efficacy gensky divides its kcd/m^2 zenith formulas by (color.h SKYEFFICACY = D65, 203).
SKYEFFICACY = 203.0
_RGB_TO_Y = (0.265, 0.670, 0.065)


def radiance_paths() -> tuple[Path, Path]:
    """(bin, lib) folders of the Radiance build shipped with pyradiance; skip if absent."""
    try:
        import importlib.util

        spec = importlib.util.find_spec("pyradiance")
    except (ImportError, ValueError):
        spec = None
    if spec is None or not spec.submodule_search_locations:
        pytest.skip("pyradiance is not installed")
    root = Path(list(spec.submodule_search_locations)[0])
    bindir, libdir = root / "bin", root / "lib"
    if not bindir.is_dir() or not libdir.is_dir():
        pytest.skip("pyradiance has no bin/ or lib/ folder")
    return bindir, libdir


def _tool(name: str) -> str:
    bindir, _ = radiance_paths()
    exe = bindir / name
    if not exe.exists():
        found = shutil.which(name)
        if found is None:
            pytest.skip(f"Radiance program {name} not found")
        return found
    return str(exe)


def _env() -> dict:
    _, libdir = radiance_paths()
    env = dict(os.environ)
    env["RAYPATH"] = os.pathsep.join([".", str(libdir)])
    return env


def run_radiance(program: str, args, stdin: bytes | str | None = None, cwd=None) -> str:
    """Run a Radiance program with RAYPATH set; return its stdout (raise on failure)."""
    if isinstance(stdin, str):
        stdin = stdin.encode()
    res = subprocess.run([_tool(program), *map(str, args)], input=stdin,
                         capture_output=True, env=_env(), cwd=cwd, timeout=120)
    if res.returncode != 0:
        raise RuntimeError(f"{program} {' '.join(map(str, args))} failed: "
                           f"{res.stderr.decode(errors='replace')}")
    return res.stdout.decode()


def radiance_azimuth(azimuth_deg_enu: float) -> float:
    """Radiance's solar azimuth (from south towards west) [deg] for an azimuth from north
    towards east [deg]: az_radiance = az_enu - 180."""
    return (azimuth_deg_enu - 180.0 + 180.0) % 360.0 - 180.0


# -- Radiance scene text: a minimal tokenizer ---------------------------------------------------
def parse_primitives(text: str) -> list[dict]:
    """Split a Radiance scene description into primitives.

    Each primitive is a dict with modifier, type, name, sargs, iargs, fargs (strings).
    Comment lines (#) and command lines (!) are dropped.
    """
    tokens = []
    for line in text.splitlines():
        s = line.strip()
        if not s or s.startswith("#") or s.startswith("!"):
            continue
        tokens.extend(s.split())
    prims, i = [], 0
    while i < len(tokens):
        mod, typ, name = tokens[i:i + 3]
        i += 3
        args = []
        for _ in range(3):
            n = int(tokens[i])
            args.append(tokens[i + 1:i + 1 + n])
            i += 1 + n
        prims.append({"modifier": mod, "type": typ, "name": name, "sargs": args[0],
                      "iargs": args[1], "fargs": args[2]})
    return prims


def format_primitives(prims: list[dict]) -> str:
    out = []
    for p in prims:
        out.append(f"{p['modifier']} {p['type']} {p['name']}")
        for key in ("sargs", "iargs", "fargs"):
            out.append(" ".join([str(len(p[key]))] + list(p[key])))
        out.append("")
    return "\n".join(out)


def generate_sky(gen_args) -> str:
    """Output of a generator command line such as ["gensky", "-ang", "30", "45", "+s"]."""
    gen_args = list(map(str, gen_args))
    return run_radiance(gen_args[0], gen_args[1:])


def sky_function_args(gen_args, function: str = "skyfunc") -> list[float]:
    """Real arguments of the brightfunc/colorfunc named ``function`` (gensky: A1..A7)."""
    for p in parse_primitives(generate_sky(gen_args)):
        if p["name"] == function:
            return [float(x) for x in p["fargs"]]
    raise LookupError(f"no primitive named {function!r} in the output of {gen_args}")


def radiance_sky_luminance(gen_args, directions, sun: bool = False,
                           efficacy: float = WHTEFFICACY) -> np.ndarray:
    """Luminance [cd m^-2] of the sky made by ``gen_args`` seen from the origin along
    ``directions`` (..., 3), by oconv + rtrace.

    The generator's ``skyfunc`` modifies a glow covering the whole sphere (as in
    Radiance's tutorials: ``skyfunc glow skyglow 0 0 4 1 1 1 0`` and ``skyglow source sky
    0 0 4 0 0 1 360``); the sun (``source`` primitives of the generator) is removed unless
    ``sun`` is True. The luminance is efficacy x (0.265 R + 0.670 G + 0.065 B); Radiance's
    own convention is efficacy = 179 lm/W.
    """
    d = np.asarray(directions, dtype=np.float64)
    shape = d.shape[:-1]
    d = d.reshape(-1, 3)
    prims = parse_primitives(generate_sky(gen_args))
    if not sun:
        prims = [p for p in prims if p["type"] != "source"]
        used = {p["modifier"] for p in prims}
        prims = [p for p in prims if not (p["type"] == "light" and p["name"] not in used)]
    scene = format_primitives(prims) + (
        "\nskyfunc glow skyglow\n0\n0\n4 1 1 1 0\n\nskyglow source skydome_sky\n0\n0\n"
        "4 0 0 1 360\n")
    with tempfile.TemporaryDirectory() as tmp:
        tmpdir = Path(tmp)
        (tmpdir / "sky.rad").write_text(scene)
        oct_bytes = subprocess.run([_tool("oconv"), "sky.rad"], capture_output=True,
                                   env=_env(), cwd=tmpdir, timeout=120)
        if oct_bytes.returncode != 0:
            raise RuntimeError(f"oconv failed: {oct_bytes.stderr.decode(errors='replace')}")
        (tmpdir / "sky.oct").write_bytes(oct_bytes.stdout)
        rays = "\n".join(f"0 0 0 {x:.17g} {y:.17g} {z:.17g}" for x, y, z in d) + "\n"
        out = run_radiance("rtrace", ["-h", "-w", "-ab", "0", "-ov", "-ld-", "sky.oct"],
                           stdin=rays, cwd=tmpdir)
    rgb = np.array([float(v) for v in out.split()], dtype=np.float64).reshape(-1, 3)
    if rgb.shape[0] != d.shape[0]:
        raise RuntimeError(f"rtrace returned {rgb.shape[0]} values for {d.shape[0]} rays")
    lum = efficacy * (rgb @ np.array(_RGB_TO_Y))
    return lum.reshape(shape)


def radiance_cal(cal_file: str, expression: str, directions, args=(),
                 extra: str = "") -> np.ndarray:
    """Evaluate ``expression`` of a Radiance .cal file with rcalc for each direction.

    Dx, Dy, Dz are set to the direction's components and A1, A2, ... to ``args`` (the
    real arguments a generator passes to its brightfunc), so a sky function can be read
    without the rest of the scene (e.g. ``sunnysky`` of skybright.cal, which skips
    gensky's ground blend ``skybr``).
    """
    d = np.asarray(directions, dtype=np.float64)
    shape = d.shape[:-1]
    d = d.reshape(-1, 3)
    # rayinit.cal (loaded by rtrace, not by rcalc) defines these helpers:
    defs = ["Dx=$1", "Dy=$2", "Dz=$3", "bound(a,x,b):if(a-x,a,if(x-b,b,x))",
            "Acos(x):acos(bound(-1,x,1))", "Asin(x):asin(bound(-1,x,1))",
            "Exp(x):if(-x-100,0,exp(x))"] + [f"A{i + 1}={a:.17g}" for i, a in enumerate(args)]
    if extra:
        defs.append(extra)
    _, libdir = radiance_paths()
    rows = "\n".join(f"{x:.17g}\t{y:.17g}\t{z:.17g}" for x, y, z in d) + "\n"
    out = run_radiance("rcalc", ["-f", str(libdir / cal_file), "-e", ";".join(defs),
                                 "-e", f"$1={expression}"], stdin=rows)
    vals = np.array([float(v) for v in out.split()], dtype=np.float64)
    if vals.size != d.shape[0]:
        raise RuntimeError(f"rcalc returned {vals.size} values for {d.shape[0]} rows")
    return vals.reshape(shape)


def hemisphere_directions(n: int, seed: int = 0, min_elevation_deg: float = 0.5) -> np.ndarray:
    """``n`` pseudo-random unit vectors of the upper hemisphere (uniform in solid angle)
    with elevation >= ``min_elevation_deg``, East-North-Up."""
    rng = np.random.default_rng(seed)
    zmin = np.sin(np.radians(min_elevation_deg))
    z = rng.uniform(zmin, 1.0, n)
    phi = rng.uniform(0.0, 2.0 * np.pi, n)
    s = np.sqrt(1.0 - z * z)
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=-1)
