"""Dobashi, Yamamoto & Nishita 2002 aerial perspective and light shafts
(skydome.effects.dobashi2002): limits, colour signatures, tables against direct quadrature,
shadowed in-scattering, the synthetic scene."""

import numpy as np
import pytest

import skydome as sd
from skydome.effects.dobashi2002 import (Camera, Heightmap, apply_aerial_perspective,
                                         build_tables, inscatter_direct, shadow_volume_top,
                                         synthetic_mountains)

WL = np.linspace(400.0, 700.0, 7)
SIDE_SUN = sd.Sun(elevation_deg=30.0, azimuth_deg=90.0)
CAM = Camera(fov_deg=40.0, azimuth_deg=0.0, elevation_deg=0.0, altitude_m=100.0)


def test_zero_distance_changes_nothing():
    """Eq. (1) with s = 0: T = 1, no in-scattering (rgb and spectral)."""
    rng = np.random.default_rng(0)
    img = rng.random((6, 8, 3))
    out = apply_aerial_perspective(img, np.zeros((6, 8)), CAM, SIDE_SUN)
    np.testing.assert_allclose(out, img, rtol=0, atol=1e-15)
    spec = rng.random((6, 8, WL.size)) * 0.1
    out = apply_aerial_perspective(spec, np.zeros((6, 8)), CAM, SIDE_SUN, wavelengths_nm=WL)
    np.testing.assert_allclose(out, spec, rtol=0, atol=1e-15)


def test_sky_pixels_unchanged():
    img = np.full((4, 4, 3), 0.3)
    depth = np.full((4, 4), np.inf)
    depth[2:] = 5000.0
    out = apply_aerial_perspective(img, depth, CAM, SIDE_SUN)
    np.testing.assert_array_equal(out[:2], img[:2])
    assert not np.allclose(out[2:], img[2:])


def _column(atm, distances):
    """A dark grey object (0.03) seen at several distances, one per image row."""
    img = np.full((len(distances), 1, 3), 0.03)
    depth = np.asarray(distances, dtype=float)[:, None]
    cam = Camera(fov_deg=1.0, azimuth_deg=0.0, elevation_deg=0.0, altitude_m=100.0)
    return apply_aerial_perspective(img, depth, cam, SIDE_SUN, atmosphere=atm)[:, 0]


def _saturation(rgb):
    return (rgb.max(-1) - rgb.min(-1)) / rgb.max(-1)


def test_distant_pixels_bluer_and_brighter_in_clear_air_greyer_in_haze():
    """Clear air (Rayleigh, turbidity 1.2): airlight is blue (Rayleigh lambda^-4), so a dark
    object grows brighter and bluer with distance; in haze (turbidity 12) the grey aerosol
    airlight dominates: the far object is less saturated than in clear air. (Survey sec.
    3: Rayleigh vs Mie wavelength dependence.)"""
    d = [0.0, 2e3, 8e3, 25e3]
    clear = _column(sd.Atmosphere.earth(turbidity=1.2), d)
    haze = _column(sd.Atmosphere.earth(turbidity=12.0), d)
    Y = clear @ np.array([0.2126, 0.7152, 0.0722])
    assert np.all(np.diff(Y) > 0)
    br = clear[:, 2] / clear[:, 0]
    assert np.all(np.diff(br) > 0) and br[-1] > 1.3
    assert _saturation(haze[-1]) < 0.7 * _saturation(clear[-1])


@pytest.mark.parametrize("elev", [2.0, 10.0, 40.0])
def test_tables_agree_with_direct_quadrature(elev):
    """The interpolated 2D tables (64 x 64) against direct quadrature (20000 nodes) of the
    same integrals at random (distance, angle) off the nodes: in-scattered light
    sum_c beta_c J_c and transmittance agree within 1 % (measured: 0.05-0.6 % and 0.4 %)."""
    atm = sd.Atmosphere.earth(turbidity=2.5)
    sun = sd.Sun(elevation_deg=elev, azimuth_deg=0.0)
    tab = build_tables(atm, WL, sun, 300.0, 40e3, (-0.3, 0.3), 64, 64)
    props = atm.optical_properties(WL)
    rng = np.random.default_rng(1)
    n = 0
    while n < 8:
        t, mu = rng.uniform(100.0, 40e3), rng.uniform(-0.3, 0.3)
        if mu * t + t * t / (2 * 6360e3) + 300.0 < 0.0:      # below the ground
            continue
        n += 1
        J, D = inscatter_direct(atm, WL, sun, 300.0, t, mu, samples=20000)
        Jt = tab.inscatter_integrals(np.array(t), np.array(mu))
        Dt = tab.columns(np.array(t), np.array(mu))
        np.testing.assert_allclose((props.scattering * Jt).sum(0), (props.scattering * J).sum(0),
                                   rtol=0.01)
        np.testing.assert_allclose(np.exp(-(Dt @ props.extinction)), np.exp(-(D @ props.extinction)),
                                   rtol=0.01)


def _wall_scene():
    """Flat ground with a 1500 m high wall west of the view (x in [-1500, -1000] m, y in
    [2000, 6000] m); with the sun from the west 40 deg up its shadow covers the ground
    ahead of the camera up to S(x) = 1500 - (x + 1000) tan 40 deg."""
    x = np.arange(-6000.0, 6001.0, 100.0)
    y = np.arange(-1000.0, 12001.0, 100.0)
    X, Y = np.meshgrid(x, y)
    H = np.where((X >= -1500) & (X <= -1000) & (Y >= 2000) & (Y <= 6000), 1500.0, 0.0)
    return Heightmap(H, x, y), sd.Sun(elevation_deg=40.0, azimuth_deg=270.0)


