"""The vectorised exp of the transport core against the C library's exp (numpy.exp)."""

import numpy as np


def _run(x):
    from skydome.transport._vexp import exp_neg_many

    out = np.empty_like(x)
    ib = np.empty(x.size, dtype=np.int64)
    exp_neg_many(x, x.size, out, ib, ib.view(np.float64))
    return out


def test_exp_neg_many_matches_libm_to_rounding():
    rng = np.random.default_rng(7)
    x = np.concatenate([-rng.uniform(0.0, 708.0, 100_000), -np.logspace(-300, np.log10(708.0), 2000),
                        [0.0, -0.0, -707.999, -0.5 * np.log(2.0), -np.log(2.0)]])
    got = _run(x)
    ref = np.exp(x)            # numpy's exp: the C library's, an independent implementation
    assert np.max(np.abs(got / ref - 1.0)) < 1e-15
    assert got[x.size - 5] == 1.0


def test_exp_neg_many_underflows_to_zero_in_place():
    x = np.array([-709.0, -1e5, -np.inf, -1.0])
    out = x.copy()
    from skydome.transport._vexp import exp_neg_many

    ib = np.empty(x.size, dtype=np.int64)
    exp_neg_many(out, x.size, out, ib, ib.view(np.float64))     # x may be out
    assert np.all(out[:3] == 0.0)
    assert abs(out[3] / np.exp(-1.0) - 1.0) < 1e-15


def test_expm1_many_matches_libm_to_rounding():
    from skydome.transport._vexp import expm1_many

    rng = np.random.default_rng(11)
    x = np.concatenate([rng.uniform(0.0, 0.5, 50_000), rng.uniform(0.5, 700.0, 50_000),
                        np.logspace(-300, np.log10(700.0), 2000), [0.5, np.nextafter(0.5, 0.0)]])
    out = np.empty_like(x)
    ib = np.empty(x.size, dtype=np.int64)
    expm1_many(x, x.size, out, ib, ib.view(np.float64))
    ref = np.expm1(x)          # numpy's expm1: the C library's
    assert np.max(np.abs(out / ref - 1.0)) < 1e-15
    zero = np.zeros(1)
    expm1_many(zero, 1, zero, ib, ib.view(np.float64))
    assert zero[0] == 0.0
