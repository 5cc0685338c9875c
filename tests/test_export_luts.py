"""The LUT bake for real-time renderers (skydome.export.luts)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest


def test_xyz_weights_give_the_luminous_solar_constant():
    """Summed over the table wavelengths, the Y weights are the illuminance of the
    extraterrestrial sun at 1 au: 683 lm/W x integral E_sun y-bar = 133 334 lx, the
    reference luminous solar constant of Darula, Kittler & Gueymard (2005), Solar Energy
    79, 559-565 (within 1 %: their spectrum and integration differ from ASTM G173's)."""
    from skydome.export.luts import xyz_weights_for_table

    for grid in (np.linspace(380.0, 780.0, 8), np.linspace(380.0, 780.0, 20)):
        K = xyz_weights_for_table(grid)
        assert K.shape == (grid.size, 3)
        assert K[:, 1].sum() == pytest.approx(133_334.0, rel=0.01)


def test_bruneton_packing():
    """(r, mu, mu_s, nu, 3) -> 3-D texture with x = i_nu * n_mu_s + i_mu_s, y = mu, z = r
    ([Bru17] GetScattering's 4-D -> 3-D packing); each cell keeps its own value."""
    from skydome.export.luts import _bruneton_3d

    n_r, n_mu, n_ms, n_nu = 3, 4, 5, 2
    idx = np.indices((n_r, n_mu, n_ms, n_nu)).astype(float)
    code = idx[0] * 1000 + idx[1] * 100 + idx[2] * 10 + idx[3]
    tab = np.stack([code, -code, 2 * code], axis=-1)
    tex = _bruneton_3d(tab)
    assert tex.shape == (n_r, n_mu, n_nu * n_ms, 4) and tex.dtype == np.float32
    for ir, im, ims, inu in [(0, 0, 0, 0), (2, 3, 4, 1), (1, 2, 3, 0), (0, 1, 4, 1)]:
        texel = tex[ir, im, inu * n_ms + ims]
        want = ir * 1000 + im * 100 + ims * 10 + inu
        assert texel.tolist() == [want, -want, 2 * want, 0.0]


@pytest.fixture(scope="module")
def small_sky():
    import skydome

    return skydome.model("precomputed", sun=skydome.Sun(elevation_deg=30.0, azimuth_deg=180.0),
                         n_wavelengths=4, scattering_r_size=4, scattering_mu_size=8,
                         scattering_mu_s_size=4, scattering_nu_size=2, orders=2,
                         transmittance_mu_size=16, transmittance_r_size=8,
                         irradiance_mu_s_size=8, irradiance_r_size=4)


def test_bake_reduces_single_scattering_in_slabs(monkeypatch):
    """The bake reduces single scattering to XYZ a few r nodes at a time without computing
    the whole table (Tables.single_scattering_slabs); each texel is the XYZ of the model's
    own single-scattering table (the whole table, computed afterwards by the same builder)
    summed over the constituents of its phase group, at [Bru17]'s packed position."""
    import skydome
    from skydome.export import luts
    from skydome.models.simulated.precomputed import _tables

    sky = skydome.model("precomputed", sun=skydome.Sun(elevation_deg=30.0, azimuth_deg=180.0),
                        n_wavelengths=4, scattering_r_size=4, scattering_mu_size=8,
                        scattering_mu_s_size=4, scattering_nu_size=2, orders=2,
                        transmittance_mu_size=16, transmittance_r_size=8,
                        irradiance_mu_s_size=8, irradiance_r_size=4)
    t = sky._t
    t.__dict__.pop("_" + _tables._LAZY_SS, None)       # as loaded from the cache
    monkeypatch.setattr(luts, "SINGLE_SLAB_ROWS", 3)     # two slabs of the 4 r nodes
    tex, _ = luts.bake_precomputed(sky, ground=True, density=False)
    assert not t.has_single_scattering                    # the table was not held whole
    with pytest.raises(ValueError, match="step = 0"):
        next(t.single_scattering_slabs(0))
    ss = t.build_single_scattering().astype(np.float64)  # (k, r, mu, mu_s, nu, l)
    K = luts.xyz_weights_for_table(t.table_wavelengths_nm)
    ray = [k for k, c in enumerate(t.phase_code) if c == 0]
    mie = [k for k, c in enumerate(t.phase_code) if c != 0]
    n_ms = ss.shape[3]
    for name, ks in [("scattering", ray), ("single_mie_scattering", mie),
                     *[(f"single_scattering_{k}", [k]) for k in range(ss.shape[0])]]:
        want = np.einsum("krmsnl,lc->rmsnc", ss[ks], K)
        for ir, im, ims, inu in [(0, 0, 0, 0), (3, 7, 3, 1), (2, 5, 1, 0), (1, 2, 3, 1)]:
            texel = tex[name][ir, im, inu * n_ms + ims]
            assert np.allclose(texel[:3], want[ir, im, ims, inu], rtol=1e-6, atol=0.0), name
            assert texel[3] == 0.0


def test_write_precomputed_luts(small_sky, tmp_path):
    from skydome.export.luts import LUT_FORMAT, write_precomputed_luts

    out = tmp_path / "luts"
    written = write_precomputed_luts(small_sky, out)
    desc = json.loads((out / "luts.json").read_text())
    assert desc["format"] == LUT_FORMAT
    assert desc["sizes"] == {"r": 4, "mu": 8, "mu_s": 4, "nu": 2}
    # the mu_s axis is the model's zenith-angle mapping (table format 2), not [Bru17]'s, and
    # the mu axis its horizon-angle mapping (table format 3)
    assert desc["table_format"] == "skydome.precomputed/4"
    assert "asinh((theta - 92 deg)/6 deg)" in desc["mappings"]["mu_s"]
    assert "asinh(e/w)/asinh(e_max/w), w = 2 deg" in desc["mappings"]["mu"]
    # [Bru17]'s texture set: Rayleigh and single Mie apart, orders 2..N, transmittance,
    # the constituents' columns (optical depths), the sky's irradiance (XYZ and spectral)
    # and (format 5) the scattering density of orders 2..N
    assert set(desc["textures"]) == {"scattering", "single_mie_scattering",
                                     "multiple_scattering", "transmittance", "optical_depth",
                                     "irradiance", "irradiance_spectral",
                                     "scattering_density"}
    for name, t in desc["textures"].items():
        raw = np.fromfile(out / t["file"], dtype="<f4").reshape(t["shape"])
        npy = np.load(out / f"{name}.npy")
        assert np.array_equal(raw, npy)
        assert np.all(np.isfinite(raw)) and np.all(raw >= 0.0)
        if t["channels"] == ["X", "Y", "Z"]:
            assert np.all(raw[..., 3] == 0.0)
    assert not [p for p in out.iterdir() if p.name.startswith(".")]     # no temporary left
    assert len(written) == 2 * 8 + 1


def test_bake_refuses_other_table_format(tmp_path):
    """A textures.json of another table format (format 1 had [Bru17]'s mu_s axis) is refused
    before anything is read or written."""
    from skydome.export.luts import write_precomputed_luts

    class OldTables:
        def export_textures(self, folder):
            (Path(folder) / "textures.json").write_text(json.dumps(
                {"format": "skydome.precomputed/1", "textures": {}}))

    out = tmp_path / "luts"
    with pytest.raises(ValueError, match="skydome.precomputed/1"):
        write_precomputed_luts(OldTables(), out)
    assert not out.exists()


def test_cli_export_luts_precomputed(tmp_path):
    """`skydome export luts --model precomputed`: Bruneton's layout in float32 EXR (3-D
    textures as stacked slices) equal to the .npy, and luts.json; an existing folder gets
    its files replaced; bad input exits 2 leaving nothing."""
    from typer.testing import CliRunner

    from skydome.cli import app
    from skydome.imaging.image import read_exr

    small = ["--n-wavelengths", "4", "--scattering-r-size", "4", "--scattering-mu-size", "8",
             "--scattering-mu-s-size", "4", "--scattering-nu-size", "2", "--orders", "2",
             "--transmittance-mu-size", "16", "--transmittance-r-size", "8",
             "--irradiance-mu-s-size", "8", "--irradiance-r-size", "4", "--cache", "false"]
    runner = CliRunner()
    out = tmp_path / "luts"
    for _ in range(2):                                   # new folder, then the existing one
        res = runner.invoke(app, ["export", "luts", "--model", "precomputed", "--format",
                                  "exr,npy", "--out", str(out), *small])
        assert res.exit_code == 0, res.output
    desc = json.loads((out / "luts.json").read_text())
    assert desc["format"] == "skydome.luts.bruneton-xyz/6"
    ms = np.load(out / "multiple_scattering.npy")
    assert ms.shape == (4, 8, 2 * 4, 4)
    ch = read_exr(out / "multiple_scattering.exr")
    assert ch["X"].dtype == np.float32 and ch["X"].shape == (4 * 8, 8)
    np.testing.assert_array_equal(ch["Y"], ms[..., 1].reshape(32, 8))
    # the EXR channels are named for what they hold (CIE XYZ; the columns by constituent),
    # as the OpenEXR reader lists them in the header; spectral layers only in .npy / .bin
    import OpenEXR

    for name in ("scattering", "single_mie_scattering", "multiple_scattering",
                 "transmittance", "irradiance"):
        with OpenEXR.File(str(out / f"{name}.exr")) as f:
            assert [c.name for c in f.header()["channels"]] == ["X", "Y", "Z"], name
    with OpenEXR.File(str(out / "optical_depth.exr")) as f:
        assert ({c.name for c in f.header()["channels"]}
                == set(desc["textures"]["optical_depth"]["channels"]) >= {"rayleigh", "aerosol"})
    assert not (out / "irradiance_spectral.exr").exists()
    assert not list(out.glob("*.bin"))
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]
    res = runner.invoke(app, ["export", "luts", "--model", "precomputed", "--format", "tiff",
                              "--out", str(tmp_path / "bad")])
    assert res.exit_code == 2 and "formats" in res.output
    assert not (tmp_path / "bad").exists()


