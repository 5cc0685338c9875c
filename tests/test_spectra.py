"""Tests of skydome.spectra.

Oracles: colour-science (colorimetry: sd_to_XYZ, XYZ_to_xy, XYZ_to_sRGB / XYZ_to_RGB,
cctf_encoding, sd_CIE_illuminant_D_series, planck_law, its CIE tables), pvlib (ASTM G173-03
table), published numbers (CIE 018:2019 data-set column sums, CIE 15 table entries,
IEC 61966-2-1 matrix, CODATA Wien and Stefan-Boltzmann constants), and fine-grid numerical
integrals written here independently of the module.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from skydome import spectra as sp

colour = pytest.importorskip("colour")

OBSERVER = "CIE 1931 2 Degree Standard Observer"


def _trapezoid(y, x, axis=-1):
    return np.trapezoid(y, x, axis=axis) if hasattr(np, "trapezoid") else np.trapz(y, x, axis=axis)


def _colour_xyz_integration(values, start, stop, step):
    """colour-science's 'Integration' tristimulus values of an emissive spectrum, absolute.

    With k given, colour divides the result by 100 ('percentages'); multiply back.
    """
    shape = colour.SpectralShape(start, stop, step)
    cmfs = colour.MSDS_CMFS[OBSERVER].copy().align(shape)
    sd = colour.SpectralDistribution(values, shape.wavelengths)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        xyz = colour.sd_to_XYZ(sd, cmfs=cmfs, illuminant=colour.sd_ones(shape), k=683,
                               method="Integration")
    return 100.0 * np.asarray(xyz)


def _test_spectra(w):
    """D65 (colour's table, linearly interpolated), a 3000 K blackbody (colour's Planck
    law), the AM0 solar spectrum (pvlib's G173 table, linearly interpolated)."""
    import pvlib

    d65 = colour.SDS_ILLUMINANTS["D65"]
    d65_w = np.interp(w, d65.wavelengths, d65.values)
    bb = colour.colorimetry.planck_law(w * 1e-9, 3000.0) * 1e-9
    g173 = pvlib.spectrum.get_reference_spectra()
    solar = np.interp(w, g173.index.values, g173["extraterrestrial"].values)
    return {"D65": d65_w, "blackbody_3000K": bb, "solar_AM0": solar}


# ----------------------------------------------------------------------------- grids

def test_default_wavelengths_is_380_780_at_10nm():
    w = sp.default_wavelengths()
    assert w.shape == (41,)
    assert w[0] == 380.0 and w[-1] == 780.0
    np.testing.assert_allclose(np.diff(w), 10.0, rtol=0, atol=1e-12)


def test_wavelength_grid_variants():
    np.testing.assert_allclose(sp.wavelength_grid(400, 700, n=4), [400, 500, 600, 700])
    np.testing.assert_allclose(sp.wavelength_grid(400, 410, step_nm=2.5),
                               [400, 402.5, 405, 407.5, 410])
    assert sp.wavelength_grid(550, 550, n=1).tolist() == [550.0]
    assert sp.wavelength_grid(360, 830, step_nm=1).size == 471


@pytest.mark.parametrize("kwargs", [
    dict(start_nm=700, stop_nm=400),           # reversed
    dict(start_nm=100),                         # below 200 nm
    dict(stop_nm=5000),                         # above 4000 nm
    dict(n=5, step_nm=10),                      # both
    dict(n=1),                                  # one sample over a span
    dict(n=0),
    dict(step_nm=0),
    dict(step_nm=7),                            # 400 nm is not a multiple of 7 nm
    dict(start_nm=float("nan")),
])
def test_wavelength_grid_rejects_bad_arguments(kwargs):
    with pytest.raises(ValueError):
        sp.wavelength_grid(**kwargs)


def test_wavelength_grid_rejects_wrong_types():
    with pytest.raises(TypeError):
        sp.wavelength_grid(n=4.0)
    with pytest.raises(TypeError):
        sp.wavelength_grid(start_nm="380")


# ----------------------------------------------------------------------------- data tables

def test_cmf_table_matches_published_column_sums():
    # Column sums of the CIE 1931 2-degree 1 nm table (360-830 nm) published with the CIE
    # data set CIE_xyz_1931_2deg (CIE 018:2019): 106.865469489595, 106.856917101172,
    # 106.892251278636. Any mistyped row would change them.
    w = sp.wavelength_grid(360, 830, step_nm=1)
    sums = sp.cmf_1931(w).sum(axis=0)
    np.testing.assert_allclose(sums, [106.865469489595, 106.856917101172, 106.892251278636],
                               rtol=0, atol=1e-9)


def test_cmf_known_entries_cie15():
    # CIE 15:2004 Table T.4: y-bar(555) = 1.0000, y-bar(560) = 0.995000,
    # (450 nm) 0.336200 0.038000 1.772110, (600 nm) 1.062200 0.631000 0.000800.
    c = sp.cmf_1931([450.0, 555.0, 560.0, 600.0])
    np.testing.assert_allclose(c[1, 1], 1.0, atol=1e-6)
    np.testing.assert_allclose(c[2, 1], 0.995, atol=1e-9)
    np.testing.assert_allclose(c[0], [0.3362, 0.038, 1.77211], atol=1e-9)
    np.testing.assert_allclose(c[3], [1.0622, 0.631, 0.0008], atol=1e-9)


def test_cmf_equals_colour_table_and_is_zero_outside():
    ref = colour.MSDS_CMFS[OBSERVER]
    np.testing.assert_allclose(sp.cmf_1931(ref.wavelengths), ref.values, rtol=0, atol=1e-15)
    # linear interpolation between the 1 nm nodes
    np.testing.assert_allclose(sp.cmf_1931([555.5])[0], 0.5 * (ref.values[195] + ref.values[196]))
    assert np.all(sp.cmf_1931([300.0, 359.0, 831.0, 1000.0]) == 0.0)


def test_daylight_basis_known_entries_and_colour_table():
    from colour.colorimetry.datasets.illuminants.sds_d_illuminant_series import (
        DATA_BASIS_FUNCTIONS_CIE_ILLUMINANT_D_SERIES as data)

    # CIE 15:2004 Table T.2: S0(560) = 100, S1(560) = S2(560) = 0.
    np.testing.assert_allclose(sp.daylight_basis([560.0])[0], [100.0, 0.0, 0.0])
    w = np.array(sorted(data["S0"]), dtype=float)
    ref = np.stack([[data[k][x] for x in sorted(data[k])] for k in ("S0", "S1", "S2")], -1)
    np.testing.assert_array_equal(sp.daylight_basis(w), ref)
    assert w[0] == 300.0 and w[-1] == 830.0


def test_solar_table_matches_pvlib_g173():
    import pvlib

    from skydome.data import load_table

    g173 = pvlib.spectrum.get_reference_spectra()
    _, table = load_table("astm_g173_extraterrestrial")
    np.testing.assert_array_equal(table[:, 0], g173.index.values)
    np.testing.assert_array_equal(table[:, 1], g173["extraterrestrial"].values)
    # integral over the file's range, 280-4000 nm: 1347.9 W/m^2 (the full Gueymard 2004
    # spectrum integrates to 1366.1 W/m^2 including > 4000 nm)
    total = _trapezoid(g173["extraterrestrial"].values, g173.index.values)
    assert abs(total - 1347.9) < 0.05
    # exact box averages over bins that tile 280-4000 nm reproduce the table's integral
    w = sp.wavelength_grid(280, 4000, step_nm=10)
    lo = np.clip(w - 5, 280, 4000)
    hi = np.clip(w + 5, 280, 4000)
    np.testing.assert_allclose(np.sum(sp.solar_irradiance(w) * (hi - lo)), total, rtol=1e-12)


def test_solar_box_average_vs_fine_numerical_integral():
    import pvlib

    g173 = pvlib.spectrum.get_reference_spectra()
    wt, e = g173.index.values, g173["extraterrestrial"].values

    def box_mean(a, b):
        x = np.linspace(a, b, 200001)
        return _trapezoid(np.interp(x, wt, e), x) / (b - a)

    w = np.array([400.0, 430.0, 550.0, 589.0, 700.0])
    got = sp.solar_irradiance(w, bandwidth_nm=10.0)
    ref = [box_mean(x - 5, x + 5) for x in w]
    np.testing.assert_allclose(got, ref, rtol=1e-7)
    # default bins on an irregular grid: half way to each neighbour, symmetric ends
    w = np.array([400.0, 410.0, 430.0])
    ref = [box_mean(395, 405), box_mean(405, 420), box_mean(420, 440)]
    np.testing.assert_allclose(sp.solar_irradiance(w), ref, rtol=1e-7)
    # one wavelength: a 1 nm box
    np.testing.assert_allclose(sp.solar_irradiance(550.0), [box_mean(549.5, 550.5)], rtol=1e-7)
    # a vanishing box is pvlib's own linear interpolation
    w = np.array([300.25, 500.0, 777.7])
    ref = pvlib.spectrum.get_reference_spectra(w)["extraterrestrial"].values
    np.testing.assert_allclose(sp.solar_irradiance(w, bandwidth_nm=1e-6), ref, rtol=1e-6)


def test_solar_box_smooths_fraunhofer_lines():
    # The Ca II K line at 393.4 nm: the table dips far below its 10 nm neighbourhood mean.
    narrow = sp.solar_irradiance([393.5], bandwidth_nm=0.5)[0]
    wide = sp.solar_irradiance([393.5], bandwidth_nm=10.0)[0]
    assert narrow < 0.6 * wide


# ----------------------------------------------------------------------------- spectrum -> XYZ

def test_equal_energy_spectrum_is_at_one_third():
    # Not exactly 1/3: the CMF table's column sums differ slightly (106.8655, 106.8569,
    # 106.8923, CIE 018:2019), so x = 0.333315, y = 0.333288 for an equal-energy spectrum.
    w = sp.wavelength_grid(360, 830, step_nm=1)
    for method in ("linear", "sum"):
        xy = sp.xyz_to_xy(sp.spectrum_to_xyz(np.ones(w.size), w, method=method))
        np.testing.assert_allclose(xy, [1 / 3, 1 / 3], atol=1e-4)
    # and equal to colour-science's chromaticity of its equal-energy illuminant E
    ref = colour.XYZ_to_xy(_colour_xyz_integration(np.ones(w.size), 360, 830, 1))
    np.testing.assert_allclose(sp.xyz_to_xy(sp.spectrum_to_xyz(np.ones(w.size), w, "sum")),
                               ref, atol=1e-12)


@pytest.mark.parametrize("start,stop,step", [(360, 830, 1), (360, 830, 5), (380, 780, 5),
                                             (380, 780, 10)])
def test_sum_method_matches_colour_integration(start, stop, step):
    w = sp.wavelength_grid(start, stop, step_nm=step)
    for name, L in _test_spectra(w).items():
        ref = _colour_xyz_integration(L, start, stop, step)
        got = sp.spectrum_to_xyz(L, w, method="sum")
        np.testing.assert_allclose(got, ref, rtol=1e-6, err_msg=name)
        np.testing.assert_allclose(sp.luminance_from_spectrum(L, w, method="sum"), ref[1],
                                   rtol=1e-6, err_msg=name)


@pytest.mark.parametrize("w", [
    np.arange(380.0, 781.0, 10.0),
    np.arange(360.0, 831.0, 5.0),
    np.array([380.0, 405.0, 433.3, 470.0, 520.0, 555.5, 601.0, 650.0, 700.0, 780.0]),
    np.arange(300.0, 1001.0, 20.0),
])
def test_linear_method_matches_fine_grid_integral(w):
    # "linear": the spectrum is the polyline through its samples, 0 outside the grid.
    # Reference: trapezoid rule on a 0.005 nm grid of interp(L) * interp(cmf) (cmf from
    # colour-science's table), written independently of the module.
    cmf = colour.MSDS_CMFS[OBSERVER]
    fine = np.linspace(w[0], w[-1], int(round((w[-1] - w[0]) / 0.005)) + 1)
    cmf_fine = np.stack([np.interp(fine, cmf.wavelengths, cmf.values[:, k], left=0, right=0)
                         for k in range(3)], -1)
    for name, L in _test_spectra(w).items():
        ref = 683.0 * _trapezoid(np.interp(fine, w, L)[:, None] * cmf_fine, fine, axis=0)
        np.testing.assert_allclose(sp.spectrum_to_xyz(L, w), ref, rtol=1e-6, err_msg=name)


def test_integration_weights_single_wavelength_and_cache():
    np.testing.assert_allclose(sp.integration_weights([555.0]), sp.cmf_1931([555.0]) * 1.0)
    np.testing.assert_allclose(sp.integration_weights([555.0], "sum"), sp.cmf_1931([555.0]))
    a = sp.integration_weights(sp.default_wavelengths())
    b = sp.integration_weights(list(sp.default_wavelengths()))
    assert a is b and not a.flags.writeable
    # grids wholly outside the CMF range weigh nothing
    assert np.all(sp.integration_weights([900.0, 1000.0]) == 0.0)


def test_spectrum_to_xyz_broadcasts():
    w = sp.default_wavelengths()
    rng = np.random.default_rng(0)
    L = rng.uniform(0, 1, (2, 3, w.size))
    xyz = sp.spectrum_to_xyz(L, w)
    assert xyz.shape == (2, 3, 3)
    np.testing.assert_allclose(xyz[1, 2], sp.spectrum_to_xyz(L[1, 2], w), rtol=1e-14)
    assert sp.luminance_from_spectrum(L, w).shape == (2, 3)
    np.testing.assert_allclose(sp.luminance_from_spectrum(L, w), xyz[..., 1], rtol=1e-14)


def test_interpolation_matrix_is_numpy_interp_with_held_ends():
    # oracle: numpy.interp (linear, end values held) applied to the values themselves
    rng = np.random.default_rng(5)
    src = np.array([300.0, 320.0, 330.0, 360.0, 500.0, 1100.0])
    dst = np.array([250.0, 300.0, 305.0, 330.0, 331.5, 777.0, 1100.0, 1200.0])
    v = rng.uniform(0.0, 2.0, (4, src.size))
    W = sp.interpolation_matrix(src, dst)
    assert W.shape == (src.size, dst.size)
    want = np.stack([np.interp(dst, src, row) for row in v])
    np.testing.assert_allclose(v @ W, want, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(W.sum(axis=0), 1.0, rtol=1e-15)
    assert np.count_nonzero(W, axis=0).max() <= 2 and W.min() >= 0.0
    # one source wavelength: its value everywhere
    np.testing.assert_array_equal(sp.interpolation_matrix([550.0], dst), np.ones((1, dst.size)))


def test_solar_xyz_matrix_is_the_integrated_interpolated_spectrum():
    # oracle: the spectrum built step by step (numpy.interp to the default wavelengths, the
    # G173 irradiance there) and integrated by spectrum_to_xyz
    rng = np.random.default_rng(6)
    tw = np.arange(300.0, 1100.0 + 1e-9, 20.0)
    S = rng.uniform(0.0, 0.1, (3, tw.size))
    wl = sp.default_wavelengths()
    spec = np.stack([np.interp(wl, tw, row) for row in S]) * sp.solar_irradiance(wl)
    want = sp.spectrum_to_xyz(spec, wl)
    np.testing.assert_allclose(S @ sp.solar_xyz_matrix(tw), want, rtol=1e-13)
    np.testing.assert_allclose(S @ sp.solar_xyz_matrix(tw, irradiance_scale=1.034),
                               1.034 * want, rtol=1e-13)
    # another wavelength grid, and another interpolation given as its matrix
    wl2 = np.arange(400.0, 700.0 + 1e-9, 5.0)
    spec2 = np.stack([np.interp(wl2, tw, row) for row in S]) * sp.solar_irradiance(wl2)
    np.testing.assert_allclose(S @ sp.solar_xyz_matrix(tw, wl2), sp.spectrum_to_xyz(spec2, wl2),
                               rtol=1e-13)
    nearest = np.zeros((tw.size, wl.size))
    nearest[np.abs(tw[:, None] - wl[None, :]).argmin(axis=0), np.arange(wl.size)] = 1.0
    spec3 = S[:, np.abs(tw[:, None] - wl[None, :]).argmin(axis=0)] * sp.solar_irradiance(wl)
    np.testing.assert_allclose(S @ sp.solar_xyz_matrix(tw, interpolation=nearest),
                               sp.spectrum_to_xyz(spec3, wl), rtol=1e-13)


# ----------------------------------------------------------------------------- colour spaces

def _random_xyz(n=200, seed=3):
    return np.random.default_rng(seed).uniform(0.0, 1.0, (n, 3))


def test_xyz_to_xy_matches_colour():
    X = _random_xyz()
    np.testing.assert_allclose(sp.xyz_to_xy(X), colour.XYZ_to_xy(X), atol=1e-12)
    xy = sp.xyz_to_xy(X)
    np.testing.assert_allclose(sp.xy_to_xyz(xy, X[:, 1]), X, rtol=1e-12)
    np.testing.assert_allclose(sp.xy_to_xyz(xy[0]), colour.xy_to_XYZ(xy[0]), rtol=1e-12)
    # black -> D65 white, CIE 15:2004 Table T.3 (0.31271, 0.32902)
    np.testing.assert_allclose(sp.xyz_to_xy([[0.0, 0.0, 0.0]]), [[0.31271, 0.32902]])
    np.testing.assert_array_equal(sp.xy_to_xyz([0.3, 0.0], 0.0), [0.0, 0.0, 0.0])


def test_linear_srgb_matches_colour():
    X = _random_xyz()
    got = sp.xyz_to_linear_srgb(X)
    # colour-science with the matrix derived from the primaries (the same definition)
    srgb = colour.models.RGB_COLOURSPACE_sRGB
    derived = colour.RGB_Colourspace("sRGB (derived)", srgb.primaries, srgb.whitepoint,
                                     use_derived_matrix_RGB_to_XYZ=True,
                                     use_derived_matrix_XYZ_to_RGB=True)
    ref = colour.XYZ_to_RGB(X, derived, illuminant=srgb.whitepoint,
                            chromatic_adaptation_transform=None)
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12)
    # colour.XYZ_to_sRGB uses the 4-decimal XYZ->RGB matrix printed in IEC 61966-2-1,
    # which is the inverse of the *rounded* RGB->XYZ matrix: measured 3.2e-4 apart here.
    iec = colour.XYZ_to_sRGB(X, apply_cctf_encoding=False)
    assert np.abs(got - iec).max() < 5e-4
    # our RGB->XYZ matrix rounds to the printed IEC 61966-2-1 RGB->XYZ matrix
    M = sp.linear_srgb_to_xyz(np.eye(3)).T
    np.testing.assert_allclose(M, [[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722],
                                   [0.0193, 0.1192, 0.9505]], rtol=0, atol=5e-5)
    np.testing.assert_allclose(sp.linear_srgb_to_xyz(got), X, atol=1e-12)
    # RGB white is the D65 white with Y = 1
    white = sp.linear_srgb_to_xyz([1.0, 1.0, 1.0])
    np.testing.assert_allclose(sp.xyz_to_xy(white), [0.3127, 0.3290], atol=1e-12)
    np.testing.assert_allclose(white[1], 1.0, atol=1e-12)


def test_acescg_matches_colour_bradford():
    X = _random_xyz()
    d65 = colour.CCS_ILLUMINANTS[OBSERVER]["D65"]
    ref = colour.XYZ_to_RGB(X, "ACEScg", illuminant=d65, chromatic_adaptation_transform="Bradford")
    got = sp.xyz_to_acescg(X)
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-6)
    assert np.abs(got - ref).max() < 1e-12
    np.testing.assert_allclose(sp.acescg_to_xyz(got), X, atol=1e-12)
    # D65 white maps to ACEScg (1, 1, 1): Bradford carries it onto the ACES white
    np.testing.assert_allclose(sp.xyz_to_acescg(sp.xy_to_xyz([0.3127, 0.3290], 1.0)),
                               [1.0, 1.0, 1.0], atol=1e-12)


