"""The ``fitted`` model: its range refused outside with the parameter, value and range; finite,
non-negative output over the whole range; the coefficient file's size and lazy loading; and
its accuracy at held-out parameters and directions against a live ``precomputed`` reference
(computed here by the reference itself, never by the fitted model)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import skydome as sd
from skydome.models.fitted import _coefficients, _grid


def _dirs(n=400, seed=3, upper=False):
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(n, 3))
    if upper:
        d[:, 2] = np.abs(d[:, 2]) + 0.01
    d /= np.linalg.norm(d, axis=1)[:, None]
    # the zenith, the nadir, the horizon (on the ground) and the sun's own vertical
    return np.vstack([d, [[0, 0, 1], [0, 0, -1], [1, 0, 0], [0, -1, 0.001]]])


@pytest.mark.parametrize("kw, name, rng", [
    ({"aerosol_optical_depth": 1.2}, "aerosol_optical_depth", "[0, 1]"),
    ({"aerosol_optical_depth": -0.01}, "aerosol_optical_depth", "[0, 1]"),
    ({"ground_albedo": 1.5}, "ground_albedo", "[0, 1]"),
    ({"observer_altitude_m": 15001.0}, "observer_altitude_m", "[0, 15000]"),
])
def test_out_of_range_parameters_refused_with_name_value_and_range(kw, name, rng):
    with pytest.raises(ValueError) as e:
        sd.model("fitted", sun=sd.Sun(elevation_deg=30, azimuth_deg=0), **kw)
    msg = str(e.value)
    assert name in msg and rng in msg and f"{list(kw.values())[0]:g}" in msg


def test_sun_below_the_fitted_range_refused():
    with pytest.raises(ValueError, match=r"sun.elevation_deg = -12.5 deg is out of range "
                                         r"\[-12, 90\] deg for model 'fitted'"):
        sd.model("fitted", sun=sd.Sun(elevation_deg=-12.5, azimuth_deg=0))


@pytest.mark.parametrize("el", [-12.0, -7.3, -2.0, -0.3, 0.0, 0.27, 12.3, 89.99, 90.0])
@pytest.mark.parametrize("aod, albedo, h", [(0.0, 0.0, 0.0), (0.25, 1.0, 15000.0),
                                            (0.17, 0.61, 2345.0), (0.0, 1.0, 15000.0),
                                            (0.25, 0.0, 0.0)])
def test_finite_and_non_negative_over_the_range(el, aod, albedo, h):
    sky = sd.model("fitted", sun=sd.Sun(elevation_deg=el, azimuth_deg=37.0),
                   aerosol_optical_depth=aod, ground_albedo=albedo, observer_altitude_m=h)
    d = _dirs()
    L = sky.radiance(d, [300.0, 555.0, 1100.0])
    xyz = sky.xyz(d)
    Y = sky.luminance(d)
    for a in (L, xyz, Y, sky.sun_radiance([300.0, 555.0, 1100.0])):
        assert np.all(np.isfinite(a)) and np.all(a >= 0.0)
    assert L.shape == (d.shape[0], 3) and xyz.shape == (d.shape[0], 3)
    # the sky above the horizon is lit: at sun -2 deg and above the darkest fitted sky is
    # > 1e-3 cd/m2; at -12 deg the data set's darkest sky (precomputed, every atmosphere
    # and altitude) is 1.1e-3 cd/m2: a tenth of it bounds the model from below
    assert np.all(Y[d[:, 2] > 0.05] > (1e-3 if el >= -2.0 else 1e-4))
    np.testing.assert_allclose(Y, xyz[:, 1], rtol=1e-9)


def test_wavelengths_outside_300_1100_refused():
    sky = sd.model("fitted", sun=sd.Sun(elevation_deg=30, azimuth_deg=0))
    with pytest.raises(ValueError, match="wavelengths_nm"):
        sky.radiance([[0, 0, 1]], [290.0, 500.0])
    with pytest.raises(ValueError, match="wavelengths_nm"):
        sky.radiance([[0, 0, 1]], [500.0, 1200.0])


def test_coefficient_file_is_small_and_loaded_lazily():
    assert _coefficients.COEFFICIENT_FILE.stat().st_size <= 50e6
    code = ("import skydome, skydome.models as m; m.available(); "
            "from skydome.models.fitted import _coefficients as c; "
            "print(c.load.cache_info().currsize)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "0"


def test_sun_visible_fraction_geometry():
    # the reference's rule (a smoothstep over the disc's radius around the horizon, its
    # equality with precomputed's: tests/test_fitted_sun.py): a disc of radius r centred on
    # the horizon is half visible; a little more than one radius above (the smoothstep runs
    # over the radius in the zenith cosine, sin r < r), whole; as far below, hidden; at
    # 15 km the horizon dips acos(R / (R + h)) = 3.93 deg
    r = 0.2665

    def vis(el, h):
        return sd.model("fitted", sun=sd.Sun(elevation_deg=el, azimuth_deg=0.0,
                                            angular_radius_deg=r),
                        observer_altitude_m=h).sun_visible_fraction()

    assert vis(0.0, 0.0) == pytest.approx(0.5, abs=1e-9)
    assert vis(1.001 * r, 0.0) == 1.0
    assert vis(-1.001 * r, 0.0) == 0.0
    assert 0.5 < vis(0.3 * r, 0.0) < 1.0 and 0.0 < vis(-0.3 * r, 0.0) < 0.5
    dip = np.degrees(np.arccos(6360e3 / (6360e3 + 15000.0)))
    assert dip == pytest.approx(3.93, abs=0.01)
    assert vis(-dip, 15000.0) == pytest.approx(0.5, abs=1e-6)


# -- accuracy at held-out points against a live reference ------------------------------------
#: One atmosphere between the fitting nodes (AOD 0.07 between 0 and 0.1, albedo 0.25
#: between 0 and 0.5), the reference's table wavelengths 380-780 nm every 20 nm (a subset of
#: the data set's, each computed independently by the reference).
HELD_AOD, HELD_ALBEDO = 0.07, 0.25
#: (sun elevation [deg], altitude [m], luminance RMS bound, luminance max bound): suns and
#: altitudes between the nodes. The bounds are the figures measured for the regime on the
#: held-out grid (docs/models.md, "fitted", clear: sun > 20 deg on the ground 2.26 % / 17.2 %;
#: 0-20 deg at 0.5-5 km 4.79 % / 56.4 %; -2 to 0 deg at 0.5-5 km 6.26 % / 56.1 %),
#: rounded up: the model's documented accuracy, not a tighter promise.
CASES = [(28.0, 0.0, 0.03, 0.18), (4.0, 5000.0, 0.05, 0.57), (-1.5, 500.0, 0.07, 0.57)]


@pytest.fixture(scope="module")
def reference():
    atm = sd.Atmosphere.earth(aerosol_optical_depth=HELD_AOD, ground_albedo=HELD_ALBEDO)
    return sd.model("precomputed", sun=sd.Sun(elevation_deg=30, azimuth_deg=180),
                    atmosphere=atm, table_wavelengths_nm=np.arange(380.0, 781.0, 20.0),
                    cache=False)


#: The ground seen from above between the first altitude nodes (350 and 700 m): (sun
#: elevation [deg], altitude [m], RMS bound, max bound). The bounds are the held-out grid's
#: figures for the ground view of the clear skies at 0.4-4.5 km (docs/models.md, "fitted",
#: "The ground seen from above between the altitude nodes": sun > 20 deg 1.14 % / 9.7 %,
#: 0-20 deg 2.76 % / 34.4 %), rounded up. With the ground node (h = 0) in the ground's
#: altitude stencil these cases were 4.91 % / 38.6 % and 6.03 % / 42.7 %.
GROUND_CASES = [(30.0, 500.0, 0.015, 0.10), (10.0, 600.0, 0.03, 0.35)]


def _ground_dirs(h, n=300, seed=5):
    """``n`` directions at the ground seen from altitude ``h`` [m]: 0.2-60 deg below the
    horizon's dip over a sphere of 6371 km, azimuths uniform."""
    rng = np.random.default_rng(seed)
    dip = np.degrees(np.arccos(6371e3 / (6371e3 + h)))
    alt = np.radians(-dip - rng.uniform(0.2, 60.0, n))
    az = np.radians(rng.uniform(0.0, 360.0, n))
    return np.stack([np.cos(alt) * np.sin(az), np.cos(alt) * np.cos(az), np.sin(alt)], -1)


