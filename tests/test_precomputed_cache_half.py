"""Cache format 13 of the ``precomputed`` model: the large tables in half precision (float16
and a power-of-two scale per row of wavelengths; the scattering density's in bands of mu_s
rows), the scattering density's Rayleigh constituent as its quadratic form in the outgoing
direction, and the single-scattering table computed again from the entry instead of stored.

The tiny tables of these tests are below ``_cache.HALF_MIN_BYTES`` (stored exactly, as in
test_precomputed_cache.py); here that threshold is set to 0 so that they take the path of
the default tables. Each test has a cache folder of its own."""

import json
import os

import numpy as np
import pytest

import skydome as sd
from skydome.models.simulated.precomputed import _cache, _precompute
from skydome.transport.geometry import direction_from_angles

TINY = dict(scattering_r_size=4, scattering_mu_size=8, scattering_mu_s_size=4,
            scattering_nu_size=2, irradiance_mu_s_size=4, irradiance_r_size=4,
            transmittance_mu_size=8, transmittance_r_size=4, orders=2,
            table_wavelengths_nm=[450.0, 550.0, 650.0])
SUN = sd.Sun(elevation_deg=30.0, azimuth_deg=180.0)
WL = [450.0, 550.0, 650.0]
DIRS = direction_from_angles([89.0, 60.0, 20.0, 5.0, -3.0], [0.0, 45.0, 90.0, 180.0, 270.0])
# float16's rounding: 11 significant bits, half a unit in the last place relative
HALF_ULP = 2.0 ** -11
# below float16's normal range (2^-14, with the row's largest value scaled into
# [2^14, 2^15): 2^28 below it) the step is 2^-24, i.e. at most 2^-38 of the row's largest
SUBNORMAL = 2.0 ** -38


def within_half(decoded, exact):
    """|decoded - exact| <= 2^-11 |exact| + 2^-38 x the largest |value| of its row (the
    last axis, wavelengths): float16's rounding of the scaled value, normal or subnormal."""
    bound = HALF_ULP * np.abs(exact) + SUBNORMAL * np.abs(exact).max(axis=-1, keepdims=True)
    return bool(np.all(np.abs(decoded.astype(np.float64) - exact) <= bound))


def tiny(**kw):
    return sd.model("precomputed", sun=SUN, **{**TINY, **kw})


@pytest.fixture(autouse=True)
def half_for_every_size(monkeypatch, tmp_path):
    """Half precision for every table size, and a cache folder of the test's own."""
    monkeypatch.setattr(_cache, "HALF_MIN_BYTES", 0)
    monkeypatch.setenv("SKYDOME_CACHE_DIR", str(tmp_path / "cache"))


def _part_rows(m):
    """(first, end): the density's mu_s rows a load of model ``m`` decodes."""
    t = m._t
    return m._density_rows({"planet_radius_m": t.planet_radius_m,
                            "top_radius_m": t.top_radius_m, "mu_s_min": t.mu_s_min},
                           t.density_shape)


def entry():
    d = _cache.cache_dir()
    (name,) = [n for n in os.listdir(d) if not n.startswith(".")]
    return os.path.join(d, name)


def test_half_rows_round_to_nearest_within_their_precision():
    """Values spanning 2^-100 .. 2^10 in one array (rows of different magnitude, a row of
    zeros, rows over 2^20 and 2^40 in range): each decoded value is the nearest float16 of
    the scaled value, so within half a unit in the last place (2^-11 relative where the
    scaled value is normal, within 2^28 of the row's largest; 2^-38 of the row's largest
    below); zeros stay zeros."""
    rng = np.random.default_rng(5)
    rows = (rng.uniform(0.5, 1.0, (6, 20)) * 2.0 ** rng.integers(-60, 10, (6, 1)))
    rows[3] = 0.0
    rows[4] *= 2.0 ** np.linspace(-20, 0, 20)
    rows[5] *= 2.0 ** np.linspace(-40, 0, 20)          # 12 decades: partly subnormal
    rows = rows.astype(np.float32)
    h, e = _cache._encode_half(rows)
    assert h.dtype == np.float16 and e.dtype == np.int8
    out = np.empty_like(rows)
    _cache._decode_half(h, e, out)
    assert np.all(out[3] == 0.0)
    assert within_half(out, rows.astype(np.float64))
    rel = np.abs(out[:5][rows[:5] != 0] / rows[:5][rows[:5] != 0] - 1.0)
    assert rel.max() <= HALF_ULP                        # rows within 2^28: relative
    # the largest value of each non-zero row is scaled into [2^14, 2^15)
    top = np.abs(h.astype(np.float32)).max(axis=1)[np.any(rows != 0, axis=1)]
    assert np.all((top >= 2.0 ** 14) & (top < 2.0 ** 15))


