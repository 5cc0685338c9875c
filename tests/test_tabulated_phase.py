"""Tabulated phase functions (skydome.atmosphere.TabulatedPhase, Lorenz-Mie tables) reach
the physically based models through the kernels' medium record."""

import math

import numpy as np
import pytest

import skydome as sd
from skydome.atmosphere import Atmosphere, Constituent, TabulatedPhase
from skydome.atmosphere.mie import MieAerosol, mie_constituent
from skydome.atmosphere.profiles import ExponentialProfile
from skydome.transport.geometry import angle_between, direction_from_angles

WL = np.array([450.0, 550.0, 650.0])
SUN = sd.Sun(elevation_deg=35.0, azimuth_deg=180.0)


def hg(g, c):
    """Henyey-Greenstein phase [sr^-1] written out here (Henyey & Greenstein 1941)."""
    return (1 - g * g) / (1 + g * g - 2 * g * c) ** 1.5 / (4 * math.pi)


def _single(atm, dirs):
    return sd.model("single_scattering", sun=SUN, atmosphere=atm).radiance(dirs, WL)


def _dirs():
    el = np.array([35.0, 38.0, 50.0, 70.0, 20.0, 5.0, 60.0])
    az = np.array([185.0, 180.0, 200.0, 300.0, 20.0, 90.0, 0.0])
    return direction_from_angles(el, az)


def test_mie_phase_reaches_single_scattering():
    """A thin layer of uniform 0.8 um spheres (m = 1.5, tau = 1e-4): with the tabulated
    Lorenz-Mie phase the single-scattered radiance is 4 pi P(theta) times the radiance
    with an isotropic phase (single scattering factors per constituent), with P from
    miepython (i_unpolarized, norm='one'), an independent Lorenz-Mie code."""
    import miepython

    aero = MieAerosol(0.8, 1.0, 1.5 + 0.0j)
    prof = ExponentialProfile(1200.0)
    mie = mie_constituent(aero, prof, optical_depth_550=1e-4, name="mie")
    assert mie.phase == "tabulated"
    iso = Constituent("mie", scattering=mie.scattering, absorption=mie.absorption, profile=prof,
                      phase="isotropic")
    atm_mie = Atmosphere((mie,), ground_albedo=0.0)
    atm_iso = Atmosphere((iso,), ground_albedo=0.0)
    d = _dirs()
    L_mie = _single(atm_mie, d)
    L_iso = _single(atm_iso, d)
    cos_t = np.cos(angle_between(d, SUN.direction))
    for j, wl in enumerate(WL):
        x = 2 * math.pi * 0.8e3 / wl
        p = miepython.i_unpolarized(1.5, x, cos_t, norm="one")
        np.testing.assert_allclose(L_mie[:, j], 4 * math.pi * p * L_iso[:, j], rtol=2e-3)


def test_tabulated_hg_table_reproduces_analytic_hg_model():
    """The Earth atmosphere with its aerosol phase given as an HG table at 1441 angles
    reproduces the analytic HG aerosol in the single-scattering model to 1e-3."""
    g = 0.76
    base = Atmosphere.earth(turbidity=4.0, aerosol_phase="henyey_greenstein", aerosol_g=g)
    theta = np.linspace(0.0, 180.0, 1441)
    table = TabulatedPhase(theta, hg(g, np.cos(np.radians(theta))), normalise=False,
                           description="HG g=0.76")
    cons = tuple(Constituent(c.name, c.scattering, c.absorption, c.profile, "tabulated", g,
                             phase_table=table) if c.name == "aerosol" else c
                 for c in base.constituents)
    tab_atm = Atmosphere(cons, ground_albedo=0.1)
    d = _dirs()
    np.testing.assert_allclose(_single(tab_atm, d), _single(base, d), rtol=1e-3)


