"""The ``precomputed`` sky in twilight against stored ``montecarlo`` references (an
independent solver: backward path tracing of every order, no tables), at the default
settings: AOD 0.2, 550 nm, five directions (10 deg up towards the sun, the twilight arch,
and opposite it, the earth's shadow; 30 deg up at 90 deg from the sun; 50 deg up opposite
it; the zenith).

References: tests/data/twilight_montecarlo_550nm.npz (sun -4 and -6 deg, 10^7 paths per
direction, seed 11; relative standard error 0.2-0.5 % at -4 deg, RMS 0.3 %, and 0.6-1.9 %
at -6 deg, RMS 1.2 %) and tests/data/twilight_montecarlo_550nm_deep.npz (sun -8 and -10 deg,
``tools/twilight_references.py``, 2 x 10^7 paths per direction, seed 21; 1.1-3.7 % at
-8 deg, RMS 2.8 %, and 3.0-10.0 % at -10 deg, RMS 7.6 %); each file's ``command`` and
``provenance`` say how it was made; tests/data/twilight_montecarlo_550nm_segment.npz (sun
-8, -10, -12 deg, montecarlo ``next_event="segment"``, seed 31, 5 x 10^5 / 10^6 / 4 x 10^6
paths per direction, RMS noise 1.64 / 2.04 / 1.96 %; one run per elevation of
``python tools/twilight_references.py tests/data/twilight_montecarlo_550nm_segment.npz
--next-event segment --seed 31 --samples N --elevations=E``, the file's ``command`` holding
the last) for the reference configuration ``twilight_reference=True``.

The bounds of the default tables' tests are the errors measured at this state of the model
(single scattering integrated at the observer with the sun below the horizon, 48 mu_s nodes
on the knee at 92 deg) rounded up by about a tenth: they guard against regressions, they are
not the accuracy wanted for a fitted model's data set (3 % RMS to -6 deg, 10 % to -12 deg),
which the default tables do not reach (docs/models.md, "Twilight: single scattering at the
observer"). The reference configuration's tests (the end of this file) hold that accuracy.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import skydome as sd
from skydome.atmosphere import Atmosphere

DATA = Path(__file__).parent / "data"
CIVIL = DATA / "twilight_montecarlo_550nm.npz"
DEEP = DATA / "twilight_montecarlo_550nm_deep.npz"
SEGMENT = DATA / "twilight_montecarlo_550nm_segment.npz"


@pytest.fixture(scope="module")
def sky():
    ref = np.load(CIVIL)
    return sd.model("precomputed", sun=sd.Sun(elevation_deg=-4.0, azimuth_deg=180.0),
                    table_wavelengths_nm=list(ref["wavelengths_nm"]),
                    atmosphere=Atmosphere.earth(aerosol_optical_depth=0.2))


def _errors(sky, path, elevation, table_single_scattering=False):
    """Relative error of the sky at the reference's directions and its relative standard
    error; ``table_single_scattering``: single scattering read from the 4-D table as with
    the sun above the horizon (the model before the observer's integral)."""
    ref = np.load(path)
    k = f"{elevation:g}"
    mc, err = ref[k][:, 0], ref[k + "_err"][:, 0]
    m = sky.with_sun(sd.Sun(elevation_deg=elevation, azimuth_deg=180.0))
    if table_single_scattering:
        m.twilight_single_scattering = False
    rel = m.radiance(ref["directions"], ref["wavelengths_nm"])[:, 0] / mc - 1.0
    return rel, err / mc


# (sun elevation, reference, its RMS noise bound, RMS bound, max bound); measured RMS / max:
# -4 deg 4.91 / +10.4 % (the earth's shadow), -6 deg 6.27 / +13.3 % (the earth's shadow),
# -8 deg 15.0 / +27.5 % (the earth's shadow), -10 deg 14.0 / +22.6 % (the earth's shadow)
CASES = [(-4.0, CIVIL, 0.005, 0.055, 0.115),
         (-6.0, CIVIL, 0.015, 0.070, 0.145),
         (-8.0, DEEP, 0.035, 0.165, 0.300),
         (-10.0, DEEP, 0.085, 0.155, 0.250)]


@pytest.mark.parametrize("elevation, path, noise_bound, rms_bound, max_bound", CASES)
def test_twilight_against_monte_carlo(sky, elevation, path, noise_bound, rms_bound,
                                      max_bound):
    """RMS and largest relative error over the five directions within the measured values
    rounded up (see CASES; at -10 deg the reference's own noise, 7.6 % RMS, is about half
    of the 14.0 %)."""
    rel, noise = _errors(sky, path, elevation)
    assert np.sqrt(np.mean(noise ** 2)) < noise_bound
    assert np.sqrt(np.mean(rel ** 2)) < rms_bound, rel
    assert np.abs(rel).max() < max_bound, rel


@pytest.mark.parametrize("elevation, path", [(-4.0, CIVIL), (-6.0, CIVIL), (-8.0, DEEP)])
def test_observer_single_scattering_beats_the_table(sky, elevation, path):
    """Single scattering integrated at the observer (each ray split at the earth's shadow)
    against the same sky with single scattering read from the 4-D table, both against the
    Monte Carlo reference: measured RMS 4.91 against 7.63 % at -4 deg, 6.27 against 8.35 %
    at -6 deg, 15.0 against 18.1 % at -8 deg. Required: at least 1.5 points lower (the
    references' RMS noise is 0.3 / 1.2 / 2.8 %, the same paths for both)."""
    rel, _ = _errors(sky, path, elevation)
    rel_table, _ = _errors(sky, path, elevation, table_single_scattering=True)
    rms, rms_table = np.sqrt(np.mean(rel ** 2)), np.sqrt(np.mean(rel_table ** 2))
    assert rms < rms_table - 0.015, (rms, rms_table)


@pytest.mark.parametrize("elevation", [0.0, 5.0, 30.0, 75.0])
def test_day_sky_reads_the_table(sky, elevation):
    """With the sun on or above the horizon the sky is that of the table path, unchanged:
    no observer map of single scattering is made, and the radiance equals (bit for bit) the
    radiance with that map switched off."""
    m = sky.with_sun(sd.Sun(elevation_deg=elevation, azimuth_deg=135.0))
    assert m._single_scattering_map() is None
    rng = np.random.default_rng(3)
    d = rng.normal(size=(300, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    wl = [450.0, 550.0, 650.0]
    a = m.radiance(d, wl)
    off = sky.with_sun(sd.Sun(elevation_deg=elevation, azimuth_deg=135.0))
    off.twilight_single_scattering = False
    assert np.array_equal(a, off.radiance(d, wl))


def test_sky_step_where_the_sun_crosses_the_horizon(sky):
    """The sun 0.0001 deg below the horizon (the observer's single-scattering map) against
    0.0001 deg above (the table's), 550 nm, 25 directions 2-90 deg up at 5 azimuths:
    measured 0.30 % RMS, at most 0.58 %, the sky below darker (the table's single
    scattering was that much too bright). Required: RMS < 0.5 %, max < 1 %."""
    el = np.radians(np.linspace(2.0, 90.0, 5))
    az = np.radians(np.linspace(0.0, 360.0, 5, endpoint=False))
    E, A = np.meshgrid(el, az)
    d = np.stack([np.cos(E) * np.sin(A), np.cos(E) * np.cos(A), np.sin(E)], -1).reshape(-1, 3)
    up = sky.with_sun(sd.Sun(elevation_deg=1e-4, azimuth_deg=180.0))
    down = sky.with_sun(sd.Sun(elevation_deg=-1e-4, azimuth_deg=180.0))
    assert up._single_scattering_map() is None
    assert down._single_scattering_map() is not None
    r = down.radiance(d, [550.0])[:, 0] / up.radiance(d, [550.0])[:, 0] - 1.0
    assert np.sqrt(np.mean(r ** 2)) < 0.005, r
    assert np.abs(r).max() < 0.01, r


@pytest.mark.parametrize("elevation", [-4.0, -8.0])
def test_aerial_perspective_beyond_the_top_is_the_twilight_sky(sky, elevation):
    """As by day (tests/test_precomputed.py, test_aerial_perspective_limits): a path beyond
    the top of the atmosphere in-scatters the sky itself, here with single scattering at
    the observer as in radiance() (the 4-D table's single scattering differs from it by up
    to some 10 % in twilight, docs/models.md); distance 0 in-scatters nothing."""
    m = sky.with_sun(sd.Sun(elevation_deg=elevation, azimuth_deg=180.0))
    d = sd.direction_from_angles(np.array([2.0, 10.0, 20.0, 45.0, 89.0]),
                                 np.array([0.0, 180.0, 90.0, 0.0, 0.0]))
    wl = [450.0, 550.0, 650.0]
    _, s_inf = m.aerial_perspective(d, 1e7, wl)
    np.testing.assert_allclose(s_inf, m.radiance(d, wl), rtol=1e-6)
    t0, s0 = m.aerial_perspective(d, 0.0, wl)
    np.testing.assert_allclose(t0, 1.0, atol=1e-6)
    np.testing.assert_allclose(s0, 0.0, atol=1e-12)


def test_observer_single_scattering_is_the_default(sky):
    """The default integrates single scattering at the observer in twilight;
    ``twilight_single_scattering=False`` reads it from the 4-D table (as the viewer's shader
    and the LUT bakes do). Same tables, so the two skies differ."""
    import copy

    m = sky.with_sun(sd.Sun(elevation_deg=-6.0, azimuth_deg=180.0))
    table = copy.copy(m)
    table.twilight_single_scattering = False
    assert table._single_scattering_map() is None
    assert m._single_scattering_map() is not None
    d = sd.direction_from_angles([10.0, 30.0], [0.0, 180.0])
    a, b = table.radiance(d, [550.0]), m.radiance(d, [550.0])
    assert np.all(np.isfinite(a)) and np.all(a > 0) and not np.allclose(a, b, rtol=1e-3)
    p = next(q for q in type(sky).parameters if q.name == "twilight_single_scattering")
    assert p.default is True and p.kind == "bool"
    assert sky.twilight_single_scattering is True      # the fixture leaves it unset



# -- the reference configuration (twilight_reference=True) -----------------------------------
@pytest.fixture(scope="module")
def reference_sky():
    ref = np.load(CIVIL)
    return sd.model("precomputed", sun=sd.Sun(elevation_deg=-4.0, azimuth_deg=180.0),
                    table_wavelengths_nm=list(ref["wavelengths_nm"]),
                    atmosphere=Atmosphere.earth(aerosol_optical_depth=0.2),
                    twilight_reference=True)


def test_reference_configuration_settings(reference_sky):
    """The switch sets the reference settings; a setting given explicitly wins."""
    from skydome.models.simulated.precomputed import TWILIGHT_REFERENCE_SETTINGS

    for k, v in TWILIGHT_REFERENCE_SETTINGS.items():
        assert getattr(reference_sky, k) == v, k
    assert reference_sky.twilight_single_scattering is True
    p = next(q for q in type(reference_sky).parameters if q.name == "twilight_reference")
    assert p.default is False and p.kind == "bool"
    with pytest.raises(ValueError, match="twilight_single_scattering"):
        sd.model("precomputed", sun=sd.Sun(elevation_deg=-5.0, azimuth_deg=0.0),
                 twilight_reference=True, twilight_single_scattering=False)


# (sun elevation, reference, target RMS of the model's own error, bound on the reference's
# RMS noise). The reference's noise adds to the measured difference in quadrature, so the
# bound on the measured RMS is sqrt(target^2 + noise^2), with the reference's noise held
# under half the target so that it cannot decide the test. Measured RMS (max) / reference
# noise: -4 deg 0.92 (1.9) / 0.32 %, -6 deg 1.79 (2.6) / 1.18 %, -8 deg 1.70 (2.5) / 1.64 %,
# -10 deg 2.90 (5.8) / 2.04 %, -12 deg 2.84 (3.5) / 1.96 % (docs/models.md, "Twilight: the
# reference configuration"; when the configuration was introduced 1.58, 2.54, 2.02, 2.79
# and 2.77 % RMS).
REFERENCE_CASES = [(-4.0, CIVIL, 0.03, 0.005),
                   (-6.0, CIVIL, 0.03, 0.015),
                   (-8.0, SEGMENT, 0.10, 0.03),
                   (-10.0, SEGMENT, 0.10, 0.03),
                   (-12.0, SEGMENT, 0.10, 0.03)]


@pytest.mark.parametrize("elevation, path, target, noise_bound", REFERENCE_CASES)
def test_reference_configuration_against_monte_carlo(reference_sky, elevation, path, target,
                                                     noise_bound):
    """``twilight_reference=True`` within 3 % RMS of ``montecarlo`` to sun -6 deg and 10 %
    to -12 deg (the issue's bounds for a fitted model's data set), five directions, 550 nm:
    at -4 / -6 deg against the 10^7-path vertex-estimator reference, at -8 / -10 / -12 deg
    against the segment-estimator reference (montecarlo ``next_event="segment"``,
    tools/twilight_references.py; the file's ``command`` says how)."""
    rel, noise = _errors(reference_sky, path, elevation)
    noise_rms = np.sqrt(np.mean(noise ** 2))
    assert noise_rms < noise_bound
    rms = np.sqrt(np.mean(rel ** 2))
    assert rms < np.hypot(target, noise_rms), (rms, rel)
