"""Aureole and Bishop's ring with the true Mie phase (skydome.effects.aureole)."""

import numpy as np
import pytest

from skydome.atmosphere import Atmosphere
from skydome.apps.aureole import render_closeup
from skydome.effects import aureole as A


def test_factorised_single_scattering_equals_kernel_with_analytic_phases():
    """Per-constituent integrals x phase (this module) reproduce the reference integrator
    (skydome.transport.single, phases inside the kernel) for an analytic atmosphere."""
    from skydome.spectra import solar_irradiance
    from skydome.sun import Sun
    from skydome.transport.single import SingleScattering

    atm = Atmosphere.earth(turbidity=3.0)
    wl = np.array([450.0, 650.0])
    sun = Sun(elevation_deg=30.0, azimuth_deg=180.0)
    dirs = A.almucantar_directions(30.0, [2.0, 10.0, 60.0])
    ours = A.single_scattering_true_phase(atm, dirs, sun, wl, view_samples=32)
    ref = SingleScattering(atm, wl, view_samples=32, light_samples=64, table_size=(128, 256),
                           quadrature_scale_m=5000.0).radiance(dirs, sun.direction, solar_irradiance(wl))
    np.testing.assert_allclose(ours, ref, rtol=1e-9)


def test_aureole_rises_with_aerosol_load():
    """Survey 5.4: the aureole is aerosol forward scattering: radiance 3 deg from the sun
    grows with the aerosol optical depth (and dominates the Rayleigh sky there)."""
    atms = [Atmosphere.volcanic_ash(t, background_turbidity=1.5) for t in (0.05, 0.2, 0.5)]
    L = A.radiance_profile(atms, 40.0, [3.0, 30.0], [550.0], view_samples=32)
    assert L[0, 0, 0] < L[1, 0, 0] < L[2, 0, 0]
    # forward peak: 3 deg is brighter than 30 deg
    assert np.all(L[:, 0, 0] > L[:, 1, 0])


def test_larger_particles_narrow_the_aureole():
    """Diffraction: the forward peak narrows as 1/x; the ratio L(3 deg)/L(15 deg) is larger
    for 1 um than for 0.3 um particles (same optical depth)."""
    small = Atmosphere.volcanic_ash(0.3, median_radius_um=0.3, geometric_std=1.3)
    big = Atmosphere.volcanic_ash(0.3, median_radius_um=1.0, geometric_std=1.3)
    L = A.radiance_profile([small, big], 40.0, [3.0, 15.0], [550.0], view_samples=32)
    assert L[1, 0, 0] / L[1, 1, 0] > L[0, 0, 0] / L[0, 1, 0]


def test_view_quadrature_converged_for_stratospheric_layer():
    atm = A.bishops_ring_atmosphere()
    dirs = A.almucantar_directions(30.0, [5.0, 12.0])
    a = A.single_scattering_true_phase(atm, dirs, 30.0, [550.0], view_samples=64)
    b = A.single_scattering_true_phase(atm, dirs, 30.0, [550.0], view_samples=256)
    np.testing.assert_allclose(a, b, rtol=0.01)


def test_bishops_ring_reddish_border_at_mie_radius():
    """Survey 5.5 / Minnaert (1993): narrow ~1 um stratospheric particles give a
    bluish-white disc with a reddish border, ~10-20 deg from the sun (Krakatoa 1883). The
    border lies inside the first diffraction minimum of blue light (Airy: 15.9 deg at
    450 nm for r = 1 um, Bohren & Huffman 4.4.3) and beyond the bluish-white disc."""
    r = A.ring_analysis(A.bishops_ring_atmosphere(), 30.0, np.arange(1.0, 30.01, 1.0),
                        np.linspace(400.0, 700.0, 7), view_samples=48)
    assert 8.0 <= r["red_border_deg"] <= 20.0
    assert r["red_blue"].max() > 1.2                       # clearly reddish border
    assert r["bluish_disc_deg"] < r["red_border_deg"] < r["red_border_outer_deg"]
    assert r["red_border_deg"] < A.diffraction_ring_radius_deg(1.0, 450.0) + 2.0
    # inside the ring the sky is bluer than the sun
    assert r["red_blue"][r["angles_deg"] <= 4.0].max() < 1.0


def test_closeup_image_no_nan_and_sun_brightest():
    img = render_closeup(A.bishops_ring_atmosphere(), 30.0, np.linspace(400, 700, 4),
                         fov_deg=20.0, size=15, view_samples=16)
    assert np.all(np.isfinite(img.data)) and np.all(img.data >= 0)
    Y = img.luminance()
    assert Y[7, 7] == Y.max()


def test_errors():
    with pytest.raises(ValueError, match="angles_deg"):
        A.almucantar_directions(60.0, [70.0])
    with pytest.raises(ValueError, match="constituents"):
        A.single_scattering_true_phase(Atmosphere.earth(), [[0, 0, 1]], 30.0, [550.0],
                                       constituents=["dust"])


def test_cli_aureole_blue_sun(tmp_path):
    """`skydome aureole --aerosol volcanic_ash`: the transmitted sun is blue (T(450) >
    T(650)), the clear sky's is not; files written; bad aerosol name -> exit 2."""
    from typer.testing import CliRunner

    from skydome.cli import app

    out = tmp_path / "ash"
    res = CliRunner().invoke(app, ["aureole", "--aerosol", "volcanic_ash", "--size", "24", "--out", str(out)])
    assert res.exit_code == 0, res.output
    lines = (out / "sun.txt").read_text().splitlines()
    assert "(blue sun)" in lines[1] and "(blue sun)" not in lines[0]
    assert (out / "profile.png").exists() and (out / "closeup.png").exists()
    res = CliRunner().invoke(app, ["aureole", "--aerosol", "dust", "--out", str(tmp_path / "x")])
    assert res.exit_code == 2 and "aerosol = 'dust'" in res.output
    assert not (tmp_path / "x").exists()
