"""Sky matrices from perez1993 against Radiance's gendaymtx (shipped with pyradiance) on the
sample TMY3 file (Greensboro, NC), and the sun matrix against gendaymtx -D."""

from __future__ import annotations

import numpy as np
import pytest

from skydome.daylighting.radiance_io import read_matrix
from skydome.daylighting.skymatrix import perez_sky_matrix, perez_sky_matrix_from_weather
from skydome.daylighting.weather import read_weather, sample_weather_path, write_wea


@pytest.fixture(scope="module")
def days():
    from _daylighting import TEST_DAYS

    w = read_weather(sample_weather_path())
    return w.select(np.isin(w.day_of_year, TEST_DAYS))


@pytest.fixture(scope="module")
def wea(days, tmp_path_factory):
    p = tmp_path_factory.mktemp("wea") / "days.wea"
    write_wea(days, p)
    return p


def _gendaymtx(wea, args, tmp_path, suns=False):
    from _daylighting import run_gendaymtx

    out = tmp_path / "g.mtx"
    out.write_bytes(run_gendaymtx(wea, ["-od", *args], suns=tmp_path / "suns.rad" if suns else
                                  None))
    m, head = read_matrix(out)
    return np.swapaxes(m, 0, 1), head  # (hours, patches, 3)


def test_radiance_sun_formula_matches_gendaymtx(days, wea, tmp_path):
    """skydome's transcription of Radiance's solar position equals gendaymtx's own suns
    (its -D output, 6 decimals)."""
    from _daylighting import read_sun_scene, run_gendaymtx, solar_minute

    run_gendaymtx(wea, ["-n"], suns=tmp_path / "suns.rad")
    ids, _, dirs = read_sun_scene(tmp_path / "suns.rad")
    pos = {m: i for i, m in enumerate(solar_minute(days))}
    ours = days.radiance_sun_directions()[[pos[i] for i in ids]]
    np.testing.assert_allclose(ours, dirs, atol=2e-6)


@pytest.mark.parametrize("mf,backend,dtype", [(1, "numba", np.float64),
                                              (4, "numba", np.float64),
                                              (1, "numpy", np.float32),
                                              (4, "numpy", np.float32)])
def test_matches_gendaymtx_every_hour_and_patch(days, wea, tmp_path, mf, backend, dtype):
    """Same inputs as gendaymtx (its sun positions, dew point 11 deg C for a .wea, ground 0.2,
    point sampling at the patch centres, the sun spread over the 4 nearest patches): every
    hour and patch of the RGB matrix within 1e-4 (gendaymtx computes in float), with the
    numba kernel (float64) and with the numpy backend's float32 matrix (a "float" file's)."""
    g, head = _gendaymtx(wea, ["-m", mf], tmp_path)
    assert head["NCOMP"] == "3"
    m = perez_sky_matrix(days.dni, days.dhi, days.radiance_sun_directions(), days.day_of_year,
                         patches="tregenza" if mf == 1 else f"reinhart:{mf}", order=0,
                         backend=backend, dtype=dtype)
    assert m.sky.shape == g.shape
    tol = 1e-4 * np.maximum(g, 1e-3)
    assert np.all(np.abs(m.sky - g) <= tol)
    # the matrix has daylight in it (not a comparison of zeros), and the sun
    assert np.count_nonzero(g[:, 1:, 1] > 1.0) > 1000
    assert g.max() > 5e3  # a sun patch (spread direct radiance)


def test_sun_disc_option_matches_gendaymtx_5(days, wea, tmp_path):
    """gendaymtx -5 0.533: the sun into the single nearest patch as a 0.533 deg disc."""
    g, _ = _gendaymtx(wea, ["-5", "0.533", "-d"], tmp_path)
    m = perez_sky_matrix(days.dni, days.dhi, days.radiance_sun_directions(), days.day_of_year,
                         order=0, sun="disc:0.533", sky_color=(0, 0, 0), ground_reflectance=0.0)
    assert np.all(np.abs(m.sky - g) <= 1e-4 * np.maximum(g, 1e-3))
    assert np.count_nonzero(g) > 100


