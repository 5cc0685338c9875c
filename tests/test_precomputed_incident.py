"""The incident rays' geometry stored once for the orders >= 3 (``_incident``): each order's
incident radiance on the stored geometry is the same bits as
``_density.incident_radiance_rays`` computing the geometry itself (but at the density's
mu_s node of the sun at the zenith, where the azimuth about the sun is singular: there
within float32 rounding) (whose own test,
tests/test_precomputed.py, compares it with one ``_multiple.ray_integral`` per ray), for
several densities and ground irradiance tables on one geometry, rays to the top and to a
reflecting ground."""

import numpy as np

from skydome.atmosphere import Atmosphere
from skydome.transport._medium import medium_from_properties
from skydome.transport._quadrature import gauss_legendre_unit as gauss_rule

WL3 = [440.0, 550.0, 680.0]


def test_stored_geometry_gives_the_same_bits_for_every_order():
    from skydome.models.simulated.precomputed import _density, _incident, _precompute as PC

    props = Atmosphere.earth(aerosol_optical_depth=0.3).optical_properties(np.array(WL3), fold=True)
    p = dict(transmittance_r_size=16, transmittance_mu_size=64)
    m = medium_from_properties(props)
    col = PC.transmittance_columns(m, p)
    sc = np.array([0, 1], dtype=np.int64)
    rule = gauss_rule(5)
    mu_s_min = float(np.cos(np.radians(108.0)))
    n_r, n_ms, n_th = 3, 4, 4
    # theta of the incident rays on J's theta nodes (snapped) and between them
    for n_tj in (9, 6):
        th_in = (np.arange(n_th) + 0.5) * np.pi / n_th
        shape = (2, n_tj, 5, 6, 7, 3)
        args = (m, sc, col, mu_s_min, *rule, 500.0, n_r, n_ms, th_in, th_in)
        g = _incident.incident_rays(shape, *args)
        assert g.kept.all()
        assert (g.gidx >= 0).sum() == g.tg.shape[0] > 0          # some rays reach the ground
        assert np.all(np.diff(g.start) >= 0) and g.start[-1] > 0   # rays at the top: no nodes
        # within a budget: the geometry of about a third of the work items stored, the rest
        # computed in each call
        part = _incident.incident_rays(shape, *args, budget=g.nbytes // 3)
        assert 0.2 < part.kept.mean() < 0.45 and part.nbytes <= g.nbytes // 3
        rng = np.random.default_rng(n_tj)
        for order in range(3):
            J = rng.uniform(0.5, 1.5, shape).astype(np.float32)
            dE = rng.uniform(0.0, 2.0, (4, 8, 3))
            ref = np.empty((n_th * n_th, n_r, n_ms, 3), dtype=np.float32)
            _density.incident_radiance_rays(J, dE, m, sc, col, mu_s_min, *rule, 500.0, n_r, n_ms,
                                            th_in, th_in, ref)
            assert (ref > 0).mean() > 0.9                  # (0 at the top: no length)
            for geometry in (g, part):
                out = np.full(ref.shape, np.nan, dtype=np.float32)
                _incident.incident_radiance(J, dE, *args, geometry, out)
                # every node but the sun at the zenith (the last mu_s node): the same bits
                np.testing.assert_array_equal(out[:, :, :-1].view(np.uint32),
                                              ref[:, :, :-1].view(np.uint32))
                np.testing.assert_allclose(out[:, :, -1], ref[:, :, -1], rtol=1e-6, atol=0)
