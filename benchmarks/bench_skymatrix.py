"""Annual sky matrices: skydome's perez1993 path against Radiance's gendaymtx, same run.

Input: the TMY3 file pvlib ships (Greensboro, NC; 8760 hours), written once as a .wea for
gendaymtx. Every case is a whole program run, end to end, as a user types it: a fresh
process from start to the finished float matrix file (interpreter start, imports, weather
read, sun positions, Perez coefficients, patch quadrature, the file). Cases, interleaved in
each round (gendaymtx, then each skydome case):

- ``gendaymtx -m MF -of y.wea > g.mtx``;
- ``skydome skymatrix --weather y.wea --order 0 --sun-position radiance``: gendaymtx's
  definition (the same .wea, Radiance's solar position, one point per patch), with the
  default backend (``auto``: numpy, no numba start-up) and with ``--backend numba`` (the
  default before); both through ``python -m skydome``, whose typer-free path takes these
  command lines;
- the same from the TMY3 file (pvlib.iotools read, pandas and pvlib imported);
- skydome's defaults (adaptive patch means, SPA suns) from the same .wea as gendaymtx (the
  like-for-like case of a default run) and from the TMY3 file, and from the TMY3 file with
  the former default, order 4; the defaults from the .wea with ``--backend numba`` (the
  adaptive rule on the numba kernel, the default before);
- in process (kernels compiled, weather parsed): the order-0 matrix (Radiance sun; numba
  and numpy backends), the default one (adaptive, SPA suns) and order 4 (SPA suns) filled
  into the file's memory map, the part of a run that is the matrix and its file;
- the start-up floor of any such run, each a fresh process: ``python -c pass``, ``import
  numpy``, ``import numba``, ``import pvlib`` (what a TMY3/EPW input adds), and the skydome
  modules with the cached sky-matrix kernel loaded and called on two hours (everything a
  run pays before its first hour of work), with numba's target started as the CLI starts
  it (``start_numba_without_blas``) and as numba starts it by itself (SciPy's BLAS probe).

Outputs are deleted before each timed run (freeing a 242 MB file is not counted for either
program). Each figure is the best of ``--repeat`` rounds, as wall-clock time and as CPU time
(user + system of the process, all threads; gendaymtx is single-threaded, skydome's kernel
uses every numba thread), with the user and system parts of the best CPU round, and the median
CPU time of the rounds: on a shared machine CPU time is the steadier figure. The ratio printed is gendaymtx / skydome. The
children run with Python's bytecode cache on (``PYTHONDONTWRITEBYTECODE`` removed from their
environment; the skydome runs are warmed once), as an installed package has it.
``uptime`` is printed before and after. With --write the table goes into docs/performance.md.

Run:  .venv/bin/python benchmarks/bench_skymatrix.py [--write] [--repeat N] [--mf 1 4]
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_single_scattering import machine, write_section  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
#: The floor of a numba run (``--backend numba``): skydome's sky-matrix modules imported and
#: the cached kernel (float32, as a "float" file takes) loaded and run on two hours of the
#: Tregenza patches. (The default backend starts no numba: its floor is ``import numpy``
#: and the skydome modules.)
_FLOOR = ("import numpy as np; from skydome.daylighting.skymatrix import perez_sky_matrix, "
          "start_numba_without_blas; {start}"
          "perez_sky_matrix([600.0, 0.0], [100.0, 0.0], [[0.0, -0.5, 0.75 ** 0.5]] * 2, [172, 172], "
          "order=0, dtype=np.float32, out=np.zeros((146, 2, 3), np.float32), backend='numba')")


def _radiance():
    import pyradiance

    root = Path(pyradiance.__file__).resolve().parent
    env = dict(os.environ, RAYPATH=os.pathsep.join([".", str(root / "lib")]))
    return root / "bin" / "gendaymtx", env


def _timed(cmd, out: Path, env, stdout_to_out: bool):
    """(wall, cpu, user, sys) seconds of one child run; ``out`` removed first."""
    out.unlink(missing_ok=True)
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    if stdout_to_out:
        with open(out, "wb") as f:
            subprocess.run(cmd, stdout=f, stderr=subprocess.DEVNULL, env=env, check=True)
    else:
        subprocess.run(cmd, stdout=subprocess.DEVNULL, env=env, check=True)
    wall = time.perf_counter() - t
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    user, system = r1.ru_utime - r0.ru_utime, r1.ru_stime - r0.ru_stime
    return wall, user + system, user, system


def _keep_best(best, name, wall, cpu, user, system):
    """Best wall and best CPU of a case, with the user/system parts of the best CPU round,
    and every round's CPU time (for the median)."""
    b = best.setdefault(name, [1e9, 1e9, 0.0, 0.0, []])
    b[0] = min(b[0], wall)
    if cpu < b[1]:
        b[1:4] = [cpu, user, system]
    b[4].append(cpu)


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--write", action="store_true")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--mf", type=int, nargs="+", default=[1, 4])
    args = ap.parse_args(argv)

    from skydome.daylighting.patches import patches
    from skydome.daylighting.radiance_io import matrix_file
    from skydome.daylighting.skymatrix import perez_sky_matrix_from_weather, warm_kernels
    from skydome.daylighting.weather import read_weather, sample_weather_path, write_wea

    tmy3 = sample_weather_path()
    gendaymtx, env = _radiance()
    senv = dict(env, PYTHONPATH=os.pathsep.join([str(ROOT / "src"),
                                                 env.get("PYTHONPATH", "")]).rstrip(os.pathsep))
    senv.pop("PYTHONDONTWRITEBYTECODE", None)  # bytecode cached, as an installed package's
    sky = [sys.executable, "-m", "skydome", "skymatrix"]
    rows, loads = [], []
    print("uptime before:", subprocess.run(["uptime"], capture_output=True,
                                           text=True).stdout.strip(), flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        write_wea(read_weather(tmy3, sun_position="radiance"), tmp / "y.wea")
        w = read_weather(tmp / "y.wea", sun_position="radiance")  # what the .wea run reads
        w_spa = read_weather(tmy3)  # what the default run reads (its dew points, SPA suns)
        warm_kernels()  # compile (or load) the kernels before timing
        for mf in args.mf:
            spec = "tregenza" if mf == 1 else f"reinhart:{mf}"
            cases = {
                "gendaymtx -of (.wea)": ([str(gendaymtx), "-m", str(mf), "-of",
                                          str(tmp / "y.wea")], env, True),
                "skydome CLI, .wea, order 0, Radiance sun": (
                    sky + ["--weather", str(tmp / "y.wea"), "--patches", spec, "--order", "0",
                           "--sun-position", "radiance", "--out", str(tmp / "s.mtx")],
                    senv, False),
                "skydome CLI, .wea, order 0, Radiance sun, --backend numba": (
                    sky + ["--weather", str(tmp / "y.wea"), "--patches", spec, "--order", "0",
                           "--sun-position", "radiance", "--backend", "numba", "--out",
                           str(tmp / "s.mtx")], senv, False),
                "skydome CLI, TMY3, order 0, Radiance sun": (
                    sky + ["--weather", str(tmy3), "--patches", spec, "--order", "0",
                           "--sun-position", "radiance", "--out", str(tmp / "s.mtx")],
                    senv, False),
                "skydome CLI, .wea, defaults (adaptive, SPA)": (
                    sky + ["--weather", str(tmp / "y.wea"), "--patches", spec, "--out",
                           str(tmp / "s.mtx")], senv, False),
                "skydome CLI, .wea, defaults (adaptive, SPA), --backend numba": (
                    sky + ["--weather", str(tmp / "y.wea"), "--patches", spec, "--backend",
                           "numba", "--out", str(tmp / "s.mtx")], senv, False),
                "skydome CLI, TMY3, defaults (adaptive, SPA)": (
                    sky + ["--weather", str(tmy3), "--patches", spec, "--out",
                           str(tmp / "s.mtx")], senv, False),
                "skydome CLI, TMY3, order 4, SPA": (
                    sky + ["--weather", str(tmy3), "--patches", spec, "--order", "4", "--out",
                           str(tmp / "s.mtx")], senv, False),
            }
            if mf == args.mf[-1]:  # the floor does not depend on the patches
                py = [sys.executable, "-c"]
                cases.update({
                    "start-up floor: python -c pass": (py + ["pass"], senv, False),
                    "start-up floor: import numpy": (py + ["import numpy"], senv, False),
                    "start-up floor: import numba": (py + ["import numba"], senv, False),
                    "start-up floor: import pvlib (TMY3/EPW input)": (
                        py + ["import pvlib"], senv, False),
                    "start-up floor: skydome + cached numba kernel, 2 hours (as --backend "
                    "numba)": (
                        py + [_FLOOR.format(start="start_numba_without_blas(); ")], senv,
                        False),
                    "start-up floor: the same, numba's own start (SciPy BLAS probe)": (
                        py + [_FLOOR.format(start="")], senv, False),
                })
            for cmd, e, _ in list(cases.values())[1:3]:  # numba and bytecode caches, warm
                _timed(cmd, tmp / "s.mtx", e, False)
            best: dict = {}
            for _ in range(args.repeat):
                for name, (cmd, e, to_out) in cases.items():
                    out = tmp / ("g.mtx" if to_out else "s.mtx")
                    _keep_best(best, name, *_timed(cmd, out, e, to_out))
                    loads.append(os.getloadavg()[0])
                for name, wx, o, sp, be in (
                        ("skydome in process, matrix + file, order 0, Radiance sun, numba "
                         "backend", w, 0, "radiance", "numba"),
                        ("skydome in process, matrix + file, order 0, Radiance sun, numpy "
                         "backend (default)", w, 0, "radiance", "numpy"),
                        ("skydome in process, matrix + file, adaptive, SPA, numba backend",
                         w_spa, "adaptive", "spa", "numba"),
                        ("skydome in process, matrix + file, defaults (adaptive, SPA, numpy "
                         "backend)", w_spa, "adaptive", "spa", "numpy"),
                        ("skydome in process, matrix + file, order 4, SPA, numba backend",
                         w_spa, 4, "spa", "numba")):
                    (tmp / "s.mtx").unlink(missing_ok=True)
                    r0 = resource.getrusage(resource.RUSAGE_SELF)
                    t = time.perf_counter()
                    # as perez_sky_matrix_file: the numpy backend checks what it writes
                    with matrix_file(tmp / "s.mtx", len(patches(spec)), len(wx), 3,
                                     check_finite=be == "numba") as body:
                        m = perez_sky_matrix_from_weather(wx, patches=spec, order=o,
                                                          sun_position=sp, dtype=np.float32,
                                                          out=body, backend=be)
                    wall = time.perf_counter() - t
                    r1 = resource.getrusage(resource.RUSAGE_SELF)
                    del m
                    user, system = r1.ru_utime - r0.ru_utime, r1.ru_stime - r0.ru_stime
                    _keep_best(best, name, wall, user + system, user, system)
            gw, gc, _, _, gall = best["gendaymtx -of (.wea)"]
            gmed = float(np.median(gall))
            for name, (bw, bc, bu, bs, call) in best.items():
                med = float(np.median(call))
                rows.append((spec, name, bw, gw / bw, bc, gc / bc, bu, bs, med, gmed / med))
                print(f"{spec:11s} {name:66s} wall {bw:6.2f} s x{gw / bw:5.1f}   "
                      f"cpu {bc:6.2f} s x{gc / bc:5.1f} (user {bu:.2f} sys {bs:.2f})   "
                      f"median cpu {med:6.2f} s x{gmed / med:5.1f}", flush=True)
    load = f"{min(loads):.1f}-{max(loads):.1f}"
    print(f"1-min load average during the runs: {load}")
    print("uptime after:", subprocess.run(["uptime"], capture_output=True,
                                          text=True).stdout.strip())
    if args.write:
        lines = [f"Annual sky matrices, 8760 h of the Greensboro TMY3 (benchmarks/bench_skymatrix.py; "
                 f"{machine()}; 1-min load average {load} during the run: the machine was "
                 "shared). Every CLI row is a whole program run from a fresh process "
                 "to the finished float matrix file (242 MB at MF:4); the in-process rows "
                 "are the matrix and its file alone (kernels loaded, weather read); the "
                 "start-up rows are fresh processes doing only that; best of "
                 f"{args.repeat} rounds, programs interleaved, and the median CPU time of the "
                 "rounds (its ratio: gendaymtx's median over the case's). CPU time is user + "
                 "system of the process over all its threads (gendaymtx is single-threaded); "
                 "ratio = gendaymtx / skydome (for a start-up row: the most a run paying that "
                 "start-up could reach were its work free).",
                 "",
                 "| patches | program | wall [s] | wall ratio | CPU [s] | CPU ratio | "
                 "user / sys [s] | median CPU [s] | median CPU ratio |",
                 "|---|---|---|---|---|---|---|---|---|"]
        for spec, name, bw, rw, bc, rc, bu, bs, med, rmed in rows:
            lines.append(f"| {spec} | {name} | {bw:.2f} | {rw:.1f}x | {bc:.2f} | {rc:.1f}x | "
                         f"{bu:.2f} / {bs:.2f} | {med:.2f} | {rmed:.1f}x |")
        write_section(ROOT / "docs" / "performance.md", "skymatrix", "\n".join(lines))


if __name__ == "__main__":
    main()
