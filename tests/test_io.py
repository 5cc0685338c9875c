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