@pytest.mark.slow
@pytest.mark.parametrize("el, h, rms_bound, max_bound", GROUND_CASES)
def test_ground_from_above_between_altitude_nodes_against_live_precomputed(
        reference, el, h, rms_bound, max_bound):
    sun = sd.Sun(elevation_deg=el, azimuth_deg=200.0)
    ref = reference.with_sun(sun, observer_altitude_m=h)
    fit = sd.model("fitted", sun=sun, aerosol_optical_depth=HELD_AOD,
                   ground_albedo=HELD_ALBEDO, observer_altitude_m=h)
    d = _ground_dirs(h)
    rel = fit.luminance(d) / ref.luminance(d) - 1.0
    rms, worst = float(np.sqrt(np.mean(rel ** 2))), float(np.max(np.abs(rel)))
    assert rms <= rms_bound and worst <= max_bound, (el, h, rms, worst)


@pytest.mark.slow
@pytest.mark.parametrize("el, h, rms_bound, max_bound", CASES)
def test_luminance_at_held_out_points_against_live_precomputed(reference, el, h, rms_bound,
                                                               max_bound):
    sun = sd.Sun(elevation_deg=el, azimuth_deg=200.0)
    ref = reference.with_sun(sun, observer_altitude_m=h)
    fit = sd.model("fitted", sun=sun, aerosol_optical_depth=HELD_AOD,
                   ground_albedo=HELD_ALBEDO, observer_altitude_m=h)
    d = _dirs(300, seed=11, upper=True)[:300]
    d = d[np.degrees(np.arccos(np.clip(d @ sun.direction, -1, 1))) > 5.0]
    y_ref = ref.luminance(d)
    y_fit = fit.luminance(d)
    rel = y_fit / y_ref - 1.0
    rms, worst = float(np.sqrt(np.mean(rel ** 2))), float(np.max(np.abs(rel)))
    assert rms <= rms_bound and worst <= max_bound, (el, h, rms, worst)
    # the sun's disc: transmittance x visible fraction, 400-780 nm (table wavelengths of
    # both): the reference's columns and rule, within the two suns' radii (0.2665 and
    # 0.2666 deg: 4e-4 at most; tests/test_fitted_sun.py)
    wl = np.arange(400.0, 781.0, 20.0)
    s_ref, s_fit = ref.sun_radiance(wl), fit.sun_radiance(wl)
    np.testing.assert_allclose(s_fit, s_ref, rtol=1e-3)


def test_coefficient_file_covers_the_declared_range():
    # the shipped file's nodes span exactly the range the constructor enforces, and it
    # records how it was made (tools/fit_fitted.py) from which data-set grid
    c = _coefficients.load()
    for nodes, rng in ((c["aod_nodes"], _grid.AOD_RANGE),
                       (c["albedo_nodes"], _grid.ALBEDO_RANGE),
                       (c["elevation_nodes_deg"], _grid.SUN_ELEVATION_RANGE_DEG),
                       (c["altitude_nodes_m"], _grid.ALTITUDE_RANGE_M)):
        assert (nodes[0], nodes[-1]) == rng and np.all(np.diff(nodes) > 0)
    np.testing.assert_array_equal(c["wavelengths_nm"], _grid.TABLE_WAVELENGTHS_NM)
    assert c["meta"]["command"].startswith("python tools/fit_fitted.py")
    assert c["meta"]["dataset_grid"]["view_grid"]["n_sky"] == _grid.N_SKY
    n = len(c["elevation_nodes_deg"])
    assert c["sky_basis"].shape == (n, c["meta"]["k_sky"], _grid.N_SKY * _grid.N_PHI)


#: The twilight point: one atmosphere off the nodes (AOD 0.08, albedo 0.35), the sun at -8.5
#: deg (between the nodes -10 and -8), the observer at 1 km (between 0.7 and 1.5 km); the
#: reference is ``precomputed`` in its twilight reference configuration
#: (``twilight_reference=True``, validated against Monte Carlo to -12 deg), as the data set.
TWILIGHT_CASE = dict(aod=0.08, albedo=0.35, el=-8.5, h=1000.0)
#: Bounds: the figures measured for the regime on the first file's held-out grid (clear, sun
#: -6 to -12 deg at 0.4-4.5 km: 9.07 % RMS, 206 % max), rounded up; the refit's are lower
#: (docs/models.md, "fitted": 3.25 % / 52.1 %), these stay as the loosest documented figure.
TWILIGHT_RMS_BOUND, TWILIGHT_MAX_BOUND = 0.10, 2.1


@pytest.fixture(scope="module")
def twilight_pair():
    """(reference, fitted model, sun) at :data:`TWILIGHT_CASE`: the reference in its
    twilight configuration, about 70 s of CPU, built once for the sky's and the ground's
    tests."""
    t = TWILIGHT_CASE
    sun = sd.Sun(elevation_deg=t["el"], azimuth_deg=200.0)
    ref = sd.model("precomputed", sun=sun,
                   atmosphere=sd.Atmosphere.earth(aerosol_optical_depth=t["aod"],
                                                  ground_albedo=t["albedo"]),
                   table_wavelengths_nm=np.arange(380.0, 781.0, 20.0), cache=False,
                   twilight_reference=True).with_sun(sun, observer_altitude_m=t["h"])
    fit = sd.model("fitted", sun=sun, aerosol_optical_depth=t["aod"],
                   ground_albedo=t["albedo"], observer_altitude_m=t["h"])
    return ref, fit, sun


@pytest.mark.slow
def test_twilight_luminance_at_a_held_out_point_against_live_precomputed(twilight_pair):
    ref, fit, _ = twilight_pair
    d = _dirs(300, seed=17, upper=True)[:300]
    y_ref = ref.luminance(d)
    y_fit = fit.luminance(d)
    assert np.all(y_ref > 0.0)
    rel = y_fit / y_ref - 1.0
    rms, worst = float(np.sqrt(np.mean(rel ** 2))), float(np.max(np.abs(rel)))
    assert rms <= TWILIGHT_RMS_BOUND and worst <= TWILIGHT_MAX_BOUND, (rms, worst)


#: The ground seen from above at the twilight point, directions 0.2-60 deg below the
#: horizon's dip: RMS and max bounds. The file fitted to the reference before its sky
#: irradiance table was fixed (docs/models.md, "precomputed", "The sky irradiance table in
#: twilight") was 34.6 % RMS and 41.4 % max (median +37.0 %) here; the bounds are the
#: held-out grid's figures of the refit for the ground view of the clear skies at 0.4-4.5 km
#: from -6 to -12 deg (docs/models.md, "fitted": 2.88 % / 29.3 %), rounded up; measured
#: here 0.75 % / 3.8 % (median -0.2 %).
TWILIGHT_GROUND_RMS_BOUND, TWILIGHT_GROUND_MAX_BOUND = 0.03, 0.30


@pytest.mark.slow
def test_twilight_ground_from_above_at_a_held_out_point_against_live_precomputed(
        twilight_pair):
    ref, fit, _ = twilight_pair
    d = _ground_dirs(TWILIGHT_CASE["h"])
    y_ref = ref.luminance(d)
    assert np.all(y_ref > 0.0)
    rel = fit.luminance(d) / y_ref - 1.0
    rms, worst = float(np.sqrt(np.mean(rel ** 2))), float(np.max(np.abs(rel)))
    assert rms <= TWILIGHT_GROUND_RMS_BOUND and worst <= TWILIGHT_GROUND_MAX_BOUND, \
        (rms, worst, float(np.median(rel)))


