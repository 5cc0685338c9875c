"""The scattering density read in part: a load from the cache decodes only the mu_s rows of
J that the observer's rays reach (``_reach.density_mu_s_rows``), the whole table on its
first read. The bound is checked against a brute-force geometry and against the rows the
kernel itself reads; the sky is the same, bit for bit, as from the whole table; the bands
of the density the load reads are checked there, the others on the first whole read (damage
there noted, the entry removed and the table of a fresh build served)."""

import json
import os
import zlib

import numpy as np
import pytest

import skydome as sd
from skydome.models.simulated import precomputed as P
from skydome.models.simulated.precomputed import _cache, _reach
from skydome.transport.geometry import direction_from_angles

# small tables with a fine mu_s axis of the density (24 nodes: the rows reached are a part)
SMALL = dict(scattering_r_size=4, scattering_mu_size=8, scattering_mu_s_size=8,
             density_mu_s_size=24, scattering_nu_size=2, irradiance_mu_s_size=4,
             irradiance_r_size=4, transmittance_mu_size=8, transmittance_r_size=4, orders=2,
             table_wavelengths_nm=[450.0, 650.0])
WL = [450.0, 650.0]
DIRS = direction_from_angles([89.0, 60.0, 20.0, 5.0, 0.5, -3.0, -40.0],
                             [0.0, 45.0, 90.0, 180.0, 200.0, 270.0, 10.0])
SUNS = [-17.5, -10.0, -4.0, 0.0, 5.0, 30.0, 60.0, 89.0, 90.0]
ALTITUDES = [0.0, 2e3, 15e3, 60e3]


@pytest.fixture(autouse=True)
def own_cache(monkeypatch, tmp_path):
    """Half precision for every table size (the default tables' path) and a cache folder
    of the test's own, with nothing held from another test."""
    monkeypatch.setattr(_cache, "HALF_MIN_BYTES", 0)
    monkeypatch.setenv("SKYDOME_CACHE_DIR", str(tmp_path / "cache"))
    with _cache._LOADED_LOCK:
        _cache._LOADED.clear()


def small(elevation=30.0, altitude=0.0, **kw):
    return sd.model("precomputed", sun=sd.Sun(elevation_deg=elevation, azimuth_deg=180.0),
                    observer_altitude_m=altitude, **{**SMALL, **kw})


def entry():
    d = _cache.cache_dir()
    (name,) = [n for n in os.listdir(d) if not n.startswith(".")]
    return os.path.join(d, name)


def _slice(m, J, j0, n=None):
    """The observer's sky map of orders 2..N of model ``m`` from ``J`` holding the
    density's mu_s rows j0.. of ``n`` (default: the tables' density's; the kernel's call in
    PrecomputedSky._observer_slices), and the rows each view zenith node's rays read (a
    node whose rays have no quadrature node, e.g. a ground observer's nadir: (n, 0))."""
    from skydome.models.simulated.precomputed import _multiple
    from skydome.models.simulated.precomputed._precompute import (QUADRATURE_SCALE_M,
                                                                   tables_medium)

    t = m._t
    cos_th, ground, cphi = m._slice_grid()
    out = np.empty((ground.size, P._SLICE_PHI, J.shape[-1]))
    reach = np.empty((ground.size, 2), dtype=np.int64)
    _multiple.multiple_scattering_slice(
        J, j0, n or t.density_shape[4], tables_medium(t), t.scattering_index, t.columns,
        t.mu_s_min, m._r0, float(m.sun.direction[2]), int(m.integration_samples),
        QUADRATURE_SCALE_M, cos_th, ground, cphi, reach, out, *m._column_rule())
    return out, reach


def _rows(m, n=None):
    t = m._t
    return _reach.density_mu_s_rows(m._r0, float(m.sun.direction[2]), t.planet_radius_m,
                                    t.top_radius_m, t.mu_s_min, n or t.density_shape[4])


