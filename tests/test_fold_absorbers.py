"""The kernels' media fold the absorbing-only constituents (``optical_properties(fold=True)``)
and skip the scattering terms of constituents that do not scatter: exact, so every
physically based model gives the same radiance as with one row per constituent.

The reference is each model run on the unfolded medium (``fold_absorbers`` replaced by the
identity), i.e. the same equations summed over all five constituents of
``Atmosphere.earth()``; the comparison is at 1e-12 relative (rounding only).
"""

import numpy as np
import pytest

import skydome as sd
import skydome.atmosphere as atmosphere_module
from skydome.transport.geometry import direction_from_angles

WL = np.array([450.0, 550.0, 687.0, 760.0])          # 687 / 760 nm: the O2 bands of the mixed gases
DIRS = direction_from_angles([90.0, 45.0, 10.0, 5.0, 20.0, -10.0],
                             [0.0, 30.0, 180.0, 0.0, 270.0, 180.0])
SUN = sd.Sun(elevation_deg=20.0, azimuth_deg=180.0)
SMALL_PRECOMPUTED = dict(scattering_r_size=8, scattering_mu_size=32, scattering_mu_s_size=8,
                         scattering_nu_size=4, irradiance_mu_s_size=16, irradiance_r_size=4,
                         transmittance_mu_size=64, transmittance_r_size=16, orders=2,
                         remaining_orders="none", sphere_samples=8, cache=False)

MODELS = {
    "single_scattering": dict(),
    "hillaire2020": dict(use_skyview=False),
    "kaneda1991": dict(),
    "nishita1996": dict(orders=2, lattice_size=5, sky_directions=12),
    "montecarlo": dict(samples=200, seed=3),
    "precomputed": dict(table_wavelengths_nm=WL, **SMALL_PRECOMPUTED),
}


def _unfolded(monkeypatch):
    monkeypatch.setattr(atmosphere_module, "fold_absorbers",
                        lambda p: (p, np.arange(p.profile_code.size)))


def test_earth_folds_to_four_constituents():
    atm = sd.Atmosphere.earth()
    assert len(atm.constituents) == 5
    assert atm.optical_properties(WL).profile_code.size == 5
    assert atm.optical_properties(WL, fold=True).profile_code.size == 4
    with pytest.raises(TypeError, match="fold"):
        atm.optical_properties(WL, fold="yes")


@pytest.mark.parametrize("name", sorted(MODELS))
def test_folding_is_exact(name, monkeypatch):
    folded = sd.model(name, sun=SUN, **MODELS[name]).radiance(DIRS, WL)
    with monkeypatch.context() as mp:
        _unfolded(mp)
        assert sd.Atmosphere.earth().optical_properties(WL, fold=True).profile_code.size == 5
        full = sd.model(name, sun=SUN, **MODELS[name]).radiance(DIRS, WL)
    assert np.all(np.isfinite(folded)) and np.all(folded >= 0.0)
    assert np.max(folded) > 0.0
    np.testing.assert_allclose(folded, full, rtol=1e-12, atol=1e-12 * np.max(full))


def test_folding_is_exact_nishita1993(monkeypatch):
    """The earth from 36 000 km, rays through the disc and past the limb."""
    kw = dict(camera_altitude_m=36e6, spheres=16, cylinders=16, surface="albedo")
    r0, R = 6_371_000.0 + 36e6, 6_371_000.0
    d = []
    for tangent_alt in (-3e6, -2e5, 5e3, 3e4):       # disc, near the limb, the limb
        a = np.arcsin((R + tangent_alt) / r0)
        d.append([0.0, -np.sin(a), -np.cos(a)])
    d = np.array(d)
    folded = sd.model("nishita1993", sun=SUN, **kw).radiance(d, WL)
    with monkeypatch.context() as mp:
        _unfolded(mp)
        full = sd.model("nishita1993", sun=SUN, **kw).radiance(d, WL)
    assert np.max(folded) > 0.0
    np.testing.assert_allclose(folded, full, rtol=1e-12, atol=1e-12 * np.max(full))


def test_aureole_single_scattering_folds_exactly(monkeypatch):
    """The aureole's single scattering with only the aerosol scattering: Rayleigh's row
    then scatters nothing, ozone / water vapour / mixed gases never do."""
    from skydome.effects.aureole import single_scattering_true_phase

    kw = dict(constituents=["aerosol"], view_samples=8, light_samples=16, table_size=(32, 64))
    folded = single_scattering_true_phase(sd.Atmosphere.earth(), DIRS[:3], SUN, WL, **kw)
    with monkeypatch.context() as mp:
        _unfolded(mp)
        full = single_scattering_true_phase(sd.Atmosphere.earth(), DIRS[:3], SUN, WL, **kw)
    assert np.max(folded) > 0.0
    np.testing.assert_allclose(folded, full, rtol=1e-12, atol=1e-12 * np.max(full))
