"""The test suite's numba kernels compiled ahead of pytest, in parallel processes.

pytest runs the suite in one process, and numba compiles a kernel in the thread that first
calls it, one at a time: in a fresh checkout about 30 % of the suite's wall time on 2 cores
(docs/performance.md, "The test suite's compile share"). The kernels' signatures are known
in advance (the suite reaches the same ones every run), so ``./scripts/test`` compiles them
first, split over one process per core, into numba's cache (the in-tree ``__pycache__``
beside the kernels, or ``NUMBA_CACHE_DIR`` where set), where the suite's own calls then
find them.

``record``
    Writes the list (``tests/suite_kernels.jsonl``) from numba's cache index files
    (``src/skydome/**/__pycache__/*.nbi``) of a checkout in which the suite has run: one
    line per cached signature (the function's module and qualified name, the signature as
    numba prints it and pickled, and the size of its compiled entry, which ranks the work
    for the split). The list is merged with the one already there (``--replace`` starts
    over).

``compile``
    Compiles every listed signature with ``Dispatcher.compile`` in ``--jobs`` processes
    (the CPUs this process may use, at most 8, by default), all signatures of one function in the same process
    (each function has one cache index file, which two processes must not write at once),
    the functions split so that each process gets about the same compiled size. Anything
    that no longer applies (a function renamed or removed, a signature that no longer
    types, a list pickled by another numba version) is skipped and counted, never an
    error: the suite then compiles what it needs itself, as without this step. A stamp
    file (``--stamp``) holding a hash of the sources, the list and the cache's index files
    makes a second run with nothing changed return at once. The exit status is 0 whatever
    happened to the kernels.

The list's pickles are numba type objects written by this tool from the checkout's own
cache; they are read only from the repository's own file.
"""

from __future__ import annotations

import argparse
import base64
import hashlib
import json
import os
import pickle
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"
LIST = ROOT / "tests" / "suite_kernels.jsonl"


# -- record ----------------------------------------------------------------------------------

def _function_of(index: Path, src: Path = SRC) -> tuple[str, str] | None:
    """(module, qualified name) of the function whose numba index file this is
    (``<folder>/__pycache__/<file stem>.<qualname>-<line>.py<version>.nbi``)."""
    head = index.name[: -len(".nbi")].rsplit("-", 1)[0]
    stem, _, qualname = head.partition(".")
    if not qualname or "locals" in qualname.split("."):
        return None   # defined inside a function (numba writes "<locals>" as "locals")
    package = index.parent.parent.relative_to(src).parts
    module = ".".join(package if stem == "__init__" else package + (stem,))
    return module, qualname


def _read_index(index: Path) -> dict:
    with open(index, "rb") as f:
        pickle.load(f)                       # numba's cache format version
        _stamp, overloads = pickle.loads(f.read())
    return overloads


def record(out: Path, replace: bool, src: Path = SRC) -> int:
    entries = {} if replace else {(e["module"], e["qualname"], e["signature"]): e
                                  for e in _load_list(out)}
    found = 0
    for index in sorted(src.glob("skydome/**/__pycache__/*.nbi")):
        function = _function_of(index, src)
        if function is None:
            continue
        try:
            overloads = _read_index(index)
        except Exception as exc:  # an index another numba wrote
            print(f"record: {index.name} not read ({type(exc).__name__})", file=sys.stderr)
            continue
        for key, data_name in overloads.items():
            sig = key[0]
            data = index.parent / data_name
            size = data.stat().st_size if data.exists() else 0
            entry = {"module": function[0], "qualname": function[1], "signature": str(sig),
                     "size": size,
                     "pickle": base64.b64encode(pickle.dumps(sig, protocol=4)).decode()}
            old = entries.get((function[0], function[1], str(sig)))
            if old is not None:
                entry["size"] = max(size, old.get("size", 0))
            entries[(function[0], function[1], str(sig))] = entry
            found += 1
    with open(out, "w") as f:
        for key in sorted(entries):
            f.write(json.dumps(entries[key], sort_keys=True) + "\n")
    print(f"record: {found} cached signatures read, {len(entries)} in {out.name}")
    return 0


def _load_list(path: Path) -> list[dict]:
    if not path.exists():
        return []
    entries = []
    for line in path.read_text().splitlines():
        try:
            entry = json.loads(line)
            entry["module"], entry["qualname"], entry["pickle"]   # noqa: B018 (required keys)
        except (ValueError, KeyError, TypeError):
            continue
        entries.append(entry)
    return entries


# -- compile ---------------------------------------------------------------------------------

def split(entries: list[dict], jobs: int) -> list[list[dict]]:
    """The entries grouped by function, the functions dealt to ``jobs`` parts largest first,
    each to the part with the least compiled size so far."""
    functions: dict[tuple[str, str], list[dict]] = {}
    for e in entries:
        functions.setdefault((e["module"], e["qualname"]), []).append(e)
    ranked = sorted(functions.values(),
                    key=lambda es: (-sum(e.get("size", 0) for e in es),
                                    es[0]["module"], es[0]["qualname"]))
    parts: list[list[dict]] = [[] for _ in range(max(1, jobs))]
    loads = [0] * len(parts)
    for es in ranked:
        i = loads.index(min(loads))
        parts[i].extend(es)
        loads[i] += sum(e.get("size", 0) for e in es)
    return parts