def test_longest_ray_turns_by_the_bound():
    """max_central_angle against a brute force: the central angle between the observer and
    the end of every ray from it (to the ground or the top, on a fine grid of zenith
    cosines), whose largest value it must bound, closely (the grazing ray is its limit)."""
    R, Rt = 6360e3, 6460e3
    for h in (0.0, 2e3, 15e3, 60e3, 99e3):
        r0 = R + h
        mu = np.linspace(-1.0, 1.0, 2_000_001)
        # ray end: ground where the ray meets it, else the top ([Bru17] distances, in NumPy)
        disc_g = r0 * r0 * (mu * mu - 1.0) + R * R
        t_g = -r0 * mu - np.sqrt(np.maximum(disc_g, 0.0))
        hits = (mu < 0) & (disc_g >= 0)
        t_top = -r0 * mu + np.sqrt(r0 * r0 * (mu * mu - 1.0) + Rt * Rt)
        t = np.where(hits, t_g, t_top)
        gamma = np.arctan2(t * np.sqrt(1.0 - mu * mu), r0 + t * mu)
        bound = _reach.max_central_angle(r0, R, Rt)
        assert gamma.max() <= bound + 1e-12          # float64 rounding of the brute force
        assert gamma.max() >= bound - 1e-3, (h, gamma.max(), bound)


def test_rows_hold_every_row_the_kernel_reads():
    """The rows the kernel reads (its ``reach``, from the whole table) for suns from the
    tables' lowest to the zenith and observers from the ground to 60 km, on density mu_s
    axes of 6 to 96 nodes (a table of zeros: the rows read depend on the geometry only),
    lie within the bound; and the bound is a part of the axis where the axis is fine."""
    m0 = small(cache=False)
    t = m0._t
    shape = t.density_shape
    parts = []
    for n in (6, 24, 48, 96):
        J = np.zeros(shape[:4] + (n, shape[5]), dtype=np.float32)
        for elevation in SUNS:
            for altitude in ALTITUDES:
                m = m0.with_sun(sd.Sun(elevation_deg=elevation, azimuth_deg=180.0),
                                observer_altitude_m=altitude)
                first, end = _rows(m, n)
                _, reach = _slice(m, J, 0, n)
                assert first <= reach[:, 0].min() and reach[:, 1].max() <= end, \
                    (n, elevation, altitude, first, end, reach.min(), reach.max())
                parts.append((end - first) / n)
    assert min(parts) < 0.3 and max(parts) <= 1.0


def test_rows_outside_the_bound_are_not_read():
    """The density with every row outside the bound set to NaN gives the observer's sky map
    of the whole table, bit for bit; so does the part alone, at its offset."""
    m0 = small(cache=False)
    J = m0._t.scattering_density
    for elevation in SUNS:
        for altitude in (0.0, 15e3):
            m = m0.with_sun(sd.Sun(elevation_deg=elevation, azimuth_deg=180.0),
                            observer_altitude_m=altitude)
            first, end = _rows(m)
            whole, _ = _slice(m, J, 0)
            nan = J.copy()
            nan[..., :first, :] = np.nan
            nan[..., end:, :] = np.nan
            masked, _ = _slice(m, nan, 0)
            part, reach = _slice(m, np.ascontiguousarray(J[..., first:end, :]), first)
            assert np.all(np.isfinite(whole)) and (whole > 0).any()
            assert np.array_equal(masked, whole), (elevation, altitude)
            assert np.array_equal(part, whole), (elevation, altitude)


def test_a_load_in_part_serves_the_sky_of_the_whole_table():
    """Models read from the cache with the density in part (the rows of their own sun and
    altitude) give the radiance of the model that built the entry and of one whose tables
    hold the whole density, bit for bit, at several suns and altitudes; the whole table is
    not decoded for the sky."""
    first = small()                                     # precomputed, stored, decoded
    assert not first.from_cache
    for elevation in SUNS:
        for altitude in (0.0, 2e3, 15e3):
            with _cache._LOADED_LOCK:
                _cache._LOADED.clear()
            m = small(elevation, altitude)
            assert m.from_cache
            part, j0 = m._t.__dict__["_density_part"]
            whole = first.with_sun(m.sun, observer_altitude_m=altitude)
            got = m.radiance(DIRS, WL)
            assert m._t.__dict__["_scattering_density"] is None    # not decoded whole
            assert np.array_equal(got, whole.radiance(DIRS, WL)), (elevation, altitude)
    assert part.shape[4] < first._t.density_shape[4]
    # the whole table, decoded on first read, is the table the first model holds
    assert np.array_equal(m._t.scattering_density, first._t.scattering_density)


