"""Sky patches: counts, order and geometry against Radiance (reinhart.cal, gendaymtx), solid
angles, and the stated order of the patch quadrature."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skydome.daylighting.patches import patches


@pytest.mark.parametrize("mf", [1, 2, 4])
def test_patch_count_matches_gendaymtx(mf, tmp_path):
    """NROWS that gendaymtx -m MF writes (ground + sky patches): 146, 578, 2306."""
    from _daylighting import run_gendaymtx

    wea = tmp_path / "one.wea"
    wea.write_text("place x\nlatitude 36.1\nlongitude 79.95\ntime_zone 75\nsite_elevation 0\n"
                   "weather_data_file_units 1\n6 21 12.5 700 100\n")
    head = run_gendaymtx(wea, ["-m", mf]).split(b"\n\n")[0].decode()
    nrows = int(head.split("NROWS=")[1].split()[0])
    assert len(patches("tregenza" if mf == 1 else f"reinhart:{mf}")) == nrows
    assert nrows == 144 * mf * mf + 2


@pytest.mark.parametrize("mf", [1, 2, 4])
def test_patch_order_matches_reinhart_cal(mf):
    """Every quadrature node of every patch lies in the patch that Radiance's reinhart.cal
    (rbin, evaluated by rcalc) assigns it; also the centres."""
    from _radiance import radiance_paths, run_radiance

    ps = patches(f"reinhart:{mf}")
    d, _, off = ps.nodes(2)
    own = np.repeat(np.arange(1, len(ps)), np.diff(off))
    dirs = np.concatenate([d, ps.centres[1:]])
    want = np.concatenate([own, np.arange(1, len(ps))])
    _, lib = radiance_paths()
    rows = "\n".join(f"{x:.17g}\t{y:.17g}\t{z:.17g}" for x, y, z in dirs) + "\n"
    # MF must be set before reinhart.cal is loaded
    out = run_radiance("rcalc", ["-e", f"MF:{mf}", "-f", str(lib / "reinhart.cal"), "-e",
                                 "Dx=$1;Dy=$2;Dz=$3", "-e", "$1=rbin"], stdin=rows)
    got = np.array(out.split(), dtype=float)
    np.testing.assert_array_equal(got.astype(int), want)
    assert np.array_equal(ps.patch_of(dirs), want)


def test_solid_angles():
    for spec in ("tregenza", "reinhart:2", "reinhart:4", "reinhart:6"):
        ps = patches(spec)
        assert ps.solid_angle_sr[0] == pytest.approx(2 * math.pi)
        assert ps.solid_angle_sr[1:].sum() == pytest.approx(2 * math.pi, rel=1e-12)
    # Tregenza's zenith cap: 6 deg half angle, 2 pi (1 - cos 6 deg) = 0.03442 sr [T87]
    assert patches("tregenza").solid_angle_sr[-1] == pytest.approx(
        2 * math.pi * (1 - math.cos(math.radians(6.0))), rel=1e-12)
    assert patches("tregenza").solid_angle_sr[-1] == pytest.approx(0.03442, abs=1e-5)


def test_quadrature_order_is_exact_for_stated_degree():
    """Order q integrates a patch mean of (sin altitude)^k exactly for k <= 2q - 1 (the
    analytic mean is (s_hi^(k+1) - s_lo^(k+1)) / ((k + 1)(s_hi - s_lo))), not beyond."""
    ps = patches("tregenza")
    slo = np.sin(ps.altitude_low_rad[1:])
    shi = np.sin(ps.altitude_high_rad[1:])
    for q in (1, 2, 3):
        d, w, off = ps.nodes(q)
        for k in range(0, 2 * q + 1):
            mean = np.add.reduceat(w * d[:, 2] ** k, off[:-1]) / np.add.reduceat(w, off[:-1])
            exact = (shi ** (k + 1) - slo ** (k + 1)) / ((k + 1) * (shi - slo))
            err = np.abs(mean - exact).max()
            if k <= 2 * q - 1:
                assert err < 1e-13, (q, k, err)
            else:
                assert err > 1e-9, (q, k, err)


def test_quadrature_in_azimuth_converges():
    """Mean of cos(phi) over a ring patch of half width h centred on phi0: cos(phi0) sin h / h
    (exact); Gauss-Legendre order q errs by O(h^(2q)) -- order 3 below 1e-6 for Tregenza."""
    ps = patches("tregenza")
    h = ps.azimuth_half_width_rad[1:-1]
    exact = np.cos(ps.azimuth_centre_rad[1:-1]) * np.sin(h) / h
    errs = []
    for q in (1, 2, 3):
        d, w, off = ps.nodes(q)
        phi = np.arctan2(d[:, 0], d[:, 1])
        mean = np.add.reduceat(w * np.cos(phi), off[:-1]) / np.add.reduceat(w, off[:-1])
        errs.append(np.abs(mean[:-1] - exact).max())
    assert errs[2] < 1e-6 < errs[0]
    assert errs[0] > errs[1] > errs[2]


@pytest.mark.parametrize("spec", ["reinhart:0", "reinhart:13", "klems", "", "reinhart:x"])
def test_unknown_patches_spec(spec):
    with pytest.raises(ValueError, match="patches = "):
        patches(spec)
    with pytest.raises(TypeError):
        patches(4)
