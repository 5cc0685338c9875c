"""The on-disk cache of the ``precomputed`` model's tables: hits without recomputation,
invalidation by every atmosphere field and table setting, recovery from corrupt files,
the size limit (least recently used files go first) and clearing.

The cache folder is a per-test temporary folder set by ``conftest.py``."""

import dataclasses
import os

import numpy as np
import pytest

import skydome as sd
from skydome.transport.geometry import direction_from_angles
from skydome.atmosphere import Atmosphere
from skydome.models.simulated import precomputed as P
from skydome.models.simulated.precomputed import _cache, _precompute

TINY = dict(scattering_r_size=4, scattering_mu_size=8, scattering_mu_s_size=4,
            scattering_nu_size=2, irradiance_mu_s_size=4, irradiance_r_size=4,
            transmittance_mu_size=8, transmittance_r_size=4, orders=2,
            table_wavelengths_nm=[550.0])
SUN = sd.Sun(elevation_deg=30.0, azimuth_deg=180.0)


def tiny(**kw):
    return sd.model("precomputed", sun=SUN, **{**TINY, **kw})


def files():
    """The cache entries (one folder per table set)."""
    d = _cache.cache_dir()
    return sorted(n for n in os.listdir(d) if not n.startswith(".")) if os.path.isdir(d) else []


def assert_same_tables(a, b, timing=True):
    for f in dataclasses.fields(a):
        if f.name == "precompute_seconds" and not timing:
            continue
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray):
            assert x.dtype == y.dtype and np.array_equal(x, y), f.name
        else:
            assert x == y, f.name


def test_second_build_reads_the_cache_without_recomputing(monkeypatch):
    first = tiny()
    assert not first.from_cache and len(files()) == 1

    def fail(*a, **k):
        raise AssertionError("recomputed although the tables are cached")

    monkeypatch.setattr(_precompute, "precompute", fail)
    second = tiny()
    assert second.from_cache
    assert_same_tables(first._t, second._t)
    d = direction_from_angles([89.0, 20.0, 5.0], [0.0, 90.0, 180.0])
    assert np.array_equal(first.radiance(d, [550.0]), second.radiance(d, [550.0]))


def test_cache_false_neither_reads_nor_writes():
    tiny()
    assert len(files()) == 1
    m = tiny(cache=False)
    assert not m.from_cache and len(files()) == 1
    with pytest.raises(TypeError, match="cache"):
        tiny(cache="yes")


@pytest.mark.parametrize("name", P._TABLE_SETTINGS)
def test_every_table_setting_changes_the_key(name):
    base = {k: v for k, v in P.PrecomputedSky._validate_params({}).items() if k in P._TABLE_SETTINGS}
    props = Atmosphere.earth().optical_properties(np.array([550.0]))
    changed = dict(base)
    v = base[name]
    if name == "remaining_orders":
        changed[name] = "geometric" if v == "none" else "none"
    elif name == "stored_table":
        changed[name] = "subset" if v == "full" else "full"
    elif v is None:
        changed[name] = 64
    else:
        changed[name] = v + (1.0 if isinstance(v, float) else 2)
    assert _cache.key(props, changed) != _cache.key(props, base)


@pytest.mark.parametrize("atm", [
    Atmosphere.earth(turbidity=3.0),
    Atmosphere.earth(ground_albedo=0.31),
    Atmosphere.earth(aerosol_optical_depth=0.2),
    Atmosphere.earth(planet_radius_m=6.371e6),
])
def test_every_atmosphere_field_changes_the_key(atm):
    wl = np.array([550.0])
    s = {"orders": 4}
    assert _cache.key(atm.optical_properties(wl), s) != _cache.key(
        Atmosphere.earth().optical_properties(wl), s)
    assert _cache.key(Atmosphere.earth().optical_properties(wl), s) == _cache.key(
        Atmosphere.earth().optical_properties(wl), s)


