"""The numba kernels of the analytic luminance models against their numpy reference forms.

Reference: each model keeps its numpy implementation of the paper's equations as a private
function (``_relative`` of the CIE skies and ASRC-CIE, ``_luminance_reference`` of Perez 1993,
``_xyY_reference`` / ``_xyz_reference`` of Preetham 1999); the public methods now run the
parallel numba kernels. They must agree to 1e-12 relative (issue 3), for directions all over
the sphere, including the horizon, below it, the zenith and the sun itself.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import skydome as sd
from skydome._validate import as_directions

RTOL = 1e-12


def _directions(sun, n=4000, seed=1):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    extra = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.3, -0.2, 0.0],
                      [0.0, 0.0, -1.0], [0.5, 0.5, -1e-9], [0.2, 0.9, 1e-9]])
    sd_ = np.asarray(sun.direction)
    # near the sun (about 1 deg), but not so close that the infinite slope of arccos at 1
    # amplifies the last-bit difference of the two dot products beyond 1e-12
    near = sd_ + 2e-2 * rng.normal(size=(8, 3))
    return np.concatenate([v, extra, near])


def _close(a, b):
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape
    assert np.all(np.isfinite(a))
    np.testing.assert_allclose(a, b, rtol=RTOL, atol=1e-300)


SUNS = [sd.Sun(elevation_deg=e, azimuth_deg=a) for e, a in ((3.0, 20.0), (35.0, 160.0),
                                                            (72.0, 290.0), (90.0, 0.0))]


@pytest.mark.parametrize("sun", SUNS, ids=lambda s: f"h{s.elevation_deg:g}")
@pytest.mark.parametrize("name,params", [
    ("cie1994_overcast", {}),
    ("cie1994_clear", {}),
    ("cie1994_intermediate", {}),
    ("cie2003", {"sky_type": 1}),
    ("cie2003", {"sky_type": 7}),
    ("cie2003", {"sky_type": 12}),
    ("cie2003", {"sky_type": 15}),
    ("asrc_cie", {"epsilon": 1.1, "delta": 0.2}),   # intermediate + overcast
    ("asrc_cie", {"epsilon": 2.0, "delta": 0.2}),   # turbid + intermediate
    ("asrc_cie", {"epsilon": 4.5, "delta": 0.2}),   # clear + turbid
])
def test_cie_family_kernel_matches_numpy(name, params, sun):
    sky = sd.model(name, sun=sun, **params)
    d = _directions(sun)
    ref = sky._relative(as_directions(d))
    _close(sky.relative_luminance(d), ref)
    _close(sky.luminance(d), sky.zenith_luminance * ref)
    assert np.all(sky.luminance(d)[d[:, 2] < 0] == 0.0)


@pytest.mark.parametrize("sun", SUNS[:3], ids=lambda s: f"h{s.elevation_deg:g}")
@pytest.mark.parametrize("params", [
    {"dni": 650.0, "dhi": 120.0},
    {"epsilon": 1.1, "delta": 0.3},          # first bin: special forms of c and d
    {"epsilon": 6.5, "delta": 0.1, "scaling": "relative"},
])
def test_perez1993_kernel_matches_numpy(params, sun):
    sky = sd.model("perez1993", sun=sun, invalid="black", **params)
    d = _directions(sun)
    _close(sky.luminance(d), sky._luminance_reference(d))


@pytest.mark.parametrize("sun", SUNS, ids=lambda s: f"h{s.elevation_deg:g}")
@pytest.mark.parametrize("turbidity", [2.0, 4.5, 10.0])
def test_preetham1999_kernel_matches_numpy(turbidity, sun):
    sky = sd.model("preetham1999", sun=sun, turbidity=turbidity)
    d = _directions(sun)
    _close(sky.xyY(d), sky._xyY_reference(d))
    _close(sky.xyz(d), sky._xyz_reference(d))


def test_shapes_and_scalar_direction():
    sun = SUNS[1]
    sky = sd.model("cie2003", sun=sun, sky_type=12)
    d = _directions(sun, n=24)[:24].reshape(2, 3, 4, 3)
    assert sky.luminance(d).shape == (2, 3, 4)
    assert sky.luminance([0.0, 0.0, 2.0]).shape == ()
    # the zenith of any CIE sky has L = Lz by definition (CIE S 011 eq. 1)
    assert sky.luminance([0.0, 0.0, 2.0]) == pytest.approx(sky.zenith_luminance, rel=1e-12)
    pre = sd.model("preetham1999", sun=sun)
    assert pre.xyz(d).shape == (2, 3, 4, 3)
    # non-unit input is normalised like as_directions does
    _close(pre.xyY(5.0 * d), pre._xyY_reference(d))


@pytest.mark.parametrize("bad,msg", [([[0.0, 0.0, 0.0]], "zero-length"),
                                     ([[np.nan, 0.0, 1.0]], "NaN or infinite"),
                                     ([[1.0, 2.0]], r"shape \(\.\.\., 3\)")])
def test_bad_directions_rejected(bad, msg):
    sun = SUNS[1]
    for name, p in (("cie1994_clear", {}), ("perez1993", {"dni": 600.0, "dhi": 100.0}),
                    ("preetham1999", {})):
        sky = sd.model(name, sun=sun, **p)
        with pytest.raises(ValueError, match=msg):
            sky.luminance(bad)


def test_numba_not_imported_by_listing_models():
    code = ("import sys, skydome; skydome.models.available(); "
            "print('numba' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "False"


# -- dobashi1995: numba kernel (own term count per ring) against the numpy form (all terms) --
@pytest.mark.parametrize("interp", ["cubic", "linear"])
def test_dobashi1995_kernel_matches_numpy(interp):
    """Reference: the model's numpy evaluation ``_radiance_reference`` (every ring summed over
    all n_max terms, the extra coefficients being zero)."""
    sun = sd.Sun(elevation_deg=37.0, azimuth_deg=150.0)
    m = sd.model("dobashi1995", sun=sun, base="preetham1999", sun_altitudes=7, rings=13,
                 azimuth_samples=32, ring_interpolation=interp, evaluation="series")
    wl = np.array([450.0, 550.0, 650.0])
    # above the kernel's serial/parallel switch, so both drivers are exercised
    from skydome.models.simulated._kernels_dobashi1995 import PARALLEL_MIN_RAYS

    d = _directions(sun, n=PARALLEL_MIN_RAYS + 100)
    d = np.concatenate([d, [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]])
    np.testing.assert_allclose(m.radiance(d[:100], wl), m._radiance_reference(d[:100], wl),
                               rtol=1e-10, atol=1e-12 * ref_scale(m, wl))
    L = m.radiance(d, wl)
    ref = m._radiance_reference(d, wl)
    assert L.shape == (d.shape[0], 3) and np.all(L >= 0.0)
    np.testing.assert_allclose(L, ref, rtol=1e-10, atol=1e-12 * ref.max())
    t = m.table(wl)
    assert t["terms"].min() < t["terms"].max()   # rings really use different term counts


def ref_scale(m, wl):
    return float(m.table(wl)["samples"].max())


def test_dobashi1995_grid_evaluation_close_to_series():
    """The ring x azimuth grid (721 azimuths) against the per-ray series it tabulates: the
    only difference is linear interpolation in azimuth at 0.25 deg steps (bound: 0.2 %)."""
    sun = sd.Sun(elevation_deg=37.0, azimuth_deg=150.0)
    kw = dict(sun=sun, base="preetham1999", sun_altitudes=7, rings=13, azimuth_samples=32)
    grid = sd.model("dobashi1995", evaluation="grid", **kw)
    series = sd.model("dobashi1995", evaluation="series", **kw)
    wl = np.array([450.0, 550.0, 650.0])
    d = _directions(sun, n=20000)
    d = d[d[:, 2] > 0.03]
    a, b = grid.radiance(d, wl), series.radiance(d, wl)
    assert np.all(np.isfinite(a)) and np.all(a >= 0.0)
    assert np.max(np.abs(a / b - 1.0)) < 2e-3
