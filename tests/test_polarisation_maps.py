"""Sky Stokes parameters, polarisation maps and neutral points (survey 5.7).

References: Chandrasekhar 1950, Radiative Transfer, sec. 18, and Hansen & Travis 1974,
Space Sci. Rev. 16, eq. 2.15 (single Rayleigh scattering: E-vector perpendicular to the
scattering plane, degree (1 - rho) sin^2 / (1 + rho + (1 - rho) cos^2)); Coulson 1988,
Polarization and Intensity of Light in the Atmosphere, and Horvath et al. 2002, J. Opt. Soc.
Am. A 19, 1093 (maximum polarisation about 90 deg from the sun; Arago, Babinet and Brewster
neutral points about 15-25 deg from the antisolar point and the sun on the solar meridian,
absent from single-scattering theory).
"""

import numpy as np
import pytest

from skydome.atmosphere import Atmosphere
from skydome.effects.polarisation import (angle_of_polarisation, degree_of_polarisation, local_frame,
                                          neutral_points_from_sign, neutral_points_on_meridian,
                                          rayleigh_degree_of_polarisation)
from skydome.effects.polarisation_maps import (e_vectors, find_neutral_points, meridian_profile,
                                               polarisation_maps, sky_stokes)
from skydome.imaging.plots import plot_polarisation_maps
from skydome.imaging.projections import Fisheye
from skydome.models.simulated.montecarlo import stokes_frame
from skydome.sun import Sun
from skydome.transport.geometry import direction_from_angles

RHO = 0.0279   # Bates 1984, 550 nm


def _pure_rayleigh():
    """Pure Rayleigh atmosphere (sea-level 5.8e-6 m^-1 at 680 nm, lambda^-4), black ground."""
    return Atmosphere.custom(rayleigh_scattering=lambda wl: 5.8e-6 * (680.0 / np.asarray(wl)) ** 4,
                             ground_albedo=0.0, depolarisation=RHO)


def test_frames_of_analytic_and_monte_carlo_agree():
    """Both frames: first axis towards increasing elevation, second k x first (k = -d).
    At the zenith they pick opposite axes (north/south): a 180 deg rotation, Q and U equal."""
    rng = np.random.default_rng(1)
    d = rng.normal(size=(50, 3))
    d[:, 2] = np.abs(d[:, 2])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    d = np.vstack([d, [[0.0, 0.0, 1.0]]])
    v, h = local_frame(d)
    a, b = stokes_frame(d)
    np.testing.assert_allclose(v[:-1], a[:-1], atol=1e-12)
    np.testing.assert_allclose(h[:-1], b[:-1], atol=1e-12)
    np.testing.assert_allclose(v[-1], -a[-1], atol=1e-12)       # 180 deg apart at the zenith
    np.testing.assert_allclose(h[-1], -b[-1], atol=1e-12)
    np.testing.assert_allclose(np.cross(-d, v), h, atol=1e-12)
    # increasing elevation: v . z > 0 off the zenith
    assert np.all(v[:-1, 2] > 0)


def test_single_order_monte_carlo_reproduces_analytic_rayleigh():
    """Pure Rayleigh, first order only: the degree must equal the analytic single-scattering
    value (Hansen & Travis 1974 eq. 2.15, rho = 0.0279) within 3 standard errors and the
    angle within 1 deg, in the common frame, for views all round the sky."""
    atm = _pure_rayleigh()
    sun = Sun(30.0, 120.0)
    d = direction_from_angles(np.array([90.0, 60, 30, 10, 45, 20, 70]),
                              np.array([0.0, 0, 90, 180, 270, 300, 200]))
    mc = sky_stokes("montecarlo", sun, d, [450.0, 550.0], atmosphere=atm, samples=600, seed=5, max_order=1)
    cos_t = d @ sun.direction
    p_ref = rayleigh_degree_of_polarisation(cos_t, RHO)[:, None]
    s, e = mc.stokes, mc.stderr
    p = degree_of_polarisation(s)
    lin = np.hypot(s[..., 1], s[..., 2])
    # delta-method standard error of sqrt(Q^2 + U^2) / I (covariances neglected: the
    # errors of I, Q, U are positively correlated, so this overstates the error)
    se_lin = np.hypot(s[..., 1] * e[..., 1], s[..., 2] * e[..., 2]) / lin
    se_p = np.hypot(se_lin, p * e[..., 0]) / s[..., 0]
    assert np.all(np.abs(p - p_ref) < 3 * se_p + 1e-6)
    assert np.all(np.abs(p - p_ref) < 0.01)
    # angle: E-vector perpendicular to the scattering plane
    an = sky_stokes("rayleigh_single", sun, d, [450.0, 550.0], atmosphere=atm)
    diff = (angle_of_polarisation(s) - angle_of_polarisation(an.stokes) + 90.0) % 180.0 - 90.0
    assert np.all(np.abs(diff) < 1.0)
    np.testing.assert_allclose(degree_of_polarisation(an.stokes), np.broadcast_to(p_ref, (7, 2)), rtol=1e-12)