def test_separate_sun_matches_gendaymtx_D(days, wea, tmp_path):
    """The sun matrix (radiance of the 0.533 deg disc, one direction per hour) equals the
    suns gendaymtx -D writes (3 significant digits printed: 5e-4 relative), and the sky
    matrix without the sun equals gendaymtx -s."""
    from _daylighting import read_sun_scene, run_gendaymtx, solar_minute

    g, _ = _gendaymtx(wea, ["-s"], tmp_path)
    run_gendaymtx(wea, ["-n"], suns=tmp_path / "suns.rad")
    ids, rad, dirs = read_sun_scene(tmp_path / "suns.rad")
    m = perez_sky_matrix(days.dni, days.dhi, days.radiance_sun_directions(), days.day_of_year,
                         order=0, sun="separate")
    assert np.all(np.abs(m.sky - g) <= 1e-4 * np.maximum(g, 1e-3))
    pos = np.array([{mm: i for i, mm in enumerate(solar_minute(days))}[i] for i in ids])
    np.testing.assert_allclose(m.sun[pos], rad, rtol=6e-4, atol=1e-6)
    np.testing.assert_allclose(m.sun_directions[pos], dirs, atol=2e-6)
    assert rad.max() > 1e6
    others = np.setdiff1d(np.arange(len(days)), pos)
    assert np.all(m.sun[others] == 0.0)


def test_spa_sun_deviation_from_gendaymtx_is_the_sun_position(days, wea, tmp_path):
    """With skydome's default sun (NREL SPA instead of Radiance's approximation, which is up
    to 0.9 deg off) and its default dew point per hour, the matrix differs from gendaymtx's;
    docs/daylighting.md gives the whole-year figures. Here: the diffuse horizontal
    illuminance of every daylight hour (the sky patches' sum of L sin(a) dOmega, 179 x
    G-channel / 1.004 tint) agrees within 1 % where the sun is above 5 deg, because each
    sky is normalised to the same Dh whatever the sun's position."""
    from skydome.daylighting.patches import patches

    g, _ = _gendaymtx(wea, ["-s", "-m", "1"], tmp_path)
    m = perez_sky_matrix_from_weather(days, order=0, sun="none", dew_point_c=11.0)
    ps = patches("tregenza")
    w = np.sin(ps.centre_altitude_rad[1:]) * ps.solid_angle_sr[1:]
    eh_g = 179.0 * (g[:, 1:, 1] @ w) / 1.004
    eh_m = 179.0 * (m.sky[:, 1:, 1] @ w) / 1.004
    up = np.degrees(np.arcsin(days.sun_directions[:, 2])) > 5.0
    assert np.count_nonzero(up) > 30
    np.testing.assert_allclose(eh_m[up], eh_g[up], rtol=0.01)


def test_integrated_patches_converge_and_keep_dh(days):
    """Patch means by quadrature: order 4 within 1 % of order 8 on every patch (the stated
    default accuracy); every order reproduces the same diffuse horizontal illuminance."""
    from skydome.daylighting.patches import patches

    kw = dict(patches="tregenza", sun="none", components="luminance")
    m4 = perez_sky_matrix_from_weather(days, order=4, **kw).sky[..., 0]
    m8 = perez_sky_matrix_from_weather(days, order=8, **kw).sky[..., 0]
    big = m8 > 1e-3 * m8.max()
    assert np.all(np.abs(m4 - m8)[big] <= 0.01 * m8[big])
    ps = patches("tregenza")
    d, wq, off = ps.nodes(8)
    # horizontal illuminance of the integrated means: sum of mean x integral of cos over patch
    cosint = np.add.reduceat(wq * d[:, 2], off[:-1])
    e4 = m4[:, 1:] @ cosint
    e8 = m8[:, 1:] @ cosint
    day = e8 > 100.0
    np.testing.assert_allclose(e4[day], e8[day], rtol=2e-3)


