"""Aerial perspective / airlight over an image with depth (survey 5.3)."""

import numpy as np
import pytest
from typer.testing import CliRunner

import skydome as sd
from skydome.cli import app
from skydome.effects.airlight import apply_airlight

SUN = sd.Sun(elevation_deg=20.0, azimuth_deg=120.0)
DIST = np.array([[1e3, 3e3, 10e3, 30e3]])
GREY = np.full((1, 4, 3), 0.1)


@pytest.mark.parametrize("method", ["precomputed", "preetham1999", "hillaire2020"])
def test_distant_objects_bluer_and_brighter_in_clear_air(method):
    out = apply_airlight(GREY, DIST, SUN, method=method, turbidity=2.0, fov_deg=10)
    br = out[0, :, 2] / out[0, :, 0]
    assert np.all(np.diff(br[:3]) > 0) and br[-1] > br[0]   # bluer with distance
    # (Preetham's airlight reddens again beyond ~10 km: its B/R at 30 km is below that at 10 km)
    assert out[0, -1].sum() > out[0, 0].sum()         # brighter with distance


def test_haze_is_less_blue_than_clear_air():
    clear = apply_airlight(GREY, DIST, SUN, method="precomputed", turbidity=2.0, fov_deg=10)
    hazy = apply_airlight(GREY, DIST, SUN, method="precomputed", turbidity=8.0, fov_deg=10)
    assert hazy[0, -1, 2] / hazy[0, -1, 0] < 0.7 * clear[0, -1, 2] / clear[0, -1, 0]


def test_zero_distance_and_sky_unchanged():
    img = np.random.default_rng(0).uniform(0, 1, (2, 3, 3))
    dep = np.array([[np.inf, np.inf, 0.0], [np.inf, 0.0, np.inf]])
    out = apply_airlight(img, dep, SUN, method="hoffman_preetham2002", turbidity=3.0)
    np.testing.assert_array_equal(out, img)


def test_short_distance_methods_agree_on_transmittance():
    """At 200 m every method is near Beer-Lambert with sea-level extinction: the
    transmittances lie within 0.94-1 and agree within 4 % (hillaire2020's froxel volume,
    4 km per slice, gives the highest: 0.98-0.99 against 0.95-0.975)."""
    ts = []
    for m in ("precomputed", "preetham1999", "hoffman_preetham2002", "hillaire2020"):
        _, t, _ = apply_airlight(GREY[:, :1], np.array([[200.0]]), SUN, method=m, turbidity=3.0,
                                 return_parts=True)
        ts.append(t[0, 0])
    ts = np.array(ts)
    assert np.all(ts > 0.94) and np.ptp(ts, axis=0).max() < 0.04


def test_cli_synthetic_and_files(tmp_path):
    r = CliRunner()
    out = tmp_path / "a.png"
    res = r.invoke(app, ["airlight", "--synthetic", "--method", "hoffman_preetham2002", "--out", str(out)])
    assert res.exit_code == 0, res.output and out.exists()
    img = np.full((4, 5, 3), 0.2)
    np.save(tmp_path / "i.npy", img)
    np.save(tmp_path / "d.npy", np.full((4, 5), 5e3))
    res = r.invoke(app, ["airlight", "--image", str(tmp_path / "i.npy"), "--depth", str(tmp_path / "d.npy"),
                         "--method", "preetham1999", "--turbidity", "3", "--out", str(tmp_path / "o.npy")])
    assert res.exit_code == 0, res.output
    assert np.load(tmp_path / "o.npy").shape == (4, 5, 3)
    res = r.invoke(app, ["airlight", "--image", str(tmp_path / "i.npy"), "--depth", str(tmp_path / "d.npy"),
                         "--method", "fog", "--out", str(tmp_path / "p.npy")])
    assert res.exit_code == 2 and "method = 'fog'" in res.output and not (tmp_path / "p.npy").exists()