def test_analytic_e_vector_is_perpendicular_to_scattering_plane():
    """Chandrasekhar 1950: the singly scattered E-vector is perpendicular to the plane
    through the sun and the viewing direction, i.e. parallel to d x s."""
    sun = Sun(35.0, 250.0)
    rng = np.random.default_rng(3)
    d = rng.normal(size=(40, 3))
    d[:, 2] = np.abs(d[:, 2]) + 0.05
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    r = sky_stokes("rayleigh_single", sun, d, [550.0], intensity="unit")
    np.testing.assert_allclose(r.stokes[..., 0], 1.0)
    np.testing.assert_allclose(r.stderr, 0.0)
    e = e_vectors(d, r.stokes[:, 0])
    n = np.cross(d, sun.direction)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    np.testing.assert_allclose(np.abs(np.sum(e * n, axis=1)), 1.0, atol=1e-9)
    np.testing.assert_allclose(np.sum(e * d, axis=1), 0.0, atol=1e-12)


@pytest.fixture(scope="module")
def low_sun_profiles():
    """Solar meridian, sun at 5 deg, turbidity 2.5 (HG aerosols), 550 nm."""
    sun = Sun(5.0, 180.0)
    mc = meridian_profile("montecarlo", sun, step_deg=2.0, samples=2500, seed=11, turbidity=2.5)
    an = meridian_profile("rayleigh_single", sun, step_deg=2.0, turbidity=2.5)
    return mc, an


def test_maximum_polarisation_about_90_degrees_from_the_sun(low_sun_profiles):
    """Coulson 1988 / Horvath et al. 2002: the maximum lies ~90 deg from the sun; multiple
    scattering and aerosols lower it below the single-scattering (1 - rho)/(1 + rho)."""
    mc, an = low_sun_profiles
    i = int(np.argmax(mc.dop))
    assert abs(mc.scattering_deg[i] - 90.0) <= 10.0
    assert 0.3 < mc.dop[i] < an.dop.max() - 0.1
    assert an.dop.max() == pytest.approx((1 - RHO) / (1 + RHO), abs=2e-3)


def test_neutral_points_in_multiple_scattering_only(low_sun_profiles):
    """Babinet (above the sun) and Arago (above the antisolar point) exist within 25 deg
    of the sun / antisolar point with multiple scattering (Coulson 1988: ~15-25 deg);
    the single-scattering profile has no sign change and its degree exceeds 0.05 except
    near the sun and the antisolar point."""
    mc, an = low_sun_profiles
    sun_e = 5.0
    anti = 180.0 + sun_e
    found = find_neutral_points(mc)
    assert set(found) >= {"babinet", "arago"}
    assert 5.0 < found["babinet"] - sun_e <= 25.0
    assert 5.0 < anti - found["arago"] <= 25.0
    # the local-minimum finder (on the noisy, shallow |Q|/I between the sun and the
    # Babinet point) agrees to about 10 deg
    mins = find_neutral_points(mc, method="minimum")
    assert abs(mins["babinet"] - found["babinet"]) <= 12.0
    assert abs(mins["arago"] - found["arago"]) <= 12.0
    # the MC degree there is small while single scattering is strongly polarised
    for x in (found["babinet"], found["arago"]):
        assert np.interp(x, mc.angle_deg, mc.dop) < 0.05
        assert np.interp(x, an.angle_deg, an.dop) > 0.02
    assert find_neutral_points(an) == {}
    far = (an.scattering_deg > 20.0) & (an.scattering_deg < 160.0)
    assert np.all(an.dop[far] > 0.05)
    assert np.all(an.signed >= -1e-12) and np.all(an.signed[far] > 0.05)


def test_brewster_point_below_a_high_sun():
    """Sun at 40 deg: the Brewster point lies below the sun within 25 deg (Coulson 1988;
    Horvath et al. 2002), Babinet above it (both close in on the sun as it rises)."""
    sun = Sun(40.0, 90.0)
    mc = meridian_profile("montecarlo", sun, step_deg=2.0, samples=2500, seed=4, turbidity=2.5)
    found = find_neutral_points(mc)
    assert "brewster" in found and "babinet" in found
    assert 3.0 < 40.0 - found["brewster"] <= 25.0
    assert 3.0 < found["babinet"] - 40.0 <= 25.0


