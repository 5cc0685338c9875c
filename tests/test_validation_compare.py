"""Models against the measured sky (Kider et al. 2014, 2013-05-27): pinned errors.

The expected values are the measured errors of this comparison when it was set up (the
reference is the measurement; the numbers pin the model against it): a regression of a
model (or of the loader's conventions) moves them beyond the stated margins.
"""

import numpy as np
import pytest

from skydome.validation import compare, kider2014


@pytest.fixture(scope="module")
def caps():
    return kider2014.load_captures(["11:00:00", "12:45:00"])


# (capture, luminance level, shape RMS all, shape RMS rest, spectral RMS, xy RMS), with the
# loader's clock correction of 2013-05-27 (-23 min, the whole-sky shape scan's; at the
# circumsolar peak's -40 min they were -0.0926 / 0.2018 / 0.1679 / 0.2658 / 0.0321 and
# -0.1448 / 0.1687 / 0.1502 / 0.2392 / 0.0307: 11:00 is the one capture whose own best
# offset is near -40 min)
SINGLE = [("11:00:00", -0.0154, 0.2940, 0.1745, 0.3166, 0.0313),
          ("12:45:00", -0.1506, 0.1624, 0.1357, 0.2321, 0.0299)]


def test_single_scattering_errors_pinned(caps):
    """single_scattering with the AERONET atmosphere: level within 2 points, RMS within
    10 % of the pinned values."""
    for c, (lab, lvl, rms, rest, spec, xy) in zip(caps, SINGLE):
        r = compare.compare_one("single_scattering", c)
        assert r.capture == lab and r.phase == "tabulated"
        assert r.luminance_level == pytest.approx(lvl, abs=0.02)
        assert r.luminance_shape["all"]["rms"] == pytest.approx(rms, rel=0.1)
        assert r.luminance_shape["rest"]["rms"] == pytest.approx(rest, rel=0.1)
        assert r.spectral_rms == pytest.approx(spec, rel=0.1)
        assert r.xy_rms == pytest.approx(xy, rel=0.1)


def test_regions_partition(caps):
    c = caps[0]
    keep = np.ones(81, bool)
    keep[0] = False
    reg = compare._regions(c, keep)
    total = reg["circumsolar"].astype(int) + reg["horizon"] + reg["rest"]
    assert np.array_equal(total, keep.astype(int))
    assert np.all(c.sun_angle_deg[reg["circumsolar"]] < 10.0)
    assert np.all(c.elevation_deg[reg["horizon"]] < 15.0)


def test_arc_directions(caps):
    c = caps[0]
    d = compare.arc_directions(c, 4)
    assert d.shape == (81, 4, 3)
    assert np.allclose(np.linalg.norm(d, axis=-1), 1.0)
    assert np.allclose(d[0], c.directions[0])
    # sample 1 moves along the lowest ring from sample 0 to its own direction: each point
    # lies on the way (the two angles add up to the step, within the ring's curvature)
    def ang(u, v):
        return np.degrees(np.arccos(np.clip(u @ v, -1, 1)))

    step = ang(c.directions[0], c.directions[1])
    for p in d[1]:
        assert ang(p, c.directions[0]) + ang(p, c.directions[1]) == pytest.approx(step, rel=0.01)
    assert ang(d[1, 0], c.directions[0]) < ang(d[1, -1], c.directions[0])
    with pytest.raises(ValueError, match="n_sub"):
        compare.arc_directions(c, 0)
    with pytest.raises(ValueError, match="move"):
        compare.arc_directions(c, 4, "sideways")


def test_analytic_inputs(caps):
    r = compare.compare_one("perez1993", caps[0])
    assert "Erbs" in r.phase and np.isfinite(r.luminance_level)
    r = compare.compare_one("cie2003", caps[0])
    assert "best fit" in r.phase and np.isnan(r.luminance_level)
    assert r.luminance_shape["all"]["rms"] < 0.3
    r = compare.compare_one("preetham1999", caps[0])
    assert "AERONET beta" in r.phase


def test_bad_model():
    with pytest.raises(ValueError, match="model"):
        compare.compare_measured(["nope"], ["11:00:00"])


def test_cli_bad_input():
    from typer.testing import CliRunner

    from skydome.cli import app

    res = CliRunner().invoke(app, ["validate", "measured", "--models", "nope"])
    assert res.exit_code == 2 and "models" in res.output
    res = CliRunner().invoke(app, ["validate", "measured", "--captures", "09:31:00"])
    assert res.exit_code == 2 and "captures" in res.output


