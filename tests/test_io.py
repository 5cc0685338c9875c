"""The atomic writers of skydome._io: permissions, replacement, clean-up on errors and signals.

Expected permissions are those POSIX gives a file made by open(2) with mode 0666 and a
folder made by mkdir(2) with mode 0777 under the process umask (POSIX.1-2017, umask()).
"""

import errno
import os
import signal
import stat
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from skydome._io import (atomic_file, atomic_folder, atomic_write, check_output_file,
                         check_output_folder, current_umask)


def _mode(p) -> int:
    return stat.S_IMODE(os.stat(p).st_mode)


def _leftovers(folder: Path) -> list[str]:
    return sorted(f.name for f in folder.iterdir() if f.name.startswith("."))


@pytest.fixture
def umask():
    """Set the umask for one test and restore it afterwards."""
    old = os.umask(0o022)
    os.umask(old)

    def set_(m):
        os.umask(m)
        return m
    yield set_
    os.umask(old)


def test_current_umask_reads_the_process_umask(umask):
    umask(0o027)
    assert current_umask() == 0o027
    umask(0o002)
    assert current_umask() == 0o002


@pytest.mark.parametrize("mask, file_mode, dir_mode", [(0o022, 0o644, 0o755), (0o077, 0o600, 0o700),
                                                       (0o002, 0o664, 0o775)])
def test_new_file_and_folder_follow_the_umask(tmp_path, umask, mask, file_mode, dir_mode):
    umask(mask)
    target = tmp_path / "a.txt"
    atomic_write(target, lambda tmp: Path(tmp).write_text("x"))
    assert target.read_text() == "x"
    assert _mode(target) == file_mode
    folder = tmp_path / "results"
    with atomic_folder(folder) as tmp:
        (tmp / "b.txt").write_text("y")
    assert (folder / "b.txt").read_text() == "y"
    assert _mode(folder) == dir_mode
    assert _mode(folder / "b.txt") == file_mode
    assert _leftovers(tmp_path) == []


def test_replacing_a_file_keeps_its_mode(tmp_path, umask):
    umask(0o022)
    target = tmp_path / "a.txt"
    target.write_text("old")
    os.chmod(target, 0o640)
    with atomic_file(target) as tmp:
        Path(tmp).write_text("new")
    assert target.read_text() == "new"
    assert _mode(target) == 0o640


def test_temporary_keeps_the_suffix_for_format_detection(tmp_path):
    seen = []
    atomic_write(tmp_path / "x.png", lambda tmp: seen.append(tmp) or Path(tmp).write_bytes(b"1"))
    assert seen[0].endswith(".png") and Path(seen[0]).parent == tmp_path


def test_existing_folder_gets_files_replaced_and_others_kept(tmp_path):
    folder = tmp_path / "out"
    folder.mkdir()
    (folder / "keep.txt").write_text("k")
    (folder / "new.txt").write_text("old")
    with atomic_folder(folder) as tmp:
        (tmp / "new.txt").write_text("new")
    assert (folder / "keep.txt").read_text() == "k"
    assert (folder / "new.txt").read_text() == "new"
    assert _leftovers(tmp_path) == []


def _enospc(*args, **kwargs):
    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


def test_full_disk_leaves_nothing(tmp_path, monkeypatch):
    target = tmp_path / "a.txt"

    def write(tmp):
        with open(tmp, "w") as fh:
            fh.write("partial")
            _enospc()
    with pytest.raises(OSError) as exc:
        atomic_write(target, write)
    assert exc.value.errno == errno.ENOSPC
    assert list(tmp_path.iterdir()) == []
    # a folder whose second file hits the full disk
    folder = tmp_path / "out"
    monkeypatch.setattr(Path, "write_text", lambda self, *a, **k: _enospc())
    with pytest.raises(OSError):
        with atomic_folder(folder) as tmp:
            (tmp / "first.bin").write_bytes(b"1")
            (tmp / "second.txt").write_text("2")
    assert list(tmp_path.iterdir()) == []


def test_full_disk_while_replacing_keeps_the_old_file(tmp_path):
    target = tmp_path / "a.txt"
    target.write_text("old")
    with pytest.raises(OSError):
        atomic_write(target, lambda tmp: _enospc())
    assert target.read_text() == "old"
    assert [f.name for f in tmp_path.iterdir()] == ["a.txt"]


