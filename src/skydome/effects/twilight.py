"""Twilight (survey section 5.2): the sky with the sun from 0 to -18 deg below the horizon.

Civil (0..-6 deg), nautical (-6..-12 deg) and astronomical (-12..-18 deg) twilight. The
functions here evaluate any model that supports the sun below the horizon (``precomputed``,
valid to -18 deg with multiple scattering, is the default; ``single_scattering`` and
``montecarlo`` also work):

* :func:`twilight_models`: one model per sun depression (tables shared where a model can);
* :func:`zenith_luminance_curve`: zenith luminance [cd m^-2] against sun depression;
* :func:`horizontal_illuminance`: the sky's illuminance on a horizontal plane [lx], by the
  quadrature of :mod:`skydome.illuminance`;
* :func:`anti_solar_profile`: luminance and colour (R/B of linear sRGB) along the vertical
  opposite the sun, where the earth's shadow (a blue-grey band on the horizon) rises under
  the Belt of Venus (a pinkish band above it);
* :func:`belt_of_venus`: locates the two bands in that profile.

The frames, sheets and files of ``skydome twilight`` are made by :mod:`skydome.apps.twilight`.

The night sky's own light (airglow, starlight, zodiacal light: about 1e-4 cd m^-2 in total)
is not modelled: below -18 deg ``precomputed`` returns 0.
"""

from __future__ import annotations

import numpy as np

__all__ = ["SUN_AZIMUTH_DEG", "twilight_models", "sky_luminance", "zenith_luminance_curve",
           "horizontal_illuminance", "anti_solar_profile", "belt_of_venus"]

SUN_AZIMUTH_DEG = 270.0   # the sun sets in the west in every figure
N_WAVELENGTHS = 21        # default grid: 380-780 nm in 20 nm steps


def _grid(wavelengths_nm):
    from skydome.spectra import wavelength_grid

    return wavelength_grid(380.0, 780.0, n=N_WAVELENGTHS) if wavelengths_nm is None else wavelengths_nm


def twilight_models(model: str = "precomputed", depressions_deg=(0.0,), **params):
    """One model per sun elevation -depression; models with ``with_sun`` (``precomputed``)
    share their tables."""
    import skydome as sd
    from skydome._validate import check_number

    elevs = [-check_number("depression", d, -90.0, 90.0, "deg") for d in depressions_deg]
    first = sd.model(model, sun=sd.Sun(elevation_deg=elevs[0], azimuth_deg=SUN_AZIMUTH_DEG), **params)
    out = [first]
    for e in elevs[1:]:
        sun = sd.Sun(elevation_deg=e, azimuth_deg=SUN_AZIMUTH_DEG)
        out.append(first.with_sun(sun) if hasattr(first, "with_sun") else sd.model(model, sun=sun, **params))
    return out


def sky_luminance(sky, directions, wavelengths_nm) -> np.ndarray:
    """Luminance [cd m^-2] of the sky in ``directions``: from the spectral radiance at
    ``wavelengths_nm`` for a spectral model, the model's own luminance otherwise."""
    from skydome.spectra import spectrum_to_xyz

    if sky.native == "spectral":
        return spectrum_to_xyz(sky.radiance(directions, wavelengths_nm), wavelengths_nm)[..., 1]
    return sky.luminance(directions)


def zenith_luminance_curve(model: str = "precomputed", depressions_deg=np.arange(0.0, 18.1, 1.0),
                           wavelengths_nm=None, **params) -> np.ndarray:
    """Zenith luminance [cd m^-2] for each sun depression [deg] (sun elevation = -depression)."""
    wl = _grid(wavelengths_nm)
    skies = twilight_models(model, list(depressions_deg), **params)
    zen = np.array([0.0, 0.0, 1.0])
    return np.array([float(sky_luminance(s, zen, wl)) for s in skies])


def horizontal_illuminance(sky, wavelengths_nm=None, n_mu: int | None = None,
                           n_phi: int | None = None) -> float:
    """Illuminance of the sky on a horizontal plane [lx]: the integral of L cos(theta) over
    the upper hemisphere (the sun's disc excluded), with the directions and weights of
    :func:`skydome.illuminance.sky_quadrature` (its defaults where ``n_mu`` / ``n_phi`` are
    None) and the luminance of :func:`sky_luminance` at ``wavelengths_nm``."""
    from skydome.illuminance import N_MU_DEFAULT, N_PHI_DEFAULT, sky_quadrature

    d, w = sky_quadrature((0.0, 0.0, 1.0), N_MU_DEFAULT if n_mu is None else n_mu,
                          N_PHI_DEFAULT if n_phi is None else n_phi)
    return float(w @ np.asarray(sky_luminance(sky, d, _grid(wavelengths_nm)), dtype=np.float64))


