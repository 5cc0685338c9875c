"""Tests of skydome.imaging (projections, render(), SkyImage, writers).

Oracles: analytic geometry (solid angle of the sphere 4 pi and hemisphere 2 pi, the
equidistant fisheye r = k theta), Radiance's own programs shipped with pyradiance
(``vwrays`` for the pixel -> direction mapping of ``-vta`` views, ``pvalue`` and
``getinfo`` for reading our RGBE pictures back), Pillow (reading PNGs), the OpenEXR
library (reading EXRs), the sRGB standard IEC 61966-2-1 (D65 white has R = G = B; transfer
function values), the CIE 1931 y-bar integral over 380-780 nm (106.857, CIE 018:2019 data
set summed at 1 nm), Reinhard et al. 2002 eq. 1 (key 0.18) and Narkowicz 2015 (ACES fit).
"""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from skydome.imaging import (AngularMap, Equirect, Fisheye, Projection, SkyImage, make_projection,
                            render)
from skydome.imaging import image as img
from skydome.sun import Sun


def _dir(el_deg, az_deg):
    el, az = np.radians(el_deg), np.radians(az_deg)
    return np.array([np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)])


# ------------------------------------------------------------------------------------------
# Fake models
# ------------------------------------------------------------------------------------------

class ConstantSpectral:
    """Constant spectral radiance c [W m^-2 sr^-1 nm^-1] everywhere; a sun of constant
    spectral radiance ``sun_level``."""

    native = "spectral"
    name = "constant"

    def __init__(self, sun=None, c=0.01, sun_level=None):
        self.sun, self.c, self.sun_level = sun, c, sun_level

    def radiance(self, directions, wavelengths_nm):
        d = np.asarray(directions)
        return np.full(d.shape[:-1] + (len(wavelengths_nm),), self.c)

    def sun_radiance(self, wavelengths_nm):
        return None if self.sun_level is None else np.full(len(wavelengths_nm), self.sun_level)

    def describe(self):
        return {"model": self.name, "reference": "test", "parameters": {"c": self.c}}


class ConstantXYZ:
    native = "xyz"
    name = "constant_xyz"
    sun = None

    def __init__(self, xyz):
        self.value = np.asarray(xyz, dtype=float)

    def xyz(self, directions):
        d = np.asarray(directions)
        return np.broadcast_to(self.value, d.shape[:-1] + (3,)).copy()


# D65 white point (IEC 61966-2-1 / CIE 15): x, y = 0.3127, 0.3290
def _d65_xyz(Y):
    x, y = 0.3127, 0.3290
    return np.array([x / y * Y, Y, (1 - x - y) / y * Y])


# ------------------------------------------------------------------------------------------
# Projections
# ------------------------------------------------------------------------------------------

ALL = [Fisheye(256), AngularMap(256), Equirect(256), Equirect(256, hemisphere=True)]


@pytest.mark.parametrize("proj,total", [(Fisheye(256), 2 * np.pi), (Fisheye(255), 2 * np.pi),
                                        (AngularMap(256), 4 * np.pi), (Equirect(256), 4 * np.pi),
                                        (Equirect(256, hemisphere=True), 2 * np.pi),
                                        (Equirect(256, 100), 4 * np.pi)])
def test_solid_angle_sums(proj, total):
    # analytic: the sphere subtends 4 pi sr, the hemisphere 2 pi sr
    om = proj.solid_angles()
    _, mask = proj.directions()
    assert om.shape == proj.shape
    assert np.all(om[~mask] == 0.0) and np.all(om[mask] > 0.0)
    assert om.sum() == pytest.approx(total, rel=1e-3)


@pytest.mark.parametrize("proj", ALL, ids=lambda p: p.name)
def test_pixel_direction_round_trip(proj):
    d, mask = proj.directions()
    assert np.allclose(np.linalg.norm(d, axis=-1), 1.0, atol=1e-12)
    r, c = proj.pixel_from_direction(d[mask])
    rows, cols = np.meshgrid(np.arange(proj.shape[0]) + 0.5, np.arange(proj.shape[1]) + 0.5,
                             indexing="ij")
    assert np.max(np.abs(r - rows[mask])) < 1e-9
    assert np.max(np.abs(c - cols[mask])) < 1e-9