def test_srgb_transfer_function_matches_colour_and_round_trips():
    v = np.linspace(0.0, 1.0, 2001)
    np.testing.assert_allclose(sp.srgb_encode(v), colour.cctf_encoding(v, "sRGB"), atol=1e-12)
    np.testing.assert_allclose(sp.srgb_decode(v), colour.cctf_decoding(v, "sRGB"), atol=1e-12)
    np.testing.assert_allclose(sp.srgb_decode(sp.srgb_encode(v)), v, atol=1e-12)
    # IEC 61966-2-1: breakpoint 0.0031308 -> 0.04045 (to 1e-6); clipping to [0, 1]
    np.testing.assert_allclose(sp.srgb_encode(0.0031308), 0.04045, atol=1e-6)
    np.testing.assert_allclose(sp.srgb_encode([-1.0, 2.0]), [0.0, 1.0], atol=1e-15)
    np.testing.assert_allclose(sp.srgb_decode([-1.0, 2.0]), [0.0, 1.0], atol=1e-15)
    assert sp.srgb_encode(np.zeros((4, 5, 3))).shape == (4, 5, 3)


# ----------------------------------------------------------------------------- daylight spectra

@pytest.mark.parametrize("name,cct", [("D50", 5003.0), ("D65", 6504.0), ("D75", 7504.0)])
def test_daylight_reconstructs_cie_d_illuminants(name, cct):
    # xy from the CCT by CIE 15:2004 eq. 3.3 (colour.temperature.CCT_to_xy_CIE_D), then the
    # spectrum S0 + M1 S1 + M2 S2, normalised at 560 nm, vs the tabulated CIE illuminant
    # (colour-science's table; 300-780 nm at 5 nm). The CIE rounded M1 and M2 to 3 decimals
    # when tabulating; we do not, hence a small difference.
    xy = colour.temperature.CCT_to_xy_CIE_D(cct)
    table = colour.SDS_ILLUMINANTS[name]
    w = np.asarray(table.wavelengths, dtype=float)
    L = sp.spectrum_from_xyz_daylight(sp.xy_to_xyz(xy, 100.0), w)
    got = 100.0 * L / L[w == 560.0]
    assert np.abs(got - table.values).max() < 1e-3 * table.values.max()
    # and colour's own D-series construction for the same xy (which also rounds M1, M2)
    ref = colour.sd_CIE_illuminant_D_series(np.asarray(xy)).copy().align(
        colour.SpectralShape(w[0], w[-1], 5)).values
    assert np.abs(got - ref).max() < 1e-3 * ref.max()