def test_cli_table(tmp_path):
    from typer.testing import CliRunner

    from skydome.cli import app

    out = tmp_path / "t.md"
    res = CliRunner().invoke(app, ["validate", "measured", "--models", "single_scattering,perez1993",
                                   "--captures", "11:00:00", "--out", str(out)])
    assert res.exit_code == 0, res.output
    text = out.read_text()
    assert "| single_scattering | tabulated |" in text and "| perez1993 |" in text
    assert [p.name for p in tmp_path.iterdir()] == ["t.md"]


# precomputed (skydome's physically based default) at the coarse test settings, with the
# measured (tabulated AERONET) phase function and its zenith-angle mu_s mapping: the errors
# against the measured sky, pinned so that a change of the model shows (at the loader's
# -23 min clock of 2013-05-27; at -40 min they were 0.2118 / 0.1228 / 0.1325 / 0.2678 /
# 0.0131 and 0.1550 / 0.0938 / 0.0806 / 0.2558 / 0.0133)
PRECOMPUTED = [("11:00:00", 0.2945, 0.1848, 0.1457, 0.3200, 0.0123),
               ("12:45:00", 0.1552, 0.0760, 0.0612, 0.2337, 0.0124)]


@pytest.mark.slow
def test_precomputed_errors_pinned(caps):
    """precomputed with the measured phase function (tabulated): luminance level within 2
    points, RMS errors within 10 % of the pinned values."""
    for c, (lab, lvl, rms, rest, spec, xy) in zip(caps, PRECOMPUTED):
        r = compare.compare_one("precomputed", c, fast=True)
        assert r.capture == lab and r.phase.startswith("tabulated")
        assert r.luminance_level == pytest.approx(lvl, abs=0.02)
        assert r.luminance_shape["all"]["rms"] == pytest.approx(rms, rel=0.1)
        assert r.luminance_shape["rest"]["rms"] == pytest.approx(rest, rel=0.1)
        assert r.spectral_rms == pytest.approx(spec, rel=0.1)
        assert r.xy_rms == pytest.approx(xy, rel=0.1)


@pytest.mark.slow
def test_precomputed_tabulated_single_order_matches_single_scattering(caps):
    """With orders = 1, precomputed must equal single_scattering on the AERONET atmosphere
    with the measured phase tabulated (both integrate [survey] eqs. 15-16); hillaire2020
    and nishita1996 do, within 2 %."""
    import skydome as sd

    c = caps[0]
    atm, _ = compare.atmosphere_for(c, "tabulated")
    ss = sd.model("single_scattering", sun=c.sun, atmosphere=atm).luminance(c.directions)
    pc = sd.model("precomputed", sun=c.sun, atmosphere=atm, orders=1,
                  n_wavelengths=8).luminance(c.directions)
    assert np.allclose(pc, ss, rtol=0.05)


def test_cli_days_bad_input():
    from typer.testing import CliRunner

    from skydome.cli import app

    res = CliRunner().invoke(app, ["validate", "measured", "--day", "2013-09-25"])
    assert res.exit_code == 2 and "day" in res.output and "2013-09-24" in res.output
    res = CliRunner().invoke(app, ["validate", "measured", "--day", "2013-09-24",
                                   "--aerosol", "aeronet"])
    assert res.exit_code == 2 and "aerosol" in res.output
    res = CliRunner().invoke(app, ["validate", "measured", "--aerosol", "nope"])
    assert res.exit_code == 2 and "aerosol" in res.output
    res = CliRunner().invoke(app, ["validate", "measured", "--day", "2013-09-24",
                                   "--captures", "11:00:00"])
    assert res.exit_code == 2 and "13:10:00" in res.output


def test_cli_every_capture_of_every_day():
    """--day all: one table per day and one row per capture of each day (a model that needs no
    aerosol, so that no fit runs)."""
    from typer.testing import CliRunner

    from skydome.cli import app

    res = CliRunner().invoke(app, ["validate", "measured", "--day", "all", "--models", "perez1993"])
    assert res.exit_code == 0, res.output
    out = res.stdout if hasattr(res, "stdout") else res.output
    assert "Day 2013-05-27 (15 captures)" in out and "Day 2013-09-24 (5 captures)" in out
    rows = [ln for ln in out.splitlines() if ln.startswith("| 2013-")]
    assert len(rows) == 15 + 5
    assert sum("| 2013-09-24 | 13:40:00 | perez1993 |" in ln for ln in rows) == 1