@settings(max_examples=300, deadline=None)
@given(el=st.floats(0.0, 90.0), az=st.floats(0.0, 360.0, exclude_max=True))
def test_fisheye_direction_round_trip(el, az):
    p = Fisheye(512)
    d = _dir(el, az)
    r, c = p.pixel_from_direction(d)
    assert np.isfinite(r) and np.isfinite(c)
    back = p.direction_from_pixel(r, c)
    assert np.max(np.abs(back - d)) < 1e-9


@settings(max_examples=200, deadline=None)
@given(el=st.floats(-90.0, 90.0), az=st.floats(0.0, 360.0, exclude_max=True),
       which=st.sampled_from(["angular", "equirect"]))
def test_sphere_direction_round_trip(el, az, which):
    p = AngularMap(300) if which == "angular" else Equirect(400)
    d = _dir(el, az)
    if which == "angular" and el < -89.999:
        return  # the nadir is the whole edge circle
    r, c = p.pixel_from_direction(d)
    back = p.direction_from_pixel(r, c)
    assert np.max(np.abs(back - d)) < 1e-9


def test_below_horizon_not_representable_in_hemispheres():
    d = _dir(-10.0, 30.0)
    for p in (Fisheye(64), Equirect(64, hemisphere=True)):
        r, c = p.pixel_from_direction(d)
        assert np.isnan(r) and np.isnan(c)
    assert np.all(np.isfinite(AngularMap(64).pixel_from_direction(d)))


def test_fisheye_orientation():
    # Radiance -vd 0 0 1 -vu 0 1 0 seen looking up: north up, east left.
    p = Fisheye(256)
    r, c = p.pixel_from_direction(_dir(45.0, 0.0))   # north, elevation 45
    assert c == pytest.approx(128.0, abs=1e-9) and r < 128.0
    assert r == pytest.approx(128.0 - 64.0, abs=1e-9)  # half way to the horizon circle
    r, c = p.pixel_from_direction(_dir(45.0, 90.0))  # east
    assert r == pytest.approx(128.0, abs=1e-9) and c < 128.0
    r, c = p.pixel_from_direction(_dir(45.0, 270.0))  # west
    assert c > 128.0
    r, c = p.pixel_from_direction(_dir(90.0, 0.0))   # zenith at the centre
    assert (r, c) == pytest.approx((128.0, 128.0), abs=1e-9)


def test_fisheye_radius_linear_in_zenith_angle():
    # equidistant fisheye: r = (size / 2) * zenith / 90 deg
    p = Fisheye(200)
    zen = np.linspace(0.0, 90.0, 19)
    d = np.stack([_dir(90.0 - z, 123.0) for z in zen])
    r, c = p.pixel_from_direction(d)
    radius = np.hypot(r - 100.0, c - 100.0)
    assert np.allclose(radius, 100.0 * zen / 90.0, atol=1e-9)
    _, mask = p.directions()
    rows, cols = np.meshgrid(np.arange(200) + 0.5, np.arange(200) + 0.5, indexing="ij")
    assert np.array_equal(mask, np.hypot(rows - 100.0, cols - 100.0) <= 100.0)


def test_angular_map_layout():
    # Debevec angular map looking up: horizon at half radius, nadir at the edge
    p = AngularMap(200)
    r, c = p.pixel_from_direction(_dir(0.0, 0.0))  # north horizon
    assert (r, c) == pytest.approx((50.0, 100.0), abs=1e-9)
    r, c = p.pixel_from_direction(_dir(-45.0, 90.0))  # east, 45 deg below the horizon
    assert (r, c) == pytest.approx((100.0, 100.0 - 75.0), abs=1e-9)


