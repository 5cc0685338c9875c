"""The environment map's numba kernels (skydome.export._kernels_envmap) against
independent references: numpy's own float64 -> float16 / float32 casts (its C rounding
code), exact rational arithmetic (Python's fractions) for the fused multiply-add chain of
the XYZ -> RGB product, and numpy's products for the directions."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from skydome._threads import run_ranges
from skydome.export import _kernels_envmap as K


def _all_half_edges() -> np.ndarray:
    """Every finite half value, the midpoints between neighbours and the doubles one ulp
    either side of them (ties and near-ties, normal and subnormal), both signs, plus
    infinities, NaN, the overflow edge and values far outside the half range."""
    h = np.arange(0, 0x7C00, dtype=np.uint16).view(np.float16).astype(np.float64)
    mid = 0.5 * (h[:-1] + h[1:])                                   # exact in float64
    top = np.float64(65504.0) + 16.0                               # the tie to infinity
    v = np.concatenate([h, mid, np.nextafter(mid, 0.0), np.nextafter(mid, np.inf),
                        [top, np.nextafter(top, 0.0), np.nextafter(top, np.inf), 1e300,
                         1e-300, 5e-324, 2.0 ** -25, np.nextafter(2.0 ** -25, 1.0),
                         np.nextafter(2.0 ** -25, 0.0), np.inf]])
    return np.concatenate([v, -v])


def test_half_planes_round_as_numpy():
    v = _all_half_edges()
    rng = np.random.default_rng(7)
    v = np.concatenate([v, rng.lognormal(0.0, 8.0, 200_000) * rng.choice([-1.0, 1.0], 200_000)])
    v = v[: v.size // 3 * 3].reshape(-1, 3)
    out = np.empty((3, v.shape[0]), dtype=np.uint16)
    with np.errstate(over="ignore"):
        ref = v.astype(np.float16)
    # on threads, as the export runs it (skydome._threads.run_ranges), in ranges of 1000
    run_ranges(K.half_planes, v.shape[0], (v.view(np.uint64), *out), 1000)
    for c in range(3):
        assert np.array_equal(out[c], ref[:, c].view(np.uint16)), c


def test_half_planes_nan():
    v = np.array([[np.nan, -np.nan, 1.0]])
    out = np.empty((3, 1), dtype=np.uint16)
    K.half_planes(v.view(np.uint64), *out, 0, 1)
    h = out.view(np.float16)
    assert np.isnan(h[0, 0]) and np.isnan(h[1, 0]) and h[2, 0] == 1.0


def test_float32_planes_as_numpy():
    rng = np.random.default_rng(3)
    v = rng.lognormal(0.0, 30.0, (100_000, 3)) * rng.choice([-1.0, 1.0], (100_000, 3))
    out = np.empty((3, v.shape[0]), dtype=np.float32)
    run_ranges(K.float32_planes, v.shape[0], (v, *out), 1000)
    with np.errstate(over="ignore"):
        ref = v.astype(np.float32)
    assert np.array_equal(out.view(np.uint32), ref.T.view(np.uint32))


def _fma_chain_exact(x, y, z, m0, m1, m2, k):
    """round(round(round(x m0) + y m1) + z m2) / k, each step rounded once (exact
    rational arithmetic, then Python's correctly rounded int / int), clipped at 0."""
    a = float(Fraction(x) * Fraction(m0))
    b = float(Fraction(y) * Fraction(m1) + Fraction(a))
    c = float(Fraction(z) * Fraction(m2) + Fraction(b))
    v = c / k
    return v if v > 0.0 else 0.0


def test_xyz_to_map_rgb_exact_chain_and_close_to_numpy():
    from skydome.spectra import _M_XYZ_TO_SRGB as M
    from skydome.spectra import xyz_to_linear_srgb

    rng = np.random.default_rng(11)
    xyz = rng.lognormal(0.0, 3.0, (3000, 3)) * rng.choice([1.0, -1.0, 0.0], (3000, 3),
                                                           p=[0.8, 0.1, 0.1])
    got = xyz.copy()
    assert K.xyz_to_map_rgb(got, M, 683.0) == 0
    for i in range(0, 3000, 7):
        for j in range(3):
            assert got[i, j] == _fma_chain_exact(*xyz[i], *M[j], 683.0)
    # the numpy definition of the map's RGB (BLAS product) to the last bits
    ref = np.maximum(xyz_to_linear_srgb(xyz) / 683.0, 0.0)
    np.testing.assert_allclose(got, ref, rtol=1e-14, atol=1e-300)
    assert not np.any(np.signbit(got))                   # no -0 (numpy's maximum gives +0)


def test_xyz_to_map_rgb_counts_non_finite():
    from skydome.spectra import _M_XYZ_TO_SRGB as M

    a = np.array([[1.0, 2.0, 3.0], [np.nan, 0.0, 0.0], [0.0, np.inf, 0.0]])
    assert K.xyz_to_map_rgb(a, M, 683.0) == 2


def test_map_rgb_rejects_nan():
    from skydome.export.envmap import _xyz_to_map_rgb

    a = np.zeros((2, 2, 3))
    a[1, 1, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        _xyz_to_map_rgb(a, np.ones((2, 2), dtype=bool))


@pytest.mark.parametrize("conv", ["skydome", "blender", "mitsuba", "unreal", "three"])
def test_latlong_directions_equal_direction_from_pixel(conv):
    from skydome.export.envmap import MapProjection

    p = MapProjection(conv, 64, 32)
    if p.layout != "latlong":
        pytest.skip("not a lat-long convention")
    d, m = p.directions()
    rows, cols = np.meshgrid(np.arange(32) + 0.5, np.arange(64) + 0.5, indexing="ij")
    ref = p.direction_from_pixel(rows, cols)
    assert m.all()
    assert np.array_equal(d, ref)


@pytest.mark.parametrize("size,ground", [("96x48", "lambertian"), ("100x51", "black"),
                                         ("64x33", 0.5)])
def test_bands_equal_one_render_of_the_whole_map(size, ground):
    """A lat-long map rendered in bands of rows (and its ground row copied) holds the
    pixels of one imaging.render of the whole map, bit for bit (odd heights put a row on
    the horizon; widths that do not divide the chunk shift the chunk boundaries)."""
    import skydome as sd
    from skydome.export.envmap import MapProjection, _xyz_to_map_rgb, render_envmap
    from skydome.imaging import render
    from skydome.spectra import wavelength_grid

    sky = sd.model("preetham1999", sun=sd.Sun(elevation_deg=30.0, azimuth_deg=135.0))
    wl = wavelength_grid(380.0, 780.0, n=16)
    W, H = (int(v) for v in size.split("x"))
    kw = {"ground": "lambertian", "ground_albedo": ground} if isinstance(ground, float) else {
        "ground": ground}
    env = render_envmap(sky, "skydome", size, wavelengths_nm=wl, **kw)
    proj = MapProjection("skydome", W, H)
    img = render(sky, proj, wl, draw_sun=False, output="xyz",
                 ground=ground if isinstance(ground, float) else ground, chunk=1000)
    ref = _xyz_to_map_rgb(img.data, img.mask)
    assert np.array_equal(env.images["map"], ref)
    assert env.sun_light is not None and img.sun_light is not None
