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
    """The lookup with numpy's arccos / arctan2 (the mappings of _grid.py): the Catmull-Rom
    spline along the rows, linear in azimuth, clamped at 0."""
    return _reference_lookup_table(sky, sky._table, d)


def _catmull_rom(p0, p1, p2, p3, f):
    """The Catmull-Rom spline between p1 (f = 0) and p2 (f = 1) in its textbook form
    (Catmull & Rom 1974): p1 + f (p2 - p0) / 2 + f^2 (2 p0 - 5 p1 + 4 p2 - p3) / 2
    + f^3 (3 p1 - 3 p2 + p3 - p0) / 2."""
    f = f[:, None]
    return p1 + 0.5 * f * ((p2 - p0) + f * ((2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3)
                                            + f * (3.0 * (p1 - p2) + p3 - p0)))


def _reference_lookup_table(sky, table, d):
    """The same in the angular table ``table`` (N_SKY + N_GROUND, N_PHI, C); beyond a
    part's (the sky's or the ground's) first and last rows, the rows on the straight line
    through its two end rows."""
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
    base = np.where(sky_side, 0, _grid.N_SKY)
    az = math.radians(float(sky.sun.azimuth_deg))
    cp = u[:, 0] * math.sin(az) + u[:, 1] * math.cos(az)
    sp = np.abs(u[:, 0] * math.cos(az) - u[:, 1] * math.sin(az))
    phi = np.arctan2(sp, cp) / math.pi
    a, b = _grid.A_PHI, 1.0 - _grid.A_PHI
    t = (-a + np.sqrt(a * a + 4.0 * b * phi)) / (2.0 * b) * (_grid.N_PHI - 1)
    it = np.minimum(t.astype(int), _grid.N_PHI - 2)
    ft = np.maximum(t - it, 0.0)[:, None]

    def row(k):        # row k of the part, linear in azimuth; k = -1 and n_u: extrapolated
        inside = np.clip(k, 0, n_u - 1)
        v = table[base + inside, it] * (1.0 - ft) + table[base + inside, it + 1] * ft
        below = (k < 0)[:, None]
        above = (k > n_u - 1)[:, None]
        v = np.where(below, 2.0 * row(np.zeros_like(k)) - row(np.ones_like(k)), v) \
            if below.any() else v
        v = np.where(above, 2.0 * row(n_u - 1) - row(n_u - 2), v) if above.any() else v
        return v

    return np.maximum(_catmull_rom(row(iu - 1), row(iu), row(iu + 1), row(iu + 2), fu), 0.0)


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


@pytest.mark.parametrize("n", [0, 1, 255, 256, 257, 3001])
def test_luminance_and_xyz_match_the_grid_mappings(n):
    """The kernel's one-channel and three-channel paths (and the block edges of its loop)
    against the numpy lookup in the luminance and XYZ tables, over the whole sphere."""
    sky = sd.model("fitted", sun=sd.Sun(elevation_deg=12.0, azimuth_deg=300.0),
                   observer_altitude_m=7000.0, aerosol_optical_depth=0.3)
    d = np.random.default_rng(n).normal(size=(n, 3))
    m = sky._xyz_matrix()
    for got, table in ((sky.xyz(d), sky._table @ m),
                       (sky.luminance(d)[:, None], sky._table @ m[:, 1:2])):
        ref = _reference_lookup_table(sky, table, d)
        assert got.shape == ref.shape == (n, table.shape[2])
        if n:
            scale = np.maximum(np.abs(ref), 1e-12 * np.abs(ref).max())
            assert np.max(np.abs(got - ref) / scale) < 1e-9
            assert np.all(got >= 0.0)


