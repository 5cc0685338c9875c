"""Every output on a full disk (issue 30): each writer runs into a small tmpfs that it
overflows (ENOSPC, errno 28) and must end with one line on stderr, exit code 2 and nothing
left in the folder: EXR images, environment maps with their sun file, LUT folders, sky
matrices (Radiance float and ascii, .npy, Zarr, and chunked on Dask with --workers 2).

The tmpfs is mounted per test (tests/_tmpfs.py); where mounting is not permitted the tests
are skipped, saying so. The command lines run as ``python -m skydome`` in a subprocess."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from _tmpfs import small_disk

SRC = Path(__file__).resolve().parents[1] / "src"


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = str(SRC)
    return env


@pytest.fixture(scope="module")
def two_days(tmp_path_factory):
    """The first 48 hours of the sample TMY3 file."""
    from skydome.daylighting.weather import sample_weather_path

    lines = sample_weather_path().read_text().splitlines(keepends=True)
    p = tmp_path_factory.mktemp("weather") / "d.csv"
    p.write_text("".join(lines[:2 + 48]))
    return p


def _cli(args, timeout=600):
    return subprocess.run([sys.executable, "-m", "skydome", *map(str, args)], env=_env(),
                          capture_output=True, text=True, timeout=timeout)


def _one_line_exit_2(res, target, report=None):
    """Exit 2 and one line on stderr naming ``target`` and the full disk; a line starting
    with ``report`` (the command's report of the work done before the write) is not an
    error line and is left out."""
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()
             and not (report and ln.startswith(report))]
    assert res.returncode == 2, (res.returncode, res.stderr[-3000:])
    assert len(lines) == 1, res.stderr[-3000:]
    assert lines[0].startswith("error: could not write") and \
        "no space left on device" in lines[0].lower(), lines[0]
    assert str(target) in lines[0], lines[0]
    return lines[0]


CASES = {
    "render exr": (["render", "--model", "cie2003", "--size", "256", "--out", "{d}/a.exr"],
                   "a.exr"),
    "render hdr": (["render", "--model", "cie2003", "--size", "256", "--out", "{d}/a.hdr"],
                   "a.hdr"),
    "export envmap": (["export", "envmap", "--model", "cie2003", "--size", "128x64",
                       "--out", "{d}/m.exr"], "m.exr"),
    "export luts": (["export", "luts", "--model", "hillaire2020", "--format", "npy,bin,exr",
                     "--out", "{d}/luts"], "luts"),
    "skymatrix float": (["skymatrix", "--weather", "{w}", "--patches", "reinhart:2",
                         "--out", "{d}/a.mtx"], "a.mtx"),
    "skymatrix ascii": (["skymatrix", "--weather", "{w}", "--patches", "reinhart:2",
                         "--format", "ascii", "--out", "{d}/a.mtx"], "a.mtx"),
    "skymatrix npy": (["skymatrix", "--weather", "{w}", "--patches", "reinhart:2",
                       "--out", "{d}/a.npy"], "a.npy"),
    "skymatrix workers 2": (["skymatrix", "--weather", "{w}", "--patches", "reinhart:2",
                             "--workers", "2", "--out", "{d}/a.mtx"], "a.mtx"),
    "skymatrix zarr": (["skymatrix", "--weather", "{w}", "--patches", "reinhart:1",
                        "--model", "oneil2005", "--components", "luminance", "--order", "0",
                        "--chunk-hours", "6", "--out", "{d}/a.zarr"], "a.zarr"),
}
# command lines whose matrix is written by write_matrix (through the command's guard); the
# library half of these cases is checked on its own below
MATRIX_WRITER_CASES = ("skymatrix ascii", "skymatrix npy")


@pytest.mark.parametrize("case", list(CASES))
def test_full_disk_one_line_exit_2_nothing_left(case, tmp_path, two_days):
    if case == "skymatrix workers 2":
        pytest.importorskip("distributed")
    args, target = CASES[case]
    with small_disk(tmp_path / "disk", "16k") as d:
        res = _cli([a.format(d=d, w=two_days) for a in args])
        # the Zarr command writes into a temporary folder .OUT.part; its error names OUT
        line = _one_line_exit_2(res, Path(d) / target)
        assert ".part" not in line, line
        if case == "skymatrix workers 2":       # the chunk folder is not left either
            assert ".chunks" in line
        assert os.listdir(d) == []


@pytest.mark.parametrize("case", MATRIX_WRITER_CASES)
def test_full_disk_matrix_writer_raises_enospc_naming_the_file(case, tmp_path, two_days):
    """The library half of the matrix-writer cases above: write_matrix raises OSError ENOSPC
    naming the output (not its temporary), and leaves nothing."""
    import errno

    from skydome.daylighting.radiance_io import write_matrix

    m = np.random.default_rng(1).random((48, 577, 3))
    name = "a.npy" if case.endswith("npy") else "a.mtx"
    with small_disk(tmp_path / "disk", "16k") as d:
        with pytest.raises(OSError) as info:
            write_matrix(Path(d) / name, m, fmt="ascii", transpose=True)
        assert info.value.errno == errno.ENOSPC
        assert info.value.filename == str(Path(d) / name)
        assert os.listdir(d) == []


def _free_bytes(folder):
    st = os.statvfs(folder)
    return st.f_bavail * st.f_frsize


def _fill_to(folder, free):
    """Write a filler file into ``folder`` so that ``free`` bytes are left (page-rounded)."""
    with open(os.path.join(folder, "filler"), "wb") as f:
        f.write(b"\0" * max(0, _free_bytes(folder) - free))


def test_map_and_sun_file_one_unit_on_a_nearly_full_disk(tmp_path):
    """Room for the map but not for its .sun.json (issue 30: the map was left without its
    sun file). Written one after the other (the control) the map is left alone; written as
    one unit (EnvMap.write(also=...)) neither is left, and with room both are."""
    import skydome as sd
    from skydome.export.envmap import render_envmap
    from skydome.export.sun import sun_json_writer, sun_light, write_sun_json

    sky = sd.model("hosek_wilkie2012", sun=sd.Sun(elevation_deg=30.0, azimuth_deg=120.0))
    env = render_envmap(sky, "skydome", size="64x32")
    light = sun_light(sky, "skydome")
    assert light is not None
    probe = tmp_path / "probe"
    probe.mkdir()
    (map_file,) = env.write(probe / "m.exr")
    need = -(-map_file.stat().st_size // 4096) * 4096     # the map's pages
    with small_disk(tmp_path / "disk", "256k") as d:
        d = Path(d)
        _fill_to(d, need)
        # the control: map, then sun file, as two writes
        env.write(d / "m.exr")
        with pytest.raises(OSError):
            write_sun_json(light, d / "m.sun.json")
        assert sorted(os.listdir(d)) == ["filler", "m.exr"]     # the map without its sun
        os.remove(d / "m.exr")
        # one unit: neither
        with pytest.raises(OSError) as info:
            env.write(d / "m.exr", also=[(d / "m.sun.json", sun_json_writer(light))])
        assert "no space left" in str(info.value).lower()
        assert sorted(os.listdir(d)) == ["filler"]
        # with room for both: both
        os.remove(d / "filler")
        written = env.write(d / "m.exr", also=[(d / "m.sun.json", sun_json_writer(light))])
        assert sorted(p.name for p in written) == ["m.exr", "m.sun.json"]
        assert sorted(os.listdir(d)) == ["m.exr", "m.sun.json"]
        import json

        assert json.loads((d / "m.sun.json").read_text()) == json.loads(json.dumps(light))


def test_export_envmap_map_and_sun_file_one_unit_on_a_nearly_full_disk(tmp_path):
    """``skydome export envmap`` on a disk with room for the map but not for its .sun.json:
    exit 2, one line naming the sun file, and neither file left (the map and its sun light
    are written as one unit). The map's size is measured by the same command on a normal
    folder first."""
    args = ["export", "envmap", "--model", "hosek_wilkie2012", "--size", "64x32",
            "--sun-elevation", "30", "--sun-azimuth", "120"]
    probe = tmp_path / "probe"
    probe.mkdir()
    res = _cli([*args, "--out", probe / "m.exr"])
    assert res.returncode == 0, res.stderr[-2000:]
    assert sorted(os.listdir(probe)) == ["m.exr", "m.sun.json"]
    need = -(-(probe / "m.exr").stat().st_size // 4096) * 4096     # the map's pages
    with small_disk(tmp_path / "disk", "256k") as d:
        d = Path(d)
        _fill_to(d, need)
        assert _free_bytes(d) >= (probe / "m.exr").stat().st_size     # the map alone fits
        res = _cli([*args, "--out", d / "m.exr"])
        _one_line_exit_2(res, d / "m.sun.json")
        assert sorted(os.listdir(d)) == ["filler"]


def test_full_disk_after_the_chunks_one_line_no_chunk_folder(tmp_path, two_days):
    """Room for the Dask chunks (about 84 pages) but not for the matrix assembled from them
    as well (about 82 more): one line, exit 2, neither the matrix nor OUT.chunks/ left."""
    pytest.importorskip("distributed")
    with small_disk(tmp_path / "disk", "400k") as d:
        res = _cli(["skymatrix", "--weather", two_days, "--patches", "reinhart:2",
                    "--workers", "2", "--chunk-hours", "24", "--out", Path(d) / "a.mtx"])
        assert "chunks: 2 computed" in res.stderr, res.stderr[-2000:]   # the chunks fitted
        _one_line_exit_2(res, Path(d) / "a.mtx", report="chunks: 2 computed, 0 reused")
        assert os.listdir(d) == []
