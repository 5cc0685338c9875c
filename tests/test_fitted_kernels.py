"""The ``fitted`` model's lookup kernel: its arithmetic arctangent against the C library's
``atan2`` (through ``math.atan2``), and its lookups against the inverse mappings of the
view grid written here with numpy's ``arccos`` and ``arctan2`` (the definitions of
skydome/models/fitted/_grid.py, independent of the kernel's code)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import skydome as sd
from skydome.models.fitted import _grid


def test_atan2_pos_matches_the_library_atan2():
    from skydome.models.fitted._kernels import atan2_pos

    rng = np.random.default_rng(5)
    s = np.abs(rng.normal(size=3000)) * rng.choice([1e-12, 1e-3, 1.0, 1e6], 3000)
    c = rng.normal(size=3000) * rng.choice([1e-12, 1e-3, 1.0, 1e6], 3000)
    # the ends and the boundaries of the argument reductions
    edges = [(0.0, 1.0), (0.0, -1.0), (1.0, 0.0), (1.0, 1.0), (1.0, -1.0)]
    edges += [(math.tan(k * math.pi / 24.0), 1.0) for k in range(1, 12)]
    edges += [(1.0, math.tan(k * math.pi / 24.0)) for k in range(1, 12)]
    for si, ci in list(zip(s, c)) + edges:
        ref = math.atan2(si, ci)
        assert abs(atan2_pos(si, ci) - ref) <= 4.0 * math.ulp(max(ref, 1e-300)) + 1e-300, \
            (si, ci)


def _reference_lookup(sky, d):
    """The bilinear lookup with numpy's arccos / arctan2 (the mappings of _grid.py)."""
    table = sky._table
    u = d / np.linalg.norm(d, axis=1)[:, None]
    th = np.arccos(np.clip(u[:, 2], -1.0, 1.0))
    th_h = _grid.horizon_zenith_rad(sky.observer_altitude_m)
    sky_side = th < th_h
    x = np.where(sky_side, np.sqrt(np.maximum(1.0 - th / (th_h - _grid.EPS), 0.0)),
                 np.sqrt(np.maximum((th - th_h - _grid.EPS) / (math.pi - th_h - _grid.EPS),
                                    0.0)))
    n_u = np.where(sky_side, _grid.N_SKY, _grid.N_GROUND)
    uu = x * (n_u - 1)
    iu = np.minimum(uu.astype(int), n_u - 2)
    fu = uu - iu
    r0 = np.where(sky_side, 0, _grid.N_SKY) + iu
    az = math.radians(float(sky.sun.azimuth_deg))
    cp = u[:, 0] * math.sin(az) + u[:, 1] * math.cos(az)
    sp = np.abs(u[:, 0] * math.cos(az) - u[:, 1] * math.sin(az))
    phi = np.arctan2(sp, cp) / math.pi
    a, b = _grid.A_PHI, 1.0 - _grid.A_PHI
    t = (-a + np.sqrt(a * a + 4.0 * b * phi)) / (2.0 * b) * (_grid.N_PHI - 1)
    it = np.minimum(t.astype(int), _grid.N_PHI - 2)
    ft = np.maximum(t - it, 0.0)
    w = [((1 - fu) * (1 - ft), 0, 0), ((1 - fu) * ft, 0, 1), (fu * (1 - ft), 1, 0),
         (fu * ft, 1, 1)]
    return sum(wi[:, None] * table[r0 + du, it + dt] for wi, du, dt in w)


@pytest.mark.parametrize("elevation, azimuth, altitude", [
    (35.0, 160.0, 0.0), (-1.5, 20.0, 15000.0), (5.0, 275.0, 1234.0), (90.0, 0.0, 0.0)])
def test_lookup_matches_the_grid_mappings(elevation, azimuth, altitude):
    sky = sd.model("fitted", sun=sd.Sun(elevation_deg=elevation, azimuth_deg=azimuth),
                   observer_altitude_m=altitude)
    rng = np.random.default_rng(11)
    d = rng.normal(size=(20000, 3)) * rng.uniform(0.01, 100.0, size=(20000, 1))
    ref = _reference_lookup(sky, d)
    got = sky._lookup(d, sky._table)
    assert got.shape == ref.shape
    # the angles agree within a few units in the last place, which the square-root
    # mappings amplify next to the horizon's node: 1e-9 relative is far above that and far
    # below any change of cell or weight
    scale = np.maximum(np.abs(ref), 1e-12 * np.abs(ref).max())
    assert np.max(np.abs(got - ref) / scale) < 1e-9


def test_spectral_basis_is_the_radiance():
    """The renderer's basis (only the table wavelengths that reach the request) gives the
    model's radiance: sample(d) @ B == radiance(d, wl)."""
    sky = sd.model("fitted", sun=sd.Sun(elevation_deg=20.0, azimuth_deg=100.0))
    d = np.random.default_rng(2).normal(size=(5000, 3))
    for wl in (np.linspace(380.0, 780.0, 41), [300.0], [555.0, 1100.0]):
        sample, B = sky._spectral_basis(wl)
        full = sky._lookup(d, sky._table) @ sky._weights(np.asarray(wl, float))
        np.testing.assert_allclose(sample(d) @ B, full, rtol=1e-12, atol=0.0)
        np.testing.assert_allclose(sky.radiance(d, wl), full, rtol=1e-12, atol=0.0)


def test_extreme_lengths_give_the_same_values():
    """Directions whose squares overflow or vanish are looked up like their unit vectors."""
    sky = sd.model("fitted", sun=sd.Sun(elevation_deg=30.0, azimuth_deg=200.0))
    u = np.random.default_rng(4).normal(size=(300, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    u = np.vstack([u, [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]])
    ref = sky.luminance(u)
    for scale in (1e-300, 1e-160, 1e160, 1e300):
        got = sky.luminance(u * scale)
        assert np.all(np.isfinite(got)) and np.all(got >= 0.0)
        np.testing.assert_allclose(got, ref, rtol=1e-9)
