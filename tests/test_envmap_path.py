"""The environment map's fast computation path gives the per-pixel path's values.

References are independent code paths of skydome itself: the generic per-pixel
``Projection.directions`` (each centre through ``direction_from_pixel``) and the model's
own ``radiance`` at the render's wavelengths integrated with the CIE weights.
"""

import numpy as np
import pytest

import skydome as sd
from skydome.camera import Projection
from skydome.export.conventions import CONVENTIONS
from skydome.export.envmap import MapProjection


@pytest.mark.parametrize("name", sorted(CONVENTIONS))
@pytest.mark.parametrize("size", [(64, 32), (37, 19)])
def test_map_directions_equal_per_pixel_path(name, size):
    p = MapProjection(name, *size)
    d, m = p.directions()
    d0, m0 = Projection.directions(MapProjection(name, *size))
    assert np.array_equal(m, m0)
    assert np.array_equal(d, d0)          # bit for bit, not merely close


def test_lambertian_ground_render_skips_nothing_it_shows():
    # ground="lambertian" samples the model above the horizon only; the pixels there equal
    # those of ground="model", and below the horizon hold rho E_h / pi
    from skydome.imaging import Equirect, render
    from skydome.imaging.ground import horizontal_irradiance, model_albedo
    from skydome.spectra import wavelength_grid

    sky = sd.model("hosek_wilkie2012", sun=sd.Sun(elevation_deg=30.0, azimuth_deg=135.0))
    wl = wavelength_grid(380.0, 780.0, n=16)
    p = Equirect(64)
    a = render(sky, p, wl, output="xyz", ground="lambertian", draw_sun=False)
    b = render(sky, p, wl, output="xyz", ground="model", draw_sun=False)
    d, _ = p.directions()
    up = d[..., 2] >= 0.0
    assert np.array_equal(a.data[up], b.data[up])
    E = horizontal_irradiance(sky, wl)                  # the model's own spectral radiance
    from skydome.spectra import spectrum_to_xyz

    L = spectrum_to_xyz(model_albedo(sky, wl) * E / np.pi, wl)
    np.testing.assert_allclose(a.data[~up], np.broadcast_to(L, a.data[~up].shape), rtol=1e-12)


def test_hosek_folded_bands_match_spectral_radiance():
    # the fused path (band interpolation folded into the XYZ weights) against the model's
    # radiance() at the render's wavelengths, integrated with the CIE weights
    from skydome.imaging import Equirect, render
    from skydome.spectra import spectrum_to_xyz, wavelength_grid

    sky = sd.model("hosek_wilkie2012", sun=sd.Sun(elevation_deg=30.0, azimuth_deg=135.0))
    wl = wavelength_grid(380.0, 780.0, n=16)
    p = Equirect(48)
    img = render(sky, p, wl, output="xyz", ground="black", draw_sun=False)
    d, m = p.directions()
    up = m & (d[..., 2] >= 0.0)
    ref = spectrum_to_xyz(sky.radiance(d[up], wl), wl)
    np.testing.assert_allclose(img.data[up], ref, rtol=1e-12, atol=1e-9)
