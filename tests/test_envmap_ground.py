"""The environment map's ground and sun are the render's (skydome.imaging): the Lambertian
ground rho E_h / pi against an independent quadrature of the model's sky plus its direct
normal illuminance, the albedo of the model's atmosphere, and the map's sun, which is the
sun light of skydome.export.sun at the map's wavelengths (luminance-only models included)."""

import numpy as np
import pytest

import skydome as sd
from skydome.export.envmap import render_envmap
from skydome.export.sun import sun_light

Y709 = np.array([0.2126, 0.7152, 0.0722])      # Rec. 709 luminance weights of the maps' RGB


def _luminance(rgb):
    return 683.0 * (np.asarray(rgb) @ Y709)


def _horizontal_illuminance_midpoint(sky, n_el=300, n_az=240):
    """E_h [lx] of the model's sky by the midpoint rule in elevation and azimuth (not the
    library's Gauss-Legendre quadrature) plus its direct normal illuminance x sin(el)."""
    el = (np.arange(n_el) + 0.5) * (0.5 * np.pi / n_el)
    az = (np.arange(n_az) + 0.5) * (2.0 * np.pi / n_az)
    E, A = np.meshgrid(el, az, indexing="ij")
    d = np.stack([np.cos(E) * np.sin(A), np.cos(E) * np.cos(A), np.sin(E)], axis=-1)
    L = sky.luminance(d.reshape(-1, 3)).reshape(E.shape)
    w = np.cos(E) * np.sin(E) * (0.5 * np.pi / n_el) * (2.0 * np.pi / n_az)
    return float((L * w).sum()) + sky.direct_normal_illuminance() * np.sin(
        np.radians(sky.sun.elevation_deg))


@pytest.mark.parametrize("name, kw, albedo", [
    ("preetham1999", {"turbidity": 3.0}, 0.2),             # no albedo of its own: 0.2
    ("hosek_wilkie2012", {"turbidity": 3.0, "albedo": 0.3}, 0.3),   # its own albedo
])
def test_lambertian_ground_is_albedo_times_horizontal_illuminance(name, kw, albedo):
    sky = sd.model(name, sun=sd.Sun(elevation_deg=30.0, azimuth_deg=120.0), **kw)
    env = render_envmap(sky, "skydome", size="64x32")
    assert env.metadata["ground_albedo"] == pytest.approx(albedo, abs=1e-12)
    E_h = _horizontal_illuminance_midpoint(sky)
    ground = _luminance(env.images["map"][-1])                   # the bottom row, every pixel
    np.testing.assert_allclose(ground, albedo * E_h / np.pi, rtol=5e-3)
    E_meta = _luminance(env.metadata["horizontal_irradiance_rgb_W_m2"])
    assert E_meta == pytest.approx(E_h, rel=5e-3)


def test_ground_albedo_is_the_atmospheres_and_the_sun_the_maps():
    """A model with an atmosphere: the ground's albedo is the atmosphere's (Atmosphere.earth:
    0.1); the map's sun light is sun_light's at the map's wavelengths, and sun="map" puts
    exactly its irradiance into the map."""
    sky = sd.model("single_scattering", sun=sd.Sun(elevation_deg=20.0, azimuth_deg=200.0))
    wl = sd.wavelength_grid(380.0, 780.0, n=16)
    sep = render_envmap(sky, "blender", size="64x32", wavelengths_nm=wl, ground="black")
    inmap = render_envmap(sky, "blender", size="64x32", wavelengths_nm=wl, ground="black",
                          sun="map")
    a555 = float(np.ravel(sky.atmosphere.ground_albedo(np.array([555.0])))[0])
    assert a555 == 0.1 and sep.metadata["ground_albedo"] == a555
    ref = sun_light(sky, "blender", wavelengths_nm=wl)
    assert sep.sun_light["rgb_irradiance_W_m2"] == ref["rgb_irradiance_W_m2"]
    assert sep.sun_light["illuminance_lx"] == ref["illuminance_lx"]
    _, w = sep.directions()
    added = ((inmap.pixels() - sep.pixels()) * w[:, None]).sum(axis=0)
    np.testing.assert_allclose(added, ref["rgb_irradiance_W_m2"], rtol=1e-9)


def test_luminance_only_model_has_its_sun():
    """perez1993 (luminance only, a sun given by its direct normal illuminance): the map's
    sun carries the model's direct normal illuminance, and lights the Lambertian ground."""
    sky = sd.model("perez1993", sun=sd.Sun(elevation_deg=35.0, azimuth_deg=180.0),
                   epsilon=4.0, delta=0.2)
    dni = sky.direct_normal_illuminance()
    assert dni > 0.0
    sep = render_envmap(sky, "skydome", size="64x32", ground="black")
    inmap = render_envmap(sky, "skydome", size="64x32", ground="black", sun="map")
    _, w = sep.directions()
    added = ((inmap.pixels() - sep.pixels()) * w[:, None]).sum(axis=0)
    assert _luminance(added) == pytest.approx(dni, rel=1e-9)
    assert sep.sun_light["illuminance_lx"] == pytest.approx(dni, rel=1e-9)
    assert sep.sun_light["spectral_irradiance_W_m2_nm"] is None
    lam = render_envmap(sky, "skydome", size="64x32")
    E_h = _horizontal_illuminance_midpoint(sky)
    np.testing.assert_allclose(_luminance(lam.images["map"][-1]), 0.2 * E_h / np.pi, rtol=5e-3)
