"""tools/fitted_accuracy.py, the tool that publishes the ``fitted`` model's error per regime:
its arithmetic and its classing into regimes, observers and atmosphere classes.

The data sets here are not the reference: they are the model's own values multiplied by
known factors (1 + eps), a different eps in each (sun elevation, altitude) cell, so that the
relative error the tool must print in each regime is known beforehand, 1 / (1 + eps) - 1,
from the factors alone. The model's accuracy itself is measured against ``precomputed`` in
tests/test_fitted.py."""

from __future__ import annotations

import json

import numpy as np
import pytest

import skydome as sd
from _tools import load_script, write_chunk
from skydome.models.fitted import _coefficients, _dataset, _grid
from skydome.spectra import solar_irradiance

tool = load_script("tools/fitted_accuracy.py")


def _store(folder, aod, alb, arr):
    write_chunk(folder, _dataset.chunk_key(aod, alb), arr)


def _err(eps):
    """The relative error the tool must report for a reference = model x (1 + eps)."""
    return abs(1.0 / (1.0 + eps) - 1.0)


# held-out set: (sun elevation, altitude) -> eps; each cell is a different regime/observer
HELD_EPS = {(28.0, 0.0): 0.03, (28.0, 15000.0): 0.01, (-9.5, 0.0): 0.005,
            (-9.5, 15000.0): 0.10}
HELD_ATM = (0.04, 0.3)              # a clear atmosphere (AOD <= 0.1) off the nodes


def _held_set(folder, els, alts, eps):
    """A held-out set of HELD_ATM at the sun elevations ``els`` and altitudes ``alts``: the
    model's values times (1 + eps[(el, h)])."""
    wl = np.asarray(_coefficients.load()["wavelengths_nm"], dtype=np.float64)
    _dataset.write_grid(folder, els, alts, [HELD_ATM], midpoints=True, wavelengths=wl)
    e_tab = solar_irradiance(wl)
    n_dir, n_phi = _grid.N_SKY + _grid.N_GROUND - 2, _grid.N_PHI - 1
    out = np.zeros((len(els), len(alts), n_dir + 1, n_phi, wl.size), dtype=np.float32)
    for i, el in enumerate(els):
        for j, h in enumerate(alts):
            sun = sd.Sun(elevation_deg=el, azimuth_deg=180.0)
            m = sd.model("fitted", sun=sun, aerosol_optical_depth=HELD_ATM[0],
                         ground_albedo=HELD_ATM[1], observer_altitude_m=h)
            d = _grid.directions(h, 180.0, midpoints=True)
            # the chunk holds radiance per unit extraterrestrial irradiance
            out[i, j, :n_dir] = m.radiance(d, wl) / e_tab * (1.0 + eps[(el, h)])
            out[i, j, n_dir, 0] = (m.sun_radiance(wl) * sun.solid_angle_sr / e_tab
                                   * (1.0 + eps[(el, h)]))
    _store(folder, *HELD_ATM, out)
    return folder


@pytest.fixture(scope="module")
def heldout(tmp_path_factory):
    return _held_set(tmp_path_factory.mktemp("held"), [28.0, -9.5], [0.0, 15000.0],
                     HELD_EPS)


def test_heldout_rows_give_the_known_error_in_each_regime_and_observer(heldout, tmp_path,
                                                                       capsys):
    js = tmp_path / "acc.json"
    assert tool.main([str(heldout), "--json", str(js), "--per-atmosphere"]) == 0
    res = json.loads(js.read_text())
    rows = {(r["regime"], r["observer"], r["model"]): r for r in res["rows"]}
    assert all(r["class"] == "clear" for r in res["rows"])
    cells = {("sun > 20 deg", "ground"): 0.03, ("sun > 20 deg", "15 km"): 0.01,
             ("sun -6 to -12 deg", "ground"): 0.005, ("sun -6 to -12 deg", "15 km"): 0.10}
    assert {(k[0], k[1]) for k in rows if k[2] == "fitted"} == set(cells)
    for (reg, obs), eps in cells.items():
        r = rows[(reg, obs, "fitted")]
        # spectral: the model's radiance at the set's own wavelengths, exactly 1/(1+eps)
        # up to the chunk's float32 rounding
        assert r["S_rms"] == pytest.approx(_err(eps), abs=1e-6), (reg, obs)
        assert r["S_max"] == pytest.approx(_err(eps), abs=1e-6), (reg, obs)
        # luminance: the reference integrated by the tool from the set's wavelengths, the
        # model's own luminance; the two integrations of the same spectrum agree to 0.1 %
        # RMS (up to 0.7 % at single points in twilight, where the spectrum is steepest)
        assert r["Y_rms"] == pytest.approx(_err(eps), abs=2e-3), (reg, obs)
        assert r["Y_max"] == pytest.approx(_err(eps), abs=1e-2), (reg, obs)
        if obs == "15 km":                # the ground seen from above: below the horizon
            assert r["G_rms"] == pytest.approx(_err(eps), abs=2e-3), (reg, obs)
        else:
            assert "G_rms" not in r
    # Hosek-Wilkie is measured on the ground with the sun up only, against the same set
    assert {k[:2] for k in rows if k[2] == "hosek_wilkie2012"} == {("sun > 20 deg",
                                                                     "ground")}
    # the sun's transmittance, where it is above 1e-3 at 560 nm: the sun at 28 deg only
    assert sorted((s[0], s[1]) for s in res["sun"]) == [(28.0, 0.0), (28.0, 15000.0)]
    for el, h, _, worst, _ in res["sun"]:
        assert worst == pytest.approx(_err(HELD_EPS[(el, h)]), rel=1e-4)
    per = {(p["regime"], p["observer"]): p for p in res["per_atmosphere"]}
    assert all((p["aod"], p["albedo"]) == HELD_ATM for p in res["per_atmosphere"])
    assert per[("sun -6 to -12 deg", "15 km")]["Y_rms"] == pytest.approx(_err(0.10),
                                                                        abs=2e-3)
    text = capsys.readouterr().out
    assert "| 0.04, 0.3 |" in text              # the --per-atmosphere table's row