def test_density_texture_follows_the_described_layout():
    """The packed scattering density against luts.json's layout, texel by texel: block b =
    ((i_theta n_scatterers) + k) layers + layer holds wavelengths 4 layer .. 4 layer + 3 in
    RGBA (zeros past the last) at x = (b mod cols) n_mu_s + i_mu_s, y = i_r, z = (b div
    cols) n_phi + i_phi; with a last, partial layer (7 and 9 wavelengths) and without (8)."""
    from skydome.export.luts import _density_texture

    rng = np.random.default_rng(3)
    for shape, cols in [((2, 3, 2, 3, 5, 7), 4), ((1, 4, 3, 2, 3, 8), 3),
                        ((2, 2, 2, 2, 2, 9), 5)]:
        J = rng.random(shape, dtype=np.float32)
        tex = _density_texture(J, cols)
        nsc, n_th, n_ph, n_r, n_ms, nl = shape
        layers = -(-nl // 4)
        want = np.zeros_like(tex)
        for it in range(n_th):
            for k in range(nsc):
                for lay in range(layers):
                    b = (it * nsc + k) * layers + lay
                    for ip in range(n_ph):
                        for ir in range(n_r):
                            for im in range(n_ms):
                                for c in range(4):
                                    if 4 * lay + c < nl:
                                        want[(b // cols) * n_ph + ip, ir,
                                             (b % cols) * n_ms + im, c] = \
                                            J[k, it, ip, ir, im, 4 * lay + c]
        assert tex.dtype == np.float32 and tex.tobytes() == want.tobytes()


def test_written_files_are_numpys_own_of_the_bake_in_memory(small_sky, tmp_path):
    """write_luts builds the large textures in their .npy files' pages: every .npy file is
    byte for byte numpy's np.save of the same bake built in memory, every .bin its raw
    little-endian float32 bytes."""
    import io

    from skydome.export.luts import bake, write_luts

    tex, _ = bake(small_sky)
    write_luts(small_sky, tmp_path / "luts", ("npy", "bin"))
    assert {p.stem for p in (tmp_path / "luts").glob("*.npy")} == set(tex)
    for name, arr in tex.items():
        buf = io.BytesIO()
        np.save(buf, arr)
        assert (tmp_path / "luts" / f"{name}.npy").read_bytes() == buf.getvalue(), name
        assert (tmp_path / "luts" / f"{name}.bin").read_bytes() == \
            np.ascontiguousarray(arr, dtype="<f4").tobytes(), name


def test_a_full_disk_before_the_mapped_texture_is_enospc_naming_it(small_sky, tmp_path,
                                                                    monkeypatch):
    """The mapped .npy file's blocks are reserved before the bake fills it: no space is an
    OSError ENOSPC naming the file in the output folder (not a SIGBUS on the mapping), and
    nothing is left behind."""
    import errno
    import os

    from skydome.export.luts import write_luts

    def no_space(fd, offset, length):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(os, "posix_fallocate", no_space, raising=False)
    with pytest.raises(OSError) as info:
        write_luts(small_sky, tmp_path / "luts", ("npy", "bin"))
    assert info.value.errno == errno.ENOSPC
    assert str(info.value.filename).startswith(str(tmp_path / "luts"))
    assert str(info.value.filename).endswith(".npy")
    assert list(tmp_path.iterdir()) == []