def test_daylight_spectrum_luminance_and_chromaticity_round_trip():
    w = sp.wavelength_grid(360, 830, step_nm=1)
    xyz = sp.xy_to_xyz(colour.CCS_ILLUMINANTS[OBSERVER]["D65"], 250.0)
    L = sp.spectrum_from_xyz_daylight(xyz, w)
    assert np.all(L >= 0.0)
    # luminance is exact on the 1 nm grid it was normalised on
    np.testing.assert_allclose(sp.luminance_from_spectrum(L, w), 250.0, rtol=1e-12)
    # chromaticity round trip: the basis reproduces daylight xy to ~1e-4
    np.testing.assert_allclose(sp.xyz_to_xy(sp.spectrum_to_xyz(L, w)), [0.3127, 0.3290],
                               atol=1e-3)
    # on the default 10 nm grid the luminance is reproduced to its quadrature error
    d = sp.default_wavelengths()
    np.testing.assert_allclose(
        sp.luminance_from_spectrum(sp.spectrum_from_xyz_daylight(xyz, d), d), 250.0, rtol=1e-4)


def test_daylight_spectrum_broadcasts_and_handles_black():
    w = sp.default_wavelengths()
    xyz = np.array([[[95.047, 100.0, 108.883], [0.0, 0.0, 0.0]],
                    [[0.5, 0.5, 0.4], [30.0, 31.0, 40.0]]])
    L = sp.spectrum_from_xyz_daylight(xyz, w)
    assert L.shape == (2, 2, w.size)
    assert np.all(L[0, 1] == 0.0)
    assert np.all(L >= 0.0) and np.all(np.isfinite(L))
    np.testing.assert_allclose(L[1, 1], sp.spectrum_from_xyz_daylight(xyz[1, 1], w))
    # a reddish chromaticity far from the daylight locus: values are clamped at 0
    Lr = sp.spectrum_from_xyz_daylight(sp.xy_to_xyz([0.6, 0.35], 10.0), sp.wavelength_grid(
        300, 830, step_nm=5))
    assert np.all(Lr >= 0.0) and np.any(Lr == 0.0)


