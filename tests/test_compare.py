"""`skydome compare`: report files, and error figures checked against closed forms."""

import csv

import numpy as np
import pytest
from typer.testing import CliRunner

from skydome.cli import app
from skydome.apps.compare import run_comparison, sky_errors

runner = CliRunner()


def test_error_measures_closed_form():
    """A sky twice as bright everywhere: RMS = bias = 100 %; same chromaticity: 0."""
    rng = np.random.default_rng(0)
    ref = rng.uniform(1, 2, (8, 8, 3))
    w = np.ones((8, 8))
    e = sky_errors(2 * ref, ref, w)
    assert e["luminance_rms"] == pytest.approx(1.0)
    assert e["luminance_mean_bias"] == pytest.approx(1.0)
    assert e["chromaticity_max"] == pytest.approx(0.0, abs=1e-12)


def test_overcast_scaled_against_overcast(tmp_path):
    """cie1994_overcast with Lz = 3000 against Lz = 1000 (eq. 13 is linear in Lz): +200 %
    everywhere; the reference against itself: 0."""
    from skydome.models import model

    def build(spec, sun):
        lz = 3000.0 if spec == "bright" else 1000.0
        return model("cie1994_overcast", sun=sun, zenith_luminance=lz)

    rows = run_comparison(["ref", "bright"], [20.0, 50.0], tmp_path / "rep", reference="ref",
                          size=32, build=build)
    by = {(r.model, r.sun_elevation_deg): r for r in rows}
    for e in (20.0, 50.0):
        assert by["bright", e].luminance_rms == pytest.approx(2.0, rel=1e-9)
        assert by["ref", e].luminance_rms == 0.0
        assert np.isnan(by["bright", e].chromaticity_mean)   # luminance-only: no colour
    names = sorted(p.name for p in (tmp_path / "rep").iterdir())
    assert names == ["error_bright.png", "grid.png", "table.csv", "table.md"]
    table = list(csv.DictReader(open(tmp_path / "rep" / "table.csv")))
    assert len(table) == 4
    assert not any(p.name.startswith(".skydome") for p in tmp_path.iterdir())


def test_cli_compare_with_refusing_model(tmp_path):
    """preetham1999 refuses a sun below the horizon: its cell is n/a, the rest is measured."""
    out = tmp_path / "report"
    res = runner.invoke(app, ["compare", "--models", "cie1994_overcast,preetham1999,cie2003:12",
                              "--reference", "cie1994_overcast", "--sun-elevation", "-2,30",
                              "--size", "24", "--out", str(out)])
    assert res.exit_code == 0, res.output
    md = (out / "table.md").read_text()
    assert "preetham1999 | -2 deg | n/a" in md
    assert (out / "grid.png").exists()


@pytest.mark.parametrize("args, frag", [
    (["--models", "nosuch"], "model = 'nosuch'"),
    (["--models", "cie2003", "--sun-elevation", "a,b"], "--sun-elevation = 'a,b'"),
    (["--models", "cie2003", "--bogus", "1"], "--bogus"),
])
def test_cli_compare_bad_input(tmp_path, args, frag):
    out = tmp_path / "r"
    res = runner.invoke(app, ["compare", "--out", str(out)] + args)
    assert res.exit_code == 2
    assert frag in res.output
    assert not out.exists()


def test_cli_compare_grid_on_dask_equals_in_process(tmp_path):
    """--scheduler: every (model, elevation) cell a Dask task; the measured errors, the notes
    of refused cells and grid.png equal the in-process run's; the chunk folder is gone."""
    from _dask import run_both

    run_both(["compare", "--models", "cie1994_overcast,preetham1999,cie2003:12", "--reference",
              "cie1994_overcast", "--sun-elevation", "-2,30", "--size", "24"],
             tmp_path / "a", tmp_path / "b")
    ta = list(csv.DictReader(open(tmp_path / "a" / "table.csv")))
    tb = list(csv.DictReader(open(tmp_path / "b" / "table.csv")))
    assert len(ta) == len(tb) == 6
    for ra, rb in zip(ta, tb):
        for k in ra:
            if "second" not in k:  # render times differ from run to run
                assert ra[k] == rb[k], k
    assert (tmp_path / "a" / "grid.png").read_bytes() == (tmp_path / "b" / "grid.png").read_bytes()
    assert not (tmp_path / "b.chunks").exists()
