"""The scattering density's fixed parts in ``precomputed``: the phase matrices in the
azimuthal Fourier basis and the matrix products built on them, the single batch of order 2.

References used here: the dense phase matrix of ``_density.phase_matrix`` (a direct sum of
the phase function over every incident direction and its mirror image, no Fourier basis)
and the dense matrix products built on it (the path kept for the grids the factorisation
does not cover); the precomputation with order 2 in several batches of wavelengths.
"""

import numpy as np
import pytest

import skydome as sd
from skydome.atmosphere import Atmosphere
from skydome.models.simulated.precomputed import _density, _precompute

RAYLEIGH, HG, CS, ISO, TAB = 0, 1, 2, 3, 4
GAMMA = 0.0279 / (2.0 - 0.0279)


def _tabulated(nl, na=181):
    """Henyey-Greenstein tables on the uniform angle grid, g from 0.6 upwards per wavelength."""
    th = np.linspace(0.0, np.pi, na)
    pt = np.zeros((2, na, nl))
    for l in range(nl):
        g = 0.6 + 0.02 * l
        d = 1.0 + g * g - 2.0 * g * np.cos(th)
        pt[1, :, l] = (1.0 - g * g) / d ** 1.5 / (4.0 * np.pi)
    return pt


def _reconstruct(q, k, l):
    """The dense matrix [o, i] from the quadrature's modes of constituent k, wavelength l."""
    n_ti, n_pi = q.th_in.size, q.ph_in.size
    P = np.zeros((q.th_out.size, q.ph_out.size, n_ti, n_pi))
    for sel, G, S in zip(q.classes, q.modes[k][l], q.synthesis):
        n_m = G.shape[0]
        P[:, sel] = np.einsum("mn,nta,nb->tmab", S[:, :n_m].astype(np.float64),
                              G.astype(np.float64), q.analysis[:n_m].astype(np.float64))
    return P.reshape(q.n_out, q.n_in)