# ----------------------------------------------------------------------------- blackbody

def test_blackbody_matches_colour_planck_law():
    h, c, k = 6.62607015e-34, 299792458.0, 1.380649e-23
    w = sp.wavelength_grid(300, 2000, step_nm=5)
    T = np.array([1500.0, 3000.0, 5778.0, 20000.0])
    ref = np.stack([colour.colorimetry.planck_law(w * 1e-9, t, c1=2 * np.pi * h * c**2,
                                                  c2=h * c / k) for t in T]) * 1e-9
    got = sp.blackbody(w, T)
    assert got.shape == (4, w.size)
    np.testing.assert_allclose(got, ref, rtol=1e-12)


def test_blackbody_wien_and_stefan_boltzmann():
    # Wien displacement constant b = 2.897771955e-3 m K (CODATA 2018)
    T = 5000.0
    w = np.arange(500.0, 700.0, 0.001)
    peak = w[np.argmax(sp.blackbody(w, T))]
    assert abs(peak - 2.897771955e6 / T) < 0.002
    # Stefan-Boltzmann: pi * integral B dl = sigma T^4, sigma = 5.670374419e-8 W m^-2 K^-4
    w = np.geomspace(50.0, 1e6, 200001)
    M = np.pi * _trapezoid(sp.blackbody(w, T), w)
    np.testing.assert_allclose(M, 5.670374419e-8 * T**4, rtol=1e-5)
    # far Wien tail underflows to 0, not NaN
    assert sp.blackbody([1.0], 300.0)[0] == 0.0