def test_second_day_clock_is_the_labels():
    """2013-09-24, 13:20: hillaire2020's luminance shape follows the scan better with the sun
    at the label time than 40 minutes earlier (the shift 2013-05-27 was given), at the
    labelled directions and along the scanner's moves alike. Measured (docs): shape RMS of
    ln(model / measured) 0.169 (point) / 0.147 (moves) near the label time."""
    from skydome.validation.compare import clock_scan

    r = clock_scan("2013-09-24", ["13:20:00"], offsets_min=[-40.0, 0.0])
    rms = r["rms"][0]
    assert rms[0, 1] < 0.8 * rms[0, 0] and rms[1, 1] < 0.8 * rms[1, 0]
    assert rms[0, 1] < 0.20 and rms[1, 1] < 0.18


@pytest.mark.slow
def test_second_day_fitted_aerosol():
    """2013-09-24, 13:20, aerosol fitted to the scan (no AERONET that day): a clean sky
    (tau440 0.042, alpha 1.74 when measured) and hillaire2020 within the bounds measured
    against the scan: level within 10 %, luminance RMS >= 10 deg from the sun under 16 %,
    band medians 400-700 nm within 15 %."""
    c = kider2014.load_captures("13:20:00", day="2013-09-24")[0]
    r = compare.compare_one("hillaire2020", c, aerosol="fitted")
    assert "fitted" in r.aerosol
    from skydome.validation.fitting import fit_aerosol

    fit = fit_aerosol(c)
    assert 0.03 < fit.tau440 < 0.06 and 1.4 < fit.alpha < 2.1
    assert abs(r.luminance_level) < 0.10 and r.luminance_rms_outside < 0.16
    assert all(abs(v) < 0.15 for v in r.band_medians.values())


@pytest.mark.slow
def test_first_day_fitted_aerosol():
    """2013-05-27, 12:45, aerosol fitted to the scan: measured (docs, -23 min clock) tau440
    0.110, alpha 1.63 against AERONET's 0.128 / 0.86 (the steeper spectral dependence the
    scans ask for), hillaire2020 level -0.8 %, luminance RMS >= 10 deg 8.4 %, band medians
    +2.9 to +9.1 %: bounds around those, and flatter in wavelength than with the AERONET
    aerosol (+9.3 % at 400 nm, +40.1 % at 700 nm)."""
    c = kider2014.load_captures("12:45:00")[0]
    from skydome.validation.fitting import fit_aerosol

    fit = fit_aerosol(c)
    assert 0.09 < fit.tau440 < 0.14 and 1.4 < fit.alpha < 2.1
    r = compare.compare_one("hillaire2020", c, aerosol="fitted")
    assert abs(r.luminance_level) < 0.06 and r.luminance_rms_outside < 0.12
    b = r.band_medians
    assert all(abs(v) < 0.12 for v in b.values())
    a = compare.compare_one("hillaire2020", c, aerosol="aeronet").band_medians
    assert abs(b[700.0] - b[400.0]) < 0.5 * abs(a[700.0] - a[400.0])


@pytest.mark.slow
def test_fitted_phase_removes_the_near_sun_deficit_only():
    """2013-05-27 12:00 (-23 min clock): with the measured (AERONET) phase table and the
    aerosol fitted, hillaire2020 is 14.8 % too dark 10-20 deg from the sun and 6.0 % too
    bright 80-100 deg away (median shape error; the reference is the measured scan). A
    Henyey-Greenstein g fitted with the aerosol (fitting.fit_aerosol_phase; measured
    0.640, above AERONET's 0.594) removes the first (+0.6 %) and leaves the second (+6.2 %)."""
    import skydome as sd
    from skydome.spectra import spectrum_to_xyz
    from skydome.validation.aeronet import aerosol_atmosphere
    from skydome.validation.fitting import fit_aerosol, fit_aerosol_phase

    c = kider2014.load_captures("12:00:00")[0]
    wl = compare.LUMINANCE_WL
    prof = {}
    r1, g = fit_aerosol_phase(c)
    assert 0.60 < g < 0.70
    for name, atm in (("table", aerosol_atmosphere(fit_aerosol(c))),
                      ("hg", aerosol_atmosphere(r1, phase="henyey_greenstein", asymmetry=g))):
        L = spectrum_to_xyz(sd.model("hillaire2020", sun=c.sun, atmosphere=atm)
                            .radiance(c.directions, wl), wl)[:, 1]
        prof[name] = compare.angle_profile([(c, L)])[1]
    assert prof["table"][0] < -0.10 and abs(prof["hg"][0]) < 0.04
    assert prof["table"][4] > 0.03 and prof["hg"][4] > 0.03