def test_changed_setting_or_atmosphere_recomputes():
    tiny()
    assert tiny(orders=3).from_cache is False
    assert tiny(atmosphere=Atmosphere.earth(ground_albedo=0.2)).from_cache is False
    assert tiny(table_wavelengths_nm=[560.0]).from_cache is False
    assert len(files()) == 4
    assert tiny().from_cache is True


@pytest.mark.parametrize("damage", ["garbage", "truncated", "empty", "no meta", "bad meta"])
def test_corrupt_cache_file_is_recomputed(damage):
    ref = tiny()
    (name,) = files()
    entry = os.path.join(_cache.cache_dir(), name)
    if damage == "no meta":
        os.remove(os.path.join(entry, "meta.json"))
    elif damage == "bad meta":
        with open(os.path.join(entry, "meta.json"), "w") as f:
            f.write("{not json")
    else:
        path = os.path.join(entry, "single_scattering.npy")
        data = open(path, "rb").read()
        with open(path, "wb") as f:
            f.write({"garbage": b"not a table file" * 100, "truncated": data[: len(data) // 2],
                     "empty": b""}[damage])
    again = tiny()
    assert not again.from_cache
    assert_same_tables(ref._t, again._t, timing=False)   # recomputed: same tables, new timing
    assert tiny().from_cache      # rewritten


def test_size_limit_evicts_least_recently_used(monkeypatch):
    a = tiny()
    size = _cache._size(os.path.join(_cache.cache_dir(), files()[0]))
    monkeypatch.setenv("SKYDOME_CACHE_LIMIT_BYTES", str(int(2.5 * size)))
    tiny(orders=3)
    first_two = files()
    # touch a's file (a cache hit), so that the orders=3 file is the least recently used
    old = os.path.getmtime(os.path.join(_cache.cache_dir(), first_two[0], "meta.json")) - 100
    for n in first_two:
        os.utime(os.path.join(_cache.cache_dir(), n, "meta.json"), (old, old))
    assert tiny().from_cache
    tiny(orders=4)
    assert len(files()) == 2
    assert tiny().from_cache            # kept: used most recently
    assert not tiny(orders=3).from_cache  # evicted
    del a


def test_tables_larger_than_the_limit_are_not_stored(monkeypatch):
    monkeypatch.setenv("SKYDOME_CACHE_LIMIT_BYTES", "1000")
    tiny()
    assert files() == []


def test_bad_limit_is_refused(monkeypatch):
    monkeypatch.setenv("SKYDOME_CACHE_LIMIT_BYTES", "-5")
    with pytest.raises(ValueError, match="SKYDOME_CACHE_LIMIT_BYTES"):
        tiny()


def test_clear_cache():
    tiny()
    tiny(orders=3)
    os.makedirs(os.path.join(_cache.cache_dir(), ".left-by-a-killed-write.tmp"))
    assert len(files()) == 2
    assert P.clear_cache() > 0
    assert os.listdir(_cache.cache_dir()) == []
    assert not tiny().from_cache


def test_unwritable_cache_folder_still_builds(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    monkeypatch.setenv("SKYDOME_CACHE_DIR", str(blocker / "sub"))
    m = tiny()
    assert not m.from_cache and np.all(np.isfinite(m._t.multiple_scattering))


def test_cli_cache_info_and_clear():
    """`skydome cache info` counts the table sets on disk and `skydome cache clear` empties
    the folder (checked on the folder itself, not through the command's own output)."""
    from typer.testing import CliRunner

    from skydome.cli import app

    tiny()
    assert len(files()) == 1
    runner = CliRunner()
    res = runner.invoke(app, ["cache", "info"])
    assert res.exit_code == 0, res.output
    assert "1 table sets" in res.output and _cache.cache_dir() in res.output
    res = runner.invoke(app, ["cache", "clear"])
    assert res.exit_code == 0, res.output
    assert files() == []


def test_cli_render_of_a_new_atmosphere_leaves_its_entry_complete(tmp_path, monkeypatch):
    """`skydome render` of an atmosphere not in the cache writes its entry on a thread
    beside the render (cli._kit._build_model: ``_cache.background_writes``); when the
    command returns the entry is complete: no write pending, and a model of the same
    settings reads it."""
    import threading

    from typer.testing import CliRunner

    from skydome.cli import app

    writers = []
    real = _cache._write_entry

    def recorded(*a, **k):
        writers.append(threading.current_thread().name)
        return real(*a, **k)

    monkeypatch.setattr(_cache, "_write_entry", recorded)

    opts = []
    for k, v in {**TINY, "n_wavelengths": 1}.items():
        if k != "table_wavelengths_nm":
            opts += ["--" + k.replace("_", "-"), str(v)]
    res = CliRunner().invoke(app, ["render", "--sun-elevation", "30", "--size", "16", "--out",
                                   str(tmp_path / "x.png")] + opts)
    assert res.exit_code == 0, res.output
    assert writers == ["skydome-cache-write"]
    assert not _cache._PENDING and len(files()) == 1
    assert tiny().from_cache


# -- the stored table of orders 2..N: built on first use, added to the entry -----------------
STORED = _cache._STORED + ".npy"
AP = (direction_from_angles([30.0, 5.0], [0.0, 180.0]), 2e3, [550.0])


def entry():
    (name,) = files()
    return os.path.join(_cache.cache_dir(), name)


def no_kernel(monkeypatch):
    from skydome.models.simulated.precomputed import _multiple

    def fail(*a, **k):
        raise AssertionError("the stored table was integrated although it is cached")

    monkeypatch.setattr(_multiple, "multiple_scattering_table", fail)


def test_stored_table_joins_the_entry_and_a_hit_reads_it(monkeypatch):
    first = tiny()
    path = entry()
    assert not os.path.exists(os.path.join(path, STORED))
    size0 = _cache._size(path)
    meta0 = os.path.getsize(os.path.join(path, "meta.json"))
    assert not first._t.has_multiple_scattering
    ref_ap = first.aerial_perspective(*AP)          # builds the table, adds it to the entry
    assert first._t.has_multiple_scattering
    table = np.array(first._t.multiple_scattering)
    on_disk = np.load(os.path.join(path, STORED))
    assert on_disk.dtype == np.float32 and np.array_equal(on_disk, table)
    # the entry grows by the table's file and its checksum record in meta.json
    grown = os.path.getsize(os.path.join(path, "meta.json")) - meta0
    assert 0 < grown < 200
    assert _cache._size(path) == size0 + os.path.getsize(os.path.join(path, STORED)) + grown
    assert [n for n in os.listdir(path) if n.startswith(".")] == []   # no temporary left
    # a later model (as a later process): a hit for both parts, nothing recomputed
    no_kernel(monkeypatch)
    monkeypatch.setattr(_precompute, "precompute", lambda *a, **k: 1 / 0)
    second = tiny()
    assert second.from_cache and second._t.has_multiple_scattering
    assert np.array_equal(second._t.multiple_scattering, table)
    for x, y in zip(second.aerial_perspective(*AP), ref_ap):
        assert np.array_equal(x, y)


def test_hit_without_the_stored_table_builds_and_adds_it(monkeypatch, tmp_path):
    tiny()
    m = tiny()
    assert m.from_cache and not m._t.has_multiple_scattering
    m.radiance(AP[0], [550.0])                      # the sky alone: not built
    assert not os.path.exists(os.path.join(entry(), STORED))
    m.export_textures(tmp_path / "tex")
    assert os.path.exists(os.path.join(entry(), STORED))
    no_kernel(monkeypatch)
    assert tiny()._t.has_multiple_scattering


@pytest.mark.parametrize("damage", ["missing", "garbage", "truncated", "empty", "wrong shape",
                                    "float64"])
def test_corrupt_or_missing_stored_table_is_rebuilt(damage):
    ref = tiny()
    ref.aerial_perspective(*AP)
    table = np.array(ref._t.multiple_scattering)
    file = os.path.join(entry(), STORED)
    data = open(file, "rb").read()
    if damage == "missing":
        os.remove(file)
    elif damage == "wrong shape":
        np.save(file, table[:1])
    elif damage == "float64":
        np.save(file, table.astype(np.float64))
    else:
        with open(file, "wb") as f:
            f.write({"garbage": b"not a table file" * 100, "truncated": data[: len(data) // 2],
                     "empty": b""}[damage])
    again = tiny()
    assert again.from_cache                          # the rest of the entry is still a hit
    assert not again._t.has_multiple_scattering and not os.path.exists(file)
    assert np.array_equal(again._t.multiple_scattering, table)      # rebuilt: the same table
    assert np.array_equal(np.load(file), table)                     # and written again
    assert tiny()._t.has_multiple_scattering


def test_stored_table_written_slab_by_slab_is_the_table(monkeypatch):
    ref = tiny(cache=False)
    table = np.array(ref._t.multiple_scattering)      # built in memory, in one piece
    monkeypatch.setattr(_precompute, "STORED_SLAB_BYTES", 1)   # one r node per slab
    m = tiny()
    calls = []
    real = _precompute.stored_table_of
    monkeypatch.setattr(_precompute, "stored_table_of",
                        lambda t, r_range=None: calls.append(r_range) or real(t, r_range))
    m.aerial_perspective(*AP)
    assert calls == [(0, 1), (1, 2), (2, 3), (3, 4)]
    assert np.array_equal(np.load(os.path.join(entry(), STORED)), table)
    assert np.array_equal(m._t.multiple_scattering, table)


def test_interrupted_stored_table_write_leaves_nothing_partial(monkeypatch):
    m = tiny()
    before = sorted(os.listdir(entry()))
    monkeypatch.setattr(_precompute, "STORED_SLAB_BYTES", 1)   # one r node per slab
    real = _precompute.stored_table_of
    calls = []

    def interrupted(t, r_range=None):
        calls.append(r_range)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(t, r_range)

    monkeypatch.setattr(_precompute, "stored_table_of", interrupted)
    with pytest.raises(KeyboardInterrupt):
        m.aerial_perspective(*AP)
    assert calls[:2] == [(0, 1), (1, 2)]          # two slabs were written before
    assert sorted(os.listdir(entry())) == before   # no partial file, no temporary
    assert not m._t.has_multiple_scattering
    monkeypatch.setattr(_precompute, "stored_table_of", real)
    m.aerial_perspective(*AP)                        # built again, and now stored
    assert os.path.exists(os.path.join(entry(), STORED))


def test_unwritable_entry_builds_the_table_in_memory(monkeypatch):
    m = tiny()
    ref = np.array(tiny(cache=False)._t.multiple_scattering)

    def full_disk(*a, **k):
        raise OSError(28, "No space left on device")

    from skydome import _io

    monkeypatch.setattr(_io, "atomic_file", full_disk)
    assert np.array_equal(m._t.multiple_scattering, ref)
    assert not os.path.exists(os.path.join(entry(), STORED))


def test_size_limit_and_clear_count_the_stored_table(monkeypatch):
    a = tiny()
    (name_a,) = files()
    b = tiny(orders=3)
    (name_b,) = set(files()) - {name_a}
    paths = [os.path.join(_cache.cache_dir(), n) for n in files()]
    path_b = os.path.join(_cache.cache_dir(), name_b)
    old = os.path.getmtime(os.path.join(path_b, "meta.json")) - 100
    for p in paths:
        if p != path_b:
            os.utime(os.path.join(p, "meta.json"), (old, old))   # a: least recently used
    table_bytes = b._t.single_scattering[0].nbytes
    total = sum(_cache._size(p) for p in paths)
    # room for both entries but not for b's stored table as well: adding it evicts a
    monkeypatch.setenv("SKYDOME_CACHE_LIMIT_BYTES", str(total + table_bytes // 2))
    b.aerial_perspective(*AP)
    assert [os.path.join(_cache.cache_dir(), n) for n in files()] == [path_b]
    assert os.path.exists(os.path.join(path_b, STORED))
    monkeypatch.delenv("SKYDOME_CACHE_LIMIT_BYTES")
    size_b = _cache._size(path_b)
    assert size_b > table_bytes
    assert P.clear_cache() == size_b and files() == []
    del a


# -- the content checked on load: checksums and finiteness -----------------------------------
def _flip(path, start_fraction=0.5, n=4096):
    """Invert ``n`` bytes (or all after the header, if fewer) from the middle of ``path``'s
    data."""
    data = bytearray(open(path, "rb").read())
    header = len(data) - np.load(path, mmap_mode="r").nbytes
    n = min(n, len(data) - header)
    a = max(header, min(len(data) - n, header + int(start_fraction * (len(data) - header))))
    data[a:a + n] = bytes(255 - b for b in data[a:a + n])
    open(path, "wb").write(bytes(data))


def _served(m):
    """What a model serves from its tables: the sky's radiance and the table of orders
    2..N (built from the scattering density; it gives the aerial perspective)."""
    try:
        return m.radiance(AP[0], [550.0]), np.array(m._t.multiple_scattering)
    except ValueError as exc:              # the model's own NaN guard
        return str(exc), None


def _damaged_without_the_check(monkeypatch):
    """What the damaged entry would serve if nothing checked it (the control)."""
    with monkeypatch.context() as mp:
        mp.setattr(_cache, "_verify", lambda *a: None)
        m = tiny(cache=True)
        assert m.from_cache
        m._t.set_multiple_scattering_sink(lambda shape, slabs: None)   # build in memory
        return _served(m)


def _differs(a, b):
    return isinstance(a[0], str) or not (np.array_equal(a[0], b[0])
                                         and np.array_equal(a[1], b[1]))


@pytest.mark.parametrize("array", ["scattering_density", "single_scattering", "irradiance"])
def test_flipped_bytes_are_found_and_the_entry_rebuilt(array, monkeypatch, capfd):
    """4096 inverted bytes inside an array file (the fault of issue 30): without the check
    the entry serves another sky; with it the entry is rebuilt, the sky equals a fresh build
    and one line on stderr names the entry."""
    fresh = _served(tiny(cache=False))
    tiny()
    path = entry()
    file = os.path.join(path, array + ".npy")
    before = np.load(file)
    _flip(file)
    assert not np.array_equal(np.load(file), before, equal_nan=True)    # really damaged
    capfd.readouterr()
    again = tiny()
    assert not again.from_cache
    note = [ln for ln in capfd.readouterr().err.splitlines() if ln.strip()]
    assert len(note) == 1 and path in note[0] and "damaged" in note[0], note
    assert "checksum" in note[0] and array in note[0]
    assert not _differs(_served(again), fresh)
    assert tiny().from_cache                                  # rebuilt entry: a clean hit
    assert capfd.readouterr().err == ""
    if array == "single_scattering":   # the control: unchecked, it serves another sky
        # (in these tiny tables the density's middle bytes and the irradiance table do
        # not reach the two directions served here; their damage is checked on the file)
        _flip(os.path.join(entry(), array + ".npy"))
        assert _differs(_damaged_without_the_check(monkeypatch), fresh)


@pytest.mark.parametrize("checksum", ["stale", "updated"])
def test_nan_in_an_entry_is_found_and_the_entry_rebuilt(checksum, capfd):
    """NaN written into an array file: with its checksum left as it was (caught by the
    checksum) and with the checksum recomputed for the new bytes (zlib.crc32 over the
    array's bytes, the format's definition: caught by the finiteness check). Either way the
    entry is rebuilt and serves the fresh sky."""
    import json
    import zlib

    fresh = tiny(cache=False).radiance(AP[0], [550.0])
    tiny()
    path = entry()
    file = os.path.join(path, "single_scattering.npy")
    a = np.load(file)
    a.reshape(-1)[::3] = np.nan
    np.save(file, a)
    if checksum == "updated":
        meta = json.load(open(os.path.join(path, "meta.json")))
        meta["checksums"]["single_scattering"]["crc32"] = zlib.crc32(a.tobytes())
        json.dump(meta, open(os.path.join(path, "meta.json"), "w"))
    capfd.readouterr()
    again = tiny()
    assert not again.from_cache
    note = [ln for ln in capfd.readouterr().err.splitlines() if ln.strip()]
    assert len(note) == 1 and path in note[0], note
    assert ("NaN" in note[0]) == (checksum == "updated")
    assert np.array_equal(again.radiance(AP[0], [550.0]), fresh)
    assert tiny().from_cache


def test_entry_without_checksums_is_rebuilt(capfd):
    import json

    tiny()
    meta_file = os.path.join(entry(), "meta.json")
    meta = json.load(open(meta_file))
    del meta["checksums"]
    json.dump(meta, open(meta_file, "w"))
    assert not tiny().from_cache
    assert "no checksums" in capfd.readouterr().err
    assert tiny().from_cache


@pytest.mark.parametrize("damage", ["flipped", "nan"])
def test_damaged_stored_table_is_removed_and_built_again(damage, capfd):
    ref = tiny()
    ref.aerial_perspective(*AP)
    table = np.array(ref._t.multiple_scattering)
    file = os.path.join(entry(), STORED)
    if damage == "flipped":
        _flip(file)
    else:
        a = np.load(file)
        a[0, 0] = np.nan
        np.save(file, a)
    capfd.readouterr()
    again = tiny()
    assert again.from_cache                                   # the rest still a hit
    note = [ln for ln in capfd.readouterr().err.splitlines() if ln.strip()]
    assert len(note) == 1 and entry() in note[0] and STORED in note[0], note
    assert not again._t.has_multiple_scattering and not os.path.exists(file)
    assert np.array_equal(again._t.multiple_scattering, table)     # built again
    assert np.array_equal(np.load(file), table)                    # and stored again
    assert tiny()._t.has_multiple_scattering
    assert capfd.readouterr().err == ""


def test_tables_that_are_not_finite_are_not_stored(monkeypatch):
    real = _precompute.precompute

    def poisoned(*a, **k):
        t = real(*a, **k)
        t.irradiance = np.full_like(t.irradiance, np.nan)
        return t

    monkeypatch.setattr(_precompute, "precompute", poisoned)
    tiny()
    assert files() == []


def test_full_cache_folder_says_so_once(tmp_path, monkeypatch, capfd):
    """A cache folder on a full disk (a 64 KiB tmpfs; the tiny entry needs about 280 KB):
    the model works from memory, one line on stderr says the cache could not be written
    (once per process, not per model), and no temporary is left in the folder."""
    from _tmpfs import small_disk

    with small_disk(tmp_path / "disk", "64k") as disk:
        monkeypatch.setenv("SKYDOME_CACHE_DIR", str(disk))
        monkeypatch.setattr(_cache, "_WRITE_FAILED_SAID", False)
        fresh = tiny(cache=False).radiance(AP[0], [550.0])
        capfd.readouterr()
        a = tiny()
        b = tiny(orders=3)
        err = [ln for ln in capfd.readouterr().err.splitlines() if ln.strip()]
        assert len(err) == 1, err
        assert str(disk) in err[0] and "could not be written" in err[0]
        assert "no space left on device" in err[0].lower()
        assert not a.from_cache and not b.from_cache
        assert np.array_equal(a.radiance(AP[0], [550.0]), fresh)
        assert os.listdir(disk) == []


@pytest.mark.parametrize("damage", ["flipped", "nan"])
def test_damaged_saved_table_file_is_refused(damage, tmp_path):
    """A file written by PrecomputedSky.save with flipped bytes (the zip member's CRC-32
    no longer matches) or with NaN in a table: load refuses it, naming the file."""
    import zipfile

    m = tiny(cache=False)
    path = tmp_path / "t.npz"
    m.save(path)
    if damage == "flipped":
        with zipfile.ZipFile(path) as z:
            info = z.getinfo("single_scattering.npy")
        data = bytearray(path.read_bytes())
        start = info.header_offset + 30 + len(info.filename) + len(info.extra) + 200
        data[start:start + 64] = bytes(255 - b for b in data[start:start + 64])
        path.write_bytes(bytes(data))
    else:
        with np.load(path) as z:
            arrays = {k: z[k] for k in z.files}
        arrays["irradiance"] = arrays["irradiance"].copy()
        arrays["irradiance"].reshape(-1)[0] = np.nan
        np.savez(path, **arrays)
    with pytest.raises(ValueError, match="damaged") as info:
        P.PrecomputedSky.load(path)
    assert str(path) in str(info.value)


# -- tables held in the process: shared while held, freed when dropped ----------------------
@pytest.mark.parametrize("half", [False, True])
def test_a_dropped_model_frees_its_tables_without_the_cyclic_collector(half, monkeypatch):
    """A model's tables are freed as soon as the model is dropped (no reference cycle keeps
    them for Python's cyclic collector, which the allocation of large arrays does not set
    off: a day's timelapse of 35 frames held 8.7 GB that way, through the reader of a
    stored table in half precision, as the default entry holds it)."""
    import gc
    import weakref

    if half:
        monkeypatch.setattr(_cache, "HALF_MIN_BYTES", 0)
    m = tiny()
    m._t.multiple_scattering                         # the stored table joins the entry
    assert (_cache._STORED in _cache.json.load(open(os.path.join(entry(), _cache._META)))
            .get("encoded", {})) == half
    del m
    gc.collect()
    gc.disable()
    try:
        m = tiny()
        assert m.from_cache
        ref = weakref.ref(m._t)
        del m
        assert ref() is None
    finally:
        gc.enable()


def test_a_held_entry_is_shared_and_read_again_once_changed_on_disk(monkeypatch):
    """A second model of an atmosphere whose tables this process still holds gets the same
    tables (no second read and decoding of the entry); once a file of the entry changes on
    disk, or the cache is cleared, the entry is read again."""
    import time

    tiny()                                           # precomputed and stored
    held = tiny()
    assert held.from_cache
    calls = []
    read = _cache._read_table
    monkeypatch.setattr(_cache, "_read_table", lambda *a, **k: calls.append(1) or read(*a, **k))
    low = sd.Sun(elevation_deg=10.0, azimuth_deg=90.0)
    again = sd.model("precomputed", sun=low, **TINY)
    assert again.from_cache and again._t is held._t and calls == []
    d = direction_from_angles([89.0, 20.0, 5.0], [0.0, 90.0, 180.0])
    alone = sd.model("precomputed", sun=low, cache=False, **TINY)
    assert np.array_equal(again.radiance(d, [550.0]), alone.radiance(d, [550.0]))
    file = os.path.join(entry(), "irradiance.npy")
    data = open(file, "rb").read()
    time.sleep(0.05)                                 # a later modification time
    open(file, "wb").write(data)
    changed = tiny()
    assert changed.from_cache and changed._t is not held._t
    assert_same_tables(changed._t, held._t)
    P.clear_cache()
    assert not tiny().from_cache