def test_neutral_point_from_sign_synthetic():
    """Zero crossings of a known profile: a parabola crossing zero at 31 and 161 deg,
    sampled every 2.5 deg (linear interpolation error < 0.1 deg)."""
    e = np.linspace(0.0, 180.0, 73)
    signed = (e - 31.0) * (161.0 - e) / 1e4
    found = neutral_points_from_sign(e, signed, sun_elevation_deg=10.0)
    assert found["babinet"] == pytest.approx(31.0, abs=0.1)
    assert found["arago"] == pytest.approx(161.0, abs=0.1)
    assert "brewster" not in found
    # the minimum finder on |signed| sees the same points to the grid step
    old = neutral_points_on_meridian(e, np.abs(signed), sun_elevation_deg=10.0)
    assert old["babinet"] == pytest.approx(31.0, abs=2.5) and old["arago"] == pytest.approx(161.0, abs=2.5)
    # a crossing within exclude_deg of the sun is ignored
    assert neutral_points_from_sign(e, signed, sun_elevation_deg=29.0) == {"arago": pytest.approx(161.0, abs=0.1)}


def test_maps_orientation_and_figure(tmp_path):
    """Fisheye north up, east left: with the sun in the east at 0+ elevation, the
    single-scattering band of maximum polarisation (90 deg from the sun) runs north-south
    through the zenith; the sun's side (left) is weakly polarised."""
    sun = Sun(2.0, 90.0)
    m = polarisation_maps("rayleigh_single", sun, *Fisheye(16).directions(), intensity="unit")
    assert m.dop.shape == (16, 16) and np.all(np.isnan(m.dop[~m.mask]))
    assert np.all((m.dop[m.mask] >= 0) & (m.dop[m.mask] <= 1))
    centre_col = m.dop[:, 7:9][m.mask[:, 7:9]]
    assert centre_col.min() > 0.85                       # 90 deg from the sun everywhere
    assert np.nanmean(m.dop[7:9, 0:3]) < 0.2             # east (left) edge: near the sun
    mc = polarisation_maps("montecarlo", Sun(20.0, 180.0), *Fisheye(8).directions(), samples=20,
                           seed=1)
    assert np.all(np.isfinite(mc.stokes)) and np.all(mc.stokes[..., 0][mc.mask] >= 0)
    out = tmp_path / "pol.png"
    plot_polarisation_maps(mc, out)
    assert out.stat().st_size > 1000 and not list(tmp_path.glob(".*tmp*"))


def test_validation():
    sun = Sun(20.0, 180.0)
    d = direction_from_angles(45.0, 0.0)
    with pytest.raises(ValueError, match="method"):
        sky_stokes("prague", sun, d, [550.0])
    with pytest.raises(ValueError, match="turbidity"):
        sky_stokes("rayleigh_single", sun, d, [550.0], atmosphere=_pure_rayleigh(), turbidity=3.0)
    with pytest.raises(ValueError, match="depolarisation"):
        sky_stokes("montecarlo", sun, d, [550.0], depolarisation=0.03)
    with pytest.raises(ValueError, match="turbidity"):
        sky_stokes("rayleigh_single", sun, d, [550.0], turbidity=0.5)
    with pytest.raises(TypeError):
        sky_stokes("rayleigh_single", "sun", d, [550.0])


def test_sun_below_horizon_and_ground_views_are_finite():
    sun = Sun(-3.0, 180.0)
    d = direction_from_angles(np.array([-10.0, 10.0, 80.0]), np.array([0.0, 180.0, 0.0]))
    for method, kw in (("rayleigh_single", {}), ("montecarlo", dict(samples=20))):
        r = sky_stokes(method, sun, d, [550.0], **kw)
        assert np.all(np.isfinite(r.stokes)) and np.all(r.stokes[..., 0] >= 0)


def test_cli_polarisation(tmp_path):
    from typer.testing import CliRunner

    from skydome.cli import app

    runner = CliRunner()
    out, csv = tmp_path / "p.png", tmp_path / "p.csv"
    res = runner.invoke(app, ["polarisation", "--method", "rayleigh_single", "--size", "12",
                              "--sun-elevation", "30", "--out", str(out), "--csv", str(csv)])
    assert res.exit_code == 0, res.output
    assert out.exists() and csv.exists()
    rows = np.loadtxt(csv, delimiter=",", skiprows=2)
    assert rows.shape[1] == 14 and np.all((rows[:, 12] >= 0) & (rows[:, 12] <= 1))
    bad = runner.invoke(app, ["polarisation", "--method", "nope", "--out", str(tmp_path / "q.png")])
    assert bad.exit_code == 2 and not (tmp_path / "q.png").exists()
    bad = runner.invoke(app, ["polarisation", "--size", "2", "--out", str(tmp_path / "q.png")])
    assert bad.exit_code == 2 and not (tmp_path / "q.png").exists()