def test_shadow_volume_top():
    """Closed form behind a wall: S(x) = h - (x - x_wall) tan(elevation)."""
    hm, sun = _wall_scene()
    top = shadow_volume_top(hm, sun.direction)
    j = np.searchsorted(hm.y_m, 4000.0)
    i = np.searchsorted(hm.x_m, 0.0)
    assert top[j, i] == pytest.approx(1500.0 - 1000.0 * np.tan(np.radians(40.0)), abs=90.0)
    assert top[np.searchsorted(hm.y_m, 9000.0), i] == 0.0     # nothing in front of it


def test_light_shafts_shadowed_rays_get_less_inscattering():
    """Rays through the wall's shadow receive less in-scattered light than with the sun
    everywhere; rays that miss the shadow are unchanged (the slab sum telescopes)."""
    hm, sun = _wall_scene()
    img = np.zeros((3, 9, 3))
    cam = Camera(fov_deg=60.0, azimuth_deg=0.0, elevation_deg=4.0, altitude_m=100.0)
    dz = cam.ray_directions(9, 3)[..., 2]
    depth = np.where(dz < 0, np.minimum(9000.0, 100.0 / np.maximum(-dz, 1e-9)), 9000.0)  # ground
    lit = apply_aerial_perspective(img, depth, cam, sun)
    shaded = apply_aerial_perspective(img, depth, cam, sun, shafts=True, heightmap=hm, n_planes=64)
    assert np.all(shaded <= lit * (1 + 1e-9) + 1e-15)
    # the centre pixel (x = 0, 4 deg up) runs through the shadow (top 660 m) from y = 2 to 6 km
    assert shaded[1, 4].sum() < 0.8 * lit[1, 4].sum()
    # the rightmost column (azimuth 27 deg) passes east of the shadow (x > 1 km at y = 2 km)
    dirs = cam.ray_directions(9, 3)
    assert 2000.0 * dirs[-1, -1, 0] / dirs[-1, -1, 1] > 1000.0
    np.testing.assert_allclose(shaded[:, -1], lit[:, -1], rtol=1e-9)


def test_synthetic_mountains_scene():
    img, depth, hm = synthetic_mountains(64, 36, seed=3)
    assert img.shape == (36, 64, 3) and depth.shape == (36, 64)
    assert np.all(img >= 0) and np.all(np.isfinite(img))
    assert np.all(np.isinf(depth[0])) and np.all(np.isfinite(depth[-1]))
    finite = np.isfinite(depth)
    assert 0.2 < finite.mean() < 0.95
    # farther terrain appears higher in the image: depth decreases down every column
    col = np.where(finite, depth, np.nan)
    upper = np.nanmedian(col[: 18][finite[:18]]) if finite[:18].any() else np.inf
    lower = np.nanmedian(col[18:][finite[18:]])
    assert upper > lower
    # the hit points lie on the heightmap (ray altitude = terrain height within 25 m)
    from skydome.effects.dobashi2002 import DEFAULT_CAMERA, _altitude_flat_consistent

    dirs = DEFAULT_CAMERA.ray_directions(64, 36)
    t = depth[finite]
    d = dirs[finite]
    alt = _altitude_flat_consistent(t, d[:, 2], DEFAULT_CAMERA.altitude_m)
    ground = hm.height(t * d[:, 0], t * d[:, 1])
    assert np.percentile(np.abs(alt - ground), 95) < 25.0
    img2, depth2, _ = synthetic_mountains(64, 36, seed=3)
    np.testing.assert_array_equal(depth, depth2)


def test_invalid_inputs():
    img = np.zeros((4, 4, 3))
    with pytest.raises(ValueError, match="depth_m shape"):
        apply_aerial_perspective(img, np.zeros((3, 4)), CAM, SIDE_SUN)
    with pytest.raises(ValueError, match="depth_m"):
        apply_aerial_perspective(img, -np.ones((4, 4)), CAM, SIDE_SUN)
    with pytest.raises(ValueError, match="heightmap"):
        apply_aerial_perspective(img, np.ones((4, 4)), CAM, SIDE_SUN, shafts=True)
    with pytest.raises(ValueError, match="method"):
        apply_aerial_perspective(img, np.ones((4, 4)), CAM, SIDE_SUN, method="fast")
    with pytest.raises(ValueError, match="fov_deg"):
        Camera(fov_deg=0.0)
    with pytest.raises(ValueError, match="channels"):
        apply_aerial_perspective(np.zeros((4, 4, 5)), np.ones((4, 4)), CAM, SIDE_SUN)


def test_camera_tuple_and_sun_below_horizon():
    """(fov, direction) cameras; a sun below the horizon adds no direct-sun airlight and
    produces no NaN."""
    img = np.full((3, 3, 3), 0.2)
    depth = np.full((3, 3), 4000.0)
    out = apply_aerial_perspective(img, depth, (40.0, [0.0, 1.0, 0.0]), sd.Sun(elevation_deg=-10.0,
                                                                              azimuth_deg=90.0))
    assert np.all(np.isfinite(out)) and np.all(out >= 0) and np.all(out <= img + 1e-12)
