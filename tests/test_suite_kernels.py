"""tools/suite_kernels.py: the suite's kernels compiled ahead of pytest. A stale list is
skipped entry by entry and never fails the set-up; the split keeps each function in one
process and balances the compiled sizes."""

import base64
import json
import os
import pickle
import subprocess
import sys
from pathlib import Path

from _tools import load_script

ROOT = Path(__file__).resolve().parents[1]
TOOL = ROOT / "tools" / "suite_kernels.py"


def _tool():
    return load_script("tools/suite_kernels.py", "suite_kernels")


def _entry(module, qualname, sig, size=1):
    return {"module": module, "qualname": qualname, "signature": str(sig), "size": size,
            "pickle": base64.b64encode(pickle.dumps(sig, protocol=4)).decode()}


def test_stale_entries_are_skipped_and_the_rest_compiled(tmp_path):
    from numba import types

    entries = [
        # a real kernel of the transport core, at the signature the models call it with
        _entry("skydome.transport._geometry", "safe_sqrt", (types.float64,)),
        # the same kernel at a signature that does not type (too many arguments)
        _entry("skydome.transport._geometry", "safe_sqrt", (types.float64, types.float64)),
        _entry("skydome.no_such_module", "kernel", (types.float64,)),   # module removed
        _entry("skydome.transport._geometry", "no_such_kernel", (types.float64,)),  # renamed
        _entry("skydome.transport._geometry", "__name__", (types.float64,)),  # no dispatcher
    ]
    lines = [json.dumps(e) for e in entries]
    bad = dict(entries[0], pickle="bm90IGEgcGlja2xl")   # a pickle another numba wrote
    lines += [json.dumps(bad), "not json", json.dumps({"module": "x"})]
    listed = tmp_path / "list.jsonl"
    listed.write_text("\n".join(lines) + "\n")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"),
               PYTHONPATH=os.pathsep.join([str(ROOT / "src")] + sys.path))
    proc = subprocess.run([sys.executable, str(TOOL), "compile", "--list", str(listed),
                           "--jobs", "2", "--stamp", str(tmp_path / "stamp")],
                          capture_output=True, text=True, env=env, timeout=600)
    assert proc.returncode == 0, proc.stderr
    # six readable entries: one compiles, five are skipped (the two unreadable lines are
    # dropped when the list is read)
    assert "1 signatures compiled, 0 already cached, 5 skipped" in proc.stdout, proc.stdout
    assert list((tmp_path / "numba").rglob("*safe_sqrt*.nbi")), "no cache entry written"
    # a second run with nothing changed returns at once
    again = subprocess.run([sys.executable, str(TOOL), "compile", "--list", str(listed),
                            "--jobs", "2", "--stamp", str(tmp_path / "stamp")],
                           capture_output=True, text=True, env=env, timeout=600)
    assert again.returncode == 0
    assert "nothing changed since" in again.stdout, again.stdout


def test_missing_list_is_not_an_error(tmp_path):
    proc = subprocess.run([sys.executable, str(TOOL), "compile", "--list",
                           str(tmp_path / "none.jsonl")], capture_output=True, text=True)
    assert proc.returncode == 0
    assert "nothing compiled" in proc.stdout


def test_split_keeps_functions_together_and_balances_sizes():
    tool = _tool()
    # sizes by function: a 10 (two signatures of 5), b 7, c 4, d 3, e 1; two parts dealt
    # largest first to the lighter part: a -> 0 (10), b -> 1 (7), c -> 1 (11), d -> 0 (13),
    # e -> 1 (12)
    entries = [{"module": "m", "qualname": q, "size": s, "pickle": ""}
               for q, s in (("a", 5), ("a", 5), ("b", 7), ("c", 4), ("d", 3), ("e", 1))]
    parts = tool.split(entries, 2)
    names = [sorted({e["qualname"] for e in p}) for p in parts]
    assert names == [["a", "d"], ["b", "c", "e"]]
    assert [sum(e["size"] for e in p) for p in parts] == [13, 12]
    assert len(tool.split(entries, 1)[0]) == len(entries)


def test_function_of_an_index_file():
    tool = _tool()
    src = ROOT / "src"
    folder = src / "skydome" / "transport" / "__pycache__"
    assert tool._function_of(folder / "_geometry.safe_sqrt-26.py311.nbi", src) == \
        ("skydome.transport._geometry", "safe_sqrt")
    assert tool._function_of(folder / "__init__.kernel-3.py311.nbi", src) == \
        ("skydome.transport", "kernel")
    assert tool._function_of(folder / "_x.outer.locals.inner-9.py311.nbi", src) is None
