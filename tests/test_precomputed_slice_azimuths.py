"""The observer's sky maps integrate each view zenith's ray once per azimuth; the parts of
that work which do not depend on the azimuth are done once per view zenith:

* ``_twilight.single_scattering_slice`` keeps a ray's quadrature nodes (their distances,
  weights, radii, view columns and scatterer densities) from one azimuth to the next while
  the ray's break points (its ends, its lowest point, its shadow crossings) are the same;
* ``_multiple.multiple_scattering_slice`` computes the angle from the sun and its theta cell
  in the scattering density once per azimuth, not once per quadrature node.

The check is the kernels' own definition: a map of all azimuths at once must equal, bit for
bit, the maps of each azimuth alone (where nothing can be kept from another azimuth), for
suns by day (no shadow: the nodes kept at every azimuth), in twilight (the shadow's crossings
move with the azimuth: the nodes computed again where they do), observers on the ground and
at 15 km (rays to the ground, split at their lowest point), with the view columns integrated
along the rays (``observer_columns``) and read from the column table."""

import numpy as np
import pytest

import skydome as sd
from skydome.models.simulated.precomputed import _cache

SMALL = dict(scattering_r_size=6, scattering_mu_size=16, scattering_mu_s_size=12,
             density_mu_s_size=12, scattering_nu_size=4, irradiance_mu_s_size=8,
             irradiance_r_size=4, transmittance_mu_size=16, transmittance_r_size=6, orders=3,
             table_wavelengths_nm=[400.0, 550.0, 700.0])


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    import os

    old = os.environ.get("SKYDOME_CACHE_DIR")
    os.environ["SKYDOME_CACHE_DIR"] = str(tmp_path_factory.mktemp("cache"))
    try:
        m = sd.model("precomputed", sun=sd.Sun(elevation_deg=30.0, azimuth_deg=180.0),
                     atmosphere=sd.Atmosphere.earth(aerosol_optical_depth=0.2),
                     observer_single_scattering=True, observer_columns=True, **SMALL)
        m._t  # the tables, built here
        yield m
    finally:
        if old is None:
            os.environ.pop("SKYDOME_CACHE_DIR", None)
        else:
            os.environ["SKYDOME_CACHE_DIR"] = old
        with _cache._LOADED_LOCK:
            _cache._LOADED.clear()


def _observer(base, elevation, altitude):
    return base.with_sun(sd.Sun(elevation_deg=elevation, azimuth_deg=180.0),
                         observer_altitude_m=altitude)


def _single(m, cphi, integrated):
    from skydome.models.simulated.precomputed import _twilight
    from skydome.models.simulated.precomputed._precompute import (QUADRATURE_SCALE_M,
                                                                   tables_medium)
    from skydome.transport._quadrature import gauss_legendre_unit

    t = m._t
    cos_th, ground, _ = m._slice_grid()
    rx, rw = gauss_legendre_unit(_twilight.TWILIGHT_SS_NODES)
    out = np.empty((t.scattering_index.size, ground.size, cphi.size, m.n_wavelengths))
    gx, gw = m._column_rule() if integrated else (np.empty(0), np.empty(0))
    _twilight.single_scattering_slice(
        t.columns, tables_medium(t), t.scattering_index,
        np.ascontiguousarray(t.scattering_coefficient, dtype=np.float64), m._alpha, m._r0,
        float(m.sun.direction[2]), QUADRATURE_SCALE_M, rx, rw, cos_th, ground, cphi, out,
        gx, gw)
    return out


def _multiple(m, cphi, integrated):
    from skydome.models.simulated.precomputed import _multiple
    from skydome.models.simulated.precomputed._precompute import (QUADRATURE_SCALE_M,
                                                                   tables_medium)

    t = m._t
    cos_th, ground, _ = m._slice_grid()
    J, j0 = t.scattering_density_rows(0, t.density_shape[4])
    out = np.empty((ground.size, cphi.size, m.n_wavelengths))
    reach = np.empty((ground.size, 2), dtype=np.int64)
    gx, gw = m._column_rule() if integrated else (np.empty(0), np.empty(0))
    _multiple.multiple_scattering_slice(
        J, j0, t.density_shape[4], tables_medium(t), t.scattering_index, t.columns,
        t.mu_s_min, m._r0, float(m.sun.direction[2]), int(m.integration_samples),
        QUADRATURE_SCALE_M, cos_th, ground, cphi, reach, out, gx, gw)
    return out


CASES = [(30.0, 0.0), (30.0, 15e3), (2.0, 15e3), (-4.0, 0.0), (-4.0, 15e3), (-10.0, 2e3)]


@pytest.mark.parametrize("integrated", [True, False])
@pytest.mark.parametrize("elevation,altitude", CASES)
def test_single_scattering_map_is_each_azimuth_alone(base, elevation, altitude, integrated):
    m = _observer(base, elevation, altitude)
    _, _, cphi = m._slice_grid()
    whole = _single(m, cphi, integrated)
    assert np.isfinite(whole).all() and whole.max() > 0.0
    for i in range(cphi.size):
        alone = _single(m, cphi[i:i + 1].copy(), integrated)
        np.testing.assert_array_equal(whole[:, :, i:i + 1], alone,
                                      err_msg=f"azimuth node {i}")


@pytest.mark.parametrize("elevation,altitude", CASES[:4])
def test_multiple_scattering_map_is_each_azimuth_alone(base, elevation, altitude):
    m = _observer(base, elevation, altitude)
    _, _, cphi = m._slice_grid()
    whole = _multiple(m, cphi, True)
    assert np.isfinite(whole).all() and whole.max() > 0.0
    for i in range(0, cphi.size, 7):
        alone = _multiple(m, cphi[i:i + 1].copy(), True)
        np.testing.assert_array_equal(whole[:, i:i + 1], alone, err_msg=f"azimuth node {i}")