def test_heldout_grid_is_off_the_fitting_nodes():
    # the held-out grid measures interpolation: none of its sun elevations, AODs or albedos
    # is a fitting node, its altitudes only at the ends of the range (0 and 15 km), and every
    # value lies inside the nodes' span (no extrapolation)
    el, alt, atm, mid = _grid.grid("heldout")
    fe, fh, fatm, fmid = _grid.grid("fit")
    assert mid and not fmid
    assert not set(el.tolist()) & set(fe.tolist())
    assert set(alt.tolist()) & set(fh.tolist()) == {0.0, 15000.0}
    aods = {a for a, _ in atm}
    assert not aods & set(_grid.AOD_NODES.tolist())
    assert not {b for _, b in atm} & set(_grid.ALBEDO_NODES.tolist())
    for values, nodes in ((el, fe), (alt, fh), (sorted(aods), _grid.AOD_NODES)):
        assert nodes[0] <= min(values) and max(values) <= nodes[-1]
    # the "fit" grid is the shipped file's (which records its nodes): a refit updates both
    c = _coefficients.load()
    np.testing.assert_array_equal(c["elevation_nodes_deg"], fe)
    np.testing.assert_array_equal(c["altitude_nodes_m"], fh)
    np.testing.assert_array_equal(c["aod_nodes"], _grid.AOD_NODES)
    # the fourth and fifth files' held-out AODs are off their own nodes (the held-out AOD
    # 0.7 lies between 0.5 and 1 there, 0.006 between 0 and 0.0125); the present nodes the
    # fourth lacks, 0.00625, 0.35 and 0.75, each have a held-out AOD on either side of them
    for name, nodes in (("heldout-v4", _grid.V4_AOD_NODES), ("heldout-v5", _grid.V5_AOD_NODES)):
        _, _, atm_v, _ = _grid.grid(name)
        assert not {a for a, _ in atm_v} & set(nodes.tolist())
    for node in sorted(set(_grid.AOD_NODES.tolist()) - set(_grid.V4_AOD_NODES.tolist())):
        i = int(np.searchsorted(_grid.AOD_NODES, node))
        lo, hi = _grid.AOD_NODES[i - 1], _grid.AOD_NODES[i + 1]
        assert any(lo < a < node for a in aods) and any(node < a < hi for a in aods)
    # the sixth file's held-out sun elevations are off its own sun nodes (0.5 deg between 0
    # and 1 there); the sun node it lacks, 0.5 deg, has a held-out sun on either side of it
    v6e, _, _, _ = _grid.grid("heldout-v6")
    assert not set(v6e.tolist()) & set(_grid.grid("fit-v6")[0].tolist())
    for node in _grid.SUPPLEMENT_SUN_ELEVATIONS_DEG:
        i = int(np.searchsorted(fe, node))
        assert any(fe[i - 1] < e < node for e in el) and any(node < e < fe[i + 1] for e in el)
    # the first file's grids stay, to reproduce its figures: its held-out sun elevations are
    # off its own nodes too
    ve, _, _, vmid = _grid.grid("heldout-v1")
    fe1, _, _, _ = _grid.grid("fit-v1")
    assert vmid and not set(ve.tolist()) & set(fe1.tolist())


# -- wavelengths between the 20-nm table wavelengths ----------------------------------------
def test_gas_interpolation_is_exact_for_beer_law_on_a_smooth_spectrum():
    """Between the table wavelengths where the gases absorb, a spectrum that follows Beer's
    law through the gases of Atmosphere.earth (their vertical optical depths from the
    atmosphere itself, not from the model) on an exponential continuum is reproduced at
    the in-between wavelengths of the Huggins band (310 nm), the water-vapour windows and
    bands (710, 930, 950 nm) and next to the O2 A band (750 nm), for any effective air mass;
    linear interpolation (the model before) is off there by up to a factor of several."""
    from skydome.models.fitted import interpolate_spectrum

    tw = _grid.WAVELENGTHS_NM
    wl = np.array([310.0, 710.0, 750.0, 930.0, 950.0])
    t = sd.Atmosphere.earth(aerosol_optical_depth=0.3).vertical_optical_depth(
        np.concatenate([tw, wl]))
    tau = t["ozone"] + t["water_vapour"] + t["mixed_gases"]
    lam = np.concatenate([tw, wl])
    for m in (1.0, 2.5, 8.0):
        exact = 0.2 * np.exp(-0.003 * (lam - 300.0) - m * tau)
        got = interpolate_spectrum(exact[:tw.size], tw, wl)
        np.testing.assert_allclose(got, exact[tw.size:], rtol=1e-9)
        # at the table wavelengths the values themselves
        np.testing.assert_allclose(interpolate_spectrum(exact[:tw.size], tw, tw),
                                   exact[:tw.size], rtol=1e-12)
        lin = np.interp(wl, tw, exact[:tw.size])
        assert np.max(np.abs(lin / exact[tw.size:] - 1.0)) > 0.05


def test_interpolated_values_positive_and_finite_for_any_table():
    """Zero, tiny and steep table values (deep twilight in the Huggins band) give finite,
    non-negative values at every wavelength, never above four times the values they come
    from."""
    from skydome.models.fitted import interpolate_spectrum

    tw = _grid.WAVELENGTHS_NM
    rng = np.random.default_rng(5)
    v = np.exp(rng.uniform(-60.0, 0.0, size=(200, tw.size)))
    v[:20, :3] = 0.0
    v[20:40, ::7] = 0.0
    wl = np.arange(300.0, 1100.1, 5.0)
    out = interpolate_spectrum(v, tw, wl)
    assert np.all(np.isfinite(out)) and np.all(out >= 0.0)
    j = np.clip(np.searchsorted(tw, wl) - 1, 0, tw.size - 2)
    around = np.maximum(v[:, np.maximum(j - 1, 0)], v[:, np.minimum(j + 2, tw.size - 1)])
    around = np.maximum(around, np.maximum(v[:, j], v[:, j + 1]))
    assert np.all(out <= 4.0 * around * (1 + 1e-12))


#: The in-between wavelengths of the live check: 510 nm (no gas: linear, as before), 730 and
#: 930 nm (water vapour: from the logarithms of three table wavelengths); an atmosphere off
#: the nodes (AOD 0.15, albedo 0.4), the sun at 35 deg (between the nodes 32 and 40), the
#: observer at 300 m. The reference: ``precomputed`` at these table wavelengths (each
#: computed independently of the others: at a table wavelength the same values as with
#: every 10-nm wavelength, docs/models.md "fitted", "Wavelengths"), in its default
#: configuration (by day the data set's twilight configuration gives the same sky, at 4x
#: the CPU).
BETWEEN_CASE = dict(aod=0.15, albedo=0.4, el=35.0, h=300.0)
#: Bounds (RMS, max) per wavelength: the model's errors measured there on the 10-nm
#: held-out grid with the sun above 20 deg (docs/models.md, "fitted", "Wavelengths": 510 nm
#: 1.2 % RMS, 12.0 % max; 730 nm 6.4 % / 28.3 %; 930 nm 7.6 % / 28.4 %; the four held-out
#: atmospheres of AOD 0.025-0.18, among which the case's 0.15 lies; with AOD 0.7 the fit's
#: own error reaches 67 % max there), rounded up: the model's documented accuracy, not a
#: tighter promise. Linear interpolation (the model before) measured 24 % and 48 % RMS at 730 and
#: 930 nm there (two atmospheres). Measured here: 1.41 % / 5.0 %, 2.91 % / 8.5 %,
#: 3.40 % / 8.4 %.
BETWEEN_BOUNDS = {510.0: (0.03, 0.15), 730.0: (0.10, 0.35), 930.0: (0.12, 0.35)}


@pytest.mark.slow
def test_spectral_radiance_between_table_wavelengths_against_live_precomputed():
    t = BETWEEN_CASE
    wl = np.array(sorted(BETWEEN_BOUNDS))
    sun = sd.Sun(elevation_deg=t["el"], azimuth_deg=200.0)
    ref = sd.model("precomputed", sun=sun,
                   atmosphere=sd.Atmosphere.earth(aerosol_optical_depth=t["aod"],
                                                  ground_albedo=t["albedo"]),
                   table_wavelengths_nm=wl, cache=False).with_sun(
                       sun, observer_altitude_m=t["h"])
    fit = sd.model("fitted", sun=sun, aerosol_optical_depth=t["aod"],
                   ground_albedo=t["albedo"], observer_altitude_m=t["h"])
    d = _dirs(300, seed=23, upper=True)[:300]
    d = d[np.degrees(np.arccos(np.clip(d @ sun.direction, -1, 1))) > 5.0]
    l_ref = ref.radiance(d, wl)
    l_fit = fit.radiance(d, wl)
    assert np.all(l_ref > 0.0)
    rel = l_fit / l_ref - 1.0
    for k, w in enumerate(wl):
        rms, worst = float(np.sqrt(np.mean(rel[:, k] ** 2))), float(np.max(np.abs(rel[:, k])))
        rms_bound, max_bound = BETWEEN_BOUNDS[w]
        print(f"{w:g} nm: RMS {100 * rms:.2f} %, max {100 * worst:.1f} %")
        assert rms <= rms_bound and worst <= max_bound, (w, rms, worst)


