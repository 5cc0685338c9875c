"""The ``fitted`` model's bake for real-time renderers (``skydome export luts --model
fitted``): for one atmosphere (aerosol optical depth, ground albedo) and one observer
altitude, the model's angular table in CIE XYZ at every sun elevation of its range, in
steps of :data:`ELEVATION_STEP_DEG`, and the sun's transmitted radiance at the same
elevations; ``export/glsl/fitted.glsl`` evaluates any direction for any sun from them.

Textures (little-endian float32, RGBA, Y in cd m^-2 for a sun at 1 au: multiply by
``Sun.irradiance_scale`` at render time):

* ``sky`` (n_elevations, N_SKY + N_GROUND, N_PHI, 4): slice k is ``FittedSky.xyz_table()``
  (the table the CPU model's ``xyz()`` looks up) at sun elevation ``first + k step``; rows
  the view grid's zenith-angle nodes (the sky's from the horizon up, then the ground's from
  the horizon down), columns its azimuth nodes from the sun's vertical plane
  (skydome.models.fitted._grid); A = 0. As a GL texture: a 2-D array texture, one layer
  per elevation, N_PHI wide and N_SKY + N_GROUND high.
* ``sun`` (n_sun_elevations, 4): the XYZ of E_sun / Omega_sun x T, the radiance of the
  disc seen through the air along the path to its centre (``FittedSky.sun_transmittance``
  on skydome's default wavelength grid, reduced to XYZ as ``SkyModel.xyz`` reduces a
  spectrum), without the fraction of the disc below the horizon (the shader applies it),
  on its own finer elevation axis (:data:`SUN_ELEVATION_STEP_DEG`: ln T grows with the air
  mass, which is strongly curved in elevation near the horizon); A = 0. As a GL texture:
  n_sun_elevations wide, 1 high.

luts.json also carries ``sun.limb_darkening`` (the coefficients of mu^0..mu^5 of Neckel's
centre-to-limb law at the X, Y and Z channels' wavelengths, divided by its disc mean: the
disc as ``skydome.render`` draws it, skydome.imaging.sun_disc) and ``xyz_to_linear_srgb``
(row-major), for the shader's disc and the three.js module's RGB output.

Between the elevation slices the shader interpolates geometrically (linearly in ln XYZ;
linearly where either value is 0, which the model's clamp can give):
the sky darkens about exponentially as the sun sets, and the model itself interpolates
its logarithm linearly in elevation between its nodes. Against the CPU model at
elevations between the slices (1 deg steps) the bake stays above 50 dB PSNR
(tests/test_export_fitted_luts.py, measured at off-step elevations).
"""

from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np

__all__ = ["bake_fitted", "FITTED_FORMAT", "ELEVATION_STEP_DEG", "SUN_ELEVATION_STEP_DEG"]

#: The bake's format (luts.json "format").
FITTED_FORMAT = "skydome.luts.fitted-xyz/1"
#: Step of the sun-elevation axis [deg] (at most; the range is split evenly).
ELEVATION_STEP_DEG = 1.0
#: Step of the sun texture's elevation axis [deg] (at most): geometric interpolation of
#: the transmitted sun between 1 deg steps is 10 % off at 1.5 deg (ln T follows the air
#: mass, not the elevation), between 0.1 deg steps 0.48 % at 0.15 deg; the error goes
#: with the step squared. A texture of at most :data:`SUN_TEXTURE_MAX` texels (the
#: smallest GL_MAX_TEXTURE_SIZE of OpenGL ES 3.0) takes a larger step where needed.
SUN_ELEVATION_STEP_DEG = 0.05
SUN_TEXTURE_MAX = 2048
#: The floor of the shader's logarithm (XYZ values in cd m^-2).
LOG_FLOOR = 1e-30


def elevation_axis(low_deg: float, high_deg: float,
                   step_deg: float = ELEVATION_STEP_DEG) -> np.ndarray:
    """Evenly spaced sun elevations [deg] from ``low_deg`` to ``high_deg`` inclusive, at
    most ``step_deg`` apart."""
    n = int(math.ceil((high_deg - low_deg) / step_deg - 1e-9)) + 1
    return np.linspace(low_deg, high_deg, max(n, 2))