# ----------------------------------------------------------------------------- invalid input

@pytest.mark.parametrize("func", [sp.cmf_1931, sp.daylight_basis, sp.solar_irradiance,
                                  sp.integration_weights])
@pytest.mark.parametrize("bad", [np.ones((2, 3)) * 500.0, [500.0, np.nan], [100.0, 500.0],
                                 [500.0, 5000.0], []])
def test_wavelength_validation(func, bad):
    with pytest.raises(ValueError):
        func(bad)


def test_invalid_inputs_raise():
    w = sp.default_wavelengths()
    with pytest.raises(ValueError, match="increasing"):
        sp.spectrum_to_xyz(np.ones(3), [500.0, 450.0, 600.0])
    with pytest.raises(ValueError, match="shape"):
        sp.spectrum_to_xyz(np.ones(40), w)
    with pytest.raises(ValueError, match="NaN"):
        sp.spectrum_to_xyz(np.full(41, np.nan), w)
    with pytest.raises(ValueError, match="method"):
        sp.spectrum_to_xyz(np.ones(41), w, method="simpson")
    with pytest.raises(ValueError, match="bandwidth_nm"):
        sp.solar_irradiance(w, bandwidth_nm=-1.0)
    with pytest.raises(ValueError, match="out of range"):
        sp.daylight_basis([250.0, 500.0])
    with pytest.raises(ValueError):
        sp.xyz_to_xy([1.0, 2.0])
    with pytest.raises(ValueError, match="NaN"):
        sp.xyz_to_linear_srgb([np.nan, 1.0, 1.0])
    with pytest.raises(ValueError, match="NaN"):
        sp.srgb_encode([np.nan])
    with pytest.raises(ValueError):
        sp.xy_to_xyz([0.3, 0.0], 1.0)
    with pytest.raises(ValueError, match="Y"):
        sp.spectrum_from_xyz_daylight([1.0, -1.0, 1.0], w)
    with pytest.raises(ValueError, match="daylight locus"):
        # M = 0.0241 + 0.2562 x - 0.7341 y = 0 at x = 0.3, y = 0.13753
        sp.spectrum_from_xyz_daylight(sp.xy_to_xyz([0.3, (0.0241 + 0.2562 * 0.3) / 0.7341]), w)
    with pytest.raises(ValueError, match="temperature_k"):
        sp.blackbody(w, 0.0)
    with pytest.raises(ValueError, match="temperature_k"):
        sp.blackbody(w, [5000.0, np.nan])