def test_dataset_wavelength_step_keeps_the_table_wavelengths_and_refuses_others(capsys):
    """tools/fitted_dataset.py --wavelength-step: 10 nm gives 300, 310, ..., 1100 nm (81),
    every other one a table wavelength (so a 10-nm held-out set holds the 20-nm one); a
    step that is not a divisor of 20 nm is refused before any work, naming the option."""
    from skydome.models.fitted import _dataset

    wl = _dataset.wavelengths_nm(10)
    assert wl.size == 81 and wl[0] == 300.0 and wl[-1] == 1100.0
    np.testing.assert_array_equal(wl[::2], _grid.WAVELENGTHS_NM)
    np.testing.assert_array_equal(_dataset.wavelengths_nm(20), _grid.WAVELENGTHS_NM)
    with pytest.raises(ValueError, match="wavelength step = 7"):
        _dataset.wavelengths_nm(7)
    mod = _load_tool("fitted_dataset")
    assert mod.main(["unused-folder", "--wavelength-step", "15"]) == 2
    err = capsys.readouterr().err
    assert "--wavelength-step = 15 nm is out of range" in err and "20, 10, 5, 4, 2, 1" in err


def test_dataset_refuses_more_workers_than_the_memory_holds(tmp_path, capsys, monkeypatch):
    """tools/fitted_dataset.py: a local cluster whose workers would need more than the
    machine's available memory (0.14 GB per table wavelength and worker: the largest
    measured, 11.2 GB at 81 wavelengths, docs/models.md "fitted", "Cost") is refused before
    any work, naming --workers, the need and what fits; nothing is written. A cluster
    (--scheduler) and --ignore-memory-check are not checked."""
    mod = _load_tool("fitted_dataset")
    assert mod.worker_memory_gb(81) == pytest.approx(11.34)
    assert mod.worker_memory_gb(41) >= 5.5          # the largest measured at 41 wavelengths
    monkeypatch.setattr(mod, "available_memory_gb", lambda: 24.0)
    out = tmp_path / "set"
    assert mod.main([str(out), "--grid", "small", "--wavelength-step", "10",
                     "--workers", "3"]) == 2
    err = capsys.readouterr().err
    assert "--workers = 3" in err and "11.3 GB per worker" in err and "--workers 2 or fewer" in err
    assert not out.exists()
    monkeypatch.setattr(mod, "available_memory_gb", lambda: 4.0)
    assert mod.main([str(out), "--grid", "small", "--workers", "1"]) == 2
    assert "1 on a larger machine" in capsys.readouterr().err
    assert not out.exists()
    # no work is started where the check passes but the run is refused later for another
    # reason: the memory check itself writes nothing either way
    assert mod.main([str(out), "--grid", "small", "--workers", "1", "--ignore-memory-check",
                     "--max-aod", "2"]) == 2
    assert not out.exists()
    real = mod.available_memory_gb()
    assert real is None or real > 0


# -- the aureole between the elevation nodes (the sun-relative reading, _coefficients.TURN) --
def _ring_directions(sun, gammas_deg, n_az=24):
    """Directions at the scattering angles ``gammas_deg`` around ``sun`` (n_az each)."""
    s = sun.direction
    a = np.cross(s, [0.0, 0.0, 1.0])
    a /= np.linalg.norm(a)
    b = np.cross(s, a)
    out = []
    for g in np.radians(gammas_deg):
        for p in np.linspace(0.0, 2.0 * np.pi, n_az, endpoint=False):
            out.append(np.cos(g) * s + np.sin(g) * (np.cos(p) * a + np.sin(p) * b))
    return np.array(out)


def test_turned_reads_keep_the_scattering_angle_of_a_node_sky():
    """A node's sky that depends on the scattering angle alone (an aureole-like power law
    of the angle to the node's own sun), read as turned_reads says for a sun 8 deg lower,
    is that law of the angle to the new sun within the bilinear lookup's error (about 1 %
    for this law on this grid) where the
    reading is fully turned, and the node's own value where it is not turned."""
    node_el, el, h = 62.0, 54.0, 0.0
    sky, _ = _grid.theta_nodes_rad(h)
    phi = _grid.phi_nodes_rad()
    th = np.repeat(sky, phi.size)
    ph = np.tile(phi, sky.size)
    d = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], axis=1)

    def law(sun_el):
        s = np.array([np.cos(np.radians(sun_el)), 0.0, np.sin(np.radians(sun_el))])
        g = np.degrees(np.arccos(np.clip(d @ s, -1.0, 1.0)))
        return (g + 10.0) ** -1.5, g

    node_sky, _ = law(node_el)
    want, gamma = law(el)
    idx, wt, keep = _coefficients.turned_reads(el, node_el, h)
    got = _coefficients._read_turned(node_sky, idx, wt, keep)
    full = keep < 1e-12
    assert full.sum() > 40 and (gamma[full] < 8.0 + 1e-9).all()
    # the law's cusp at the sun itself is not bilinear: 3 deg and more from it (the model's
    # accuracy is stated outside 5 deg)
    sel = full & (gamma > 3.0)
    assert sel.sum() > 20
    np.testing.assert_allclose(got[sel], want[sel], rtol=0.03)
    untouched = keep == 1.0
    assert (gamma[untouched] > 8.0).all()
    np.testing.assert_array_equal(got[untouched], node_sky[untouched])
    # no turn at a node, nor below the turned range of suns
    assert _coefficients.turned_reads(62.0, 62.0, h) is None
    assert _coefficients.turned_reads(10.0, 14.0, h) is None


@pytest.mark.slow
def test_aureole_between_elevation_nodes_against_live_precomputed(reference):
    """The sky 5.5-14 deg from a sun between the elevation nodes 62 and 75 deg: each node's
    aureole read where it stands to its own sun. Reference: precomputed (the module's
    fixture, computed by the reference itself). Measured 2.4 % largest error (8.1 % when
    each node is read at the grid's own directions, as before the sun-relative reading);
    bound 3.5 %."""
    sun = sd.Sun(elevation_deg=68.5, azimuth_deg=200.0)
    ref = reference.with_sun(sun)
    fit = sd.model("fitted", sun=sun, aerosol_optical_depth=HELD_AOD,
                   ground_albedo=HELD_ALBEDO)
    d = _ring_directions(sun, [5.5, 7.0, 10.0, 14.0])
    rel = fit.luminance(d) / ref.luminance(d) - 1.0
    assert float(np.max(np.abs(rel))) <= 0.035, float(np.max(np.abs(rel)))


def _load_tool(name):
    from _tools import load_script

    return load_script(f"tools/{name}.py")


def _write_dataset(folder, el, alt, atms, wl, chunks):
    """A data-set folder as tools/fitted_dataset.py writes it: grid.json and one chunk per
    atmosphere with its SHA-256 (skydome.distributed's layout)."""
    from _tools import write_chunk
    from skydome.models.fitted import _dataset

    folder.mkdir(parents=True)
    for (aod, alb), arr in zip(atms, chunks):
        write_chunk(folder, _dataset.chunk_key(aod, alb), arr)
    _dataset.write_grid(folder, el, alt, atms, False, True, wl)


@pytest.mark.parametrize("axis", ["altitude", "elevation", "gas", "wavelength"])
def test_supplement_joins_as_the_whole_grid(tmp_path, capsys, axis):
    """tools/fit_fitted.py --altitude-supplement, --elevation-supplement and
    --wavelength-supplement (or its earlier name --gas-bands): a
    data set split by altitude, sun elevation or wavelength (the supplements of
    tools/fitted_dataset.py --altitudes, --elevations and --gas-bands) gives the same
    coefficient arrays as the whole data set; a supplement whose altitudes, elevations or
    wavelengths overlap, or (altitude, elevation) whose wavelengths differ, is refused
    naming the option, and no file is written."""
    fit = _load_tool("fit_fitted")
    rng = np.random.default_rng(3)
    el = np.array([-1.0, 0.0, 0.5, 10.0])
    alt = np.array([0.0, 2000.0, 5000.0, 15000.0])
    atms = [(a, b) for a in (0.0, 0.5) for b in (0.0, 0.5, 1.0)]
    wl = np.array([500.0, 550.0, 600.0, 650.0])
    n_rows = _grid.N_SKY + _grid.N_GROUND + 1
    chunks = [rng.uniform(0.01, 1.0, (el.size, alt.size, n_rows, _grid.N_PHI, wl.size))
              .astype(np.float32) for _ in atms]
    ax = {"altitude": 1, "elevation": 0, "gas": -1, "wavelength": -1}[axis]
    option = "--gas-bands" if axis == "gas" else f"--{axis}-supplement"

    def cut(idx, shift=0.0):
        e = el[idx] if ax == 0 else el
        h = alt[idx] if ax == 1 else alt
        w = wl[idx] if ax == -1 else wl
        return e, h, atms, w + shift, [np.take(c, idx, axis=ax) for c in chunks]

    part = [0, 1, 3]                   # the data set; 5 km or 0.5 deg is the supplement
    _write_dataset(tmp_path / "whole", el, alt, atms, wl, chunks)
    _write_dataset(tmp_path / "part", *cut(part))
    _write_dataset(tmp_path / "sup", *cut([2]))
    args = ["--k-sky", "3", "--k-ground", "2"]
    assert fit.main([str(tmp_path / "whole"), "--out", str(tmp_path / "a.npz")] + args) == 0
    assert fit.main([str(tmp_path / "part"), option, str(tmp_path / "sup"),
                     "--out", str(tmp_path / "b.npz")] + args) == 0
    a, b = np.load(tmp_path / "a.npz"), np.load(tmp_path / "b.npz")
    np.testing.assert_array_equal(b["altitude_nodes_m"], alt)
    np.testing.assert_array_equal(b["elevation_nodes_deg"], el)
    np.testing.assert_array_equal(b["wavelengths_nm"], wl)
    for key in a.files:
        if key != "meta":
            np.testing.assert_array_equal(a[key], b[key], err_msg=key)
    capsys.readouterr()
    # a supplement at an altitude or elevation the data set has, or at other wavelengths:
    # refused
    _write_dataset(tmp_path / "dup", *cut([1]))
    assert fit.main([str(tmp_path / "part"), option, str(tmp_path / "dup"),
                     "--out", str(tmp_path / "c.npz")] + args) == 2
    assert option in capsys.readouterr().err
    if ax == -1:
        assert not (tmp_path / "c.npz").exists()
        return
    _write_dataset(tmp_path / "wl", *cut([2], 10.0))
    assert fit.main([str(tmp_path / "part"), option, str(tmp_path / "wl"),
                     "--out", str(tmp_path / "c.npz")] + args) == 2
    assert option in capsys.readouterr().err
    assert not (tmp_path / "c.npz").exists()


