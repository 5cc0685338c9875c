"""Sky matrices of any model (patch means of luminance or spectral radiance) and Zarr output."""

from __future__ import annotations

import numpy as np
import pytest

import skydome as sd
from skydome.daylighting.patches import patches
from skydome.daylighting.skymatrix import model_sky_matrix


def test_cie_overcast_patch_means_are_exact():
    """CIE overcast L = Lz (1 + 2 sin a) / 3 (Moon & Spencer 1942; CIE S 011 type 16) is linear
    in sin(altitude): its patch mean is Lz (1 + s_lo + s_hi) / 3, exact for every order >= 1."""
    lz = 5000.0
    sun = sd.Sun(elevation_deg=30.0, azimuth_deg=180.0)
    ps = patches("reinhart:2")
    m = model_sky_matrix(lambda h: sd.model("cie1994_overcast", sun=sun, zenith_luminance=lz),
                         2, patches=ps, order=2)
    slo, shi = np.sin(ps.altitude_low_rad[1:]), np.sin(ps.altitude_high_rad[1:])
    np.testing.assert_allclose(m[0, 1:, 0], lz * (1 + slo + shi) / 3, rtol=1e-12)
    assert np.all(m[:, 0] == 0.0)


def test_spectral_matrix_to_zarr_equals_in_memory(tmp_path):
    pytest.importorskip("zarr")
    import zarr

    suns = [sd.Sun(elevation_deg=e, azimuth_deg=180.0) for e in (10.0, 30.0, 60.0, -5.0, 45.0)]

    def make(h):
        if suns[h].elevation_deg < 0:
            return None
        return sd.model("preetham1999", sun=suns[h], turbidity=3.0)

    wl = np.array([450.0, 550.0, 650.0])
    mem = model_sky_matrix(make, 5, components="spectral", wavelengths_nm=wl, order=1)
    z = model_sky_matrix(make, 5, components="spectral", wavelengths_nm=wl, order=1,
                         zarr_path=tmp_path / "m.zarr", chunk_hours=2)
    back = zarr.open_array(str(tmp_path / "m.zarr"), mode="r")
    assert back.shape == (5, 146, 3) and back.chunks[0] == 2
    np.testing.assert_array_equal(back[:], mem)
    assert np.all(mem[3] == 0.0) and mem[4, 1:].min() > 0.0
    with pytest.raises(ValueError, match="exists"):
        model_sky_matrix(make, 5, zarr_path=tmp_path / "m.zarr")