def test_equirect_layout():
    # documented convention: left edge north, W/4 east, centre south; top zenith
    p = Equirect(360)
    assert p.shape == (180, 360)
    assert Equirect(360, hemisphere=True).shape == (90, 360)
    for az, col in ((90.0, 90.0), (180.0, 180.0), (270.0, 270.0)):
        r, c = p.pixel_from_direction(_dir(30.0, az))
        assert (r, c) == pytest.approx((60.0, col), abs=1e-9)
    _, mask = p.directions()
    assert mask.all()


def _vwrays(view, n):
    import _radiance

    out = _radiance.run_radiance("vwrays", ["-fa", "-x", n, "-y", n, *view.split()])
    rays = np.array(out.split(), dtype=float).reshape(n, n, 6)
    return rays[..., 3:]


@pytest.mark.parametrize("proj", [Fisheye(24), AngularMap(24)], ids=lambda p: p.name)
def test_directions_match_radiance_vwrays(proj):
    # Radiance's vwrays prints the ray of every pixel of a view, top scanline first.
    ref = _vwrays(proj.radiance_view, 24)
    d, mask = proj.directions()
    assert mask.sum() > 300
    assert np.max(np.abs(d[mask] - ref[mask])) < 2e-5  # vwrays prints 6 digits


def test_make_projection_and_errors():
    assert isinstance(make_projection("fisheye", "64"), Fisheye)
    assert make_projection("equirect", "128x32").shape == (32, 128)
    assert make_projection("equirect", 128).shape == (64, 128)
    assert make_projection("equirect-hemisphere", "128").shape == (32, 128)
    assert make_projection("angular", "32x32").shape == (32, 32)
    assert isinstance(make_projection("angular", 32), Projection)
    with pytest.raises(ValueError, match="projection = 'x' is not one of"):
        make_projection("x", "64")
    for bad in ("0", "-3", "abc", "64x", "1", "99999"):
        with pytest.raises(ValueError, match=f"size = '{bad}'"):
            make_projection("fisheye", bad)
    with pytest.raises(ValueError, match="size = '64x32'"):
        make_projection("fisheye", "64x32")


# ------------------------------------------------------------------------------------------
# render()
# ------------------------------------------------------------------------------------------