def test_supplements_join_in_the_order_given(tmp_path, capsys):
    """Two supplements along two axes (the eighth file's: the sun node 0.5 deg at the 49
    wavelengths, then 570, 590 and 610 nm at every sun node, the new one included) join in
    command-line order: elevations first, then the wavelengths at the joined elevations,
    give the whole data set's arrays; the other order is refused (the wavelength
    supplement has an elevation that the data set lacks until its elevation supplement
    joins), naming the option, and writes no file."""
    fit = _load_tool("fit_fitted")
    rng = np.random.default_rng(5)
    el = np.array([-1.0, 0.0, 0.5, 10.0])
    alt = np.array([0.0, 15000.0])
    atms = [(a, b) for a in (0.0, 0.5) for b in (0.0, 1.0)]
    wl = np.array([560.0, 570.0, 580.0, 600.0])
    n_rows = _grid.N_SKY + _grid.N_GROUND + 1
    chunks = [rng.uniform(0.01, 1.0, (el.size, alt.size, n_rows, _grid.N_PHI, wl.size))
              .astype(np.float32) for _ in atms]
    e_base, e_sup, w_base, w_sup = [0, 1, 3], [2], [0, 2, 3], [1]

    def cut(ei, wi):
        return (el[ei], alt, atms, wl[wi],
                [c[ei][..., wi] for c in chunks])
    _write_dataset(tmp_path / "whole", el, alt, atms, wl, chunks)
    _write_dataset(tmp_path / "base", *cut(e_base, w_base))
    _write_dataset(tmp_path / "sun", *cut(e_sup, w_base))
    _write_dataset(tmp_path / "wl", *cut(list(range(el.size)), w_sup))
    args = ["--k-sky", "3", "--k-ground", "2"]
    assert fit.main([str(tmp_path / "whole"), "--out", str(tmp_path / "a.npz")] + args) == 0
    assert fit.main([str(tmp_path / "base"), "--elevation-supplement", str(tmp_path / "sun"),
                     "--wavelength-supplement", str(tmp_path / "wl"),
                     "--out", str(tmp_path / "b.npz")] + args) == 0
    a, b = np.load(tmp_path / "a.npz"), np.load(tmp_path / "b.npz")
    for key in a.files:
        if key != "meta":
            np.testing.assert_array_equal(a[key], b[key], err_msg=key)
    capsys.readouterr()
    assert fit.main([str(tmp_path / "base"), "--wavelength-supplement", str(tmp_path / "wl"),
                     "--elevation-supplement", str(tmp_path / "sun"),
                     "--out", str(tmp_path / "c.npz")] + args) == 2
    assert "--wavelength-supplement" in capsys.readouterr().err
    assert not (tmp_path / "c.npz").exists()


def test_dataset_being_generated_reads_its_wavelengths_from_a_chunk(tmp_path):
    """A data set whose run has not ended (no grid.json yet) takes its table wavelengths
    from a chunk's last axis: the gas bands' 11 (--gas-bands), the 20-nm ones and the gas
    bands' together, 52 (--with-gas-bands: not evenly spaced), the earlier files' 8 and 49,
    the Chappuis band's 3 (--wavelengths 570,590,610), or 300-1100 nm evenly spaced
    (--wavelength-step 10: 81)."""
    from skydome.models.fitted._dataset import DataSet

    el, alt = np.array([10.0]), np.array([0.0])
    n_rows = _grid.N_SKY + _grid.N_GROUND + 1
    for name, wl in (("gas", _grid.GAS_BAND_WAVELENGTHS_NM),
                     ("with", _grid.TABLE_WAVELENGTHS_NM),
                     ("gas7", _grid.V7_GAS_BAND_WAVELENGTHS_NM),
                     ("with7", _grid.V7_TABLE_WAVELENGTHS_NM),
                     ("chappuis", np.array([570.0, 590.0, 610.0])),
                     ("ten", np.arange(300.0, 1100.0 + 1e-9, 10.0))):
        folder = tmp_path / name
        _write_dataset(folder, el, alt, [(0.1, 0.0)], wl,
                       [np.ones((1, 1, n_rows, _grid.N_PHI, wl.size), np.float32)])
        (folder / "grid.json").unlink()
        ds = DataSet(folder, require_all=False)
        assert ds.present == [(0.1, 0.0)]
        np.testing.assert_array_equal(ds.wavelengths_nm, wl)


def _projection_case(tmp_path, seed, name, aod):
    """(tool, albedo nodes) after writing a random data set "base" (AOD 0, 0.5, 1 x albedo
    0, 0.5, 1; 2 sun nodes, 2 altitudes, 3 wavelengths) and a data set ``name`` holding the
    chunks of AOD 1 as AOD ``aod``."""
    fit = _load_tool("fit_fitted")
    rng = np.random.default_rng(seed)
    el = np.array([-1.0, 10.0])
    alt = np.array([0.0, 15000.0])
    wl = np.array([500.0, 600.0, 700.0])
    n_rows = _grid.N_SKY + _grid.N_GROUND + 1
    albs = (0.0, 0.5, 1.0)
    atms = [(a, b) for a in (0.0, 0.5, 1.0) for b in albs]
    chunks = {x: rng.uniform(0.01, 1.0, (el.size, alt.size, n_rows, _grid.N_PHI, wl.size))
              .astype(np.float32) for x in atms}
    _write_dataset(tmp_path / "base", el, alt, atms, wl, [chunks[x] for x in atms])
    _write_dataset(tmp_path / name, el, alt, [(aod, b) for b in albs], wl,
                   [chunks[(1.0, b)] for b in albs])
    return fit, albs


def _assert_node_projected(a, b, key, i_b, tol):
    """The node ``i_b`` of array ``key`` in file ``b`` equals node AOD 1 (index 2) of file
    ``a`` (scaled float16 rows compared as the model reads them) within ``tol`` of its
    largest magnitude."""
    x, y = b[key][i_b].astype(np.float64), a[key][2].astype(np.float64)
    if key + "_scale" in a.files:
        x = x * b[key + "_scale"][i_b][..., None]
        y = y * a[key + "_scale"][2][..., None]
    if not key.endswith("_scale"):
        np.testing.assert_allclose(x, y, rtol=0, atol=tol * np.abs(y).max(), err_msg=key)


#: (options of the base fit, tolerance of a projected node's arrays)
_PROJECTION_FITS = (([], 1e-5), (["--float16"], 4e-3))


