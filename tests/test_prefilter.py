"""Prefiltered (GGX split-sum) mip levels for image-based lighting against brute-force
integration of the map: for a few texels of each level, the sum over every pixel of the
level-0 map of L D(h) max(r.l, 0) dOmega / sum D(h) max(r.l, 0) dOmega ([Kar13]
PrefilterEnvMap with n = v = r, written out here directly over the pixels' directions and
exact solid angles), within 1 %."""

import numpy as np
import pytest

import skydome as sd
from skydome.export.envmap import render_envmap
from skydome.export.prefilter import mip_roughness, prefiltered_mips


@pytest.fixture(scope="module")
def sky():
    return sd.model("hosek_wilkie2012", sun=sd.Sun(elevation_deg=20.0, azimuth_deg=100.0),
                    turbidity=3.0, albedo=0.3)


def _brute(env0, r_dir, roughness):
    """Direct sum over the level-0 map's pixels (ENU directions, solid angles)."""
    d, w = env0.directions()
    L = env0.pixels()
    a2 = roughness ** 4                                   # alpha = roughness^2 [Kar13]
    h = d + r_dir
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    nh = h @ r_dir
    D = a2 / (np.pi * (nh * nh * (a2 - 1.0) + 1.0) ** 2)  # [Wal07] eq. 33
    wt = D * np.maximum(d @ r_dir, 0.0) * w
    return (L * wt[:, None]).sum(axis=0) / wt.sum()


def _check_level(env0, lev, picks):
    for name, (row, col) in picks:
        proj = lev.projections[name]
        dirs, _ = proj.directions()
        want = _brute(env0, dirs[row, col], lev.metadata["roughness"])
        got = lev.images[name][row, col]
        np.testing.assert_allclose(got, want, rtol=0.01, err_msg=f"{name} {row} {col} "
                                   f"roughness {lev.metadata['roughness']}")


@pytest.mark.parametrize("convention", ["skydome", "blender"])
def test_latlong_mips_against_brute_force(sky, convention):
    env = render_envmap(sky, convention, size="256x128")
    mips = prefiltered_mips(env, levels=5)
    assert [m.images["map"].shape for m in mips] == [(128 >> k, 256 >> k, 3) for k in range(5)]
    assert mips[0] is env
    np.testing.assert_allclose([m.metadata.get("roughness", 0.0) for m in mips],
                               mip_roughness(5))
    rng = np.random.default_rng(1)
    for k in range(1, 5):
        h, w = mips[k].images["map"].shape[:2]
        picks = [("map", (int(rng.integers(h)), int(rng.integers(w)))) for _ in range(5)]
        picks.append(("map", (0, 0)))                      # next to the zenith
        _check_level(env, mips[k], picks)


def test_cube_mips_against_brute_force(sky):
    env = render_envmap(sky, "unity", size=64, layout="cubemap")
    mips = prefiltered_mips(env, levels=4)
    assert [m.images["+Y"].shape for m in mips] == [(64 >> k, 64 >> k, 3) for k in range(4)]
    rng = np.random.default_rng(2)
    for k in range(1, 4):
        n = 64 >> k
        picks = [(f, (int(rng.integers(n)), int(rng.integers(n))))
                 for f in ("+X", "-X", "+Y", "-Y", "+Z", "-Z")]
        picks.append(("+X", (0, 0)))                       # a face corner
        _check_level(env, mips[k], picks)


def test_mip_options_refused(sky):
    from skydome.export.prefilter import check_mip_levels

    env = render_envmap(sky, "pbrt", size=32)
    with pytest.raises(ValueError, match="latlong"):
        prefiltered_mips(env, 3)
    with pytest.raises(ValueError, match="mip_levels = 9"):
        check_mip_levels(9, 128)


def test_cli_writes_the_mip_chain(tmp_path):
    import json

    from typer.testing import CliRunner

    from skydome.cli import app
    from skydome.render.image import read_exr

    runner = CliRunner()
    out = tmp_path / "sky.exr"
    res = runner.invoke(app, ["export", "envmap", "--model", "hosek_wilkie2012", "--size",
                              "64x32", "--half", "--mips", "4", "--out", str(out)])
    assert res.exit_code == 0, res.output
    doc = json.loads((tmp_path / "sky.mips.json").read_text())
    assert [lv["roughness"] for lv in doc["levels"]] == pytest.approx([0, 1 / 3, 2 / 3, 1])
    for k, lv in enumerate(doc["levels"]):
        ch = read_exr(tmp_path / lv["file"])
        assert ch["R"].shape == (32 >> k, 64 >> k) and ch["R"].dtype == np.float16
    res = runner.invoke(app, ["export", "envmap", "--model", "hosek_wilkie2012", "--size",
                              "64x32", "--mips", "9", "--out", str(tmp_path / "x.exr")])
    assert res.exit_code == 2 and "--mips = 9" in res.output
    assert not (tmp_path / "x.exr").exists()