def test_measured_table_is_normalised_and_interpolated():
    """A table of relative values at 1 deg (5 x HG, two wavelengths) is normalised to 1 over
    the sphere and follows HG on the kernels' grid within the 1 deg interpolation error;
    between the measured wavelengths it is interpolated linearly."""
    theta = np.linspace(0.0, 180.0, 181)
    c = np.cos(np.radians(theta))
    vals = np.stack([5 * hg(0.5, c), 5 * hg(0.7, c)], axis=-1)
    t = TabulatedPhase(theta, vals, [400.0, 800.0])
    grid = t.on_grid([400.0, 600.0, 800.0])
    th = np.radians(np.linspace(0.0, 180.0, grid.shape[0]))
    norm = 2 * math.pi * np.trapezoid(grid * np.sin(th)[:, None], th, axis=0)
    np.testing.assert_allclose(norm, 1.0, rtol=1e-12)
    np.testing.assert_allclose(grid[:, 0], hg(0.5, np.cos(th)), rtol=2e-2)
    np.testing.assert_allclose(grid[:, 2], hg(0.7, np.cos(th)), rtol=2e-2)
    raw = np.interp(np.degrees(th), theta, 0.5 * (vals[:, 0] + vals[:, 1]))
    np.testing.assert_allclose(grid[:, 1], raw / (2 * math.pi * np.trapezoid(raw * np.sin(th), th)),
                               rtol=1e-12)


def test_mie_table_normalised_over_the_sphere():
    """The Lorenz-Mie phase table integrates to 1 over the sphere ([BH83] eq. 3.16)."""
    aero = MieAerosol(0.5, 1.3, 1.5 - 0.001j, n_radii=15)
    theta, p = aero.phase_table([450.0, 650.0])
    th = np.radians(theta)
    np.testing.assert_allclose(2 * math.pi * np.trapezoid(p * np.sin(th)[:, None], th, axis=0),
                               1.0, rtol=2e-3)


def test_tabulated_phase_errors():
    theta = np.linspace(0.0, 180.0, 19)
    with pytest.raises(ValueError, match="theta_deg"):
        TabulatedPhase(np.linspace(0.0, 170.0, 19), np.ones(19))
    with pytest.raises(ValueError, match="non-negative"):
        TabulatedPhase(theta, -np.ones(19))
    with pytest.raises(ValueError, match="wavelengths_nm"):
        TabulatedPhase(theta, np.ones((19, 2)))
    with pytest.raises(ValueError, match="does not match"):
        TabulatedPhase(theta, np.ones(18))
    with pytest.raises(ValueError, match="phase_table"):
        Constituent("dust", scattering=1e-5, phase="tabulated")
    with pytest.raises(TypeError, match="phase_table"):
        Constituent("dust", scattering=1e-5, phase="tabulated", phase_table=np.ones(19))


def _hg_tabulated_pair():
    g = 0.76
    base = Atmosphere.earth(turbidity=4.0, aerosol_phase="henyey_greenstein", aerosol_g=g)
    theta = np.linspace(0.0, 180.0, 1441)
    table = TabulatedPhase(theta, hg(g, np.cos(np.radians(theta))), normalise=False)
    cons = tuple(Constituent(c.name, c.scattering, c.absorption, c.profile, "tabulated", g,
                             phase_table=table) if c.name == "aerosol" else c
                 for c in base.constituents)
    return base, Atmosphere(cons, ground_albedo=0.1)


@pytest.mark.parametrize("name, params", [
    ("nishita1993", dict(camera_altitude_m=10e3, surface="albedo", albedo=0.1)),
    ("nishita1996", dict(orders=2, sky_directions=8, lattice_size=5)),
    ("kaneda1991", {}),
    ("hillaire2020", dict(use_skyview=False)),
])
def test_tabulated_phase_reaches_every_model(name, params):
    """Every physically based model that evaluates a phase function gives the same sky
    with the aerosol's HG phase function given as a table as with the analytic HG
    (within 1e-3): the tabulated path reaches each model's kernels."""
    base, tab_atm = _hg_tabulated_pair()
    d = _dirs()[:5]
    a = sd.model(name, sun=SUN, atmosphere=base, **params).radiance(d, WL)
    b = sd.model(name, sun=SUN, atmosphere=tab_atm, **params).radiance(d, WL)
    np.testing.assert_allclose(b, a, rtol=1e-3)


def test_tabulated_phase_reaches_montecarlo():
    """Monte Carlo with the aerosol's HG phase as a table (sampled by inverting its
    cumulative distribution) agrees with the analytic HG run within 4 standard errors."""
    base, tab_atm = _hg_tabulated_pair()
    d = _dirs()[:3]
    a, ea = sd.model("montecarlo", sun=SUN, atmosphere=base, samples=400).radiance_with_error(d, WL[1:2])
    b, eb = sd.model("montecarlo", sun=SUN, atmosphere=tab_atm, samples=400).radiance_with_error(d, WL[1:2])
    assert np.all(np.abs(a - b) <= 4.0 * np.hypot(ea, eb) + 1e-3 * a)