def bake_fitted(sky, step_deg: float = ELEVATION_STEP_DEG
                ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """(textures, description) of the fitted model ``sky``'s atmosphere and observer
    altitude over its whole sun-elevation range (module docstring); the sun's azimuth and
    distance of ``sky`` do not matter (the shader takes the sun's direction, the values are
    at 1 au)."""
    from skydome.constants import K_M
    from skydome.imaging import sun_disc
    from skydome.models.fitted import _grid
    from skydome.spectra import xyz_to_linear_srgb
    from skydome.spectra import default_wavelengths, integration_weights, solar_irradiance
    from skydome.sun import Sun

    cls = type(sky)
    params = {p.name: getattr(sky, p.name) for p in cls.parameters}
    lo, hi = (float(v) for v in cls.sun_elevation_range_deg)
    elev = elevation_axis(lo, hi, step_deg)
    wl = default_wavelengths()
    w_xyz = K_M * np.asarray(integration_weights(wl))                     # (n_wl, 3)
    e_top = solar_irradiance(wl)                                          # 1 au
    rows, n_phi = _grid.N_SKY + _grid.N_GROUND, _grid.N_PHI
    tab = np.zeros((elev.size, rows, n_phi, 4))
    radius = float(sky.sun.angular_radius_deg)
    for k, e in enumerate(elev):
        s = Sun(elevation_deg=float(e), azimuth_deg=180.0, angular_radius_deg=radius)
        tab[k, :, :, :3] = cls(sun=s, **params).xyz_table()
    # the sun: the transmittance depends on the sun's elevation alone, not on the angular
    # table, so one model answers it for every elevation with its sun replaced
    sun_elev = elevation_axis(lo, hi, max(SUN_ELEVATION_STEP_DEG,
                                          (hi - lo) / (SUN_TEXTURE_MAX - 1)))
    sun_tex = np.zeros((sun_elev.size, 4))
    m = copy.copy(sky)
    for k, e in enumerate(sun_elev):
        m.sun = Sun(elevation_deg=float(e), azimuth_deg=180.0, angular_radius_deg=radius)
        sun_tex[k, :3] = (e_top * m.sun_transmittance(wl) / m.sun.solid_angle_sr) @ w_xyz
    if not (np.all(np.isfinite(tab)) and np.all(tab >= 0.0) and np.all(np.isfinite(sun_tex))
            and np.all(sun_tex >= 0.0)):
        raise ValueError("the fitted bake has non-finite or negative values")
    th_h = _grid.horizon_zenith_rad(sky.observer_altitude_m)
    s0 = Sun(elevation_deg=45.0, azimuth_deg=180.0, angular_radius_deg=radius)
    # the disc's centre-to-limb law as skydome.render draws it into an XYZ image ([Nec05] at
    # the channels' wavelengths, divided by its disc mean so that the disc averages to 1)
    ch = np.asarray(sun_disc.XYZ_CHANNEL_WAVELENGTHS_NM)
    limb = sun_disc._neckel_coefficients(ch) / sun_disc.limb_darkening_mean(ch)[:, None]
    desc = {
        "format": FITTED_FORMAT,
        "model": sky.name,
        "model_parameters": {k: float(v) for k, v in params.items()},
        "glsl": "export/glsl/fitted.glsl (struct SkydomeFitted: fill it from this file)",
        "units": "CIE 1931 XYZ, Y in cd m^-2, for a sun at 1 au: multiply by "
                 "Sun.irradiance_scale (1 / distance_au^2)",
        "elevation_axis": {"first_deg": float(elev[0]), "step_deg": float(elev[1] - elev[0]),
                           "count": int(elev.size),
                           "interpolation": "geometric between neighbouring slices "
                                            f"(linear in ln max(XYZ, {LOG_FLOOR:g})); "
                                            "linear where either value is 0"},
        "sun_elevation_axis": {"first_deg": float(sun_elev[0]),
                               "step_deg": float(sun_elev[1] - sun_elev[0]),
                               "count": int(sun_elev.size),
                               "interpolation": "geometric, as elevation_axis"},
        "view_grid": {
            "n_sky": _grid.N_SKY, "n_ground": _grid.N_GROUND, "n_phi": _grid.N_PHI,
            "a_phi": _grid.A_PHI, "eps_rad": _grid.EPS, "theta_h_rad": th_h,
            "inv_sky": 1.0 / (th_h - _grid.EPS),
            "inv_ground": 1.0 / (math.pi - th_h - _grid.EPS),
            "sky": "row i < n_sky: theta = (theta_h - eps) (1 - x^2), x = i / (n_sky - 1)",
            "ground": "row n_sky + j: theta = theta_h + eps + (pi - theta_h - eps) x^2, "
                      "x = j / (n_ground - 1)",
            "azimuth": "column c: phi = pi (a t + (1 - a) t^2), t = c / (n_phi - 1), phi "
                       "from the sun's vertical plane, folded into [0, pi]"},
        "sun": {"angular_radius_deg": radius, "angular_radius_rad": math.radians(radius),
                "solid_angle_sr": float(s0.solid_angle_sr),
                "note": "texture sun: the disc's mean radiance through the air; the mean "
                        "over the whole disc is that times the fraction above the horizon "
                        "(skydomeFittedSunVisibleFraction); limb_darkening spreads it over "
                        "the disc (skydomeFittedSunDisc)",
                "limb_darkening": {
                    "law": "Neckel 2005, I(mu) / I_mean = sum_k c_k mu^k, mu = sqrt(1 - "
                           "rho^2), rho = sin(angle from the centre) / sin(angular radius)",
                    "channel_wavelengths_nm": [float(v) for v in ch],
                    "coefficients_xyz": [[float(v) for v in row] for row in limb.T]}},
        "xyz_to_linear_srgb": [[float(v) for v in row]
                               for row in xyz_to_linear_srgb(np.eye(3)).T],
        "textures": {
            "sky": {"file": "sky.bin", "shape": list(tab.shape), "dtype": "float32",
                    "channels": "XYZ",
                    "gl": "2-D array texture: layer = elevation slice, width n_phi, height "
                          "n_sky + n_ground; texelFetch (the shader interpolates)"},
            "sun": {"file": "sun.bin", "shape": list(sun_tex.shape), "dtype": "float32",
                    "channels": "XYZ",
                    "gl": "2-D texture, width = sun_elevation_axis count, height 1; "
                          "texelFetch"}},
    }
    return {"sky": tab, "sun": sun_tex}, desc