def test_heldout_where_lists_the_largest_errors_of_each_regime(heldout, capsys):
    """--where on a held-out set: per regime, the largest errors come from the observer whose
    factor is the larger there, with that factor's error (1/(1+eps) - 1, to the luminance
    integration's 1 %)."""
    assert tool.main([str(heldout), "--where", "2"]) == 0
    text = capsys.readouterr().out.split("largest luminance errors")[1]
    found, reg = {}, None
    for line in text.splitlines():
        if line.startswith("sun ") and line.endswith(":"):      # a regime's list
            reg = line[:-1]
            found[reg] = []
        elif line.startswith("sun transmittance"):
            break
        elif reg and line.startswith("| ") and "%" in line:
            found[reg].append([x.strip() for x in line.strip("|").split("|")])
    assert set(found) == {"sun > 20 deg", "sun -6 to -12 deg"}
    for reg, (el, eps, obs, h) in {"sun > 20 deg": (28.0, 0.03, "ground", 0.0),
                                   "sun -6 to -12 deg": (-9.5, 0.10, "15 km", 15000.0)}.items():
        assert len(found[reg]) == 2
        for r in found[reg]:
            assert float(r[0].rstrip(" %")) / 100 == pytest.approx(1 / (1 + eps) - 1,
                                                                    abs=1e-2), reg
            assert (r[1], r[2], r[3], r[4], r[9]) == ("0.04", "0.3", f"{el:g} deg",
                                                      f"{h:g} m", obs)


def test_supplement_joins_elevations_and_leaves_out_the_files_sun_nodes(heldout, tmp_path,
                                                                       capsys):
    """--supplement: the held-out set split by sun elevation measures as the whole set; a
    joined elevation that is a sun node of the measured file (given a 50 % factor here) is
    left out unless --elevations names it; overlapping sets and unknown elevations are
    refused naming the option."""
    node = float(np.asarray(_coefficients.load()["elevation_nodes_deg"])[-4])   # 50 deg
    eps = {**HELD_EPS, (node, 0.0): 0.5, (node, 15000.0): 0.5}
    alts = [0.0, 15000.0]
    _held_set(tmp_path / "a", [28.0], alts, eps)
    _held_set(tmp_path / "b", [-9.5, node], alts, eps)
    whole, split = tmp_path / "whole.json", tmp_path / "split.json"
    assert tool.main([str(heldout), "--json", str(whole)]) == 0
    assert tool.main([str(tmp_path / "a"), "--supplement", str(tmp_path / "b"), "--json",
                      str(split)]) == 0
    assert f"left out (sun nodes of the measured file): [{node}]" in capsys.readouterr().out
    rw, rs = (json.loads(f.read_text())["rows"] for f in (whole, split))
    assert rw == rs
    # named, the node is measured: its 50 % factor is the sun > 20 deg maximum
    assert tool.main([str(tmp_path / "a"), "--supplement", str(tmp_path / "b"), "--json",
                      str(split), "--elevations", f"28,{node:g}"]) == 0
    rows = {(r["regime"], r["observer"]): r for r in json.loads(split.read_text())["rows"]
            if r["model"] == "fitted"}
    assert set(rows) == {("sun > 20 deg", "ground"), ("sun > 20 deg", "15 km")}
    assert rows[("sun > 20 deg", "ground")]["S_max"] == pytest.approx(_err(0.5), abs=1e-6)
    capsys.readouterr()
    assert tool.main([str(heldout), "--supplement", str(tmp_path / "b")]) == 2
    assert "--supplement" in capsys.readouterr().err
    assert tool.main([str(heldout), "--elevations", "3.3"]) == 2
    assert "--elevations = '3.3'" in capsys.readouterr().err