def test_axes_and_grid_nodes_match_the_grid_mappings():
    """The zenith, the nadir, the horizon, the sun's vertical plane and the grid's own
    nodes (where a cell index changes) against the numpy lookup."""
    sky = sd.model("fitted", sun=sd.Sun(elevation_deg=3.0, azimuth_deg=90.0),
                   observer_altitude_m=15000.0)
    nodes = _grid.directions(15000.0, 90.0).reshape(-1, 3)
    mids = _grid.directions(15000.0, 90.0, midpoints=True).reshape(-1, 3)
    axes = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0],
                     [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [1.0, 0.0, 1e-9], [1.0, 0.0, -1e-9],
                     [1e-12, 0.0, 1.0], [-1e-12, 1e-12, -1.0]])
    d = np.vstack([nodes, mids, axes])
    table = sky._table @ sky._xyz_matrix()
    ref = _reference_lookup_table(sky, table, d)
    got = sky.xyz(d)
    scale = np.maximum(np.abs(ref), 1e-12 * np.abs(ref).max())
    # at a node the cell may be the one below or above it: the value is the same there,
    # up to the node's rounding in the mappings (1e-9 relative covers it)
    assert np.max(np.abs(got - ref) / scale) < 1e-9


@pytest.mark.parametrize("bad, message", [
    (np.nan, "NaN or infinite"), (np.inf, "NaN or infinite"), (-np.inf, "NaN or infinite"),
    (0.0, "zero-length")])
def test_bad_directions_give_the_checks_errors(bad, message):
    """The kernel's own count of non-finite and zero-length rows raises the same errors as
    the shared check (flat_directions of the analytic models), wherever the row is."""
    from skydome.models.analytic._kernels_analytic import flat_directions

    sky = sd.model("fitted", sun=sd.Sun(elevation_deg=30.0, azimuth_deg=200.0))
    rng = np.random.default_rng(8)
    for n, row, col in ((1, 0, 2), (1000, 0, 0), (1000, 999, 1), (1000, 517, 2)):
        d = rng.normal(size=(n, 3))
        d[row] = [1.0, 0.5, 2.0] if bad != 0.0 else 0.0
        d[row, col] = bad
        with pytest.raises(ValueError, match=message) as ours:
            sky.luminance(d)
        with pytest.raises(ValueError) as shared:
            flat_directions(d)
        assert str(ours.value) == str(shared.value)
        for f in (sky.xyz, lambda v: sky.radiance(v, [550.0, 700.0])):
            with pytest.raises(ValueError, match=message):
                f(d)
    # both kinds at once: the non-finite row is named first, as by the shared check
    d = rng.normal(size=(600, 3))
    d[10] = 0.0
    d[400, 1] = np.nan
    with pytest.raises(ValueError, match="NaN or infinite"):
        sky.luminance(d)
    for shape in [(4, 2), (), (2,)]:
        with pytest.raises(ValueError, match=r"shape \(\.\.\., 3\)"):
            sky.luminance(np.ones(shape))


def test_leading_shapes_and_layouts():
    """Any leading shape, a non-contiguous view and a read-only array give the values of
    the same directions as one C-contiguous (N, 3) array."""
    sky = sd.model("fitted", sun=sd.Sun(elevation_deg=50.0, azimuth_deg=10.0))
    d = np.random.default_rng(9).normal(size=(6, 7, 3))
    flat = sky.xyz(d.reshape(-1, 3))
    np.testing.assert_array_equal(sky.xyz(d), flat.reshape(6, 7, 3))
    # (the luminance table is its own product of the spectral table: rounding apart)
    np.testing.assert_allclose(sky.luminance(d), flat[:, 1].reshape(6, 7), rtol=1e-13)
    f = np.asfortranarray(d.reshape(-1, 3))
    np.testing.assert_array_equal(sky.xyz(f), flat)
    r = d.reshape(-1, 3).copy()
    r.setflags(write=False)
    np.testing.assert_array_equal(sky.xyz(r), flat)
    np.testing.assert_array_equal(sky.xyz(d[0, 0]), flat[0])


def test_out_receives_the_values_of_a_call_without_it():
    """``out=`` (a reused output) gets the values of the same call without it (checked
    against numpy's grid mappings above), every leading shape, and is returned."""
    sky = sd.model("fitted", sun=sd.Sun(elevation_deg=-4.0, azimuth_deg=200.0),
                   observer_altitude_m=3000.0)
    d = np.random.default_rng(21).normal(size=(4, 50_000, 3))
    wl = np.array([400.0, 555.0, 700.0, 1010.0])
    for f, shape in ((sky.xyz, (4, 50_000, 3)), (sky.luminance, (4, 50_000)),
                     (lambda dd, **k: sky.radiance(dd, wl, **k), (4, 50_000, 4))):
        want = f(d)
        out = np.full(shape, np.nan)
        assert f(d, out=out) is out
        np.testing.assert_array_equal(out, want)
        one = np.full(shape[1:], np.nan)
        np.testing.assert_array_equal(f(d[1], out=one), want[1])
    single = np.empty(3)
    np.testing.assert_array_equal(sky.xyz(d[0, 0], out=single), sky.xyz(d[0, 0]))


