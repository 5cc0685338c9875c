"""Display: hue preservation of the default transform, exposure, picture metadata.

Oracles: colour-science (sRGB decoding, XYZ -> CIELAB -> LCh, independent of skydome's
colour code), the sRGB standard IEC 61966-2-1 (the PNG sRGB chunk, [PNG] 11.3.3.5), the
saturation-based exposure of Lagarde & de Rousiers 2014 (L_max = 1.2 x 2^EV100), and the
ordering of twilight sky luminance (it falls with the sun's depression).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

import skydome as sd
from skydome.imaging import Fisheye, render
from skydome.imaging.display import display_transform, ev100_to_exposure, exposure_to_ev100

colour = pytest.importorskip("colour")


def _hue_deg(xyz):
    """CIELAB hue angle [deg] (D65 white), the colour scaled to Y = 0.5 so that every
    colour lies on the cube-root branch of CIELAB (hue is then independent of scale)."""
    xyz = np.asarray(xyz, dtype=float)
    xyz = xyz / xyz[..., 1:2] * 0.5
    lab = colour.XYZ_to_Lab(xyz, colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"])
    return colour.Lab_to_LCHab(lab)[..., 2]


def _png_xyz(path, rc):
    code = np.asarray(Image.open(path).convert("RGB"), dtype=float)[rc] / 255.0
    return colour.RGB_to_XYZ(code, colour.RGB_COLOURSPACES["sRGB"], apply_cctf_decoding=True)


def _hue_gap(a, b):
    return abs((a - b + 180.0) % 360.0 - 180.0)


SCENES = [  # (sun elevation, pixel (elevation, azimuth)): what the issue names
    (2.0, (0.7, 270.0)),    # the horizon under a 2 deg sun: orange-red
    (60.0, (90.0, 0.0)),    # the noon zenith: blue
    (-2.0, (10.0, 90.0)),   # the Belt of Venus at -2 deg: pink-orange band above the shadow
]


@pytest.fixture(scope="module")
def scenes(tmp_path_factory):
    out = []
    d = tmp_path_factory.mktemp("hue")
    for k, (el, (pe, pa)) in enumerate(SCENES):
        sky = sd.model("single_scattering", sun=sd.Sun(elevation_deg=el, azimuth_deg=270.0))
        p = Fisheye(128)
        im = render(sky, p)
        r, c = p.pixel_from_direction(sd.direction_from_angles(pe, pa))
        rc = (int(r), int(c))
        paths = {}
        for tm in ("hue-preserving", "filmic"):
            paths[tm] = im.save(d / f"s{k}_{tm}.png", tonemap=tm)
        out.append((el, im, rc, paths))
    return out


@pytest.mark.parametrize("k", range(len(SCENES)))
def test_png_keeps_the_hue_of_the_linear_colour(scenes, k):
    el, im, rc, paths = scenes[k]
    true = _hue_deg(im.xyz()[rc])
    shown = _hue_deg(_png_xyz(paths["hue-preserving"], rc))
    assert _hue_gap(true, shown) < 10.0, (el, true, shown)


def test_per_channel_curve_loses_the_sunset_hue(scenes):
    # why the default changed: the per-channel curve turns the orange-red horizon under a
    # 2 deg sun towards yellow
    el, im, rc, paths = scenes[0]
    true = _hue_deg(im.xyz()[rc])
    assert _hue_gap(true, _hue_deg(_png_xyz(paths["filmic"], rc))) > 10.0


def test_png_metadata_and_srgb_chunk(scenes, tmp_path):
    el, im, rc, paths = scenes[1]
    raw = paths["hue-preserving"].read_bytes()
    assert raw.find(b"sRGB") > 0 and raw.find(b"sRGB") < raw.find(b"IDAT")
    info = Image.open(paths["hue-preserving"]).info
    assert "display-referred" in info["colour"] and info["display_transform"] == "hue-preserving"
    k = float(info["exposure_m2_per_cd"])
    assert k == pytest.approx(im.auto_exposure(), rel=1e-9)
    assert float(info["ev100"]) == pytest.approx(np.log2(1.0 / (1.2 * k)), abs=1e-3)
    assert "exposure_m2_per_cd" in json.loads(info["Description"])
    # an explicit EV100 is recorded as given; 16-bit PNGs carry the same text
    p = im.save(tmp_path / "ev.png", ev100=13.0, bits=16)
    info = Image.open(p).info
    assert float(info["ev100"]) == pytest.approx(13.0) and info["exposure_mode"] == "ev100"


def test_hdr_header_states_radiance_convention(scenes, tmp_path):
    el, im, rc, paths = scenes[1]
    head = im.save(tmp_path / "a.hdr").read_bytes()[:3000]
    units = [l for l in head.split(b"\n") if l.startswith(b"SKYDOME_UNITS=")][0]
    assert b"179" in units and b"W sr^-1 m^-2" in units


def test_ev100_exposure():
    # Lagarde & de Rousiers 2014: L_max = 1.2 x 2^EV100; EV100 15 ("sunny 16") -> 39 322
    assert 1.0 / ev100_to_exposure(15.0) == pytest.approx(1.2 * 2 ** 15)
    assert exposure_to_ev100(ev100_to_exposure(7.5)) == pytest.approx(7.5)
    with pytest.raises(ValueError, match="ev100"):
        ev100_to_exposure(40.0)


def test_display_transform_properties():
    rng = np.random.default_rng(3)
    rgb = rng.uniform(-0.2, 30.0, size=(2000, 3))
    out = display_transform(rgb)
    assert np.all((out >= 0) & (out <= 1))
    # below the path to white, channel ratios (hue) are kept exactly for in-gamut colours
    x = np.array([[0.5, 0.2, 0.05], [2.0, 0.8, 0.2]])
    y = display_transform(x)
    assert np.allclose(y[:, 1] / y[:, 0], x[:, 1] / x[:, 0])
    # brighter in, brighter out; the sun runs to white
    assert y[1, 0] > y[0, 0]
    assert np.allclose(display_transform(np.array([[1e5, 3e4, 5e3]])), 1.0)
    with pytest.raises(ValueError, match="transform"):
        display_transform(x, "agx9")


# -- the noon zenith's colourfulness (Hunt effect) ----------------------------------------

def _lab(xyz):
    return colour.XYZ_to_Lab(np.asarray(xyz, float),
                             colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"])


def test_noon_zenith_keeps_its_chroma_and_hue(scenes):
    # the displayed zenith (PNG, decoded by colour-science) against the linear colour scaled
    # to the displayed luminance: the chroma at least 1.3 x (the Hunt-effect gain at the noon
    # sky's adapting luminance is about 1.5; the colorimetric picture has 1.0) and the hue
    # within 10 deg
    el, im, rc, paths = scenes[1]
    shown = _png_xyz(paths["hue-preserving"], rc)
    true = im.xyz()[rc] / im.xyz()[rc][1] * shown[1]
    lab_s, lab_t = _lab(shown), _lab(true)
    c_s, c_t = np.hypot(*lab_s[1:]), np.hypot(*lab_t[1:])
    assert c_s >= 1.3 * c_t, (c_s, c_t)
    assert _hue_gap(_hue_deg(true), _hue_deg(shown)) < 10.0
    # the gain is recorded, and without it the chroma stays that of the linear colour
    info = Image.open(paths["hue-preserving"]).info
    assert float(info["chroma_gain"]) == pytest.approx(im.chroma_gain(), rel=1e-3) and im.chroma_gain() > 1.3
    plain = im.to_srgb(tonemap="hue-preserving", hunt=False)[rc]
    lab_p = _lab(colour.RGB_to_XYZ(plain, colour.RGB_COLOURSPACES["sRGB"], apply_cctf_decoding=True))
    true_p = _lab(im.xyz()[rc] / im.xyz()[rc][1] * colour.sRGB_to_XYZ(plain)[1])
    assert np.hypot(*lab_p[1:]) == pytest.approx(np.hypot(*true_p[1:]), rel=0.05)


def test_luminance_adaptation_factor_cie159_worked_example():
    # CIE 159:2004 worked example (L_A = 318.31 cd/m^2): F_L = 1.16754; colour-science's
    # CIECAM02 viewing-condition parameters as a second oracle over a range of L_A
    from skydome.imaging.display import hunt_chroma_gain, luminance_adaptation_factor
    from colour.appearance.ciecam02 import viewing_conditions_dependent_parameters as vc

    assert luminance_adaptation_factor(318.31) == pytest.approx(1.16754, abs=5e-5)
    for la in (0.5, 16.0, 200.0, 4000.0, 1e5):
        assert luminance_adaptation_factor(la) == pytest.approx(float(vc(20.0, 100.0, la)[1]), rel=1e-9)
    # the gain: (F_L(scene) / F_L(80 / 5))^(1/4), never below 1
    g = hunt_chroma_gain(4000.0)
    assert g == pytest.approx((float(vc(20.0, 100.0, 4000.0)[1]) / float(vc(20.0, 100.0, 16.0)[1])) ** 0.25)
    assert hunt_chroma_gain(1.0) == 1.0
    with pytest.raises(ValueError, match="scene_adapting_luminance_cd_m2"):
        hunt_chroma_gain(-1.0)


def test_scale_chroma_against_colour_science():
    from skydome.imaging.display import scale_chroma
    from skydome.spectra import linear_srgb_to_xyz

    rgb = np.array([[0.3, 0.4, 0.9], [0.45, 0.5, 0.6], [0.6, 0.5, 0.4], [0.5, 0.5, 0.5], [0.9, 0.3, 0.05]])
    out = scale_chroma(rgb, 1.5)
    lab_in, lab_out = _lab(linear_srgb_to_xyz(rgb)), _lab(linear_srgb_to_xyz(out))
    assert np.allclose(lab_out[:, 0], lab_in[:, 0], atol=1e-6)           # same luminance
    lch_in, lch_out = colour.Lab_to_LCHab(lab_in), colour.Lab_to_LCHab(lab_out)
    assert np.allclose(lch_out[:3, 2], lch_in[:3, 2], atol=1e-6)        # same CIELAB hue
    # on the cube-root branch (L* = 100 after normalising to Y = 1) chroma scales exactly
    lab1_in = _lab(linear_srgb_to_xyz(rgb) / linear_srgb_to_xyz(rgb)[:, 1:2])
    lab1_out = _lab(linear_srgb_to_xyz(out) / linear_srgb_to_xyz(out)[:, 1:2])
    c_in, c_out = np.hypot(lab1_in[:, 1], lab1_in[:, 2]), np.hypot(lab1_out[:, 1], lab1_out[:, 2])
    assert np.allclose(c_out[:3], 1.5 * c_in[:3])
    assert np.allclose(out[3], 0.5)                                    # grey stays grey
    # an orange that a 1.5 x gain would push out of the gamut stops on its boundary
    assert out[4].min() == pytest.approx(0.0, abs=1e-12) and 1.0 < c_out[4] / c_in[4] < 1.5
    assert abs(lch_out[4, 2] - lch_in[4, 2]) < 3.0


# -- AgX and the ACES 1.x fit --------------------------------------------------------------

def test_rec709_to_rec2020_matrix_itu_bt2087():
    # ITU-R BT.2087-0 eq. (2): linear BT.709 -> BT.2020 to four decimals
    from skydome.imaging.display import _rec709_rec2020

    to2020, _ = _rec709_rec2020()
    bt2087 = np.array([[0.6274, 0.3293, 0.0433], [0.0691, 0.9195, 0.0114], [0.0164, 0.0880, 0.8956]])
    assert np.allclose(to2020, bt2087, atol=6e-5)


@pytest.mark.parametrize("tm", ["agx", "aces-hill"])
def test_agx_and_aces_fit_keep_greys_and_order(tm):
    # both are built from white-preserving matrices (rows summing to 1): greys stay grey;
    # the curves are monotone and bounded; a transposed matrix would tint the greys
    grey = np.geomspace(1e-4, 1e3, 60)[:, None] * np.ones(3)
    y = display_transform(grey, tm)
    assert np.all((y >= 0) & (y <= 1))
    assert np.allclose(y[:, 0], y[:, 1], atol=2e-3) and np.allclose(y[:, 2], y[:, 1], atol=2e-3)
    assert np.all(np.diff(y[:, 1]) >= -1e-9) and y[-1, 1] > 0.98 and y[0, 1] < 0.01


def test_cli_render_transform_and_no_hunt(tmp_path):
    from typer.testing import CliRunner

    from skydome.cli import app

    runner = CliRunner()
    args = ["render", "--model", "single_scattering", "--sun-elevation", "60", "--size", "32",
            "--wavelengths", "8"]
    r = runner.invoke(app, args + ["--tonemap", "agx", "--no-hunt", "--out", str(tmp_path / "a.png")])
    assert r.exit_code == 0, r.output
    info = Image.open(tmp_path / "a.png").info
    assert info["display_transform"] == "agx" and float(info["chroma_gain"]) == 1.0
    r = runner.invoke(app, args + ["--out", str(tmp_path / "b.png")])
    assert r.exit_code == 0 and float(Image.open(tmp_path / "b.png").info["chroma_gain"]) > 1.3
    r = runner.invoke(app, args + ["--tonemap", "agx9", "--out", str(tmp_path / "c.png")])
    assert r.exit_code == 2 and not (tmp_path / "c.png").exists()


def test_default_display_in_one_kernel_matches_the_equations_and_the_numpy_path():
    # The default (hue-preserving) display of a picture runs as one numba kernel
    # (SkyImage._display); against (1) values worked by hand from [Nar15]'s curve and
    # [IEC 61966-2-1]'s encoding, (2) the NumPy expression (display_transform, srgb_encode)
    # over colours in and out of gamut, dark, exposed beyond the path to white, masked, NaN.
    import math

    from skydome.imaging.image import SkyImage
    from skydome.spectra import srgb_encode

    def aces(x):
        return min(max(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0), 1.0)

    def enc(v):
        return 12.92 * v if v <= 0.0031308 else 1.055 * v ** (1.0 / 2.4) - 0.055

    def image_of(rgb, mask):
        im = SkyImage.__new__(SkyImage)
        im.mask = mask
        im.linear_srgb = lambda: rgb
        return im

    rng = np.random.default_rng(5)
    rgb = np.concatenate([rng.lognormal(-1.0, 2.0, size=(4000, 3)),
                          rng.normal(0.2, 0.3, size=(2000, 3)),
                          [[0.5, 0.5, 0.5], [10.0, 5.0, 1.0], [200.0, 100.0, 50.0],
                           [0.0, 0.0, 0.0], [-0.1, 0.3, 0.2], [1e-9, 2e-9, 0.0]]])
    rgb = rgb.reshape(-1, 1, 3)
    mask = np.ones(rgb.shape[:2], dtype=bool)
    mask[::7] = False
    got = image_of(rgb, mask)._display(1.0, "hue-preserving", 1.0)
    ref = np.clip(srgb_encode(display_transform(rgb, "hue-preserving")), 0.0, 1.0)
    ref[~mask] = 0.0
    assert np.max(np.abs(got - ref)) < 1e-12
    # by hand: a grey of 0.5 (no path to white below 4), an over-exposed orange halfway
    # along the path (m = 16: w = log2(16 / 4) / log2(64 / 4) = 1/2), and one past it (white)
    g = enc(aces(0.5))
    assert np.allclose(got[-6, 0], [g, g, g], rtol=0, atol=1e-14)
    m, fm = 16.0, aces(16.0)
    w = 0.5
    orange = [enc(min(max(c * fm / m * (1 - w) + fm * w, 0.0), 1.0)) for c in (16.0, 8.0, 2.0)]
    got2 = image_of(np.array([[[16.0, 8.0, 2.0], [200.0, 100.0, 50.0]]]),
                    np.ones((1, 2), dtype=bool))._display(1.0, "hue-preserving", 1.0)
    assert np.allclose(got2[0, 0], orange, rtol=0, atol=1e-14)
    assert np.allclose(got2[0, 1], enc(aces(200.0)), rtol=0, atol=1e-14)
    assert math.isclose(got[-1, 0, 2], enc(aces(2e-9) * 0.0), abs_tol=1e-15)
    bad = rgb.copy()
    bad[3, 0, 1] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        image_of(bad, mask)._display(1.0, "hue-preserving", 1.0)
