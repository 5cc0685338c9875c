"""Environment map and shortest-render path: wall and CPU time per stage, warm caches.

In process, for a 4096x2048 lat-long half-float map of ``hosek_wilkie2012``,
``preetham1999``, ``fitted`` and ``precomputed`` (sun at 30 deg, azimuth 135 deg, the CLI's 16
wavelengths, Lambertian ground, the sun as a separate light) it prints the stages of
:func:`skydome.export.envmap.render_envmap` and the write:

* ``directions``: the map projection's pixel directions (a fresh projection);
* ``render``: :func:`skydome.imaging.render` (``output="xyz"``, ground included);
* ``envmap``: the whole :func:`render_envmap` (render, RGB, sun light, metadata);
* ``write``: ``EnvironmentMap.write(half=True)`` (EXR, half floats);

and the 512 px fisheye render of the precomputed sky (the shortest ``skydome render``).
Then, in fresh ``python -m skydome`` processes (tables and numba caches warm), the
commands ``export envmap --size 4096x2048 --half`` for each model and
``render --sun-elevation 30 --out x.png``, the best of ``--repeat`` runs (wall and the
child's CPU time, its peak RSS and its minor page faults: the fresh memory it touched,
which on a virtual machine costs about 1 ms per MB), after one untimed run of each. The
children run with Python's bytecode cache on (``PYTHONDONTWRITEBYTECODE`` removed from
their environment), as an installed package has it. The machine is shared: compare runs
made at the same load (printed), and CPU times and page faults rather than wall times.

Run: ``PYTHONPATH=src python benchmarks/bench_envmap_path.py [--repeat N] [--no-cli]
[--models NAME ...] [--no-render] [--trees BEFORE/src AFTER/src]``.
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import time

MODELS = ("hosek_wilkie2012", "preetham1999", "fitted", "precomputed")
SIZE = "4096x2048"


def _clock(fn):
    w0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - w0, time.process_time() - c0


def _row(name, wall, cpu):
    print(f"  {name:34s} wall {wall:6.2f} s   cpu {cpu:6.2f} s", flush=True)


def in_process(folder: str, models=MODELS) -> None:
    import skydome as sd
    from skydome.export.envmap import MapProjection, render_envmap
    from skydome.imaging import Fisheye, render
    from skydome.spectra import wavelength_grid

    wl = wavelength_grid(380.0, 780.0, n=16)
    sun = sd.Sun(elevation_deg=30.0, azimuth_deg=135.0)
    W, H = (int(v) for v in SIZE.split("x"))
    for name in models:
        print(f"{name}: {SIZE} half EXR, in process", flush=True)
        sky, w, c = _clock(lambda: sd.model(name, sun=sun))
        _row("model (warm caches)", w, c)
        render_envmap(sky, "skydome", "64x32", wavelengths_nm=wl)      # warm the kernels
        proj, w, c = _clock(lambda: MapProjection("skydome", W, H))
        _, w, c = _clock(proj.directions)
        _row("directions", w, c)
        _, w, c = _clock(lambda: render(sky, proj, wl, draw_sun=False, output="xyz",
                                        ground="lambertian"))
        _row("render (xyz, ground)", w, c)
        env, w1, c1 = _clock(lambda: render_envmap(sky, "skydome", SIZE, wavelengths_nm=wl))
        _row("render_envmap (total)", w1, c1)
        path = os.path.join(folder, f"{name}.exr")
        _, w2, c2 = _clock(lambda: env.write(path, half=True))
        _row("write (half EXR)", w2, c2)
        _row("render_envmap + write", w1 + w2, c1 + c2)
    print("precomputed: 512 px fisheye render, in process", flush=True)
    sky, w, c = _clock(lambda: sd.model("precomputed", sun=sd.Sun(elevation_deg=30.0,
                                                                  azimuth_deg=180.0)))
    _row("model (warm caches)", w, c)
    img, w1, c1 = _clock(lambda: render(sky, Fisheye(512), wl, output="xyz"))
    _row("render", w1, c1)
    _, w2, c2 = _clock(lambda: img.save(os.path.join(folder, "x.png")))
    _row("save (png)", w2, c2)


def _env(src):
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # bytecode cached, as an installed package's
    if src is not None:
        env["PYTHONPATH"] = src
    return env


def _cli_once(args, env) -> tuple[float, float, float, float]:
    """(wall [s], CPU [s], peak RSS [MB], minor page faults [MB of 4 KiB pages]) of one
    ``python -m skydome`` run."""
    t0 = time.perf_counter()
    p = subprocess.Popen([sys.executable, "-m", "skydome", *args], stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL, env=env)
    _, status, ru = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    if os.waitstatus_to_exitcode(status) != 0:
        raise RuntimeError(f"skydome {' '.join(args)} failed")
    return wall, ru.ru_utime + ru.ru_stime, ru.ru_maxrss / 1024.0, ru.ru_minflt * 4.0 / 1024.0


def _commands(folder, models=MODELS, render=True):
    cmds = [(f"export envmap {name}", ["export", "envmap", "--model", name, "--size", SIZE,
                                       "--half", "--out", os.path.join(folder, f"{name}.exr")])
            for name in models]
    if render:
        cmds.append(("render --sun-elevation 30 (512 px)",
                     ["render", "--sun-elevation", "30", "--out",
                      os.path.join(folder, "x.png")]))
    return cmds


def fresh_processes(folder: str, repeat: int, trees, models=MODELS, render=True) -> None:
    """Each command in fresh processes, the trees' runs alternating (A, B, A, B, ...) after
    one untimed run each (bytecode and kernel caches warm): best wall, best CPU, the median
    CPU, the median wall, the peak RSS and the fewest page faults per tree."""
    import statistics

    print(f"fresh processes (python -m skydome, best of {repeat}, trees alternating)",
          flush=True)
    for label, args in _commands(folder, models, render):
        for src in trees:
            _cli_once(args, _env(src))
        runs = {src: [] for src in trees}
        for _ in range(repeat):
            for src in trees:
                runs[src].append(_cli_once(args, _env(src)))
        for src in trees:
            r = runs[src]
            name = label if src is None else f"{label} [{src}]"
            print(f"  {name:34s} wall {min(x[0] for x in r):6.2f} s   cpu "
                  f"{min(x[1] for x in r):6.2f} s (median "
                  f"{statistics.median(x[1] for x in r):.2f}) (median wall "
                  f"{statistics.median(x[0] for x in r):.2f})   peak RSS "
                  f"{max(x[2] for x in r):6.0f} MB   page faults {min(x[3] for x in r):5.0f} MB",
                  flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=2, help="fresh-process runs per command")
    ap.add_argument("--no-cli", action="store_true", help="skip the fresh processes")
    ap.add_argument("--no-inprocess", action="store_true", help="skip the in-process stages")
    ap.add_argument("--models", nargs="+", default=list(MODELS), metavar="NAME",
                    help=f"models of the envmap commands (default {' '.join(MODELS)})")
    ap.add_argument("--no-render", action="store_true",
                    help="skip the shortest render command in the fresh processes")
    ap.add_argument("--trees", nargs="+", default=None, metavar="SRC",
                    help="src folders to compare in the fresh processes (alternating); "
                    "default the PYTHONPATH as it is")
    a = ap.parse_args()
    cpu = next((ln.split(":", 1)[1].strip() for ln in open("/proc/cpuinfo")
                if ln.startswith("model name")), platform.processor())
    print(f"machine: {cpu}, {os.cpu_count()} cores, Python {platform.python_version()}; "
          f"load average at start {os.getloadavg()[0]:.1f}")
    with tempfile.TemporaryDirectory() as folder:
        if not a.no_inprocess:
            in_process(folder, a.models)
        if not a.no_cli:
            fresh_processes(folder, a.repeat, a.trees or [None], a.models, not a.no_render)
    print(f"load average at end {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
