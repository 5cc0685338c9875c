"""Start-up time of `import skydome` and `skydome --help` (targets: 1.5 s and 0.5 s).

Prints the median of several cold-process runs. Run: .venv/bin/python benchmarks/bench_startup.py
"""

import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

BIN = Path(sys.executable).with_name("skydome")


def _time(cmd, n=7):
    ts = []
    for _ in range(n):
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True)
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts)


def main():
    cpu = next((ln.split(":", 1)[1].strip() for ln in open("/proc/cpuinfo") if ln.startswith("model name")),
               platform.processor())
    print(f"machine: {cpu}, {os.cpu_count()} cores, Python {platform.python_version()}")
    base = _time([sys.executable, "-c", "pass"])
    imp = _time([sys.executable, "-c", "import skydome; skydome.Sun, skydome.Atmosphere, skydome.model"])
    helpt = _time([str(BIN), "--help"])
    models = _time([str(BIN), "models"])
    print(f"python -c pass      {base:.3f} s")
    print(f"import skydome      {imp:.3f} s   (target < 1.5 s)")
    print(f"skydome --help      {helpt:.3f} s   (target < 0.5 s)")
    print(f"skydome models      {models:.3f} s")


if __name__ == "__main__":
    main()