def test_entry_layout_and_sizes():
    m = tiny()
    path = entry()
    names = sorted(os.listdir(path))
    assert "single_scattering.npy" not in names         # computed again from the entry
    meta = json.load(open(os.path.join(path, "meta.json")))
    assert meta["cache_format"] == "skydome.precomputed-cache/16"
    assert meta["encoded"] == {"scattering_density": "half-bands"}
    # the Rayleigh constituent (phase code 0) as a quadratic form, the aerosol's in float16
    rayleigh = [int(k) for k in np.nonzero(m._t.phase_code == 0)[0]]
    assert meta["quadratic"]["scattering_density"]["constituents"] == rayleigh
    import _density_bands

    # in bands of mu_s rows: the mu_s axis first on disk, each band's high bytes compressed
    half, _ = _density_bands.read(path)
    J = m._t.scattering_density
    assert half.dtype == np.float16
    assert os.path.getsize(os.path.join(path, "scattering_density.npy")) < 0.8 * half.nbytes
    assert half.shape == (J.shape[4], J.shape[0] - 1) + J.shape[1:4] + (J.shape[5],)
    exp = np.load(os.path.join(path, "scattering_density.exp.npy"))
    assert exp.shape == half.shape[:-1]
    assert len(meta["checksums"]["scattering_density"]["band_crc32"]) == J.shape[4]
    # band b holds the rows J[k, ..., b, :] of the constituent stored in float16 (not the
    # quadratic form's): NumPy's float16 cast times 2^e gives the values the model serves
    k = [i for i in range(J.shape[0]) if i not in rayleigh]
    values = half.astype(np.float32) * np.ldexp(np.float32(1), exp.astype(np.int32))[..., None]
    assert np.array_equal(np.moveaxis(values, 0, -2), J[k])
    coef = np.load(os.path.join(path, "scattering_density.quadratic.npy"))
    assert coef.shape == (1, 6) + J.shape[3:]


def test_stored_values_against_the_exact_tables_and_a_hit_serves_the_same():
    """The first model (whose tables were stored) serves the stored precision; a later hit
    serves the same values bit for bit; both are within the formats' rounding of a model
    built without the cache (float32 tables): the density's float16 constituent within
    float16's rounding (:func:`within_half`), its quadratic-form constituent within 1e-5
    of each column's largest value (QUADRATIC_TOL), the sky's radiance within 2^-11 (a
    weighted sum of them)."""
    exact = tiny(cache=False)
    first = tiny()
    assert not first.from_cache
    second = tiny()
    assert second.from_cache
    Je, J1, J2 = (x._t.scattering_density for x in (exact, first, second))
    assert np.array_equal(J1, J2)
    ray = int(np.nonzero(exact._t.phase_code == 0)[0][0])
    mie = 1 - ray
    assert within_half(J1[mie], Je[mie].astype(np.float64))
    colmax = np.abs(Je[ray]).max(axis=(0, 1))
    assert np.all(np.abs(J1[ray] - Je[ray]).max(axis=(0, 1)) <= _cache.QUADRATIC_TOL * colmax)
    r0, r1, r2 = (x.radiance(DIRS, WL) for x in (exact, first, second))
    assert np.array_equal(r1, r2)
    assert np.abs(r1 / r0 - 1).max() <= HALF_ULP