@pytest.mark.parametrize("make, message", [
    (lambda: np.empty((10, 3), dtype=np.float32), r"out must be .*float64.* float32 array"),
    (lambda: np.empty((10, 4)), r"out must be .*shape \(10, 3\).*shape \(10, 4\)"),
    (lambda: np.empty((30,)), r"out must be .*shape \(10, 3\).*shape \(30,\)"),
    (lambda: np.empty((3, 10)).T, r"out must be .*C-contiguous.*non-C-contiguous"),
    (lambda: _read_only((10, 3)), r"out must be .*writeable.*read-only"),
    (lambda: [[0.0] * 3] * 10, r"out must be a numpy array or None, got list"),
])
def test_a_bad_out_is_refused_naming_what_it_must_be(make, message):
    sky = sd.model("fitted", sun=sd.Sun(elevation_deg=30.0, azimuth_deg=0.0))
    d = np.random.default_rng(2).normal(size=(10, 3))
    with pytest.raises(ValueError, match=message):
        sky.xyz(d, out=make())


def _read_only(shape):
    a = np.zeros(shape)
    a.setflags(write=False)
    return a


def test_out_sharing_memory_with_the_directions_is_refused():
    sky = sd.model("fitted", sun=sd.Sun(elevation_deg=30.0, azimuth_deg=0.0))
    d = np.random.default_rng(3).normal(size=(10, 3))
    with pytest.raises(ValueError, match="out must not share memory with directions"):
        sky.xyz(d, out=d)
    with pytest.raises(ValueError, match="out must not share memory with directions"):
        sky.luminance(d, out=d.reshape(-1)[:10])


def test_threads_give_identical_values():
    """Every thread has its own block buffers: the values do not depend on the number of
    threads (the values themselves are checked against numpy above)."""
    import numba

    sky = sd.model("fitted", sun=sd.Sun(elevation_deg=20.0, azimuth_deg=70.0))
    d = np.random.default_rng(12).normal(size=(300_000, 3))
    n = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = sky.xyz(d)
    finally:
        numba.set_num_threads(n)
    for _ in range(3):
        np.testing.assert_array_equal(sky.xyz(d), one)


def test_sky_cell_inverts_the_grid_mappings():
    """_grid.sky_cell against the forward mappings (theta_nodes_rad, phi_nodes_rad): at the
    nodes, the node's own index with no fraction (the last node as the last cell's end);
    between them, fractions in [0, 1] whose forward mapping gives the angles back."""
    from skydome.models.fitted import _grid as G

    rng = np.random.default_rng(11)
    phi = G.phi_nodes_rad()
    for alt in (0.0, 2200.0, 15000.0):
        th_h = G.horizon_zenith_rad(alt)
        sky, _ = G.theta_nodes_rad(alt)
        th_n, ph_n = np.meshgrid(sky, phi, indexing="ij")
        iu, it, fu, ft = G.sky_cell(th_n, ph_n, th_h)
        ju = np.arange(G.N_SKY)[:, None] * np.ones(G.N_PHI, dtype=int)
        jt = np.ones(G.N_SKY, dtype=int)[:, None] * np.arange(G.N_PHI)
        assert np.array_equal(iu + np.rint(fu).astype(int), ju)
        assert np.array_equal(it + np.rint(ft).astype(int), jt)
        assert np.allclose(np.where(fu > 0.5, fu - 1, fu), 0, atol=1e-9)
        assert np.allclose(np.where(ft > 0.5, ft - 1, ft), 0, atol=1e-9)
        # random directions of the sky: the forward mapping of the cell coordinates
        u = rng.uniform(0, G.N_SKY - 1, 4000)
        v = rng.uniform(0, G.N_PHI - 1, 4000)
        xs, t = u / (G.N_SKY - 1), v / (G.N_PHI - 1)
        th = (th_h - G.EPS) * (1 - xs * xs)
        ph = np.pi * (G.A_PHI * t + (1 - G.A_PHI) * t * t)
        iu, it, fu, ft = G.sky_cell(th, ph, th_h)
        assert np.all((fu >= 0) & (fu <= 1) & (ft >= 0) & (ft <= 1))
        assert np.all((iu >= 0) & (iu <= G.N_SKY - 2) & (it >= 0) & (it <= G.N_PHI - 2))
        xb, tb = (iu + fu) / (G.N_SKY - 1), (it + ft) / (G.N_PHI - 1)
        assert np.allclose((th_h - G.EPS) * (1 - xb * xb), th, rtol=0, atol=1e-9)
        assert np.allclose(np.pi * (G.A_PHI * tb + (1 - G.A_PHI) * tb * tb), ph, rtol=0,
                           atol=1e-9)


