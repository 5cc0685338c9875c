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
from skydome.render import Fisheye, render
from skydome.render.display import display_transform, ev100_to_exposure, exposure_to_ev100

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