def test_mie_only_density_is_not_taken_for_a_quadratic_form():
    """A constituent whose phase function is not a polynomial of degree <= 2 (the aerosol's
    Cornette-Shanks) fails the fit's residual test; a made-up quadratic field passes it and
    comes back from its coefficients."""
    m = tiny(cache=False)
    J = np.array(m._t.scattering_density)
    ks, coef = _cache._quadratic_fit(J)
    assert ks == [int(k) for k in np.nonzero(m._t.phase_code == 0)[0]]
    n_th, n_ph = J.shape[1:3]
    th = np.linspace(0, np.pi, n_th)[:, None]
    ph = np.linspace(0, np.pi, n_ph)[None, :]
    ox, oz = np.sin(th) * np.cos(ph), np.cos(th) + 0 * ph
    field = (2.0 + 0.3 * ox - 0.7 * oz + 0.5 * ox * ox + 0.2 * oz * oz - 0.4 * ox * oz)
    J[0] = field[..., None, None, None] * np.arange(1, 1 + np.prod(J.shape[3:])).reshape(
        J.shape[3:])
    J[1] = J[0] * (1.0 + 0.2 * np.cos(3 * ph))[..., None, None, None]   # not quadratic
    ks, coef = _cache._quadratic_fit(J)
    assert ks == [0]
    back = np.empty_like(J[0])
    _cache._quadratic_eval(coef[0], back)
    assert np.abs(back / J[0] - 1).max() <= _cache.QUADRATIC_TOL


def test_single_scattering_is_computed_again_bit_for_bit():
    exact = tiny(cache=False)
    tiny()
    hit = tiny()
    assert hit.from_cache and not hit._t.has_single_scattering
    rows = hit._t.single_scattering_rows(1, 3)           # the observer's two r nodes only
    assert not hit._t.has_single_scattering
    assert np.array_equal(rows, exact._t.single_scattering[:, 1:3])
    assert np.array_equal(hit._t.single_scattering, exact._t.single_scattering)


def test_ground_rows_of_single_scattering_are_stored_and_served_without_the_kernel(
        monkeypatch):
    """The first two r nodes (a ground observer's) are stored exactly; a hit serves the
    ground's sky from them without computing single scattering."""
    exact = tiny(cache=False)
    tiny()
    stored = np.load(os.path.join(entry(), "single_scattering_ground.npy"))
    assert np.array_equal(stored, exact._t.single_scattering[:, :2])
    from skydome.models.simulated.precomputed import _single

    with monkeypatch.context() as mp:
        mp.setattr(_single, "single_scattering_rows", lambda *a, **k: 1 / 0)
        hit = tiny()
        assert hit.from_cache and hit.observer_altitude_m == 0.0
        rad = hit.radiance(DIRS, WL)
        assert not hit._t.has_single_scattering
    assert np.array_equal(rad, tiny().radiance(DIRS, WL))
    assert np.array_equal(rad, tiny(observer_altitude_m=0.0).radiance(DIRS, WL))
    # the same sky as the exact tables' to float16's rounding of the density
    assert np.abs(rad / exact.radiance(DIRS, WL) - 1).max() <= HALF_ULP


def test_stored_table_in_half_precision_joins_the_entry_and_is_read_on_use(monkeypatch):
    exact = tiny(cache=False)
    first = tiny()
    ap1 = first.aerial_perspective(DIRS, 5e3, WL)
    path = entry()
    # packed: its float16 values' two byte planes compressed (_cache._write_half with packed=True)
    assert not os.path.exists(os.path.join(path, "multiple_scattering.npy"))
    with open(os.path.join(path, "multiple_scattering.packed"), "rb") as f:
        assert f.read(len(_cache._PACK_MAGIC)) == _cache._PACK_MAGIC
    # the table is a positively weighted integral of the stored density (within float16's
    # rounding, or QUADRATIC_TOL, of the exact one), then rounded to float16 itself
    ms_e = exact._t.multiple_scattering.astype(np.float64)
    ms_1 = first._t.multiple_scattering
    bound = ((2 * HALF_ULP + _cache.QUADRATIC_TOL) * np.abs(ms_e)
             + 2 * SUBNORMAL * np.abs(ms_e).max(axis=-1, keepdims=True))
    assert np.all(np.abs(ms_1 - ms_e) <= bound)
    from skydome.models.simulated.precomputed import _multiple

    monkeypatch.setattr(_multiple, "multiple_scattering_table", lambda *a, **k: 1 / 0)
    monkeypatch.setattr(_precompute, "precompute", lambda *a, **k: 1 / 0)
    hit = tiny()
    assert hit.from_cache and not hit._t.has_multiple_scattering      # read on first use
    ap2 = hit.aerial_perspective(DIRS, 5e3, WL)
    assert np.array_equal(ap1[0], ap2[0]) and np.array_equal(ap1[1], ap2[1])