def test_a_night_sky_from_the_cache_decodes_no_row(capfd):
    """The sun below the tables' lowest (night: the sky reads no density): the load
    decodes no row of it (every file still checked) and the sky is 0; another sun of the
    same tables then reads the whole table."""
    ref = small()
    with _cache._LOADED_LOCK:
        _cache._LOADED.clear()
    night = small(-30.0)
    assert night.from_cache
    part, _ = night._t.__dict__["_density_part"]
    assert part.shape[4] == 0
    assert not night.radiance(DIRS, WL).any()
    day = night.with_sun(ref.sun)
    assert np.array_equal(day.radiance(DIRS, WL), ref.radiance(DIRS, WL))
    assert capfd.readouterr().err == ""


def test_a_shared_entry_serves_a_sun_outside_the_first_models_rows(capfd):
    """A second model of the same entry, while the first's tables are held (the same
    tables), whose sun needs rows outside the part the first decoded: its sky is that of
    the whole table (decoded then), and the first model's sky is unchanged."""
    ref = small()
    with _cache._LOADED_LOCK:
        _cache._LOADED.clear()
    high = small(89.0)
    high_sky = high.radiance(DIRS, WL)
    low = small(-10.0, 15e3)
    assert low._t is high._t
    part, j0 = high._t.__dict__["_density_part"]
    first, end = _rows(low)
    assert first < j0 or end > j0 + part.shape[4]          # not held by the part
    assert np.array_equal(low.radiance(DIRS, WL),
                          ref.with_sun(low.sun, observer_altitude_m=15e3).radiance(DIRS, WL))
    assert high._t.__dict__["_scattering_density"] is not None    # decoded whole for it
    assert np.array_equal(high.radiance(DIRS, WL), high_sky)
    assert capfd.readouterr().err == ""


def test_a_bound_too_narrow_is_found_and_the_whole_table_used(monkeypatch, capfd):
    """Were the bound wrong (here made one row wide), the kernel's report of the rows it
    read says so: one line on stderr and the sky from the whole table."""
    ref = small()
    with _cache._LOADED_LOCK:
        _cache._LOADED.clear()
    narrow = _reach.density_mu_s_rows

    def one_row(*a):
        lo, hi = narrow(*a)
        return lo + (hi - lo) // 2, lo + (hi - lo) // 2 + 1

    monkeypatch.setattr(_reach, "density_mu_s_rows", one_row)
    m = small()
    capfd.readouterr()
    got = m.radiance(DIRS, WL)
    err = capfd.readouterr().err
    assert "outside the bound" in err and err.count("\n") == 1, err
    assert np.array_equal(got, ref.radiance(DIRS, WL))


def _damage_band(path, band, damage):
    """Damage the value in the middle of mu_s row ``band`` of the density's float16 file
    (banded: the mu_s axis first on disk): its bytes flipped, or NaN written with the
    band's CRC-32 recorded again (so that only the finiteness check can find it)."""
    import _density_bands

    a, meta = _density_bands.read(path)
    assert a.dtype == np.float16 and a.ndim == 6
    row = a[band].reshape(-1)
    i = row.size // 2
    if damage == "flipped":
        row.view(np.uint16)[i] ^= 0x0155           # mantissa bits: still finite
    else:
        row[i] = np.nan
    _density_bands.write(path, a, meta,
                         new_checksums=() if damage == "flipped" else (band,))


def _notes(capfd):
    return [ln for ln in capfd.readouterr().err.splitlines() if ln.strip()]


@pytest.mark.parametrize("damage", ["flipped", "nan with its checksum"])
def test_damage_outside_the_rows_decoded_is_found_at_the_first_whole_read(damage, capfd):
    """A damaged value in an mu_s band the load does not read: the load serves the sky (of
    the rows it reads, undamaged: the first build's, bit for bit) without a note; the first
    read of the whole table finds the damage (the band's CRC-32; NaN with its checksum
    recorded again: the finiteness of the values decoded), says so in one line naming the
    entry, removes it and serves the whole table of a fresh build (the precomputation's
    again, stored: the first build's values); the entry is then written again."""
    first = small()
    sky = first.radiance(DIRS, WL)
    J = first._t.scattering_density.copy()
    path = entry()
    rows = _rows(first)
    n = first._t.density_shape[4]
    assert rows != (0, n)
    band = 0 if rows[0] > 0 else n - 1
    _damage_band(path, band, damage)
    with _cache._LOADED_LOCK:
        _cache._LOADED.clear()
    capfd.readouterr()
    again = small()
    assert again.from_cache and _notes(capfd) == []
    assert np.array_equal(again.radiance(DIRS, WL), sky)
    assert again._t.__dict__["_scattering_density"] is None
    whole = again._t.scattering_density                # read whole: the damage found
    note = _notes(capfd)
    assert len(note) == 1 and path in note[0] and "scattering_density.npy" in note[0], note
    assert ("NaN or infinite" in note[0]) == (damage != "flipped")
    assert np.array_equal(whole, J)
    # the entry written again, undamaged: a load and its whole read say nothing
    with _cache._LOADED_LOCK:
        _cache._LOADED.clear()
    later = small()
    assert later.from_cache
    assert np.array_equal(later._t.scattering_density, J) and _notes(capfd) == []


