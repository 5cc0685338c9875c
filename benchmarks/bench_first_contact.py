"""First contact: the README's commands in fresh processes, caches empty and warm (issue 27).

Each command runs as its own process (``python -m skydome ...``) with numba's cache
(``NUMBA_CACHE_DIR``) and the precomputed model's table cache (``SKYDOME_CACHE_DIR``)
pointed at temporary folders:

- **cold**: both folders empty (a new user's first command after ``pip install``);
- **warm**: the same command again in the folders its cold run filled.

Commands marked "new atmosphere" run their warm pass with a fresh, empty table cache and the
warm numba cache: the cost of an atmosphere met for the first time once skydome's kernels
are compiled. Per run the script prints the wall time, the CPU time of the process and its
children (user + system, from ``wait4``) and the peak resident memory (``ru_maxrss``).

``--fresh-venv`` adds the scenario of issue 27's first target: a new virtual environment,
``pip install --no-deps .`` of this checkout (the runtime dependencies come from the running
interpreter's environment through a ``.pth`` file; pip's isolated build environment takes
setuptools, numpy, scipy, numba and threadpoolctl from the configured index or wheel folder,
numba, llvmlite and numpy pinned to the running environment's versions), an empty table
cache and no ``NUMBA_CACHE_DIR``, then ``skydome render --sun-elevation 30 --out x.png``
twice. ``SKYDOME_BUILD_KERNELS=0`` in the environment gives the wheel without its kernels
(the "before" figures).

``--prewarm`` runs ``python -m skydome.apps.warmup --kernels`` (the set-up's kernel step) into
the cold numba folder first, to show the cold command as it is after the set-up.

``--warm-only N`` skips the cold pass: each command runs once untimed in the caches the
environment names (numba's cache of the checkout or ``NUMBA_CACHE_DIR``, the table cache of
``SKYDOME_CACHE_DIR`` or the user's), which fills them if needed, then N times timed, each
line with the 1-minute load average at its start (the machine's load moves the wall time);
a "new atmosphere" command's timed runs each get a new, empty table cache (numba's cache
warm: the figure of issue 27's "a new atmosphere as a command").

The commands run without ``PYTHONDONTWRITEBYTECODE`` (an installed package has its
bytecode compiled at install; with the variable set, every process compiles skydome's
modules again, about 0.2 s of a warm render).

Run: ``.venv/bin/python benchmarks/bench_first_contact.py [--quick] [--only NAME ...]
[--fresh-venv] [--warm-only N] [--write]``; ``--write`` replaces the ``bench:first_contact`` block of
docs/performance.md.
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


@dataclass
class Command:
    name: str
    argv: list
    quick: bool = False          # part of --quick
    new_atmosphere: bool = False  # warm pass with an empty table cache


COMMANDS = [
    Command("render (shortest)", ["render", "--sun-elevation", "30", "--out", "{out}/x.png"],
            quick=True),
    Command("render fisheye 512 exr (README)",
            ["render", "--sun-elevation", "30", "--sun-azimuth", "135", "--projection", "fisheye",
             "--size", "512", "--out", "{out}/noon.exr"]),
    Command("render equirect 2048x1024 place/time (README)",
            ["render", "--lat", "48.21", "--lon", "16.37", "--time", "2026-06-21T20:45+02:00",
             "--projection", "equirect", "--size", "2048x1024", "--out", "{out}/sunset.png"]),
    Command("table1", ["table1"]),
    Command("sun", ["sun", "--lat", "48.21", "--lon", "16.37", "--time",
                    "2026-06-21T12:00+02:00"]),
    Command("models", ["models"], quick=True),
    Command("export envmap 4096x2048 --half (precomputed)",
            ["export", "envmap", "--size", "4096x2048", "--half", "--out", "{out}/env.exr"],
            quick=True),
    Command("export envmap 4096x2048 --half (hosek_wilkie2012)",
            ["export", "envmap", "--model", "hosek_wilkie2012", "--turbidity", "3", "--size",
             "4096x2048", "--half", "--out", "{out}/hw.exr"], quick=True),
    Command("export luts --model precomputed",
            ["export", "luts", "--model", "precomputed", "--out", "{out}/luts"]),
    Command("new atmosphere (render --turbidity 4)",
            ["render", "--turbidity", "4", "--sun-elevation", "30", "--out", "{out}/t4.png"],
            quick=True, new_atmosphere=True),
    Command("render cie2003 (README)",
            ["render", "--model", "cie2003", "--sky-type", "12", "--sun-elevation", "40",
             "--out", "{out}/cie12.hdr"]),
    Command("render preetham1999 equirect (README)",
            ["render", "--model", "preetham1999", "--turbidity", "3", "--projection", "equirect",
             "--size", "2048x1024", "--out", "{out}/env.exr"]),
    Command("timelapse one day at 30 min",
            ["timelapse", "--lat", "48.21", "--lon", "16.37", "--date", "2026-06-21",
             "--utc-offset", "+02:00", "--every", "30min", "--out", "{out}/day"]),
]


@dataclass
class Run:
    wall: float
    cpu: float
    rss_gb: float
    rc: int
    tail: str


def run(argv, env, cwd) -> Run:
    """One process: wall time, CPU time (user + system, its own and its children's) and
    peak resident memory, from ``wait4``."""
    t0 = time.perf_counter()
    with tempfile.TemporaryFile() as log:
        p = subprocess.Popen(argv, env=env, cwd=cwd, stdout=log, stderr=subprocess.STDOUT)
        _, status, ru = os.wait4(p.pid, 0)
        wall = time.perf_counter() - t0
        p.returncode = os.waitstatus_to_exitcode(status)
        log.seek(0)
        tail = log.read().decode("utf-8", "replace").strip().splitlines()[-3:]
    return Run(wall, ru.ru_utime + ru.ru_stime, ru.ru_maxrss / 1024 ** 2, p.returncode,
               " | ".join(tail))


def environment(numba_dir, table_dir, extra_path=None) -> dict:
    env = dict(os.environ)
    if numba_dir is not None:
        env["NUMBA_CACHE_DIR"] = str(numba_dir)
    if table_dir is not None:
        env["SKYDOME_CACHE_DIR"] = str(table_dir)
    if extra_path is not None:
        env["PYTHONPATH"] = str(extra_path)
    env.pop("NUMBA_DISABLE_JIT", None)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def _fmt(r: Run) -> str:
    bad = "" if r.rc == 0 else f" (exit {r.rc}: {r.tail[:160]})"
    return f"{r.wall:.1f} s | {r.cpu:.1f} s | {r.rss_gb:.2f} GB{bad}"


def bench_commands(commands, python, prewarm: bool, work: Path) -> list:
    rows = []
    for c in commands:
        d = Path(tempfile.mkdtemp(prefix="fc-", dir=work))
        out, nb, tab = d / "out", d / "numba", d / "tables"
        for f in (out, nb, tab):
            f.mkdir()
        env = environment(nb, tab)
        argv = [python, "-m", "skydome"] + [a.format(out=out) for a in c.argv]
        if prewarm:
            r = run([python, "-m", "skydome.apps.warmup", "--kernels"], env, out)
            print(f"  (set-up kernel step: {_fmt(r)})", flush=True)
        cold = run(argv, env, out)
        print(f"{c.name:50s} cold {_fmt(cold)}", flush=True)
        if c.new_atmosphere:
            tab2 = d / "tables2"
            tab2.mkdir()
            env = environment(nb, tab2)
        warm = run(argv, env, out)
        print(f"{c.name:50s} warm {_fmt(warm)}", flush=True)
        rows.append((c, cold, warm))
        shutil.rmtree(d, ignore_errors=True)
    return rows


def bench_warm(commands, python, repeat: int, work: Path) -> list:
    """Each command once untimed in the environment's own caches (filling them where
    needed), then ``repeat`` timed runs; rows of (command, [(load average, Run), ...])."""
    rows = []
    for c in commands:
        out = Path(tempfile.mkdtemp(prefix="fc-warm-", dir=work))
        env = environment(None, None)
        argv = [python, "-m", "skydome"] + [a.format(out=out) for a in c.argv]
        first = run(argv, env, out)
        print(f"{c.name:50s} fill {_fmt(first)}", flush=True)
        runs = []
        for i in range(repeat):
            if c.new_atmosphere:
                # numba's cache as the environment has it (warm after the fill), the table
                # cache a new empty folder: an atmosphere met for the first time
                tab = out / f"tables-{i}"
                tab.mkdir()
                env = environment(None, tab)
            load = os.getloadavg()[0]
            r = run(argv, env, out)
            print(f"{c.name:50s} warm {_fmt(r)} (load {load:.1f})", flush=True)
            runs.append((load, r))
        rows.append((c, runs))
        shutil.rmtree(out, ignore_errors=True)
    return rows


def warm_block(rows) -> str:
    lines = ["| command | runs: wall, CPU (1-min load average) | best wall | best CPU | peak RSS |",
             "|---|---|---|---|---|"]
    for c, runs in rows:
        each = "; ".join(f"{r.wall:.2f} s, {r.cpu:.2f} s ({load:.1f})" for load, r in runs)
        lines.append(f"| `{c.name}` | {each} | {min(r.wall for _, r in runs):.2f} s | "
                     f"{min(r.cpu for _, r in runs):.2f} s | "
                     f"{max(r.rss_gb for _, r in runs):.2f} GB |")
    lines += ["", f"Machine: {machine()}."]
    return "\n".join(lines)


def bench_fresh_venv(work: Path) -> list:
    """A new virtual environment, ``pip install --no-deps .`` (the wheel built in pip's
    isolated build environment, so with setup.py's kernel step; the runtime dependencies
    through a .pth file pointing at the running interpreter's site-packages), empty table
    cache and no ``NUMBA_CACHE_DIR`` (numba's cache is then the installed package's own
    ``__pycache__``), the shortest render, twice."""
    import importlib.metadata as md
    import sysconfig

    d = Path(tempfile.mkdtemp(prefix="fc-venv-", dir=work))
    venv, out, tab = d / "venv", d / "out", d / "tables"
    for f in (out, tab):
        f.mkdir()
    rows = []
    t = run([sys.executable, "-m", "venv", str(venv)], dict(os.environ), d)
    rows.append(("python -m venv", t))
    py = str(venv / "bin" / "python")
    site = subprocess.run([py, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                          capture_output=True, text=True, check=True).stdout.strip()
    Path(site, "_deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    env = dict(os.environ)
    for var in ("PYTHONPATH", "NUMBA_CACHE_DIR", "NUMBA_DISABLE_JIT"):
        env.pop(var, None)
    # the build environment gets the numba, llvmlite and numpy of the environment that runs
    # the kernels (pip passes PIP_CONSTRAINT on to the build environment's installation)
    pins = d / "constraints.txt"
    pins.write_text("".join(f"{p}=={md.version(p)}\n" for p in ("numba", "llvmlite", "numpy")))
    env["PIP_CONSTRAINT"] = str(pins)
    build = d / "src"
    shutil.copytree(ROOT, build, ignore=shutil.ignore_patterns(
        ".git", ".venv*", ".vendor", "out", "__pycache__", "*.egg-info", "build", "node_modules"))
    t = run([py, "-m", "pip", "install", "--quiet", "--no-deps", str(build)], env, d)
    rows.append(("pip install --no-deps . (wheel build with the kernel step)", t))
    print(f"{'fresh venv: pip install --no-deps .':50s}      {_fmt(t)}", flush=True)
    nb = sum(1 for _ in Path(site, "skydome").rglob("*.nbc"))
    print(f"{'fresh venv: compiled kernel files installed':50s}      {nb}", flush=True)
    env.pop("PIP_CONSTRAINT")
    env["SKYDOME_CACHE_DIR"] = str(tab)
    for name in ("first render (empty table cache)", "second render (warm)"):
        r = run([str(venv / "bin" / "skydome"), "render", "--sun-elevation", "30", "--out",
                 str(out / "x.png")], env, out)
        rows.append((name, r))
        print(f"{'fresh venv: ' + name:50s}      {_fmt(r)}", flush=True)
    shutil.rmtree(d, ignore_errors=True)
    return rows


def machine() -> str:
    cpu = next((ln.split(":", 1)[1].strip() for ln in open("/proc/cpuinfo")
                if ln.startswith("model name")), platform.processor())
    import numba

    return (f"{cpu}, {os.cpu_count()} cores, numba {numba.__version__}, "
            f"Python {platform.python_version()}")


def block(rows, venv_rows, load0, load1) -> str:
    lines = ["| command | cold: wall | CPU | peak RSS | warm: wall | CPU | peak RSS |",
             "|---|---|---|---|---|---|---|"]
    for c, cold, warm in rows:
        note = " (warm pass: empty table cache)" if c.new_atmosphere else ""
        lines.append(f"| `{c.name}`{note} | {_fmt(cold)} | {_fmt(warm)} |")
    if venv_rows:
        lines += ["", "| fresh virtual environment | wall | CPU | peak RSS |", "|---|---|---|---|"]
        lines += [f"| {name} | {_fmt(r)} |" for name, r in venv_rows]
    lines += ["", f"Machine: {machine()}. Load average {load0:.1f} at the start, "
                  f"{load1:.1f} at the end."]
    return "\n".join(lines)


def write_block(text: str) -> None:
    doc = ROOT / "docs" / "performance.md"
    s = doc.read_text()
    a, b = "<!-- bench:first_contact -->", "<!-- /bench:first_contact -->"
    if a in s:
        s = s[:s.index(a)] + a + "\n" + text + "\n" + s[s.index(b):]
    else:
        s = s.rstrip("\n") + "\n\n" + a + "\n" + text + "\n" + b + "\n"
    doc.write_text(s)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="only the issue's short list")
    ap.add_argument("--only", nargs="*", default=None,
                    help="commands whose name contains one of these words")
    ap.add_argument("--fresh-venv", action="store_true",
                    help="also: new venv + pip install --no-deps . + first render")
    ap.add_argument("--no-commands", action="store_true", help="skip the command list")
    ap.add_argument("--prewarm", action="store_true",
                    help="run the set-up's kernel step before each cold command")
    ap.add_argument("--warm-only", type=int, default=0, metavar="N",
                    help="no cold pass: N timed runs in the environment's own caches")
    ap.add_argument("--write", action="store_true", help="update docs/performance.md")
    a = ap.parse_args(argv)
    cmds = [c for c in COMMANDS if c.quick or not a.quick]
    if a.only:
        cmds = [c for c in cmds if any(w in c.name for w in a.only)]
    if a.no_commands:
        cmds = []
    print(f"machine: {machine()}; load average {os.getloadavg()[0]:.1f}", flush=True)
    print(f"{'command':50s} pass wall | CPU (user+sys) | peak RSS", flush=True)
    load0 = os.getloadavg()[0]
    with tempfile.TemporaryDirectory(prefix="skydome-first-contact-") as work:
        # the commands import this checkout's skydome
        os.environ["PYTHONPATH"] = os.pathsep.join(
            [str(ROOT / "src")] + [p for p in [os.environ.get("PYTHONPATH")] if p])
        if a.warm_only:
            text = warm_block(bench_warm(cmds, sys.executable, a.warm_only, Path(work)))
            print(text)
            return
        rows = bench_commands(cmds, sys.executable, a.prewarm, Path(work))
        venv_rows = bench_fresh_venv(Path(work)) if a.fresh_venv else []
    text = block(rows, venv_rows, load0, os.getloadavg()[0])
    print(text)
    if a.write:
        write_block(text)


if __name__ == "__main__":
    main()