@pytest.mark.parametrize("elevation, altitude, aod", [(12.0, 3000.0, 0.3), (-7.0, 0.0, 0.05)])
def test_render_reads_the_spectral_lookup_integrated(elevation, altitude, aod):
    """skydome.imaging.render reads fitted's XYZ in one lookup of the table times the
    spectrum's map to XYZ (FittedSky._fused_xyz, three channels instead of the table
    wavelengths): the model's radiance at the render's wavelengths integrated with the
    render's weights (the lookup is linear in the table's values), over the whole sphere."""
    from skydome.imaging import _fused_sampler, _xyz_weights
    from skydome.spectra import default_wavelengths

    sky = sd.model("fitted", sun=sd.Sun(elevation_deg=elevation, azimuth_deg=200.0),
                   observer_altitude_m=altitude, aerosol_optical_depth=aod)
    wl = default_wavelengths()
    sample, to_xyz = _fused_sampler(sky, wl)
    assert to_xyz is None
    d = np.random.default_rng(5).normal(size=(20000, 3))
    got = sample(d)
    ref = sky.radiance(d, wl) @ _xyz_weights(wl)
    assert got.shape == ref.shape == (20000, 3)
    np.testing.assert_allclose(got, ref, rtol=1e-11, atol=1e-12 * ref.max())


@pytest.mark.parametrize("channels", [1, 3, 7])
@pytest.mark.parametrize("azimuth, altitude", [(180.0, 2000.0), (90.0, 0.0), (0.0, 15000.0),
                                               (237.0, 700.0)])
def test_lookup_reads_nothing_outside_its_table(channels, azimuth, altitude):
    """The table laid inside a buffer of NaN: every value of the lookup is finite and the
    numpy lookup's. Directions in the sun's vertical plane on its side (azimuth from the
    sun 0: the grid's first column, the zenith) put the azimuth's cell at 0, where
    fastmath's rearranged root gave t = -5e-16: the kernel's floor made the cell -1 and
    read the element before the table in the sky's first cell (1e216 and NaN came out of
    ``radiance`` at the horizon of an observer at 2 km, 700 nm)."""
    from skydome.models.fitted import _kernels

    sky = sd.model("fitted", sun=sd.Sun(elevation_deg=19.0, azimuth_deg=azimuth),
                   observer_altitude_m=altitude)
    table = np.ascontiguousarray(sky._table[:, :, :channels])
    pad = 4 * _grid.N_PHI * channels
    buf = np.full(table.size + 2 * pad, np.nan)
    buf[pad:pad + table.size] = table.reshape(-1)
    inside = buf[pad:pad + table.size]
    d = np.vstack([_grid.directions(altitude, azimuth).reshape(-1, 3),
                   _grid.directions(altitude, azimuth, midpoints=True).reshape(-1, 3),
                   [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]])
    out = np.empty((d.shape[0], channels))
    _kernels.lookup(d, d.view(np.int64), inside, channels, sky._theta_h, sky._sin_az,
                    sky._cos_az, out)
    assert np.isfinite(out).all(), np.argwhere(~np.isfinite(out))[:5]
    ref = _reference_lookup_table(sky, table, d)
    scale = np.maximum(np.abs(ref), 1e-12 * np.abs(ref).max())
    # the grid's nodes next to the horizon: the angle's last-place rounding through the
    # square-root mapping reaches 1.3e-9 relative here (at 700 m, azimuth 237 deg)
    assert np.max(np.abs(out - ref) / scale) < 1e-8