def test_keyboard_interrupt_leaves_nothing(tmp_path):
    with pytest.raises(KeyboardInterrupt):
        with atomic_folder(tmp_path / "out") as tmp:
            with atomic_file(tmp / "a.txt") as f:
                Path(f).write_text("x")
                raise KeyboardInterrupt
    assert list(tmp_path.iterdir()) == []


_CHILD = textwrap.dedent("""
    import sys, time
    from pathlib import Path
    from skydome._io import atomic_file, atomic_folder
    root = Path(sys.argv[1])
    with atomic_folder(root / "out") as tmp:
        (tmp / "a.txt").write_text("x")
        with atomic_file(root / "single.txt") as f:
            Path(f).write_text("y")
            print("ready", flush=True)
            time.sleep(60)
""")


def test_sigterm_mid_write_leaves_no_temporary(tmp_path):
    env = dict(os.environ)
    env["PYTHONPATH"] = str(Path(__file__).resolve().parents[1] / "src")
    proc = subprocess.Popen([sys.executable, "-c", _CHILD, str(tmp_path)], stdout=subprocess.PIPE,
                            env=env, text=True)
    try:
        assert proc.stdout.readline().strip() == "ready"
        assert len(_leftovers(tmp_path)) == 2          # the temporaries exist mid-write
        proc.send_signal(signal.SIGTERM)
        rc = proc.wait(timeout=20)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert rc == -signal.SIGTERM                       # still dies of SIGTERM
    assert list(tmp_path.iterdir()) == []


def test_checks_refuse_before_work(tmp_path):
    f = tmp_path / "file.txt"
    f.write_text("x")
    with pytest.raises(ValueError, match=r"out = .*file\.txt.* is an existing file"):
        check_output_folder(f)
    with pytest.raises(ValueError, match="does not exist"):
        check_output_folder(tmp_path / "missing" / "out")
    with pytest.raises(ValueError, match=r"must end in \.png"):
        check_output_file(tmp_path / "a.jpg", (".png",))
    with pytest.raises(ValueError, match="existing folder"):
        check_output_file(tmp_path, None)
    if os.geteuid() != 0:
        ro = tmp_path / "ro"
        ro.mkdir()
        os.chmod(ro, 0o555)
        try:
            with pytest.raises(ValueError, match="not writable"):
                check_output_folder(ro / "out")
        finally:
            os.chmod(ro, 0o755)
    with pytest.raises(ValueError):
        with atomic_folder(f):
            pass
    assert f.read_text() == "x"


# -- several files as one unit, errors naming the target, registered temporaries -----------
def test_atomic_files_all_or_none(tmp_path):
    from skydome._io import atomic_files

    a, b = tmp_path / "m.exr", tmp_path / "m.sun.json"
    with pytest.raises(OSError):
        with atomic_files([a, b]) as (ta, tb):
            assert ta.endswith(".exr") and tb.endswith(".json")   # suffixes kept
            Path(ta).write_text("map")
            _enospc()                       # the second file finds the disk full
    assert list(tmp_path.iterdir()) == []
    with atomic_files([a, b]) as (ta, tb):
        Path(ta).write_text("map")
        Path(tb).write_text("sun")
    assert a.read_text() == "map" and b.read_text() == "sun"
    assert _leftovers(tmp_path) == []


def test_atomic_files_failed_rename_removes_the_first(tmp_path):
    """Should the second rename fail (its target became a folder meanwhile), the first file
    renamed is removed again: never a map without its sun file."""
    from skydome._io import atomic_files

    a, b = tmp_path / "m.exr", tmp_path / "m.sun.json"
    with pytest.raises(OSError):
        with atomic_files([a, b]) as (ta, tb):
            Path(ta).write_text("map")
            Path(tb).write_text("sun")
            b.mkdir()
            (b / "x").write_text("blocks the rename")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.sun.json"]   # the blocker only
    assert not a.exists()


def test_errors_name_the_target_not_the_temporary(tmp_path):
    target = tmp_path / "a.txt"
    with pytest.raises(OSError) as info:
        atomic_write(target, lambda tmp: _enospc())
    assert info.value.filename == str(target)
    with pytest.raises(OSError) as info:
        with atomic_folder(tmp_path / "out") as tmp:
            with open(tmp / "b.bin", "wb"):
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(tmp / "b.bin"))
    assert info.value.filename == str(tmp_path / "out" / "b.bin")
    assert list(tmp_path.iterdir()) == []