def test_extend_adds_an_aod_node_on_the_file_bases(tmp_path, capsys):
    """tools/fit_fitted.py --extend: a node added to a fitted file keeps every node the file
    had bit for bit and inserts the new one in AOD order. Its coefficients are the
    projection of its y on the file's bases and spectral vectors: for an atmosphere whose
    radiance is that of a fitted node (the chunk of AOD 1 given as AOD 0.75), they are the
    fit's own at that node (the fit's coefficients are the same projection). A data set
    with no AOD node the file lacks is refused naming the option, and nothing written."""
    fit, _ = _projection_case(tmp_path, 5, "new", 0.75)
    for opts, tol in _PROJECTION_FITS:
        base, ext = tmp_path / f"base{len(opts)}.npz", tmp_path / f"ext{len(opts)}.npz"
        args = ["--k-sky", "3", "--k-ground", "2", "--spectral-rank", "2"] + opts
        assert fit.main([str(tmp_path / "base"), "--out", str(base)] + args) == 0
        assert fit.main([str(tmp_path / "new"), "--extend", str(base), "--out",
                         str(ext)]) == 0
        a, b = np.load(base), np.load(ext)
        np.testing.assert_array_equal(b["aod_nodes"], [0.0, 0.5, 0.75, 1.0])
        for key in a.files:
            if key == "meta" or key == "aod_nodes":
                continue
            if a[key].shape[:1] == (3,) and b[key].shape[:1] == (4,):   # per AOD node
                np.testing.assert_array_equal(b[key][[0, 1, 3]], a[key], err_msg=key)
                _assert_node_projected(a, b, key, 2, tol)
            else:
                np.testing.assert_array_equal(b[key], a[key], err_msg=key)
        meta = json.loads(str(b["meta"]))
        assert meta["aod_nodes_projected"] == [0.75]
    capsys.readouterr()
    # nothing to add: refused before any work
    assert fit.main([str(tmp_path / "base"), "--extend", str(base), "--out",
                     str(tmp_path / "c.npz")]) == 2
    assert "--extend" in capsys.readouterr().err
    assert not (tmp_path / "c.npz").exists()


def test_replace_projects_a_node_again_and_keeps_the_others(tmp_path, capsys):
    """tools/fit_fitted.py --replace: the arrays of an AOD node the file has are those of
    the projection of a new data set's y on the file's bases, every other node and every
    shared array kept bit for bit. Given the chunks of AOD 1 as AOD 0.5, node 0.5 gets the
    fit's own coefficients of node 1 (the fit's coefficients are the same projection). A
    data set with no node the file has is refused naming the option, as is --replace beside
    --extend, and nothing is written."""
    fit, albs = _projection_case(tmp_path, 7, "again", 0.5)
    for opts, tol in _PROJECTION_FITS:
        base, rep = tmp_path / f"base{len(opts)}.npz", tmp_path / f"rep{len(opts)}.npz"
        args = ["--k-sky", "3", "--k-ground", "2", "--spectral-rank", "2"] + opts
        assert fit.main([str(tmp_path / "base"), "--out", str(base)] + args) == 0
        assert fit.main([str(tmp_path / "again"), "--replace", str(base), "--out",
                         str(rep)]) == 0
        a, b = np.load(base), np.load(rep)
        assert sorted(a.files) == sorted(b.files)
        for key in a.files:
            if key == "meta":
                continue
            assert b[key].shape == a[key].shape and b[key].dtype == a[key].dtype, key
            if a[key].shape[:2] == (3, 3):              # per (AOD, albedo) node
                np.testing.assert_array_equal(b[key][[0, 2]], a[key][[0, 2]], err_msg=key)
                _assert_node_projected(a, b, key, 1, tol)
            else:
                np.testing.assert_array_equal(b[key], a[key], err_msg=key)
        meta = json.loads(str(b["meta"]))
        assert meta["aod_nodes_reprojected"] == [0.5]
        assert [s["aod_nodes"] for s in meta["reprojection_steps"]] == [[0.5]]
    # a second step (a data set generated over several runs) adds to the record
    rep2 = tmp_path / "rep_twice.npz"
    assert fit.main([str(tmp_path / "again"), "--replace", str(rep), "--out",
                     str(rep2)]) == 0
    meta = json.loads(str(np.load(rep2)["meta"]))
    assert meta["aod_nodes_reprojected"] == [0.5]
    assert [s["aod_nodes"] for s in meta["reprojection_steps"]] == [[0.5], [0.5]]
    capsys.readouterr()
    chunk = np.load(tmp_path / "again" / f"{_dataset_key(0.5, 0.0)}.npy")
    _write_dataset(tmp_path / "other", np.array([-1.0, 10.0]), np.array([0.0, 15000.0]),
                   [(0.75, b) for b in albs], np.array([500.0, 600.0, 700.0]),
                   [chunk] * len(albs))
    assert fit.main([str(tmp_path / "other"), "--replace", str(base), "--out",
                     str(tmp_path / "c.npz")]) == 2
    assert "--replace" in capsys.readouterr().err
    assert fit.main([str(tmp_path / "again"), "--replace", str(base), "--extend", str(base),
                     "--out", str(tmp_path / "c.npz")]) == 2
    assert "--replace" in capsys.readouterr().err
    assert not (tmp_path / "c.npz").exists()


def test_dataset_wavelengths_option_computes_only_those(tmp_path, monkeypatch):
    """tools/fitted_dataset.py --wavelengths 610,570,590: every chunk of the grid is asked
    for exactly 570, 590 and 610 nm (sorted, each once), every sun node and altitude of the
    grid, and the data set's grid.json records those wavelengths (the chunks' computation
    replaced by a recorder: a real chunk takes minutes)."""
    import skydome.distributed as dist
    from skydome.models.fitted._dataset import DataSet

    mod = _load_tool("fitted_dataset")
    seen = []

    class Report:
        computed, verified = [], []

    def run_chunks(chunks, out, **kw):
        seen.extend(chunks)
        Path(out).mkdir(parents=True, exist_ok=True)
        return Report()
    monkeypatch.setattr(dist, "run_chunks", run_chunks)
    out = tmp_path / "chappuis"
    assert mod.main([str(out), "--grid", "small", "--wavelengths", "610,570,590,570",
                     "--ignore-memory-check"]) == 0
    el, alt, atms = _grid.grid("small")[:3]
    assert len(seen) == len(atms)
    for c in seen:
        np.testing.assert_array_equal(c.args[-1], [570.0, 590.0, 610.0])
        np.testing.assert_array_equal(c.args[2], el)
        np.testing.assert_array_equal(c.args[3], alt)
    np.testing.assert_array_equal(DataSet(out).wavelengths_nm, [570.0, 590.0, 610.0])


def _dataset_key(aod, albedo):
    from skydome.models.fitted import _dataset

    return _dataset.chunk_key(aod, albedo)


def test_dataset_altitudes_option_refuses_altitudes_off_the_grid(tmp_path, capsys):
    """tools/fitted_dataset.py --altitudes and --elevations: only the grid's altitude and
    sun elevation nodes (a supplement's values must be the grid's); any other is refused
    before any work, naming the option and the grid's values. --with-gas-bands refuses
    --gas-bands beside it; --wavelengths takes only the 10-nm grid's wavelengths and
    neither --gas-bands nor --wavelength-step."""
    mod = _load_tool("fitted_dataset")
    out = tmp_path / "set"
    assert mod.main([str(out), "--altitudes", "4000,4500", "--ignore-memory-check"]) == 2
    err = capsys.readouterr().err
    assert "--altitudes = '4000,4500'" in err and "12000.0" in err
    assert mod.main([str(out), "--altitudes", "4 km", "--ignore-memory-check"]) == 2
    assert "--altitudes" in capsys.readouterr().err
    # --elevations likewise: the held-out grid's 0.25 deg is not a sun node of the fit grid
    assert mod.main([str(out), "--elevations", "0.5,0.25", "--ignore-memory-check"]) == 2
    err = capsys.readouterr().err
    assert "--elevations = '0.5,0.25'" in err and "3.5" in err
    assert mod.main([str(out), "--elevations", "low", "--ignore-memory-check"]) == 2
    assert "--elevations" in capsys.readouterr().err
    assert mod.main([str(out), "--with-gas-bands", "--gas-bands",
                     "--ignore-memory-check"]) == 2
    assert "--with-gas-bands" in capsys.readouterr().err
    # --wavelengths: only the 10-nm grid's wavelengths, and alone
    assert mod.main([str(out), "--wavelengths", "570,575", "--ignore-memory-check"]) == 2
    err = capsys.readouterr().err
    assert "--wavelengths = '570,575'" in err and "580.0" in err
    assert mod.main([str(out), "--wavelengths", "570", "--gas-bands",
                     "--ignore-memory-check"]) == 2
    assert "--wavelengths" in capsys.readouterr().err
    assert mod.main([str(out), "--wavelengths", "570", "--wavelength-step", "10",
                     "--ignore-memory-check"]) == 2
    assert "--wavelengths" in capsys.readouterr().err
    assert not out.exists()
    np.testing.assert_array_equal(
        np.union1d(_grid.WAVELENGTHS_NM, _grid.GAS_BAND_WAVELENGTHS_NM),
        _grid.TABLE_WAVELENGTHS_NM)


