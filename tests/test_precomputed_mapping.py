"""precomputed's view-zenith (mu) table mapping (``_mapping.mu_unit``): the nodes at any planet
radius and altitude, and the sky of a thin atmosphere on a very large planet against the
independent Monte Carlo model."""

import math

import numpy as np
import pytest

import skydome as sd
from skydome.models.simulated.precomputed import _mapping

# (planet radius, top altitude) of the earth and of the plane-parallel limit the API accepts
RADII = [(6.36e6, 1e5), (1e8, 8e3)]


def _nodes(n, r, R, Rt):
    return [_mapping.cell_mu(i, n, r, R, Rt) for i in range(n)]


@pytest.mark.parametrize("R, top", RADII)
@pytest.mark.parametrize("alt_frac", [0.0, 0.3, 1.0])
def test_mu_nodes_split_at_the_horizon_and_invert(R, top, alt_frac):
    """At the ground, inside the atmosphere and at its top: the ground half runs from the
    horizon (mu_h = -sqrt(1 - (R/r)^2), the tangent to the sphere) to the nadir, the sky half
    from the zenith to the horizon, both strictly monotone; mu_index inverts cell_mu."""
    n = 128
    Rt = R + top
    r = R + alt_frac * top
    mu_h = -math.sqrt(max(1.0 - (R / r) ** 2, 0.0))
    nodes = _nodes(n, r, R, Rt)
    mu = np.array([m for m, _ in nodes])
    ground = np.array([g for _, g in nodes])
    assert np.all(ground[:n // 2]) and not np.any(ground[n // 2:])
    assert mu[0] == pytest.approx(mu_h, abs=1e-12) and mu[-1] == pytest.approx(mu_h, abs=1e-12)
    assert mu[n // 2 - 1] == pytest.approx(-1.0, abs=1e-12)
    assert mu[n // 2] == pytest.approx(1.0, abs=1e-12)
    assert np.all(np.diff(mu[:n // 2]) < 0) and np.all(np.diff(mu[n // 2:]) < 0)
    for i, (m, g) in enumerate(nodes):
        j, b = _mapping.mu_index(r, m, g, n, R, Rt)
        assert j + b == pytest.approx(i, abs=1e-7)


@pytest.mark.parametrize("R, top", RADII)
def test_mu_nodes_resolve_the_sky_at_any_radius(R, top):
    """A ground observer's sky half (64 of the default 128 nodes) gives view zenith 0-70 deg
    at least 20 nodes at the earth's radius and at 1e8 m (Bruneton's distance-to-the-top
    mapping gives them 11 and 1), and the cell next to the horizon is at most 0.15 deg
    (Bruneton's at the earth's radius: 0.149 deg)."""
    n = 128
    mu = np.array([m for m, _ in _nodes(n, R, R, R + top)])[n // 2:]
    th = np.degrees(np.arccos(mu))
    assert np.sum(th <= 70.0) >= 20
    assert th[-1] - th[-2] <= 0.15
    # an observer at the top: the limb (sky rays between the horizon and the horizontal, the
    # only ones that cross the atmosphere) gets nodes at most 0.15 deg apart next to the
    # horizon and at least 5 of them (the limb is 10.1 deg wide at the earth's radius,
    # 0.72 deg at 1e8 m; Bruneton's mapping puts all sky nodes there)
    Rt = R + top
    mu_top = np.array([m for m, _ in _nodes(n, Rt, R, Rt)])[n // 2:]
    th_top = np.degrees(np.arccos(mu_top))
    assert np.sum(mu_top < 0.0) >= 5
    assert th_top[-1] - th_top[-2] <= 0.15


def test_thin_atmosphere_on_a_large_planet_against_monte_carlo():
    """Issue 11's case: sun 60 deg up, 650 nm, Rayleigh + Henyey-Greenstein aerosol, ground
    albedo 0.3, planet radius 1e8 m (the largest the API accepts; the default top of the
    atmosphere, 100 km): precomputed at its default settings against ``montecarlo``
    (40 000 paths per direction, relative standard error 0.25-0.65 %), at the zenith, 60 and
    30 deg up towards the sun and 30 deg up away from it. Measured (the Monte Carlo's default
    seed): +0.25, +0.04, +0.47, +0.47 % (with Bruneton's mu mapping: +0.05, -0.62, -0.75,
    -0.35 %; issue 11 reported +1.5, +9.7, +41.7, -3.8 % before the mu_s mapping was
    changed). At the earth's radius the same case is +0.06, +0.23, +1.22, +0.35 % (Bruneton's
    mu mapping: +0.04, +0.22, +1.10, +0.28 %). Required: 2 % plus three standard
    errors."""
    atm = sd.Atmosphere.custom(
        rayleigh_scattering=lambda w: 1.1815e-5 * (540 / np.asarray(w)) ** 4,
        mie_scattering=0.9 * 1.67e-4, mie_extinction=1.67e-4, mie_phase="henyey_greenstein",
        ground_albedo=0.3, planet_radius_m=1e8)
    sun = sd.Sun(elevation_deg=60, azimuth_deg=180)
    d = sd.direction_from_angles([90, 60, 30, 30], [0, 0, 0, 180])
    wl = [650.0]
    p = sd.model("precomputed", sun=sun, atmosphere=atm, table_wavelengths_nm=wl).radiance(d, wl)
    m, err = sd.model("montecarlo", sun=sun, atmosphere=atm, samples=40000,
                      seed=3).radiance_with_error(d, wl)
    assert np.all(err / m < 0.01)
    assert np.all(np.abs(p - m) <= 0.02 * m + 3.0 * err), np.c_[p / m - 1, err / m]


def test_viewer_shader_uses_the_same_mu_knee():
    """The browser shader's copy of the knee width (precomputed.glsl: MU_WIDTH) is the
    model's (``_mapping.MU_WIDTH``, 2 deg): the page and the CPU model index the same
    nodes (the viewer tests compare their skies)."""
    import re
    from importlib import resources

    src = (resources.files("skydome.viewer") / "static" / "shaders" / "precomputed.glsl").read_text()
    m = re.search(r"const float MU_WIDTH = ([0-9.eE+-]+);", src)
    assert m is not None
    assert float(m.group(1)) == pytest.approx(math.radians(2.0), rel=1e-12)
    assert _mapping.MU_WIDTH == pytest.approx(math.radians(2.0), rel=1e-12)