def test_published_rows_are_what_the_command_prints():
    """docs/validation_measured.md publishes the command's output verbatim: the rows it prints
    for one capture (2013-05-27 12:00, AERONET aerosol, no fit; montecarlo and the fitted
    model included, whose rows drifted once when the fitted model was refitted) must stand
    in the page character for character, so the page cannot drift from the code. The reference of every
    figure in them is the measured scan."""
    from pathlib import Path

    from typer.testing import CliRunner

    from skydome.cli import app

    doc = (Path(__file__).resolve().parents[1] / "docs" / "validation_measured.md").read_text()
    res = CliRunner().invoke(app, ["validate", "measured", "--day", "2013-05-27", "--aerosol",
                                   "aeronet", "--captures", "12:00:00", "--models",
                                   "hillaire2020,single_scattering,hosek_wilkie2012,perez1993,"
                                   "fitted,montecarlo"])
    assert res.exit_code == 0, res.output
    out = res.stdout if hasattr(res, "stdout") else res.output
    rows = [ln for ln in out.splitlines() if ln.startswith("| 2013-05-27 | 12:00:00 |")]
    assert len(rows) == 6
    missing = [ln for ln in rows if ln not in doc.splitlines()]
    assert not missing, "rows printed by the command but not published:\n" + "\n".join(missing)


def test_ring_offsets_recover_a_ring_response(caps):
    """ring_offsets on a constructed 'model': the measured luminance times an error that
    depends on the angle from the sun only (constant in each 10 deg bin, as a phase function
    error would be) and a known response per ring (+10 % at 33.7 deg, -5 % at 71.9 deg).
    The angle-only part must cancel and the ring factors come back."""
    factors = {12.1: 1.0, 33.7: 1.10, 53.4: 1.0, 71.9: 0.95, 90.0: 1.0}
    pairs = []
    for c in caps:
        lum, _ = compare.measured_luminance(c)
        ring = np.array([min(factors, key=lambda r: abs(r - e)) for e in c.elevation_deg])
        f = np.array([factors[r] for r in ring])
        angle_part = np.exp(0.3 * np.cos(np.radians(10.0 * np.floor(c.sun_angle_deg / 10.0))))
        pairs.append((c, lum * f * angle_part))
    r = compare.ring_offsets(pairs)
    off = dict(zip(r["rings_deg"], r["offset"]))
    # relative to the 12.1 deg ring (the offsets are relative to each bin's mean)
    assert abs((1 + off[33.7]) / (1 + off[12.1]) - 1.10) < 0.01
    assert abs((1 + off[71.9]) / (1 + off[12.1]) - 0.95) < 0.01
    assert abs((1 + off[53.4]) / (1 + off[12.1]) - 1.0) < 0.01


def test_fitted_model_in_the_comparison(caps):
    """skydome's fitted model in the measured-sky comparison takes the aerosol optical depth
    at 550 nm of the capture's aerosol (AERONET here: tau440 (550 / 440)^-alpha) and the
    inversion's surface albedo at 550 nm. Against the scans (the reference) it was measured
    at level +7.8 / -0.2 % and shape RMS 31.2 / 28.6 % (11:00 / 12:45): bounds around
    those, loose enough for a refit of its coefficients (its error here is its aerosol's,
    docs/validation_measured.md)."""
    from skydome.validation.fitting import base_retrieval

    for c in caps:
        r = compare.compare_one("fitted", c, aerosol="aeronet")
        ret = base_retrieval(c)
        aod = ret.tau440 * (550.0 / 440.0) ** (-ret.alpha)
        assert f"AOD550 {aod:.3f}" in r.phase and "aeronet" in r.aerosol
        assert abs(r.luminance_level) < 0.2
        assert 0.15 < r.luminance_shape["all"]["rms"] < 0.45
        assert np.isfinite(r.xy_rms) and len(r.band_medians) == len(compare.BANDS_NM)