def _flip(path, n=64, row=None):
    """Flip ``n`` bytes in the middle of the .npy file ``path``, or, with ``row``, in the
    middle of that row of its first axis (a band of a banded file)."""
    data = bytearray(open(path, "rb").read())
    a_ = np.load(path, mmap_mode="r")
    header = len(data) - a_.nbytes
    if row is None:
        a = header + (len(data) - header - n) // 2
    elif os.path.basename(path) == "scattering_density.npy":
        # the density's file: its bands' stored bytes (uint8); the band's place from
        # meta.json (tests/_density_bands.py)
        meta = json.load(open(os.path.join(os.path.dirname(path), "meta.json")))
        offs = meta["checksums"]["scattering_density"]["band_offsets"]
        a = header + (offs[row] + offs[row + 1] - n) // 2
    else:
        band = a_.nbytes // a_.shape[0]
        a = header + row * band + (band - n) // 2
    data[a:a + n] = bytes(255 - b for b in data[a:a + n])
    open(path, "wb").write(bytes(data))


@pytest.mark.parametrize("file", ["scattering_density", "scattering_density.exp",
                                  "scattering_density.quadratic"])
def test_flipped_bytes_in_a_half_table_rebuild_the_entry(file, capfd):
    """Damage the load reads (the coefficients, or a band of the density's rows the
    model's sky reads): the entry rebuilt before anything is served."""
    fresh = tiny(cache=False)
    first = tiny()
    row = None if file.endswith("quadratic") else sum(_part_rows(first)) // 2
    _flip(os.path.join(entry(), file + ".npy"), row=row)
    capfd.readouterr()
    again = tiny()
    assert not again.from_cache
    note = [ln for ln in capfd.readouterr().err.splitlines() if ln.strip()]
    assert len(note) == 1 and "damaged" in note[0] and file + ".npy" in note[0], note
    assert np.array_equal(again.radiance(DIRS, WL), first.radiance(DIRS, WL))
    assert np.abs(again.radiance(DIRS, WL) / fresh.radiance(DIRS, WL) - 1).max() <= HALF_ULP
    assert tiny().from_cache


def test_damaged_half_stored_table_is_built_again_on_use(capfd):
    first = tiny()
    ap = first.aerial_perspective(DIRS, 5e3, WL)
    file = os.path.join(entry(), "multiple_scattering.packed")
    data = bytearray(open(file, "rb").read())
    a = len(data) // 2
    data[a:a + 64] = bytes(255 - b for b in data[a:a + 64])
    open(file, "wb").write(bytes(data))
    capfd.readouterr()
    again = tiny()
    assert again.from_cache
    ap2 = again.aerial_perspective(DIRS, 5e3, WL)      # read, found damaged, built again
    note = [ln for ln in capfd.readouterr().err.splitlines() if ln.strip()]
    assert len(note) == 1 and "multiple_scattering.packed" in note[0], note
    assert np.array_equal(ap[1], ap2[1])
    assert os.path.exists(file)                         # and stored again
    assert tiny().aerial_perspective(DIRS, 5e3, WL)[1].tolist() == ap[1].tolist()


