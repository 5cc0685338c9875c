"""The ``precomputed`` model's stored 4-D table of orders 2..N, built on its first read:
the same table as the precomputation's step 4 (the same integral of the same summed
density, bit for bit), never built by the sky's ``radiance()`` or a day-sky render, built
by aerial perspective, the texture export and ``save``.

The eager reference is the precomputation's step 4 as it was called inside ``precompute``
before the table became lazy: ``stored_multiple_scattering`` on the summed density with
``max(4, (integration_samples + 1) // 2)`` quadrature nodes, at every node of the table
(or on the subset of ``stored_table_nodes`` with ``MS_NU_SIZE`` nu nodes)."""

import numpy as np
import pytest

import skydome as sd
from skydome.models.simulated.precomputed import _multiple
from skydome.models.simulated.precomputed import _precompute as PC
from skydome.transport.geometry import direction_from_angles

SMALL = dict(scattering_r_size=6, scattering_mu_size=16, scattering_mu_s_size=8,
             scattering_nu_size=4, irradiance_mu_s_size=8, irradiance_r_size=4,
             transmittance_mu_size=32, transmittance_r_size=8, orders=3, sphere_samples=8,
             high_order_sphere_samples=8, table_wavelengths_nm=[450.0, 550.0, 650.0],
             cache=False)
DAY = sd.Sun(elevation_deg=35.0, azimuth_deg=180.0)
DIRS = direction_from_angles([89.0, 40.0, 10.0, 2.0, -5.0, -40.0], [0.0, 90.0, 180.0, 0.0,
                                                                     180.0, 0.0])


def small(**kw):
    return sd.model("precomputed", sun=DAY, **{**SMALL, **kw})