def test_nodes_mode_classes_points_by_whether_they_are_the_files_nodes(tmp_path, capsys):
    c = _coefficients.load()
    en = np.asarray(c["elevation_nodes_deg"], dtype=np.float64)
    k = int(np.argmin(np.abs(en - 30.0)))
    at, between = float(en[k]), float(0.5 * (en[k] + en[k + 1]))
    eps = {at: 0.04, between: 0.02}
    aod, alb = 0.1, 0.5                           # a node of the file (class clear)
    wl = np.asarray(c["wavelengths_nm"], dtype=np.float64)
    _dataset.write_grid(tmp_path, [at, between], [0.0], [(aod, alb)], wavelengths=wl)
    n_dir = _grid.N_SKY + _grid.N_GROUND
    out = np.zeros((2, 1, n_dir + 1, _grid.N_PHI, wl.size), dtype=np.float32)
    for i, el in enumerate((at, between)):
        out[i, 0, :n_dir] = _coefficients.radiance_grid(c, aod, alb, el, 0.0) * (1 + eps[el])
    _store(tmp_path, aod, alb, out)
    assert tool.main([str(tmp_path), "--nodes"]) == 0
    lines = [x for x in capsys.readouterr().out.splitlines() if x.startswith("| clear |")]
    found = {}
    for line in lines:
        cols = [x.strip() for x in line.strip("|").split("|")]
        found[cols[3].split(" (")[0]] = (cols[1], float(cols[4].rstrip(" %")) / 100)
    assert set(found) == {"at nodes", "sun between nodes"}
    assert found["at nodes"][0] == "> 20 deg"
    # both sides integrated by the tool alike: the factor alone, to the printed digits
    assert found["at nodes"][1] == pytest.approx(_err(0.04), abs=6e-5)
    assert found["sun between nodes"][1] == pytest.approx(_err(0.02), abs=6e-5)
    # an AOD the set does not hold: refused with the value and what the set holds
    assert tool.main([str(tmp_path), "--nodes", "--aod", "0.5"]) == 2
    err = capsys.readouterr().err
    assert "--aod = 0.5" in err and "(0.1, 0.5)" in err


def test_nodes_where_names_the_direction_of_the_largest_error(tmp_path, capsys):
    """--where: one view-grid node of the set is given a larger factor than the rest; it must
    lead the list, with its row, column, elevation and angle from the sun."""
    c = _coefficients.load()
    en = np.asarray(c["elevation_nodes_deg"], dtype=np.float64)
    el = float(en[int(np.argmin(np.abs(en - 30.0)))])
    aod, alb, h = 0.1, 0.5, 15000.0
    wl = np.asarray(c["wavelengths_nm"], dtype=np.float64)
    _dataset.write_grid(tmp_path, [el], [h], [(aod, alb)], wavelengths=wl)
    n_dir = _grid.N_SKY + _grid.N_GROUND
    out = np.zeros((1, 1, n_dir + 1, _grid.N_PHI, wl.size), dtype=np.float32)
    fac = np.full((n_dir, _grid.N_PHI, 1), 1.01)
    row, col = 5, 40                                   # the limb from 15 km, away from the sun
    fac[row, col] = 1.25
    out[0, 0, :n_dir] = _coefficients.radiance_grid(c, aod, alb, el, h) * fac
    _store(tmp_path, aod, alb, out)
    assert tool.main([str(tmp_path), "--nodes", "--where", "3"]) == 0
    text = capsys.readouterr().out.split("largest luminance errors")[1]
    rows = [[x.strip() for x in line.strip("|").split("|")]
            for line in text.splitlines() if line.startswith("| ") and "%" in line]
    assert len(rows) == 3
    d = _grid.directions(h, 180.0)[row, col]
    sun = sd.Sun(elevation_deg=el, azimuth_deg=180.0)
    first = rows[0]
    # model / reference - 1 = 1 / 1.25 - 1, to the printed digits and the integration
    assert float(first[0].rstrip(" %")) / 100 == pytest.approx(1 / 1.25 - 1, abs=2e-3)
    assert (first[5], first[6]) == (str(row), str(col))
    assert float(first[7].split()[0]) == pytest.approx(np.degrees(np.arcsin(d[2])), abs=0.01)
    assert float(first[8].split()[0]) == pytest.approx(
        np.degrees(np.arccos(d @ sun.direction)), abs=0.01)
    # the others carry the common factor only
    assert all(float(r[0].rstrip(" %")) / 100 == pytest.approx(1 / 1.01 - 1, abs=2e-3)
               for r in rows[1:])
    assert tool.main([str(tmp_path), "--nodes", "--where", "-1"]) == 2
    assert "--where = -1 is out of range" in capsys.readouterr().err


def test_bad_arguments_refused_with_the_value(heldout, tmp_path, capsys):
    missing = tmp_path / "none.npz"
    assert tool.main([str(heldout), "--coefficients", str(missing)]) == 2
    assert str(missing) in capsys.readouterr().err
    # --nodes needs a fitting grid's data set, not a held-out one (cell centres)
    assert tool.main([str(heldout), "--nodes"]) == 2
    assert "--grid fit" in capsys.readouterr().err