def test_render_constant_spectrum_uniform_and_progress():
    calls = []
    sky = ConstantSpectral(sun=Sun(30.0, 180.0), c=0.01)
    p = Fisheye(64)
    im = render(sky, p, progress=lambda done, total: calls.append((done, total)), chunk=500)
    assert im.kind == "spectral" and im.data.shape == (64, 64, 16)
    n = int(im.mask.sum())
    assert calls[-1] == (n, n) and len(calls) == -(-n // 500)
    assert all(a[0] < b[0] for a, b in zip(calls, calls[1:]))
    Y = im.luminance()
    assert np.all(Y[~im.mask] == 0.0)
    assert np.ptp(Y[im.mask]) == 0.0
    # 683 lm/W * 0.01 * integral of y-bar over 380-780 nm (106.857, CIE 1931 at 1 nm)
    assert Y[im.mask][0] == pytest.approx(683 * 0.01 * 106.857, rel=5e-3)
    assert im.metadata["model"] == "constant"


def test_render_xyz_model():
    im = render(ConstantXYZ(_d65_xyz(1000.0)), Equirect(32))
    assert im.kind == "xyz" and im.wavelengths_nm is None
    assert np.allclose(im.luminance(), 1000.0)
    # IEC 61966-2-1: the D65 white has R = G = B (= Y for the Y-scaled linear sRGB)
    assert np.allclose(im.linear_srgb(), 1000.0, rtol=2e-4)


def test_sun_disc_large_pixels_flux_preserving():
    # sun (radius 0.2665 deg) much smaller than a pixel (~2.8 deg): one pixel absorbs the
    # disc's flux, L_pix + (L_sun - L_pix) Omega_sun / Omega_pix (flux conservation)
    sun = Sun(elevation_deg=50.0, azimuth_deg=200.0)
    c, Ls = 0.01, 1.0e4
    p = Fisheye(64)
    im = render(ConstantSpectral(sun=sun, c=c, sun_level=Ls), p)
    om = p.solid_angles()
    bright = np.argwhere(im.data[..., 0] > c * 1.0000001)
    assert len(bright) == 1
    i, j = bright[0]
    r, cc = p.pixel_from_direction(sun.direction)
    assert (i, j) == (int(r), int(cc))
    expected = c + (Ls - c) * sun.solid_angle_sr / om[i, j]
    assert im.data[i, j, 0] == pytest.approx(expected, rel=1e-12)
    # total flux: sum L Omega grows by (L_sun - c) Omega_sun
    plain = render(ConstantSpectral(sun=sun, c=c, sun_level=Ls), p, draw_sun=False)
    gain = ((im.data[..., 0] - plain.data[..., 0]) * om).sum()
    assert gain == pytest.approx((Ls - c) * sun.solid_angle_sr, rel=1e-9)


def test_sun_disc_resolved():
    # a 5 deg sun on a 0.7 deg/pixel fisheye: the pixels more than half covered by the
    # (uniform) disc, value > (c + L_sun) / 2, cover its solid angle; a pixel whose centre
    # lies outside a convex disc is at most half covered, so they lie within 5 deg
    sun = Sun(elevation_deg=40.0, azimuth_deg=100.0, angular_radius_deg=5.0)
    p = Fisheye(256)
    im = render(ConstantSpectral(sun=sun, c=0.01, sun_level=50.0), p, limb_darkening=False)
    disc = im.data[..., 0] > 0.5 * (0.01 + 50.0)
    assert disc.sum() > 100
    assert (p.solid_angles()[disc]).sum() == pytest.approx(sun.solid_angle_sr, rel=0.03)
    d, _ = p.directions()
    ang = np.degrees(np.arccos(np.clip(d[disc] @ sun.direction, -1, 1)))
    assert ang.max() <= 5.0
    # no sun below the horizon-grazing limit, none when draw_sun is False
    low = render(ConstantSpectral(sun=Sun(-1.0, 100.0), c=0.01, sun_level=50.0), p)
    assert np.all(low.data[low.mask] == 0.01)
    off = render(ConstantSpectral(sun=sun, c=0.01, sun_level=50.0), p, draw_sun=False)
    assert np.all(off.data[off.mask] == 0.01)


def test_render_rejects_bad_input():
    with pytest.raises(TypeError):
        render(ConstantSpectral(), "fisheye")
    with pytest.raises(ValueError, match="chunk"):
        render(ConstantSpectral(), Fisheye(8), chunk=0)


# ------------------------------------------------------------------------------------------
# Tone mapping and display values
# ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("tm", ["clamp", "reinhard", "filmic"])
def test_tonemaps_monotone_in_unit_interval(tm):
    x = np.concatenate([[-1.0, 0.0], np.logspace(-6, 6, 2000)])
    y = img.tonemap_curve(x, tm)
    assert np.all((y >= 0) & (y <= 1))
    assert np.all(np.diff(y) >= 0)
    assert y[0] == 0.0 and y[1] == 0.0


def test_tonemap_values():
    # Reinhard 2002 eq. 3: 1 -> 0.5; Narkowicz 2015 at x = 1: 2.54 / 3.16
    assert img.tonemap_curve(1.0, "reinhard") == pytest.approx(0.5)
    assert img.tonemap_curve(1.0, "filmic") == pytest.approx(2.54 / 3.16)
    assert img.tonemap_curve(2.0, "clamp") == 1.0


def test_auto_exposure_key_and_sun_excluded():
    Y = np.full((8, 8), 2000.0)
    Y[0, 0] = 1.6e9  # a sun pixel: left out of the log average
    im = SkyImage(np.stack([_d65_xyz(v) for v in Y.ravel()]).reshape(8, 8, 3), "xyz")
    assert im.auto_exposure() == pytest.approx(0.18 / 2000.0, rel=1e-6)
    out = im.to_srgb(tonemap="clamp")
    # key 0.18 through the sRGB transfer function: 1.055 * 0.18^(1/2.4) - 0.055
    assert out[3, 3] == pytest.approx([0.46135612950044164] * 3, abs=2e-4)
    assert out[0, 0] == pytest.approx([1.0] * 3, abs=1e-12)
    assert np.all((out >= 0) & (out <= 1))


def test_masked_pixels_black_and_negatives_clipped():
    data = np.zeros((4, 4, 3))
    data[...] = _d65_xyz(100.0)
    data[0, 0] = [0.0, 50.0, 300.0]  # far outside the sRGB gamut: negative R
    mask = np.ones((4, 4), bool)
    mask[3, 3] = False
    im = SkyImage(data, "xyz", mask=mask)
    assert im.linear_srgb()[0, 0].min() < 0
    out = im.to_srgb(exposure=0.001, tonemap="reinhard")
    assert np.all(out[3, 3] == 0.0)
    assert np.all(out >= 0.0)


# ------------------------------------------------------------------------------------------
# Writers
# ------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def sky_image():
    sun = Sun(elevation_deg=35.0, azimuth_deg=150.0)

    class Gradient(ConstantSpectral):
        def radiance(self, directions, wavelengths_nm):
            d = np.asarray(directions)
            w = np.asarray(wavelengths_nm)
            return (0.002 + 0.02 * np.clip(d[..., 2], 0, 1))[..., None] * (500.0 / w) ** 4

    return render(Gradient(sun=sun, sun_level=2.0e4), Fisheye(48))


def test_exr_round_trip(tmp_path, sky_image):
    path = tmp_path / "sky.exr"
    sky_image.save(path)
    ch = img.read_exr(path)
    rgb = sky_image.linear_srgb()
    for k, name in enumerate("RGB"):
        assert ch[name].dtype == np.float32
        assert np.allclose(ch[name], rgb[..., k], rtol=1e-6, atol=1e-30)
    assert np.allclose(ch["Y"], sky_image.luminance(), rtol=1e-6)
    h = ch["header"]
    assert "cd/m^2" in h["units"]
    assert h["skydome:model"] == "constant"
    assert "fisheye" in h["skydome:projection"]
    assert h["whiteLuminance"] == 1.0
    assert [p for p in os.listdir(tmp_path)] == ["sky.exr"]


def test_hdr_round_trip(tmp_path, sky_image):
    path = tmp_path / "sky.hdr"
    sky_image.save(path)
    back = img.read_hdr(path)
    ref = np.maximum(sky_image.linear_srgb(), 0) / 179.0
    # RGBE keeps 8 bits of mantissa of the largest component: 1 % of it
    err = np.abs(back - ref) / np.maximum(ref.max(axis=-1, keepdims=True), 1e-30)
    assert err[sky_image.mask].max() < 0.01
    text = path.read_bytes()[:4000]
    assert text.startswith(b"#?RADIANCE\n") and b"FORMAT=32-bit_rle_rgbe" in text
    assert b"EXPOSURE" not in text and b"\n\n-Y 48 +X 48\n" in text


def test_rgbe_encoding_values():
    # [Ward91]: 1.0 = 0.5 * 2^1 -> mantissa 128, exponent 129; decode (c + 0.5) 2^(e-136)
    enc = img.rgbe_encode(np.array([[1.0, 0.5, 0.0], [0.0, 0.0, 0.0]]))
    assert enc.tolist() == [[128, 64, 0, 129], [0, 0, 0, 0]]
    assert img.rgbe_decode(enc)[0].tolist() == pytest.approx([128.5 / 128, 64.5 / 128, 0.5 / 128])


def test_hdr_read_by_radiance(tmp_path, sky_image):
    import _radiance

    path = tmp_path / "sky.hdr"
    sky_image.save(path)
    out = _radiance.run_radiance("pvalue", ["-h", "-H", "-d", str(path)])
    vals = np.array(out.split(), dtype=float).reshape(48, 48, 3)
    ref = np.maximum(sky_image.linear_srgb(), 0) / 179.0
    err = np.abs(vals - ref) / np.maximum(ref.max(axis=-1, keepdims=True), 1e-30)
    assert err[sky_image.mask].max() < 0.01
    info = _radiance.run_radiance("getinfo", [str(path)])
    assert "VIEW= -vta" in info
    # pcomb re-writes the picture with Radiance's run-length encoded scanlines: our reader
    # must decode that to the same pixels
    import subprocess

    bindir, libdir = _radiance.radiance_paths()
    rle = tmp_path / "rle.hdr"
    with open(rle, "wb") as f:
        subprocess.run([str(bindir / "pcomb"), str(path)], stdout=f, check=True, timeout=60,
                       env={**os.environ, "RAYPATH": str(libdir)})
    assert rle.stat().st_size < path.stat().st_size
    assert np.array_equal(img.read_hdr(rle), img.read_hdr(path))


def test_hdr_luminance_convention_with_radiance(tmp_path):
    # Radiance's pvalue -b reports 0.265 R + 0.670 G + 0.065 B; times 179 lm/W that is the
    # luminance: a D65 white of 1000 cd/m^2 must read back as 1000 cd/m^2.
    import _radiance

    im = render(ConstantXYZ(_d65_xyz(1000.0)), Equirect(16))
    path = tmp_path / "white.hdr"
    im.save(path)
    out = _radiance.run_radiance("pvalue", ["-h", "-H", "-d", "-b", str(path)])
    lum = 179.0 * np.array(out.split(), dtype=float)
    assert np.allclose(lum, 1000.0, rtol=0.01)


def test_png_8_and_16_bit(tmp_path, sky_image):
    from PIL import Image

    disp = sky_image.to_srgb()
    p8, p16 = tmp_path / "a.png", tmp_path / "b.png"
    sky_image.save(p8)
    sky_image.save(p16, bits=16)
    a = np.asarray(Image.open(p8))
    assert a.dtype == np.uint8 and a.shape == (48, 48, 3)
    assert np.array_equal(a, np.round(disp * 255).astype(np.uint8))
    b16 = img.read_png16(p16)
    assert np.array_equal(b16, np.round(disp * 65535).astype(np.uint16))
    im = Image.open(p16)
    im.load()
    assert im.size == (48, 48) and "Description" in im.info
    # Pillow reads 16-bit RGB as 8-bit RGB keeping the most significant byte
    assert np.array_equal(np.asarray(im.convert("RGB")), (b16 >> 8).astype(np.uint8))
    assert np.all(a[~sky_image.mask] == 0)


def test_png8_writer_read_back_by_pillow(tmp_path):
    # skydome's own 8-bit PNG encoder (rows filtered "Up") decoded by Pillow, an independent
    # PNG reader: the same pixels, the sRGB chunk, the text chunks; random values and a
    # gradient (wrap-around of the filter's byte differences modulo 256 on both)
    from PIL import Image

    rng = np.random.default_rng(3)
    for a in (rng.integers(0, 256, size=(37, 53, 3), dtype=np.uint8),
              (np.add.outer(np.arange(64), np.arange(80))[..., None] * [1, 3, 7] % 256
               ).astype(np.uint8)):
        p = tmp_path / "a.png"
        img.write_png8(p, a, {"Description": '{"units": "x"}', "Software": "skydome test"})
        im = Image.open(p)
        im.load()
        assert im.mode == "RGB" and im.size == (a.shape[1], a.shape[0])
        assert np.array_equal(np.asarray(im), a)
        assert im.info["Description"] == '{"units": "x"}' and im.info["Software"] == "skydome test"
        assert im.info.get("srgb") == 0
        assert np.array_equal(img.read_png16(p), a.astype(np.uint16) * 257)
    with pytest.raises(ValueError, match="rgb8"):
        img.write_png8(tmp_path / "b.png", np.zeros((4, 4, 3), dtype=np.uint16))


def test_bad_paths_raise_and_leave_nothing(tmp_path, sky_image):
    for bad in (tmp_path / "sky.jpg", tmp_path / "sky"):
        with pytest.raises(ValueError, match=bad.name):
            sky_image.save(bad)
        with pytest.raises(ValueError, match=bad.name):
            img.check_output_path(bad)
    with pytest.raises(ValueError, match=r"\.exr, \.hdr, \.png"):
        img.check_output_path(tmp_path / "sky.tif")
    missing = tmp_path / "no" / "such" / "sky.png"
    with pytest.raises(ValueError, match="sky.png"):
        sky_image.save(missing)
    (tmp_path / "afile").write_text("x")
    with pytest.raises(ValueError, match="sky.exr"):
        img.check_output_path(tmp_path / "afile" / "sky.exr")
    assert sorted(os.listdir(tmp_path)) == ["afile"]


@pytest.mark.skipif(hasattr(os, "geteuid") and os.geteuid() == 0,
                    reason="root can write into read-only folders")
def test_unwritable_folder(tmp_path, sky_image):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        with pytest.raises(ValueError, match="out.png"):
            sky_image.save(ro / "out.png")
    finally:
        ro.chmod(0o700)
    assert os.listdir(ro) == []


def test_failed_write_leaves_no_temp_file(tmp_path, sky_image, monkeypatch):
    def boom(*a, **k):
        raise RuntimeError("disk full")

    monkeypatch.setattr(img, "rgbe_encode", boom)
    with pytest.raises(RuntimeError):
        sky_image.save(tmp_path / "x.hdr")
    assert os.listdir(tmp_path) == []
    # an existing file is left untouched by a failed write
    (tmp_path / "x.hdr").write_bytes(b"old")
    with pytest.raises(RuntimeError):
        sky_image.save(tmp_path / "x.hdr")
    assert os.listdir(tmp_path) == ["x.hdr"] and (tmp_path / "x.hdr").read_bytes() == b"old"


def test_import_is_light():
    import subprocess
    import sys

    code = ("import sys, skydome.imaging; "
            "print(any(m in sys.modules for m in ('numba', 'matplotlib', 'OpenEXR', 'PIL')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_package_level_render_after_subpackage_import():
    # ``skydome.render`` is the function and the package is ``skydome.imaging``: importing
    # the package's submodules, in every form, leaves the function in place.
    import skydome as sd
    import skydome.imaging.sun_disc as _sd  # noqa: F401
    from skydome.imaging import make_projection as _mp  # noqa: F401

    assert callable(sd.render) and sd.render.__module__ == "skydome.imaging"
    assert sd.imaging.sun_disc is _sd

    im = sd.render(ConstantSpectral(c=0.02), sd.Fisheye(8))
    assert isinstance(im, SkyImage) and im.data.shape == (8, 8, 16)


def test_fused_xyz_path_equals_spectral_then_xyz():
    # output="xyz" folds the spectrum -> XYZ step into one matrix: the same XYZ as the
    # spectral image converted afterwards (CIE 1931 integration of the same spectra)
    import skydome as sd

    sun = Sun(elevation_deg=20.0, azimuth_deg=120.0)
    wl = np.linspace(380.0, 780.0, 12)
    for sky in (sd.model("single_scattering", sun=sun),
                sd.model("precomputed", sun=sun, scattering_r_size=8, scattering_mu_size=32,
                         scattering_mu_s_size=8, orders=2, n_wavelengths=6)):
        p = Equirect(48)
        a = render(sky, p, wl, draw_sun=False)
        b = render(sky, p, wl, output="xyz", draw_sun=False)
        assert a.kind == "spectral" and b.kind == "xyz" and b.wavelengths_nm is None
        assert np.allclose(b.data, a.xyz(), rtol=1e-9, atol=1e-12 * a.xyz().max())
        # with the sun (limb darkening per XYZ channel instead of per wavelength): the
        # image's luminance flux is the same to 0.5 %
        om = p.solid_angles()
        fa = (render(sky, p, wl).luminance() * om).sum()
        fb = (render(sky, p, wl, output="xyz").luminance() * om).sum()
        assert fb == pytest.approx(fa, rel=0.005)
    with pytest.raises(ValueError, match="output"):
        render(sky, p, wl, output="rgb")