def anti_solar_profile(sky, elevations_deg=np.arange(0.5, 40.0, 0.5), wavelengths_nm=None):
    """(luminance [cd m^-2], R/B of linear sRGB) along the vertical opposite the sun."""
    from skydome.spectra import spectrum_to_xyz, xyz_to_linear_srgb
    from skydome.transport.geometry import direction_from_angles

    wl = _grid(wavelengths_nm)
    az = (sky.sun.azimuth_deg + 180.0) % 360.0
    d = direction_from_angles(np.asarray(elevations_deg, dtype=float), az)
    xyz = spectrum_to_xyz(sky.radiance(d, wl), wl)
    rgb = xyz_to_linear_srgb(xyz)
    with np.errstate(divide="ignore", invalid="ignore"):
        rb = np.where(rgb[:, 2] > 0, rgb[:, 0] / rgb[:, 2], np.nan)
    return xyz[:, 1], rb


def belt_of_venus(elevations_deg, red_blue, luminance=None) -> dict:
    """Locate the Belt of Venus and the earth's shadow in an anti-solar profile.

    The belt is the reddest point (maximum R/B) of the profile above 2 deg elevation; the
    earth's shadow is the band between the horizon and the belt, bluer (lower R/B) and, where
    ``luminance`` [cd m^-2] is given, darker than the belt.

    Parameters
    ----------
    elevations_deg : array_like
        Elevations along the anti-solar vertical [deg], increasing.
    red_blue : array_like
        R/B of linear sRGB at those elevations (:func:`anti_solar_profile`).
    luminance : array_like, optional
        Luminance at those elevations [cd m^-2].

    Returns
    -------
    dict
        ``belt_deg`` (elevation of the R/B maximum [deg]), ``belt_rb``, ``shadow_rb`` (the
        minimum R/B below the belt), ``contrast`` (belt_rb - shadow_rb), ``shadow_top_deg``
        (where R/B, rising from the shadow towards the belt, passes half way between the two
        [deg]), ``found`` (True where the belt is at least 0.05 redder than the shadow, lies
        above the profile's lowest point above 2 deg and below its highest point (a band,
        not R/B still rising at the profile's top) and the shadow band has a top); with
        ``luminance`` also ``belt_luminance`` and ``shadow_luminance`` (mean
        luminance below ``shadow_top_deg``) [cd m^-2].
    """
    e = np.asarray(elevations_deg, dtype=float)
    rb = np.asarray(red_blue, dtype=float)
    ok = (e >= 2.0) & np.isfinite(rb)
    if not ok.any():
        raise ValueError("elevations_deg: the profile needs finite R/B values above 2 deg")
    i = int(np.flatnonzero(ok)[np.argmax(rb[ok])])
    below = np.isfinite(rb) & (e < e[i])
    if below.any():
        j = int(np.flatnonzero(below)[np.argmin(rb[below])])
        shadow = float(rb[j])
        half = 0.5 * (shadow + rb[i])
        k = j + int(np.argmax(rb[j:i + 1] >= half))      # first point at or above half way
        top = float(e[k])
    else:
        shadow, top = float("nan"), float("nan")
    out = {"belt_deg": float(e[i]), "belt_rb": float(rb[i]), "shadow_rb": shadow,
           "contrast": float(rb[i] - shadow), "shadow_top_deg": top}
    # a band: the R/B maximum inside the profile (above its lowest point above 2 deg and
    # below its top, where R/B that still rises is no band), 0.05 redder than the shadow
    inner = int(np.flatnonzero(ok)[0]) < i < int(np.flatnonzero(ok)[-1])
    out["found"] = bool(out["contrast"] >= 0.05 and inner and np.isfinite(top))
    if luminance is not None:
        lum = np.asarray(luminance, dtype=float)
        out["belt_luminance"] = float(lum[i])
        sel = e < top
        out["shadow_luminance"] = float(np.mean(lum[sel])) if sel.any() else float("nan")
    return out