def test_write_exr_turns_openexr_errors_into_oserror(tmp_path, monkeypatch):
    """OpenEXR reports a full disk as RuntimeError("... No space left on device"); write_exr
    raises OSError ENOSPC naming the file instead (and EIO for its other failures)."""
    OpenEXR = pytest.importorskip("OpenEXR")
    import numpy as np

    from skydome._io import write_exr

    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    ch = {"Y": np.zeros((4, 4), np.float32)}
    write_exr(tmp_path / "ok.exr", header, ch)
    assert (tmp_path / "ok.exr").stat().st_size > 0

    class Full:
        def __init__(self, *a):
            pass

        def __enter__(self):
            return self

        def __exit__(self, *a):
            return False

        def write(self, path):
            raise RuntimeError(f'Failed to write pixel data to image file "{path}". '
                               "No space left on device.")

    monkeypatch.setattr(OpenEXR, "File", Full)
    with pytest.raises(OSError) as info:
        write_exr(tmp_path / ".tmp.exr", header, ch, target=tmp_path / "a.exr")
    assert info.value.errno == errno.ENOSPC and info.value.filename == str(tmp_path / "a.exr")
    Full.write = lambda self, path: (_ for _ in ()).throw(RuntimeError("bad channel"))
    with pytest.raises(OSError) as info:
        write_exr(tmp_path / "b.exr", header, ch)
    assert info.value.errno == errno.EIO and "bad channel" in info.value.strerror


def test_write_npy_round_trip_and_enospc(tmp_path):
    import numpy as np

    from skydome._io import write_npy

    a = np.arange(24, dtype=np.float32).reshape(2, 3, 4)
    write_npy(tmp_path / "a.npy", a)
    b = np.load(tmp_path / "a.npy")
    assert b.dtype == a.dtype and np.array_equal(b, a)
    from _tmpfs import small_disk

    with small_disk(tmp_path / "disk", "16k") as d:
        with pytest.raises(OSError) as info:
            write_npy(Path(d) / "big.npy", np.zeros(100_000))
        assert info.value.errno == errno.ENOSPC


_TEMPORARY_CHILD = textwrap.dedent("""
    import os, sys, time
    from skydome._io import temporary
    folder = os.path.join(sys.argv[1], ".made-by-a-writer.part")
    os.mkdir(folder)
    open(os.path.join(folder, "chunk"), "w").write("x")
    with temporary(folder, is_dir=True):
        print("ready", flush=True)
        time.sleep(60)
""")


def _sigterm_child(script, folder, temporary_name):
    """Run ``script`` (it prints "ready" once ``temporary_name`` exists in ``folder``), send
    it SIGTERM then, and check that it died of it leaving ``folder`` empty."""
    env = dict(os.environ)
    env["PYTHONPATH"] = str(Path(__file__).resolve().parents[1] / "src")
    proc = subprocess.Popen([sys.executable, "-c", script, str(folder)],
                            stdout=subprocess.PIPE, env=env, text=True)
    try:
        assert proc.stdout.readline().strip() == "ready"
        assert _leftovers(folder) == [temporary_name]
        proc.send_signal(signal.SIGTERM)
        rc = proc.wait(timeout=20)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert rc == -signal.SIGTERM
    assert list(folder.iterdir()) == []


def test_registered_temporary_removed_on_sigterm(tmp_path):
    _sigterm_child(_TEMPORARY_CHILD, tmp_path, ".made-by-a-writer.part")


_NESTED_CHILD = textwrap.dedent("""
    import os, sys, time
    from skydome._io import temporary
    folder = os.path.join(sys.argv[1], ".held-across-a-call.part")
    with temporary(folder, is_dir=True):          # the caller's block
        with temporary(folder, is_dir=True):      # a library call's own block, same path
            os.mkdir(folder)
            open(os.path.join(folder, "chunk"), "w").write("x")
        print("ready", flush=True)                # between the library's block and the rename
        time.sleep(60)
""")


def test_nested_registrations_hold_until_the_outermost_block_ends(tmp_path):
    """A caller holding a temporary across a library call that registers the same path for
    its own block (the Zarr sky matrix): when the inner block ends the path stays registered,
    so a SIGTERM before the caller's rename still removes it (it was left, under load, when
    the caller's registration started only after the library's had ended)."""
    from skydome import _io

    p = str(tmp_path / "x.part")
    with _io.temporary(p):
        with _io.temporary(p):
            assert p in _io._LIVE
        assert p in _io._LIVE
    assert p not in _io._LIVE
    _sigterm_child(_NESTED_CHILD, tmp_path, ".held-across-a-call.part")