def test_no_negative_or_nan_and_night_is_black(days):
    m = perez_sky_matrix_from_weather(days, patches="reinhart:2", order=2)
    assert np.all(np.isfinite(m.sky)) and np.all(m.sky >= 0.0)
    night = (days.dni + days.dhi) <= 0.0
    assert np.any(night)
    assert np.all(m.sky[night] == 0.0)


@pytest.mark.parametrize("kw, message", [
    (dict(sun="blur"), "sun = "),
    (dict(sun="spread:9"), "sun = "),
    (dict(patches="klems"), "patches = "),
    (dict(order=17), "order"),
    (dict(components="xyz"), "components"),
    (dict(ground_reflectance=1.5), "ground_reflectance"),
])
def test_bad_arguments(days, kw, message):
    with pytest.raises(ValueError, match=message):
        perez_sky_matrix_from_weather(days, **kw)
    with pytest.raises(ValueError, match="dni"):
        perez_sky_matrix(-np.ones(2), np.ones(2), [[0, 0, 1.0]] * 2, [1, 1])


def test_kernel_independent_of_thread_count_and_storage(days):
    """The hours are split into one run per numba thread: one thread or all give the same
    bits, and filling a caller's (patches, hours, components) array (a file's memory map)
    equals the matrix the function allocates itself."""
    import numba

    from skydome.daylighting.patches import patches

    ps = patches("reinhart:2")
    n0 = numba.get_num_threads()
    ref = perez_sky_matrix_from_weather(days, patches=ps, order=1, dtype=np.float32,
                                         backend="numba")
    try:
        numba.set_num_threads(1)
        one = perez_sky_matrix_from_weather(days, patches=ps, order=1, dtype=np.float32,
                                             backend="numba")
    finally:
        numba.set_num_threads(n0)
    assert np.array_equal(one.sky, ref.sky)
    out = np.zeros((len(ps), len(days), 3), dtype=np.float32)
    m = perez_sky_matrix_from_weather(days, patches=ps, order=1, dtype=np.float32,
                                      out=out, backend="numba")
    assert np.shares_memory(m.sky, out) and np.array_equal(out, ref.radiance_layout())
    assert np.any(out > 0.0)


def test_read_only_inputs_same_bits_and_no_new_compilation(days):
    """Read-only arguments (a broadcast albedo, arrays received by a Dask worker) reach the
    kernel as the function's own writable copies: the same compiled specialisation, the same
    bits."""
    from skydome.daylighting import _kernels as DK

    sd = days.radiance_sun_directions()
    rho = np.full(len(days), 0.25)
    ref = perez_sky_matrix(days.dni, days.dhi, sd, days.day_of_year, patches="tregenza",
                           order=1, ground_reflectance=rho, backend="numba")
    n_sig = len(DK.fill_perez_sky.signatures)
    ro = [np.array(a) for a in (days.dni, days.dhi, sd, rho)]
    for a in ro:
        a.flags.writeable = False
    m = perez_sky_matrix(ro[0], ro[1], ro[2], days.day_of_year, patches="tregenza", order=1,
                         ground_reflectance=np.broadcast_to(ro[3], ro[3].shape),
                         backend="numba")
    assert np.array_equal(m.sky, ref.sky)
    assert len(DK.fill_perez_sky.signatures) == n_sig


def test_out_must_be_a_c_contiguous_file_order_array(days):
    n = len(days)
    sd = days.radiance_sun_directions()
    for bad in (np.zeros((n, 146, 3)).swapaxes(0, 1),  # right shape, not contiguous
                np.zeros((146, n, 3), dtype=np.float32),  # wrong dtype for float64
                np.zeros((n, 146, 3))):  # (hours, patches): not Radiance's order
        with pytest.raises(ValueError, match="out must be"):
            perez_sky_matrix(days.dni, days.dhi, sd, days.day_of_year, out=bad)