def test_thin_haze_form_passes_its_nodes_and_reproduces_its_family():
    """_coefficients.thin_haze_form: through L(0), L(h), L(2h) it gives (a + b tau)
    exp(-c tau) exactly where L is of that form (values worked from the closed form, c of
    either sign), a straight line where L is linear, and the node values at t = 0, 1, 2 for
    any positive values (ln L convex in tau included); zeros (the model's clamp) give L
    quadratic in tau; never negative."""
    f = _coefficients.thin_haze_form
    h = 0.025
    for a, b, c in ((0.05, 20.0, 30.0), (0.3, 2.0, -4.0), (0.0, 5.0, 60.0), (1.0, 0.0, 12.0)):
        L = lambda tau: (a + b * tau) * np.exp(-c * tau)     # noqa: E731
        for t in (0.0, 0.2, 0.5, 1.0, 1.5, 2.0):
            assert f(np.array(L(0.0)), np.array(L(h)), np.array(L(2 * h)), t) == \
                pytest.approx(L(t * h), rel=1e-12, abs=1e-15)
    assert f(np.array(1.0), np.array(2.0), np.array(3.0), 0.5) == pytest.approx(1.5)
    rng = np.random.default_rng(11)
    v = rng.uniform(0.01, 1.0, (3, 1000))
    for t, k in ((0.0, 0), (1.0, 1), (2.0, 2)):
        np.testing.assert_allclose(f(*v, t), v[k], rtol=1e-12)
    assert np.all(f(*v, 0.5) > 0.0) and np.all(np.isfinite(f(*v, 0.5)))
    assert f(np.array(0.0), np.array(1.0), np.array(0.0), 0.5) == pytest.approx(0.75)
    assert f(np.array(1.0), np.array(0.0), np.array(1.0), 0.5) >= 0.0


def test_aod_rule_thin_haze_form_over_doubling_nodes():
    """_coefficients.aod_stencil with the node at 0.00625 (nodes 0, 0.00625, 0.0125, 0.025
    doubling): the form through 0, 0.00625, 0.0125 below 0.0125, through 0, 0.0125, 0.025
    from 0.0125 to 0.025 (t = AOD / 0.0125 in [1, 2)); L quadratic in sqrt(AOD) from 0.025;
    continuous at 0.0125, where both forms give the node's value (the form passes through its
    three nodes); nodes that do not double (0, 0.01, 0.025) give no form."""
    stn = _coefficients.aod_stencil
    nodes = np.array([0.0, 0.00625, 0.0125, 0.025, 0.05, 0.075, 0.1, 0.15, 0.25, 0.35, 0.5,
                      0.75, 1.0])
    for aod, idx in ((0.001, [0, 1, 2]), (0.006, [0, 1, 2]), (0.0124, [0, 1, 2]),
                     (0.0125, [0, 2, 3]), (0.018, [0, 2, 3]), (0.0249, [0, 2, 3])):
        st, how = stn(nodes, aod)
        assert how == "form" and [i for i, _ in st] == idx, (aod, st)
    assert stn(nodes, 0.025)[1] == "L" and stn(nodes, 0.03)[1] == "L"
    assert stn(np.array([0.0, 0.01, 0.025, 0.05, 0.1]), 0.005)[1] == "L"
    # the values: at 0.0125 the node's value from either side; between, positive and
    # between the forms' limits, the same function as thin_haze_form through the nodes
    rng = np.random.default_rng(3)
    L = {float(a): rng.uniform(0.5, 1.5, 50) * (1.0 + 8.0 * a) for a in nodes}

    def at(x):
        st, how = stn(nodes, x)
        return _coefficients.apply_aod_stencil(nodes, x, st, how, lambda i: L[float(nodes[i])])

    np.testing.assert_allclose(at(0.0125), L[0.0125], rtol=1e-12)
    np.testing.assert_allclose(at(0.0125 * (1 - 1e-9)), L[0.0125], rtol=1e-6)
    np.testing.assert_allclose(at(0.00625), L[0.00625], rtol=1e-12)
    np.testing.assert_allclose(
        at(0.018), _coefficients.thin_haze_form(L[0.0], L[0.0125], L[0.025], 0.018 / 0.0125),
        rtol=1e-12)
    np.testing.assert_allclose(
        at(0.003), _coefficients.thin_haze_form(L[0.0], L[0.00625], L[0.0125], 0.003 / 0.00625),
        rtol=1e-12)


def test_aod_rule_thin_haze_form_below_0p025_over_either_node_set():
    """_coefficients.aod_stencil, sun above the horizon: the thin-haze form through the
    nodes 0, h, 2 h for every AOD strictly between 0 and 0.025 (t = AOD / h), with the node
    at 0.0125 (h = 0.0125, t up to 2) as without it (h = 0.025, t up to 1); from 0.025 up
    L quadratic in sqrt(AOD) over three nodes around it, above 0.1 ln L; at the nodes
    themselves the node alone."""
    stn = _coefficients.aod_stencil
    new = np.array([0.0, 0.0125, 0.025, 0.05, 0.075, 0.1, 0.15, 0.25, 0.5, 1.0])
    old = np.array([0.0, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0])
    for nodes, h in ((new, 0.0125), (old, 0.025)):
        for aod in (0.001, 0.006, 0.0124, 0.018, 0.0249):
            st, how = stn(nodes, aod)
            assert how == "form" and [i for i, _ in st] == [0, 1, 2], (aod, st)
            assert nodes[1] == h
        for aod in (0.03, 0.045, 0.07, 0.09):
            st, how = stn(nodes, aod)
            assert how == "L" and len(st) == 3
            assert min(nodes[i] for i, _ in st) <= aod <= max(nodes[i] for i, _ in st)
            assert sum(w for _, w in st) == pytest.approx(1.0)
        assert stn(nodes, 0.18)[1] == "lnL"
        for k, a in enumerate(nodes[1:], start=1):
            st, how = stn(nodes, float(a))
            assert dict(st).get(k) == pytest.approx(1.0)
            assert all(abs(w) < 1e-12 for i, w in st if i != k)
    # the stencil between 0.05 and 0.1 reads the node at 0.075, and at 0.18 (ln L) the node
    # at 0.15, where there are such nodes
    assert {i for i, _ in stn(new, 0.07)[0]} == {3, 4, 5}
    assert {i for i, _ in stn(new, 0.18)[0]} == {5, 6, 7}
    assert {i for i, _ in stn(old, 0.18)[0]} == {3, 4, 5}


def _live_reference(aod, albedo, el, h, wl):
    """``precomputed`` in the data set's configuration (twilight_reference=True, no cache)
    at the table wavelengths ``wl`` alone (each computed independently by the reference)."""
    sun = sd.Sun(elevation_deg=el, azimuth_deg=200.0)
    ref = sd.model("precomputed", sun=sun,
                   atmosphere=sd.Atmosphere.earth(aerosol_optical_depth=aod, ground_albedo=albedo),
                   table_wavelengths_nm=np.asarray(wl, float), cache=False,
                   twilight_reference=True).with_sun(sun, observer_altitude_m=h)
    fit = sd.model("fitted", sun=sun, aerosol_optical_depth=aod, ground_albedo=albedo,
                   observer_altitude_m=h)
    return sun, ref, fit


def _sky_near_horizon(sun, h, n=400, seed=23, top_deg=15.0):
    """Directions 0.1-``top_deg`` deg above the observer's horizon, more than 5 deg from
    the sun."""
    rng = np.random.default_rng(seed)
    dip = np.degrees(np.arccos(6371e3 / (6371e3 + h)))
    alt = np.radians(-dip + rng.uniform(0.1, top_deg, n))
    az = np.radians(rng.uniform(0.0, 360.0, n))
    d = np.stack([np.cos(alt) * np.sin(az), np.cos(alt) * np.cos(az), np.sin(alt)], -1)
    return d[np.degrees(np.arccos(np.clip(d @ sun.direction, -1, 1))) > 5.0]


#: The issue's day targets (RMS 2 %, max 6 %) for the two cases below, which the model
#: before this file and its AOD form missed: the thinnest haze near the horizon (AOD 0.01
#: on the ground; the quadratic in sqrt(AOD) was 2-4 % RMS and 10-16 % max there) and the
#: haze seen from between the altitude nodes 3 and 6 km (up to 29 % off in altitude alone).
DAY_TARGET_RMS, DAY_TARGET_MAX = 0.02, 0.06