# -- the precomputed model (Bruneton 2017) -----------------------------------------------------
# small tables as in tests/test_precomputed.py's fast tests
PC_SMALL = dict(scattering_r_size=12, scattering_mu_size=48, scattering_mu_s_size=12,
                scattering_nu_size=6, irradiance_mu_s_size=32, irradiance_r_size=8,
                transmittance_mu_size=128, transmittance_r_size=32, orders=4,
                remaining_orders="none", sphere_samples=16, cache=False)


def _precomputed(atm, **kw):
    return sd.model("precomputed", sun=SUN, atmosphere=atm, table_wavelengths_nm=WL,
                    **{**PC_SMALL, **kw})


def test_tabulated_phase_reaches_precomputed():
    """The precomputed model (4 orders: the single-scattering lookup, the scattering
    density J of each order, the ground irradiance and the observer's slice) with the
    aerosol's HG phase given as a 1441-angle table gives the analytic-HG sky within 1e-3,
    and so does its aerial perspective."""
    base, tab_atm = _hg_tabulated_pair()
    d = _dirs()
    a_m, b_m = _precomputed(base), _precomputed(tab_atm)
    a, b = a_m.radiance(d, WL), b_m.radiance(d, WL)
    assert np.all(a > 0)
    np.testing.assert_allclose(b, a, rtol=1e-3)
    (ta, la), (tb, lb) = (m.aerial_perspective(d[:5], 5000.0, WL) for m in (a_m, b_m))
    np.testing.assert_allclose(tb, ta, rtol=1e-12)
    np.testing.assert_allclose(lb, la, rtol=1e-3)
    np.testing.assert_allclose(b_m.ground_irradiance(WL), a_m.ground_irradiance(WL), rtol=1e-3)


def _thin_mie_atmosphere(phase="tabulated"):
    """Uniform-size 0.8 um spheres (m = 1.5) in a 1.2 km exponential layer, tau = 1e-3, no
    ground reflection: optically thin, so single scattering is the whole sky."""
    aero = MieAerosol(0.8, 1.0, 1.5 + 0.0j)
    prof = ExponentialProfile(1200.0)
    mie = mie_constituent(aero, prof, optical_depth_550=1e-3, name="mie")
    if phase != "tabulated":
        mie = Constituent("mie", scattering=mie.scattering, absorption=mie.absorption,
                          profile=prof, phase=phase)
    return Atmosphere((mie,), ground_albedo=0.0)


def _sun_angle_dirs():
    """Views 3, 6, 12, 30 deg from the sun (in its vertical plane, above it) and 48, 108,
    125 deg away."""
    el = np.array([38.0, 41.0, 47.0, 65.0, 35.0, 10.0, 20.0])
    az = np.array([180.0, 180.0, 180.0, 180.0, 240.0, 300.0, 0.0])
    return direction_from_angles(el, az)


def test_mie_phase_in_precomputed_against_miepython():
    """Order 1 of the precomputed model stores single scattering without the phase and
    applies it at the lookup: with the Lorenz-Mie table the sky is 4 pi P(theta) times the
    sky with an isotropic phase, P from miepython (an independent Lorenz-Mie code) at the
    view's scattering angle, within 2e-3 (the table's 0.125 deg linear interpolation and
    the Mie size-distribution quadrature, as in the single-scattering test above)."""
    import miepython

    d = _sun_angle_dirs()
    L_mie = _precomputed(_thin_mie_atmosphere(), orders=1).radiance(d, WL)
    L_iso = _precomputed(_thin_mie_atmosphere("isotropic"), orders=1).radiance(d, WL)
    cos_t = np.cos(angle_between(d, SUN.direction))
    for j, wl in enumerate(WL):
        p = miepython.i_unpolarized(1.5, 2 * math.pi * 0.8e3 / wl, cos_t, norm="one")
        np.testing.assert_allclose(L_mie[:, j], 4 * math.pi * p * L_iso[:, j], rtol=2e-3)