@pytest.mark.parametrize("n_in, n_out", [(32, 32), (16, 32), (16, 16), (12, 8)])
@pytest.mark.parametrize("codes", [(RAYLEIGH, CS), (ISO, HG), (RAYLEIGH, TAB)])
def test_azimuthal_modes_reproduce_the_dense_phase_matrix(n_in, n_out, codes):
    """The phase matrices in the azimuthal Fourier basis (Rayleigh and isotropic on 3 modes
    only) equal the dense matrix summed over every incident direction, to float32 rounding
    of the stored modes."""
    pc = np.array(codes)
    pp = np.array([GAMMA if codes[0] == RAYLEIGH else 0.0, 0.76])
    pt = _tabulated(3)
    q = _precompute._DensityQuadrature(pc, pp, pt, n_in, n_out)
    assert q.modes is not None
    assert len(q.classes) == (1 if (2 * n_in // n_out) % 2 == 0 else 2)
    for k in range(2):
        n_l = pt.shape[2] if codes[k] == TAB else 1
        assert len(q.modes[k]) == n_l
        if codes[k] in (RAYLEIGH, ISO):
            assert q.modes[k][0][0].shape[0] == 3
        for l in range(n_l):
            dense = np.empty((q.n_out, q.n_in))
            _density.phase_matrix(pc, pp, pt, k, l, q.th_out, q.ph_out, q.th_in, q.ph_in,
                                  q.d_omega, dense)
            err = np.abs(_reconstruct(q, k, l) - dense).max() / np.abs(dense).max()
            assert err < 2e-6, (k, l, err)


def test_rayleigh_modes_beyond_the_second_vanish():
    """A phase function quadratic in the cosine has no azimuthal mode above 2: the modes
    3 .. N that the factorisation leaves out are zero to double rounding."""
    q = _precompute._DensityQuadrature(np.array([RAYLEIGH]), np.array([GAMMA]),
                                       np.zeros((1, 2, 1)), 16)
    G = np.empty((16, q.th_out.size, 16))
    _density.azimuth_modes(np.array([RAYLEIGH]), np.array([GAMMA]), np.zeros((1, 2, 1)), 0, 0,
                           q.th_out, q.th_in, q.d_omega, 16, 0.5, G)
    assert np.abs(G[3:]).max() < 1e-13 * np.abs(G[:3]).max()
    assert np.abs(G[2]).max() > 1e-3 * np.abs(G[0]).max()


@pytest.mark.parametrize("n_in, n_out, codes", [(32, 32, (RAYLEIGH, CS)), (16, 32, (RAYLEIGH, CS)),
                                                (12, 8, (ISO, TAB)), (16, 16, (RAYLEIGH, TAB))])
def test_azimuthal_products_equal_the_dense_products(n_in, n_out, codes, monkeypatch):
    """J from the azimuthal products equals J from the dense phase matrices (independent
    path: ``azimuthal=False``) on a positive incident field with a forward peak, in blocks
    that split the columns unevenly, to float32 rounding."""
    monkeypatch.setattr(_precompute, "DENSITY_BLOCK_COLUMNS", 50)
    rng = np.random.default_rng(3)
    nl, n_r, n_ms = 5, 3, 7
    pc = np.array(codes)
    pp = np.array([GAMMA, 0.76])
    pt = _tabulated(nl + 2)
    qa = _precompute._DensityQuadrature(pc, pp, pt, n_in, n_out)
    qd = _precompute._DensityQuadrature(pc, pp, pt, n_in, n_out, azimuthal=False)
    assert qa.modes is not None and qd.modes is None
    # incident radiance: a smooth field plus a peak around the sun (small th_in)
    th = np.repeat(qa.th_in, qa.ph_in.size)
    peak = np.exp(-(th / 0.15) ** 2)[:, None, None, None]
    L = (rng.random((qa.n_in, n_r, n_ms, nl)) + 50.0 * peak).astype(np.float32)
    beta_s = rng.random((2, nl)) * 1e-5
    w = _precompute._column_weights(beta_s, n_r, n_ms, nl)
    rhs = np.empty((10, n_r * n_ms * nl), np.float32)
    shape = (2, qa.th_out.size, qa.ph_out.size, n_r, n_ms, nl)
    Ja, Jd = np.empty(shape, np.float32), np.empty(shape, np.float32)
    _precompute.density_products(qa, L, w, beta_s, None, Ja, 2)
    _precompute.density_products(qd, L, w, beta_s, rhs, Jd, 2)
    assert np.all(Jd > 0)
    np.testing.assert_allclose(Ja, Jd, rtol=1e-5)


def test_grids_outside_the_factorisation_keep_the_dense_matrices():
    """Where 2 n_in is no multiple of n_out (here 24 / 16) the dense matrices are used."""
    q = _precompute._DensityQuadrature(np.array([RAYLEIGH, CS]), np.array([GAMMA, 0.76]),
                                       np.zeros((2, 2, 1)), 12, 16)
    assert q.modes is None and q.left.shape[0] == q.n_out


def test_order_two_in_one_batch_equals_several_batches(monkeypatch):
    """Order 2 in one batch of every wavelength (J written straight into the summed
    density) gives the tables of the same precomputation in one batch per wavelength."""
    small = dict(scattering_r_size=6, scattering_mu_size=16, scattering_mu_s_size=6,
                 scattering_nu_size=4, irradiance_mu_s_size=8, irradiance_r_size=4,
                 transmittance_mu_size=32, transmittance_r_size=8, orders=3,
                 sphere_samples=8, high_order_sphere_samples=8)
    atm = Atmosphere.earth(aerosol_optical_depth=0.3)
    kw = dict(sun=sd.Sun(elevation_deg=20, azimuth_deg=180), atmosphere=atm,
              table_wavelengths_nm=[450.0, 550.0, 650.0], cache=False, **small)
    one = sd.model("precomputed", **kw)._t
    monkeypatch.setattr(_precompute, "ORDER_BATCH_BYTES", 1)
    p = sd.model("precomputed", **kw)
    assert _precompute.order_batch_size(p._validate_params(small), 3, 2) == 1
    sep = p._t
    for name in ("scattering_density", "multiple_scattering", "irradiance"):
        a, b = getattr(one, name), getattr(sep, name)
        np.testing.assert_allclose(a, b, rtol=1e-5, atol=1e-6 * np.abs(b).max(), err_msg=name)


@pytest.mark.parametrize("n_in, n_out, codes", [(16, 32, (RAYLEIGH, CS)), (12, 8, (ISO, TAB)),
                                                (16, 16, (RAYLEIGH, TAB))])
def test_source_functional_equals_the_source_total_of_the_products(n_in, n_out, codes):
    """The source strength of the density made from an incident radiance, taken from the
    radiance by ``_SourceFunctional`` (the summed path's remainder ratio, known before the
    products), equals ``source_total`` of the density the products make (independent
    path: the outgoing grid summed node by node), to float32 rounding."""
    rng = np.random.default_rng(7)
    nl, n_r, n_ms = 4, 5, 6
    pc = np.array(codes)
    pp = np.array([GAMMA, 0.76])
    pt = _tabulated(nl)
    q = _precompute._DensityQuadrature(pc, pp, pt, n_in, n_out)
    th = np.repeat(q.th_in, q.ph_in.size)
    peak = np.exp(-(th / 0.15) ** 2)[:, None, None, None]
    L = (rng.random((q.n_in, n_r, n_ms, nl)) + 50.0 * peak).astype(np.float32)
    beta_s = rng.random((2, nl)) * 1e-5
    w = _precompute._column_weights(beta_s, n_r, n_ms, nl)
    J = np.empty((2, q.th_out.size, q.ph_out.size, n_r, n_ms, nl), np.float32)
    _precompute.density_products(q, L, w, beta_s, None, J, 0)
    props = Atmosphere.earth(aerosol_optical_depth=0.3).optical_properties(
        np.linspace(400.0, 700.0, nl), fold=True)
    from skydome.transport._medium import medium_from_properties

    sc = np.array([0, 1], dtype=np.int64)
    args = (medium_from_properties(props), sc)
    ref = _precompute.source_total(J, q, *args)
    got = _precompute._SourceFunctional(q, *args, beta_s, n_r, n_ms)(L)
    assert np.all(ref > 0)
    np.testing.assert_allclose(got, ref, rtol=1e-5)