@pytest.mark.slow
@pytest.mark.parametrize("aod, albedo, el, h", [(0.01, 0.3, 6.0, 0.0),
                                                 (0.6, 0.2, 2.5, 4500.0)])
def test_thin_haze_and_between_altitude_nodes_against_live_precomputed(aod, albedo, el, h):
    wl = [500.0, 560.0, 620.0]
    sun, ref, fit = _live_reference(aod, albedo, el, h, wl)
    d = _sky_near_horizon(sun, h)
    r_ref, r_fit = ref.radiance(d, np.array(wl)), fit.radiance(d, np.array(wl))
    assert np.all(r_ref > 0.0)
    rel = r_fit / r_ref - 1.0
    rms, worst = float(np.sqrt(np.mean(rel ** 2))), float(np.max(np.abs(rel)))
    print(f"AOD {aod:g}, sun {el:g} deg, {h:g} m: RMS {100 * rms:.2f} %, max {100 * worst:.1f} %")
    assert rms <= DAY_TARGET_RMS and worst <= DAY_TARGET_MAX, (rms, worst)


def test_node_spacing_tool_applies_the_models_aod_rule():
    """tools/fitted_node_spacing.py's apply_aod_rule: over values of the thin-haze family
    (a + b tau) exp(-c tau) it reproduces the family below 0.025 (the form's own case), and
    over values quadratic in sqrt(AOD) it reproduces them between 0.025 and 0.1 (the rule
    there), for the node set with 0.0125 and 0.075; closed forms, not the model."""
    mod = _load_tool("fitted_node_spacing")
    nodes = (0.0, 0.0125, 0.025, 0.05, 0.075, 0.1)
    rng = np.random.default_rng(5)
    a, b, c = rng.uniform(0.05, 1.0, 50), rng.uniform(1.0, 30.0, 50), rng.uniform(-5, 60, 50)
    form = lambda tau: (a + b * tau) * np.exp(-c * tau)      # noqa: E731
    L = {x: form(x) for x in nodes}
    L[0.0] = L[0.0].copy()
    for x in (0.003, 0.009, 0.018, 0.024):
        np.testing.assert_allclose(mod.apply_aod_rule(L, nodes, x), form(x), rtol=1e-10)
    p0, p1, p2 = rng.uniform(0.1, 1.0, (3, 50))
    quad = lambda tau: p0 + p1 * np.sqrt(tau) + p2 * tau       # noqa: E731
    L = {x: quad(x) for x in nodes}
    for x in (0.03, 0.06, 0.09):
        np.testing.assert_allclose(mod.apply_aod_rule(L, nodes, x), quad(x), rtol=1e-10)


def test_node_spacing_tool_refuses_bad_input_before_any_work(capsys):
    """tools/fitted_node_spacing.py: an albedo or AOD outside [0, 1] is refused with exit 2,
    naming the option, its value and the range, before any reference is computed."""
    mod = _load_tool("fitted_node_spacing")
    assert mod.main(["altitude", "--albedo", "1.5"]) == 2
    assert "--albedo = 1.5 is out of range [0, 1]" in capsys.readouterr().err
    assert mod.main(["altitude", "--aod", "-0.1"]) == 2
    assert "--aod = -0.1 is out of range [0, 1]" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        mod.main(["neither"])


#: (sun nodes, the nodes a sun between 0 deg and the next node reads, the first node above)
_STENCIL_GRIDS = [(_grid.SUN_ELEVATION_NODES_DEG, [0.0, 0.5, 1.0, 2.0], 0.5),
                  (_grid.V6_SUN_ELEVATION_NODES_DEG, [0.0, 1.0, 2.0, 3.5], 1.0)]


@pytest.mark.parametrize("nodes, reads, first", _STENCIL_GRIDS)
def test_elevation_stencil_keeps_a_risen_sun_off_the_nodes_below_the_horizon(nodes, reads,
                                                                             first):
    """_coefficients.elevation_stencil: for a sun between 0 deg and the next node the cubic
    reads the four nodes from 0 deg up (0, 0.5, 1, 2 deg; 0, 1, 2, 3.5 on the sixth file's
    nodes: none below the horizon), reproduces any cubic in elevation there and meets the
    nodes at 0 deg and the next; a sun below the horizon and one above the next node keep
    the centred cubic of _coefficients.stencil."""
    est = _coefficients.elevation_stencil
    for e in first * np.array([0.01, 0.25, 0.5, 0.75, 0.99]):
        st = est(nodes, e)
        assert [float(nodes[i]) for i, _ in st] == reads
        for poly in (lambda x: 1.0 + 0.0 * x, lambda x: 2.0 - x + 0.3 * x ** 3):
            assert sum(w * poly(nodes[i]) for i, w in st) == pytest.approx(poly(e), abs=1e-12)
    for e in (0.0, first):
        assert {float(nodes[i]): w for i, w in est(nodes, e) if abs(w) > 1e-15} == {e: 1.0}
    for e in (-11.5, -1.5, -0.5, -0.01, first + 0.5, 16.0, 90.0):
        assert est(nodes, e) == _coefficients.stencil(nodes, e, 3)


@pytest.mark.parametrize("nodes, reads, first", _STENCIL_GRIDS)
def test_elevation_stencil_in_log_elevation_at_the_clear_aod_nodes(nodes, reads, first):
    """With the offset of _coefficients.elevation_log_offset (the AOD nodes 0 and 0.00625:
    0.5 deg, the others up to 0.1: 2 deg; None above), a sun whose stencil reads the node at 0 deg from above (between 0
    and 1 deg; 0 and 2 deg on the sixth file's nodes) reads the nodes from 0 deg up with the
    cubic in x = ln(e + 2 deg), which it reproduces (and not the cubic in e), meeting the
    nodes; below 0 and above that the stencil is the one in e."""
    est = _coefficients.elevation_stencil
    off = _coefficients.elevation_log_offset
    assert [off(a) for a in (0.0, 0.00625)] == [0.5] * 2
    assert [off(a) for a in (0.0125, 0.05, 0.075, 0.1)] == [2.0] * 4
    assert [off(a) for a in (0.15, 0.25, 0.5, 1.0)] == [None] * 4
    c = 2.0
    top = reads[2]                          # the log stencil's range: (0, top)
    for e in top * np.array([0.005, 0.125, 0.25, 0.375, 0.495, 0.505, 0.75, 0.995]):
        st = est(nodes, e, c)
        assert [float(nodes[i]) for i, _ in st] == reads
        for poly in (lambda x: 1.0 + 0.0 * x, lambda x: 2.0 - x + 0.3 * x ** 3):
            got = sum(w * poly(np.log(nodes[i] + c)) for i, w in st)
            assert got == pytest.approx(poly(np.log(e + c)), abs=1e-12)
        assert sum(w * nodes[i] ** 3 for i, w in st) != pytest.approx(e ** 3, abs=1e-6)
    for e in reads[:3]:
        assert {float(nodes[i]): w for i, w in est(nodes, e, c) if abs(w) > 1e-12} == \
            pytest.approx({e: 1.0}, abs=1e-12)
    for e in (-11.5, -1.5, -0.5, -0.01, top + 0.01, 16.0, 90.0):
        assert est(nodes, e, c) == est(nodes, e)


@pytest.mark.parametrize("aod", [0.05, 0.1, 0.12, 0.2])
def test_the_sky_does_not_step_where_the_elevation_rule_changes(aod):
    """The stencil in ln(e + 2 deg) between 0 and 2 deg (at the AOD nodes up to 0.1) meets
    the stencils in e at 0 and 2 deg and the hazier nodes' across AOD 0.1-0.15: the model's
    sky on either side of those sun elevations, and of AOD 0.1, differs by no more than a
    change of 1e-6 deg (or 1e-7 in AOD) can make (a step would be percents: at 0.5 deg the
    two rules' weights differ by up to 0.27)."""
    d = np.random.default_rng(5).normal(size=(2000, 3))
    d[:, 2] = np.abs(d[:, 2]) + 0.05

    def lum(e, a=aod):
        return sd.model("fitted", sun=sd.Sun(elevation_deg=e, azimuth_deg=120.0),
                        aerosol_optical_depth=a).luminance(d)

    for e in (0.0, 2.0):
        lo, hi = lum(e - 1e-6), lum(e + 1e-6)
        np.testing.assert_allclose(hi, lo, rtol=2e-5)
    if aod == 0.1:
        for e in (0.5, 1.5):
            np.testing.assert_allclose(lum(e, 0.1 + 1e-7), lum(e, 0.1 - 1e-7), rtol=2e-5)