def _compile_part(entries: list[dict]) -> dict:
    """Compile the entries in this process; counts of what happened."""
    import importlib

    from numba.core import event
    from numba.core.dispatcher import Dispatcher

    counts = {"compiled": 0, "cached": 0, "skipped": 0, "seconds": 0.0}
    compiles = []

    class _Count(event.Listener):
        def on_start(self, ev):
            compiles.append(1)

        def on_end(self, ev):
            pass

    event.register("numba:compile", _Count())
    reasons: dict[str, int] = {}
    t0 = time.perf_counter()
    for e in entries:
        try:
            obj = importlib.import_module(e["module"])
            for name in e["qualname"].split("."):
                obj = getattr(obj, name)
            if not isinstance(obj, Dispatcher):
                raise TypeError("not a numba dispatcher")
            sig = pickle.loads(base64.b64decode(e["pickle"]))
            n = len(compiles)
            obj.compile(sig)
            counts["compiled" if len(compiles) > n else "cached"] += 1
        except Exception as exc:  # the list is stale here: the suite compiles it itself
            counts["skipped"] += 1
            reasons[type(exc).__name__] = reasons.get(type(exc).__name__, 0) + 1
    counts["seconds"] = time.perf_counter() - t0
    counts["reasons"] = reasons
    return counts


def _stamp_of(path: Path) -> str:
    h = hashlib.sha256()
    for f in sorted(SRC.rglob("*.py")):
        h.update(str(f.relative_to(SRC)).encode())
        h.update(f.read_bytes())
    h.update(path.read_bytes() if path.exists() else b"")
    h.update(os.environ.get("NUMBA_CACHE_DIR", "").encode())
    for f in sorted(SRC.rglob("*.nbi")):    # the cache entries still there
        h.update(f"{f.relative_to(SRC)} {f.stat().st_size}".encode())
    return h.hexdigest()


def compile_all(path: Path, jobs: int, stamp: Path | None) -> int:
    entries = _load_list(path)
    if not entries:
        print(f"kernels: no list ({path.name}), nothing compiled ahead of the suite")
        return 0
    if stamp is not None and stamp.exists() and stamp.read_text() == _stamp_of(path):
        print("kernels: the suite's kernels are compiled (nothing changed since)")
        return 0
    t0 = time.perf_counter()
    c0 = os.times()
    procs = [subprocess.Popen([sys.executable, __file__, "_part", str(path), f"{i}/{jobs}"],
                              stdout=subprocess.PIPE, text=True) for i in range(jobs)]
    total = {"compiled": 0, "cached": 0, "skipped": 0}
    reasons: dict[str, int] = {}
    died = 0
    for p in procs:
        out, _ = p.communicate()
        try:
            counts = json.loads(out.strip().splitlines()[-1])
        except (ValueError, IndexError):
            died += 1   # a part that failed: said below, never fatal
            continue
        for k in total:
            total[k] += counts[k]
        for k, v in counts["reasons"].items():
            reasons[k] = reasons.get(k, 0) + v
    c1 = os.times()
    cpu = (c1.children_user - c0.children_user) + (c1.children_system - c0.children_system)
    why = ", ".join(f"{v} {k}" for k, v in sorted(reasons.items()))
    print(f"kernels: {total['compiled']} signatures compiled, {total['cached']} already cached, "
          f"{total['skipped']} skipped{f' ({why})' if why else ''} in {jobs} processes: "
          f"{time.perf_counter() - t0:.1f} s wall, {cpu:.1f} s CPU"
          + (f"; {died} process(es) failed, the suite compiles their part itself"
             if died else ""))
    if stamp is not None and not died:
        try:
            stamp.write_text(_stamp_of(path))
        except OSError:
            pass
    return 0


def _default_jobs() -> int:
    try:
        cpus = len(os.sched_getaffinity(0))
    except AttributeError:
        cpus = os.cpu_count() or 1
    return max(1, min(cpus, 8))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    r = sub.add_parser("record", help="write the list from the checkout's numba cache")
    r.add_argument("--out", type=Path, default=LIST)
    r.add_argument("--replace", action="store_true", help="drop the list's old entries")
    r.add_argument("--src", type=Path, default=SRC,
                   help="the source folder whose __pycache__ folders are read (this checkout's)")
    c = sub.add_parser("compile", help="compile the listed signatures in parallel processes")
    c.add_argument("--list", type=Path, default=LIST)
    c.add_argument("--jobs", type=int, default=_default_jobs(),
                   help="compiling processes (default: the CPUs this process may use, at "
                        "most 8; each held up to 0.8 GB here)")
    c.add_argument("--stamp", type=Path, default=None,
                   help="skip when this file holds the hash of an unchanged checkout")
    p = sub.add_parser("_part")   # one compiling process (internal)
    p.add_argument("list", type=Path)
    p.add_argument("part")
    args = ap.parse_args(argv)
    if args.command == "record":
        return record(args.out, args.replace, args.src.resolve())
    if args.command == "compile":
        if args.jobs < 1:
            ap.error(f"--jobs must be >= 1, got {args.jobs}")
        return compile_all(args.list, args.jobs, args.stamp)
    i, n = (int(x) for x in args.part.split("/"))
    counts = _compile_part(split(_load_list(args.list), n)[i])
    print(json.dumps(counts))
    return 0


if __name__ == "__main__":
    sys.exit(main())