def eager_table(m):
    """Step 4 of the precomputation as it was called eagerly (see the module docstring)."""
    t = m._t
    shape = t.single_scattering.shape[1:]
    n_q = max(4, (m.integration_samples + 1) // 2)
    if m.stored_table == "full":
        nodes, n_nu = (np.arange(shape[1]), np.arange(shape[2])), shape[3]
    else:
        nodes, n_nu = None, PC.MS_NU_SIZE
    return PC.stored_multiple_scattering(
        t.scattering_density, PC.tables_medium(t), t.scattering_index, t.columns, t.mu_s_min,
        n_q, shape, nodes=nodes, n_nu=n_nu)


@pytest.mark.parametrize("stored", ["full", "subset"])
def test_lazy_table_is_the_eager_table(stored):
    m = small(stored_table=stored)
    assert not m._t.has_multiple_scattering
    lazy = m._t.multiple_scattering
    assert m._t.has_multiple_scattering
    ref = eager_table(m)
    assert lazy.dtype == np.float32 and lazy.shape == ref.shape
    assert np.array_equal(lazy, ref)
    assert np.all(np.isfinite(lazy)) and lazy.min() >= 0.0 and lazy.max() > 0.0
    assert m._t.multiple_scattering is lazy          # built once


def test_slabs_of_r_nodes_are_the_table():
    m = small()
    ref = eager_table(m)
    per_r = ref[0].nbytes
    for rows in (1, 4, 6):
        slabs = list(PC.stored_table_slabs(m._t, slab_bytes=rows * per_r))
        assert [s.shape[0] for s in slabs] == [min(rows, 6 - a) for a in range(0, 6, rows)]
        assert np.array_equal(np.concatenate(slabs), ref)
    assert not m._t.has_multiple_scattering
    with pytest.raises(ValueError, match="r_range"):
        PC.stored_table_of(m._t, (4, 9))


def test_day_sky_radiance_and_render_do_not_build_the_table(monkeypatch):
    m = small()

    def fail(*a, **k):
        raise AssertionError("the stored table was built by the sky's radiance")

    monkeypatch.setattr(_multiple, "multiple_scattering_table", fail)
    L = m.radiance(DIRS, [450.0, 550.0, 650.0])
    assert np.all(np.isfinite(L)) and L.min() >= 0.0 and L[:4].min() > 0.0
    m.radiance_table(DIRS)
    m.irradiance_components([550.0])
    img = sd.render(m.with_sun(sd.Sun(elevation_deg=5.0, azimuth_deg=90.0)),
                    sd.Fisheye(24), [450.0, 550.0, 650.0])
    assert np.all(np.isfinite(np.asarray(img.data)))
    assert not m._t.has_multiple_scattering


def test_aerial_perspective_builds_it_once_with_the_same_result():
    m = small()
    ref = small()
    ref._t.multiple_scattering = eager_table(ref)     # the eager table, given up front
    calls = []
    orig = _multiple.multiple_scattering_table

    def counted(*a):
        calls.append(1)
        return orig(*a)

    _multiple.multiple_scattering_table = counted
    try:
        for elev in (35.0, -3.0):
            a = m.with_sun(sd.Sun(elevation_deg=elev, azimuth_deg=180.0))
            b = ref.with_sun(sd.Sun(elevation_deg=elev, azimuth_deg=180.0))
            for x, y in zip(a.aerial_perspective(DIRS[:4], 5e3, [550.0]),
                            b.aerial_perspective(DIRS[:4], 5e3, [550.0])):
                assert np.array_equal(x, y)
    finally:
        _multiple.multiple_scattering_table = orig
    assert len(calls) == 1 and m._t.has_multiple_scattering


def test_export_and_save_build_the_table(tmp_path):
    m = small()
    m.export_textures(tmp_path / "tex")
    assert np.array_equal(np.load(tmp_path / "tex" / "multiple_scattering.npy"),
                          eager_table(m))
    m2 = small()
    m2.save(tmp_path / "t.npz")
    assert m2._t.has_multiple_scattering
    back = type(m2).load(tmp_path / "t.npz")
    assert back._t.has_multiple_scattering
    assert np.array_equal(back._t.multiple_scattering, eager_table(m2))


def test_orders_one_has_a_zero_table_without_density():
    m = small(orders=1)
    assert not m._t.has_density and m._t.has_multiple_scattering
    assert not np.any(m._t.multiple_scattering)


def test_tables_without_a_builder_say_so_and_build_once_given_one():
    """The Tables record imports no kernel: tables made from arrays alone (no stored table,
    no builder) refuse to build the stored table with a ValueError naming the way out, and
    build the eager table once the precomputation's builder is attached."""
    from skydome.models.simulated.precomputed._tables import Tables

    m = small()
    bare = Tables.from_arrays({k: v for k, v in m._t.arrays().items()
                               if k != "multiple_scattering"})
    assert not bare.has_multiple_scattering
    with pytest.raises(ValueError, match="set_multiple_scattering_builder"):
        bare.build_multiple_scattering()
    assert PC.attach_stored_table_builder(bare) is bare
    assert np.array_equal(bare.multiple_scattering, eager_table(m))


def test_the_medium_of_the_tables_is_the_atmosphere_s():
    """``tables_medium`` (the kernels' Medium rebuilt from the tables, for the stored table
    and the observer's slice) holds the planet, the density profiles, the extinction and
    the ground albedo of the atmosphere's own optical properties on the table wavelengths
    (``transport._medium.medium_from_properties``), and its scattering rows at
    ``scattering_index``."""
    from skydome.transport._medium import medium_from_properties

    m = small()
    t = m._t
    got = PC.tables_medium(t)
    ref = medium_from_properties(m.atmosphere.optical_properties(t.table_wavelengths_nm,
                                                                 fold=True))
    assert (got.R, got.Rt) == (ref.R, ref.Rt)
    for name in ("profile_code", "profile_p0", "profile_p1", "extinction", "albedo"):
        assert np.array_equal(getattr(got, name), getattr(ref, name)), name
    sc = t.scattering_index
    assert np.array_equal(got.scattering[sc], ref.scattering[sc])
    assert np.array_equal(got.phase_code[sc], ref.phase_code[sc])
    others = np.setdiff1d(np.arange(ref.scattering.shape[0]), sc)
    assert not np.any(got.scattering[others]) and not np.any(ref.scattering[others])