@pytest.mark.parametrize("damage", ["flipped", "nan with its checksum"])
def test_damage_inside_the_rows_decoded_is_found_at_the_load(damage, capfd):
    """A damaged value in an mu_s band the load reads: found at the load, one line on
    stderr, the entry rebuilt before anything is served (the sky of the first build)."""
    first = small()
    sky = first.radiance(DIRS, WL)
    path = entry()
    lo, hi = _rows(first)
    _damage_band(path, (lo + hi) // 2, damage)
    with _cache._LOADED_LOCK:
        _cache._LOADED.clear()
    capfd.readouterr()
    again = small()
    assert not again.from_cache
    note = _notes(capfd)
    assert len(note) == 1 and path in note[0] and "scattering_density.npy" in note[0], note
    assert ("NaN or infinite" in note[0]) == (damage != "flipped")
    assert np.array_equal(again.radiance(DIRS, WL), sky)


def test_damaged_exponents_outside_the_rows_decoded_are_found_at_the_first_whole_read(capfd):
    """The exponents' bands are checked as the float16 file's: a flipped exponent outside
    the rows the load reads is found on the first whole read, noted and repaired."""
    first = small()
    J = first._t.scattering_density.copy()
    path = entry()
    rows = _rows(first)
    band = 0 if rows[0] > 0 else first._t.density_shape[4] - 1
    file = os.path.join(path, "scattering_density.exp.npy")
    e = np.load(file)
    e[band].reshape(-1)[e[band].size // 2] ^= 0x55
    np.save(file, e)
    with _cache._LOADED_LOCK:
        _cache._LOADED.clear()
    capfd.readouterr()
    again = small()
    assert again.from_cache and _notes(capfd) == []
    assert np.array_equal(again._t.scattering_density, J)
    note = _notes(capfd)
    assert len(note) == 1 and "scattering_density.exp.npy" in note[0], note


def test_the_whole_table_is_read_after_the_entry_is_removed_and_checked_again(capfd):
    """The tables hold the density's files: the whole table decodes after the entry was
    removed (the cache cleared); a file changed in place after the load is found on that
    read: one line on stderr, the entry removed and the whole table of a fresh build
    served."""
    ref = small()
    with _cache._LOADED_LOCK:
        _cache._LOADED.clear()
    m = small()
    assert m._t.__dict__["_scattering_density"] is None
    P.clear_cache()
    assert not os.listdir(_cache.cache_dir())
    assert np.array_equal(m._t.scattering_density, ref._t.scattering_density)

    small()                                            # stored again (a miss)
    with _cache._LOADED_LOCK:
        _cache._LOADED.clear()
    m = small()
    assert m.from_cache and m._t.__dict__["_scattering_density"] is None
    path = entry()
    file = os.path.join(path, "scattering_density.npy")
    with open(file, "r+b") as f:                       # the same file, changed in place
        f.seek(-8, os.SEEK_END)
        f.write(b"\x00\x7c" * 4)
    capfd.readouterr()
    assert np.array_equal(m._t.scattering_density, ref._t.scattering_density)
    note = _notes(capfd)
    assert len(note) == 1 and path in note[0], note


def test_without_a_rebuild_damage_at_the_whole_read_is_an_error(capfd):
    """_cache.load without ``rebuild_density``: damage found on the whole read is
    DamagedEntry (after its note, the entry removed)."""
    first = small()
    path = entry()
    rows = _rows(first)
    band = 0 if rows[0] > 0 else first._t.density_shape[4] - 1
    _damage_band(path, band, "flipped")
    with _cache._LOADED_LOCK:
        _cache._LOADED.clear()
    k = os.path.basename(path)
    t = _cache.load(k, lambda scalars, shape: rows)
    assert t is not None
    with pytest.raises(_cache.DamagedEntry):
        t.scattering_density
    assert not os.path.exists(path)


def test_bands_read_in_part_are_the_rows_of_the_whole_table(tmp_path):
    """A table written in mu_s bands (_write_bands) and read back by bands: every range of
    rows decodes to NumPy's float16 cast of the rows times their power of two, the same
    bits as the whole table's rows; the bands on disk are the table's rows [..., b, :]."""
    rng = np.random.default_rng(3)
    shape = (1, 3, 4, 2, 6, 5)
    table = (rng.uniform(-1.0, 1.0, shape) * 2.0 ** rng.integers(-30, 5, shape[:-1] + (1,)))
    table = table.astype(np.float32)
    scale = 2.0 ** (np.floor(np.log2(np.abs(table).max(axis=-1, keepdims=True))) - 14)
    expected = ((table / scale).astype(np.float16).astype(np.float64) * scale).astype(np.float32)
    a = table.copy()
    enc = _cache._encode_table("d", [a], shape, block=shape[-2])
    sums = _cache._write_encoded(str(tmp_path / "d.npy"), str(tmp_path / "d.exp.npy"), "d",
                                 enc, banded=True)
    import zlib

    # the bands' stored bytes: each band's high bytes (zlib) then its low bytes
    raw = np.load(tmp_path / "d.npy").tobytes()
    offs, highs = sums["d"]["band_offsets"], sums["d"]["band_high_bytes"]
    bands = []
    for b in range(6):
        band = raw[offs[b]:offs[b + 1]]
        assert zlib.crc32(band) == sums["d"]["band_crc32"][b]
        high = np.frombuffer(zlib.decompress(band[:highs[b]]), dtype=np.uint8)
        low = np.frombuffer(band[highs[b]:], dtype=np.uint8)
        bands.append((high.astype(np.uint16) << 8 | low).view(np.float16))
    on_disk = np.stack(bands).reshape(6, 1, 3, 4, 2, 5)
    for b in range(6):
        assert np.array_equal(on_disk[b].astype(np.float32) * scale[..., b, :].astype(np.float32),
                              expected[..., b, :])
    with _cache._HalfTable(str(tmp_path), "d", sums, banded=True) as t:
        assert np.array_equal(t.decode(), expected)
        for lo in range(7):
            for hi in range(lo, 7):
                assert np.array_equal(t.decode((lo, hi)), expected[..., lo:hi, :]), (lo, hi)


def test_rows_that_cannot_be_said_decode_the_whole_table(monkeypatch, capfd):
    """An error in the caller's ``density_rows`` is not damage: the entry is kept and its
    whole density decoded at the load, as without rows."""
    ref = small()
    with _cache._LOADED_LOCK:
        _cache._LOADED.clear()

    def fails(self, scalars, shape):
        raise KeyError("planet_radius_m")

    monkeypatch.setattr(P.PrecomputedSky, "_density_rows", fails)
    m = small()
    assert m.from_cache and m._t.__dict__["_scattering_density"] is not None
    assert np.array_equal(m.radiance(DIRS, WL), ref.radiance(DIRS, WL))
    assert capfd.readouterr().err == ""


def test_the_bounds_mapping_is_the_kernels():
    """_reach's plain-Python mu_s mapping (read before numba is imported) is
    _mapping.mu_s_unit: the same constants, the same unit coordinate to rounding over sun
    zenith angles 0..180 deg and three lowest suns."""
    from skydome.models.simulated.precomputed import _mapping

    assert _reach._CENTRE == _mapping.MU_S_CENTRE and _reach._WIDTH == _mapping.MU_S_WIDTH
    for mu_s_min in (np.cos(np.radians(96.0)), np.cos(np.radians(108.0)), -0.5):
        for theta in np.linspace(0.0, np.pi, 721):
            x = _mapping.mu_s_unit(float(np.cos(theta)), float(mu_s_min))
            assert abs(_reach._unit(float(theta), float(mu_s_min)) - x) <= 1e-12