def test_mie_precomputed_matches_single_scattering_thin_limit():
    """Optically thin Lorenz-Mie layer, orders=1: precomputed (small tables) agrees with the
    single_scattering model (direct ray marching, its own kernels) within 1 % at 3-30 deg
    from the sun and 48-125 deg away. Both apply the same Mie table; what differs is the
    geometry of the 4-D table (the unphased single scattering interpolated on 48 mu x 12
    mu_s x 6 nu nodes, the sun's transmittance from the transmittance table): at tau = 1e-3
    the sky is beta_s rho P times a path length, and the table's interpolation of that path
    integral in mu and nu is what the tolerance covers (measured: 0.15 % at most)."""
    d = _sun_angle_dirs()
    atm = _thin_mie_atmosphere()
    pc = _precomputed(atm, orders=1).radiance(d, WL)
    ss = sd.model("single_scattering", sun=SUN, atmosphere=atm).radiance(d, WL)
    assert np.all(ss > 0)
    np.testing.assert_allclose(pc, ss, rtol=1e-2)


def test_precomputed_cache_key_holds_the_phase_table():
    """Two atmospheres differing only in the aerosol's phase table get different cache
    keys (the table is among the optical properties hashed)."""
    from skydome.models.simulated.precomputed import _cache

    base, tab_atm = _hg_tabulated_pair()
    theta = np.linspace(0.0, 180.0, 1441)
    other = TabulatedPhase(theta, hg(0.7, np.cos(np.radians(theta))), normalise=False)
    cons = tuple(Constituent(c.name, c.scattering, c.absorption, c.profile, "tabulated", 0.76,
                             phase_table=other) if c.name == "aerosol" else c
                 for c in tab_atm.constituents)
    atm2 = Atmosphere(cons, ground_albedo=0.1)
    keys = {_cache.key(a.optical_properties(WL), {}) for a in (base, tab_atm, atm2)}
    assert len(keys) == 3


def test_precomputed_tabulated_phase_export_and_lut_refusal(tmp_path):
    """The exported textures carry the phase table (code 4); the XYZ LUT bake, which
    applies analytic phase functions only, refuses it with a clear ValueError; save/load
    keeps it (the loaded model renders the same sky)."""
    import json

    from skydome.export.luts import bake_precomputed

    m = _precomputed(_thin_mie_atmosphere(), orders=1)
    m.export_textures(tmp_path / "tex")
    desc = json.loads((tmp_path / "tex" / "textures.json").read_text())
    assert desc["phase_code"] == [4]
    tab = np.load(tmp_path / "tex" / "phase_table.npy")
    want = _thin_mie_atmosphere().optical_properties(WL).phase_table
    np.testing.assert_allclose(tab, want, rtol=1e-6)
    with pytest.raises(ValueError, match="tabulated phase"):
        bake_precomputed(m)
    m.save(tmp_path / "t.npz")
    back = type(m).load(tmp_path / "t.npz")
    d = _sun_angle_dirs()
    np.testing.assert_array_equal(back.radiance(d, WL), m.radiance(d, WL))


def test_precomputed_spectral_table_per_wavelength():
    """A table whose phase changes with the wavelength (HG with g = 0.6, 0.7, 0.8 at 450,
    550, 650 nm) gives, at each table wavelength, the sky of the analytic HG aerosol with
    that wavelength's g (4 orders: J's phase matrix is the one of its own wavelength),
    within 1e-3."""
    gs = (0.6, 0.7, 0.8)
    theta = np.linspace(0.0, 180.0, 1441)
    c = np.cos(np.radians(theta))
    table = TabulatedPhase(theta, np.stack([hg(g, c) for g in gs], axis=-1), WL,
                           normalise=False)
    base = Atmosphere.earth(turbidity=4.0, aerosol_phase="henyey_greenstein", aerosol_g=0.7)
    cons = tuple(Constituent(k.name, k.scattering, k.absorption, k.profile, "tabulated", 0.7,
                             phase_table=table) if k.name == "aerosol" else k
                 for k in base.constituents)
    d = _dirs()
    # per unit solar irradiance (radiance_table): the solar spectrum on a one-wavelength
    # table is not the one on the three-wavelength table
    L = _precomputed(Atmosphere(cons, ground_albedo=0.1)).radiance_table(d)
    for j, g in enumerate(gs):
        ref_atm = Atmosphere.earth(turbidity=4.0, aerosol_phase="henyey_greenstein", aerosol_g=g)
        ref_atm = Atmosphere(ref_atm.constituents, ground_albedo=0.1)
        ref = sd.model("precomputed", sun=SUN, atmosphere=ref_atm,
                       table_wavelengths_nm=[WL[j]], **PC_SMALL).radiance_table(d)
        np.testing.assert_allclose(L[:, j], ref[:, 0], rtol=1e-3)