def test_checked_decode_is_numpys_cast_bit_for_bit_on_every_float16():
    """The load's decode (float16 bits moved into float32's fields, one power-of-two product
    per row) against NumPy's IEEE float16 -> float32 cast times 2^e: every finite float16
    bit pattern (zeros of both signs, subnormals, normals; 63,488 of the 65,536) in rows
    scaled by 2^e for e over the exponents the format writes (-127 .. 127: chunks with e
    beyond 15 take NumPy's product itself), bit for bit, the flag saying whether the result
    is finite; then inf and NaN of both signs among finite values: flagged."""
    bits = np.arange(65536, dtype=np.uint32).astype(np.uint16)
    finite_bits = bits[(bits & 0x7C00) != 0x7C00]
    rng = np.random.default_rng(11)
    with np.errstate(over="ignore"):           # rows scaled beyond float32's range: inf
        for e_values in (np.arange(-127, 16), np.arange(-127, 128), np.array([15, 16, -3])):
            h = rng.permutation(finite_bits)[: 20 * (finite_bits.size // 20)].reshape(-1, 20)
            e = rng.choice(e_values, h.shape[0]).astype(np.int8)
            hv = h.view(np.float16)
            scale = np.ldexp(np.float32(1.0), e.astype(np.int32))[:, None]
            reference = hv.astype(np.float32) * scale
            out = np.full(hv.shape, np.nan, dtype=np.float32)
            assert _cache._decode_half_checked(hv, e, out) is bool(np.isfinite(reference).all())
            assert np.array_equal(out.view(np.uint32), reference.view(np.uint32))
    for special in (0x7C00, 0xFC00, 0x7E00, 0xFE01):          # +inf, -inf, NaNs
        h = rng.choice(finite_bits, (50, 20)).astype(np.uint16)
        h[17, 3] = special
        out = np.empty(h.shape, dtype=np.float32)
        assert not _cache._decode_half_checked(h.view(np.float16),
                                               np.full(50, -20, np.int8), out)


@pytest.mark.parametrize("value", [np.nan, np.inf])
def test_not_finite_in_a_half_table_with_its_checksum_updated_rebuilds_the_entry(value, capfd):
    """NaN or inf written into the float16 file with its CRC-32 recomputed (so that the
    checksum passes): the finiteness check of the load finds it, the entry is rebuilt and
    serves the sky of the first build."""
    import zlib

    first = tiny()
    path = entry()
    import _density_bands

    a, meta = _density_bands.read(path)
    band = sum(_part_rows(first)) // 2               # a band the load reads
    a[band].reshape(-1)[a[band].size // 2] = value
    _density_bands.write(path, a, meta, new_checksums=(band,))
    capfd.readouterr()
    again = tiny()
    assert not again.from_cache
    note = [ln for ln in capfd.readouterr().err.splitlines() if ln.strip()]
    assert len(note) == 1 and "NaN or infinite" in note[0], note
    assert np.array_equal(again.radiance(DIRS, WL), first.radiance(DIRS, WL))


def _entry_files(path):
    """{file name: bytes} of a cache entry, meta.json without the precomputation's time."""
    out = {}
    for n in sorted(os.listdir(path)):
        data = open(os.path.join(path, n), "rb").read()
        if n == "meta.json":
            meta = json.loads(data)
            meta["scalars"].pop("precompute_seconds")
            data = json.dumps(meta).encode()
        out[n] = data
    return out


def test_entry_written_in_the_background_is_the_entry_written_at_once(monkeypatch, tmp_path):
    """Within ``background_writes`` (the command line's construction) the entry's files are
    written on a thread: the model serves the same values as one whose entry was written
    at once (the large tables are encoded before the constructor returns), a second model
    meanwhile reads the entry (the load waits for the write), and the files are those of
    the entry written at once, byte for byte (the precomputation's time apart)."""
    monkeypatch.setenv("SKYDOME_CACHE_DIR", str(tmp_path / "at-once"))
    at_once = tiny()
    files_at_once = _entry_files(entry())
    monkeypatch.setenv("SKYDOME_CACHE_DIR", str(tmp_path / "background"))
    started = []
    real = _cache._write_entry

    def slow(*a, **k):          # the write still running when the second model loads
        started.append(True)
        import time
        time.sleep(0.3)
        return real(*a, **k)

    monkeypatch.setattr(_cache, "_write_entry", slow)
    with _cache.background_writes():
        first = tiny()
    assert not first.from_cache
    second = tiny()
    assert started and second.from_cache and not _cache._PENDING
    r = [x.radiance(DIRS, WL) for x in (at_once, first, second)]
    assert np.array_equal(r[0], r[1]) and np.array_equal(r[1], r[2])
    assert _entry_files(entry()) == files_at_once


def test_table_encoded_on_threads_is_numpys_float16_of_each_row(monkeypatch, tmp_path):
    """A table split into many steps (a small step size) and encoded on 1 or 3 threads
    writes the same file, and each value read back is NumPy's float16 cast of the value
    divided by its row's power of two (the row's largest value in [2^14, 2^15)), times it
    again; the table itself receives those values."""
    rng = np.random.default_rng(7)
    table = (rng.uniform(0.0, 1.0, (2, 50, 20)) * 2.0 ** rng.integers(-30, 5, (2, 50, 1)))
    table = table.astype(np.float32)
    scale = 2.0 ** (np.floor(np.log2(np.abs(table).max(axis=-1, keepdims=True))) - 14)
    expected = (table / scale).astype(np.float16).astype(np.float64) * scale
    monkeypatch.setattr(_cache, "_CHECK_BYTES", 4 * 20 * 7)       # 7 rows per step
    written = []
    for threads in (1, 3):
        monkeypatch.setattr(_cache, "_encode_threads", lambda n=threads: n)
        a = table.copy()
        enc = _cache._encode_table("t", [a[0:1], a[1:2]], a.shape)
        assert len(enc.chunks) == 2 * 8
        f, fe = str(tmp_path / f"t{threads}.npy"), str(tmp_path / f"t{threads}.exp.npy")
        sums = _cache._write_encoded(f, fe, "t", enc)
        back = _cache._read_half(str(tmp_path), f"t{threads}", {f"t{threads}": sums["t"],
                                 f"t{threads}.exp": sums["t.exp"]})
        assert np.array_equal(back, expected.astype(np.float32))
        assert np.array_equal(a, back)
        written.append(open(f, "rb").read() + open(fe, "rb").read())
    assert written[0] == written[1]


def test_packed_half_table_round_trip_and_damage(tmp_path):
    """The packed file of a half table (_cache._write_half with packed=True, _read_packed): every float16
    bit pattern of a finite value, in rows scaled by powers of two, read back bit for bit
    (the same float32 values the plain half file's decoding gives, _read_half); a smooth
    table packs to less than half of its float16 bytes; a truncated file, one with bytes
    changed or appended, a wrong record and a NaN are each refused (DamagedEntry)."""
    from skydome.models.simulated.precomputed._cache import (DamagedEntry, _read_half,
                                                             _read_packed, _write_half)

    bits = np.arange(65536, dtype=np.uint32).astype(np.uint16).view(np.float16)
    bits = bits[np.isfinite(bits)].astype(np.float32)
    rows = np.resize(bits, (3, 4, 1000, 8))                 # (a, b, c, wavelength)
    rows *= np.float32(2.0) ** np.arange(-20, 20, 10)[None, :, None, None].astype(np.float32)
    smooth = np.exp(-np.linspace(0, 4, 2 * 64 * 48 * 20)).reshape(2, 64, 48, 20).astype(
        np.float32) * (1 + 0.3 * np.sin(np.arange(20) / 3.0)).astype(np.float32)
    for name, table in (("t", rows), ("s", smooth)):
        a, b = table.copy(), table.copy()
        sums = _write_half(str(tmp_path / f"{name}.npy"), str(tmp_path / f"{name}.exp.npy"),
                           name, [a[:1], a[1:]], table.shape)
        plain = _read_half(str(tmp_path), name, sums)
        recs = _write_half(str(tmp_path / f"{name}.packed"), str(tmp_path / f"p{name}.exp.npy"),
                           f"p{name}", [b[:2], b[2:]], table.shape, packed=True)
        os.replace(tmp_path / f"{name}.packed", tmp_path / f"p{name}.packed")
        packed = _read_packed(str(tmp_path), f"p{name}", recs)
        assert packed.dtype == np.float32 and packed.shape == table.shape
        assert np.array_equal(packed.view(np.uint32), plain.view(np.uint32))
        assert np.array_equal(a.view(np.uint32), b.view(np.uint32))    # decoded in place alike
    assert os.path.getsize(tmp_path / "ps.packed") < 0.5 * smooth.size * 2
    file = tmp_path / "ps.packed"
    good = file.read_bytes()
    for bad in (good[:len(good) // 2], good + b"x",
                good[:len(good) // 2] + bytes([good[len(good) // 2] ^ 0xFF]) + good[len(good) // 2 + 1:]):
        file.write_bytes(bad)
        with pytest.raises(DamagedEntry):
            _read_packed(str(tmp_path), "ps", recs)
    file.write_bytes(good)
    with pytest.raises(DamagedEntry):
        _read_packed(str(tmp_path), "ps", {**recs, "ps": {**recs["ps"], "crc32": 1}})
    nan = smooth.copy()
    nan[1, 2, 3, 4] = np.nan
    with pytest.raises(_cache._NotFinite):
        _write_half(str(tmp_path / "n.packed"), str(tmp_path / "n.exp.npy"), "n", [nan],
                    nan.shape, packed=True)
