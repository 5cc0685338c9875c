"""The geometry of the scanner-polarisation test (skydome.validation.scanner_polarisation).

References: single Rayleigh scattering polarises the light perpendicular to the scattering
plane, with the degree (1 - cos^2 theta) / (1 + cos^2 theta) for a non-depolarising
molecule and (1 - rho) sin^2 theta / (1 + rho + (1 - rho) cos^2 theta) with the
depolarisation factor rho (Chandrasekhar 1950, Radiative Transfer, sec. 18; Hansen &
Travis 1974, Space Sci. Rev. 16, eq. 2.15). The expected angles below are worked out by
hand from that rule for views whose scattering plane is known (the solar vertical plane,
the horizontal plane, the zenith).
"""

import numpy as np
import pytest

from skydome.validation import scanner_polarisation as sp


def _sun(azimuth_deg, elevation_deg):
    a, e = np.radians(azimuth_deg), np.radians(elevation_deg)
    return np.array([np.cos(e) * np.sin(a), np.cos(e) * np.cos(a), np.sin(e)])


def test_scan_frame_is_orthonormal_and_oriented():
    az = np.array([0.0, 90.0, 200.0, 0.0, 135.0])
    el = np.array([0.0, 30.0, 60.0, 90.0, 12.1])
    d, ev, eh = sp.scan_frame(az, el)
    for a, b in ((d, ev), (d, eh), (ev, eh)):
        assert np.allclose(np.sum(a * b, axis=-1), 0.0, atol=1e-12)
    for v in (d, ev, eh):
        assert np.allclose(np.linalg.norm(v, axis=-1), 1.0)
    # due north on the horizon: e_v is up, e_h (k x e_v, k = -d) is west
    assert np.allclose(ev[0], [0, 0, 1]) and np.allclose(eh[0], [-1, 0, 0])
    # the zenith seen by a head turned to azimuth 0: e_v points away from north (south),
    # e_h west
    assert np.allclose(ev[3], [0, -1, 0]) and np.allclose(eh[3], [-1, 0, 0])


@pytest.mark.parametrize("view", [(180.0, 70.0), (180.0, 12.1), (0.0, 40.0), (0.0, 89.0)])
def test_solar_vertical_plane_polarisation_is_horizontal(view):
    # sun at azimuth 180, elevation 30: every view in the solar vertical plane has that
    # plane as its scattering plane, so the E-vector is perpendicular to it: horizontal,
    # chi = 90 deg from the local vertical (cos 2 chi = -1)
    chi = sp.single_scattering_angle(np.array([view[0]]), np.array([view[1]]), _sun(180.0, 30.0))
    assert np.degrees(chi[0]) == pytest.approx(90.0, abs=1e-9)
    X, Y = sp.response_terms(np.array([0.5]), chi)
    assert X[0] == pytest.approx(-0.5, abs=1e-12) and Y[0] == pytest.approx(0.0, abs=1e-12)


def test_sun_at_zenith_polarises_every_view_horizontally():
    az = np.array([0.0, 37.0, 145.0, 300.0])
    el = np.array([5.0, 20.0, 45.0, 80.0])
    chi = sp.single_scattering_angle(az, el, np.array([0.0, 0.0, 1.0]))
    assert np.allclose(np.abs(np.degrees(chi)), 90.0, atol=1e-9)


def test_horizontal_scattering_plane_polarises_vertically():
    # sun on the horizon due east, view on the horizon due north: the scattering plane is
    # the horizontal plane (theta = 90 deg), the E-vector vertical, chi = 0
    chi = sp.single_scattering_angle(np.array([0.0]), np.array([0.0]), _sun(90.0, 0.0))
    assert np.degrees(chi[0]) == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("sun_az, expected", [(90.0, 0.0), (0.0, 90.0), (45.0, -45.0)])
def test_zenith_view_angle_follows_the_head_azimuth(sun_az, expected):
    # zenith view, head at azimuth 0 (e_v south, e_h west); sun on the horizon at sun_az:
    # the E-vector is along z x s. East sun: north-south, chi 0. North sun: east-west, chi
    # 90. North-east sun: along north-west / south-east, 45 deg from south towards east,
    # i.e. away from e_h: chi -45.
    chi = sp.single_scattering_angle(np.array([0.0]), np.array([90.0]), _sun(sun_az, 0.0))
    assert np.degrees(chi[0]) == pytest.approx(expected, abs=1e-9)


def test_degree_is_the_analytic_rayleigh_value():
    sun = _sun(180.0, 0.0)
    # 90 deg from the sun (the zenith), 60 deg (azimuth 180, elevation 60) and 120 deg
    az, el = np.array([0.0, 180.0, 0.0]), np.array([90.0, 60.0, 60.0])
    p0 = sp.single_scattering_degree(az, el, sun, depolarisation=0.0)
    # (1 - cos^2) / (1 + cos^2): 1 at 90 deg, 0.75 / 1.25 = 0.6 at 60 and 120 deg
    assert p0 == pytest.approx([1.0, 0.6, 0.6], abs=1e-12)
    p = sp.single_scattering_degree(az[:1], el[:1], sun, depolarisation=0.0279)
    assert p[0] == pytest.approx(0.9721 / 1.0279, abs=1e-12)   # (1 - rho) / (1 + rho)


def test_angle_agrees_with_the_effects_module_off_the_zenith():
    # an independent path: the E-vector angle of
    # skydome.effects.polarisation.rayleigh_single_scattering_stokes (local meridian frame)
    from skydome.effects.polarisation import rayleigh_single_scattering_stokes

    rng = np.random.default_rng(1)
    az, el = rng.uniform(0, 360, 50), rng.uniform(1, 85, 50)
    sun = _sun(123.0, 41.0)
    d, _, _ = sp.scan_frame(az, el)
    s = rayleigh_single_scattering_stokes(d, sun)
    psi = 0.5 * np.arctan2(s[:, 2], s[:, 1])
    chi = sp.single_scattering_angle(az, el, sun)
    assert np.allclose(np.cos(2 * psi), np.cos(2 * chi), atol=1e-9)
    assert np.allclose(np.sin(2 * psi), np.sin(2 * chi), atol=1e-9)


def test_fit_response_recovers_a_known_response():
    rng = np.random.default_rng(0)
    groups = []
    for c in (0.1, -0.05, 0.0):
        X, Y = rng.uniform(-0.6, 0.6, 70), rng.uniform(-0.6, 0.6, 70)
        groups.append((c + 0.04 * X - 0.02 * Y, X, Y))
    f = sp.fit_response(groups)
    assert (f.m, f.n) == (pytest.approx(0.04, abs=1e-12), pytest.approx(-0.02, abs=1e-12))
    assert f.const == pytest.approx([0.1, -0.05, 0.0], abs=1e-12)
    assert f.rms_after == pytest.approx(0.0, abs=1e-12) and f.rms_before > 0.01
    assert f.diattenuation == pytest.approx(np.hypot(0.04, 0.02))
    # most transmitted axis: 0.5 atan2(n, m)
    assert f.axis_deg == pytest.approx(0.5 * np.degrees(np.arctan2(-0.02, 0.04)))


def test_bad_input_names_the_parameter():
    with pytest.raises(ValueError, match="groups"):
        sp.fit_response([])
    with pytest.raises(ValueError, match="one length"):
        sp.fit_response([(np.zeros(3), np.zeros(2), np.zeros(3))])
    with pytest.raises(ValueError, match="elevation_deg"):
        sp.scan_frame(np.array([0.0]), np.array([95.0]))