# -- the command line: the library's notes as one line each on stderr -----------------------
@pytest.fixture(scope="module")
def note_weather(tmp_path_factory):
    """Two .wea files of the sample's first day with a lit hour of the sun below the
    horizon (twilight: outside preetham1999's sun range), one of them with a winter noon
    beyond the clear-sky limit (DNI 1366, DHI 5 W/m^2: gendaylit's rule 2)."""
    import dataclasses

    w = read_weather(sample_weather_path())
    el = 90.0 - w.sun_zenith_deg
    lit = (w.dni + w.dhi) > 1e-4
    k = int(np.argmax(lit & (el < 0.0)))
    day = w.select(slice(k // 24 * 24, k // 24 * 24 + 24))
    folder = tmp_path_factory.mktemp("notes")
    write_wea(day, folder / "twilight.wea")
    noon = int(np.argmin(day.sun_zenith_deg))
    dni, dhi = day.dni.copy(), day.dhi.copy()
    dni[noon], dhi[noon] = 1366.0, 5.0
    write_wea(dataclasses.replace(day, dni=dni, dhi=dhi), folder / "clear.wea")
    return folder


def _stderr_lines(text):
    return [ln for ln in text.splitlines() if ln.strip()]


def _one_note(lines, fragment):
    assert len(lines) == 1, lines
    assert lines[0].startswith("note: ") and fragment in lines[0], lines
    assert "Warning" not in lines[0] and "warn(" not in lines[0]


def test_cli_notes_one_line_each(note_weather, tmp_path):
    """The model path's SunRangeNote and the Perez path's ClearSkyNote (typer command and
    the fast path of `skydome skymatrix`) as one line `note: ...`, not Python's warning."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    from typer.testing import CliRunner

    from skydome.cli import app

    runner = CliRunner()
    res = runner.invoke(app, ["skymatrix", "--weather", str(note_weather / "twilight.wea"),
                              "--out", str(tmp_path / "p.zarr"), "--model", "preetham1999",
                              "--components", "luminance", "--order", "1"])
    assert res.exit_code == 0, res.output
    _one_note(_stderr_lines(res.stderr),
              "model 'preetham1999' covers sun elevations [0, 90] deg: 2 lit hour(s)")
    assert (tmp_path / "p.zarr").is_dir()

    res = runner.invoke(app, ["skymatrix", "--weather", str(note_weather / "clear.wea"),
                              "--out", str(tmp_path / "t.mtx"), "--order", "0"])
    assert res.exit_code == 0, res.output
    _one_note(_stderr_lines(res.stderr), "1 hour(s) beyond the clear-sky limit")
    assert (tmp_path / "t.mtx").is_file()

    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1] / "src"))
    proc = subprocess.run([sys.executable, "-m", "skydome", "skymatrix", "--weather",
                           str(note_weather / "clear.wea"), "--out", str(tmp_path / "f.mtx"),
                           "--order", "0", "--backend", "numpy"],
                          capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr
    _one_note(_stderr_lines(proc.stderr), "1 hour(s) beyond the clear-sky limit")
    assert (tmp_path / "f.mtx").stat().st_size == (tmp_path / "t.mtx").stat().st_size


def test_cli_bad_input_before_any_note(note_weather, tmp_path):
    from typer.testing import CliRunner

    from skydome.cli import app

    res = CliRunner().invoke(app, ["skymatrix", "--weather", str(note_weather / "clear.wea"),
                                   "--out", str(tmp_path / "t.mtx"), "--albedo", "2"])
    lines = _stderr_lines(res.stderr)
    assert res.exit_code == 2 and len(lines) == 1, res.output
    assert lines[0].startswith("error: ") and "albedo" in lines[0] and "'2'" in lines[0]
    assert list(tmp_path.iterdir()) == []
