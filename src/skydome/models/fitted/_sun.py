"""The sun's disc of the ``fitted`` model: Beer's law along the ray to the sun's centre, as
the ``precomputed`` reference computes it.

The reference's disc ([Bru17] GetTransmittanceToSun; ``PrecomputedSky.sun_radiance``) is

    L_sun = E_sun / Omega_sun x exp(-sum_c col_c(r, mu_s) beta_c(lambda)) x v(r, mu_s),

col_c the column of constituent c (density integrated along the straight ray from radius r
to the top, zenith cosine mu_s: a table over (r, mu_s) in Bruneton's transmittance mapping,
``skydome.transport._tables.lookup_columns``), beta_c its extinction per unit density and v
the visible fraction of the disc (a smoothstep over the disc's angular radius around the
horizon, :func:`visible_fraction`). For the fitted model's atmospheres
(``Atmosphere.earth`` with the aerosol optical depth scaled, :func:`._dataset.atmosphere`)
every density profile is fixed (air 7994 m, aerosol 1200 m, water vapour 2000 m
exponential, ozone a tent at 25 +- 15 km): the columns are geometry alone and only the
aerosol's beta depends on the AOD, in proportion to it. So the model ships

* ``sun_columns`` (n_c, n_r, n_mu): the reference's own column table (the same kernel,
  ``precomputed._precompute.transmittance_columns``, the same mapping and sizes: 64 x 256),
  computed from the profiles by :func:`derive` (tools/fit_fitted.py), never from the
  reference's sun radiance;
* ``sun_profiles`` (3, n_c): the rows' density profiles (kernel code and its two
  parameters), which the model checks against the atmosphere's;
* ``sun_geometry``: the planet's and the top's radii [m];

and looks the columns up as the reference does (bilinear in the transmittance mapping; a
ray below the observer's horizon reads the horizon's columns: the mapping clamps there, as
in the reference). The extinction spectra beta_c come from the atmosphere itself at the
wavelengths asked for (:func:`extinction`: ``Atmosphere.optical_properties``, 4-9 ms per
wavelength set, cached per model): Beer's law at every wavelength, where interpolating T
between table wavelengths 10-20 nm apart would miss the steep spectrum of a long path (at
the horizon 30-68 % off the reference computed at the 10-nm wavelengths themselves).
"""

from __future__ import annotations

import math

import numpy as np

#: The arrays this module adds to the coefficient file.
SUN_KEYS = ("sun_columns", "sun_profiles", "sun_geometry")


def derive(wavelengths_nm) -> dict:
    """The sun's arrays (module docstring), from ``Atmosphere.earth``'s profiles (its
    spectra at ``wavelengths_nm`` for the checks) (:func:`._dataset.atmosphere`) with the
    reference's column kernel and table sizes. Checks that the profiles do not depend on
    the AOD and that beta is linear in it (ValueError otherwise)."""
    from skydome.models.fitted._dataset import atmosphere
    from skydome.models.simulated.precomputed import PrecomputedSky
    from skydome.models.simulated.precomputed._precompute import transmittance_columns
    from skydome.transport._medium import medium_from_properties

    wl = np.asarray(wavelengths_nm, dtype=np.float64)
    # albedo does not enter the columns or beta; fold=True as the reference (absorbers that
    # share a profile folded into one row: exact)
    props = {a: atmosphere(a, 0.0).optical_properties(wl, fold=True)
             for a in (0.0, 0.18, 0.7, 1.0)}
    p0 = props[0.0]
    for a, p in props.items():
        for k in ("profile_code", "profile_p0", "profile_p1"):
            if not np.array_equal(getattr(p, k), getattr(p0, k)):
                raise ValueError(f"the density profiles depend on the AOD ({k} at AOD {a})")
    e0 = np.asarray(p0.extinction, dtype=np.float64)
    e1 = np.asarray(props[1.0].extinction, dtype=np.float64) - e0
    for a in (0.18, 0.7):
        lin = e0 + a * e1
        if not np.allclose(props[a].extinction, lin, rtol=1e-12, atol=0.0):
            raise ValueError(f"the extinction is not linear in the AOD (at AOD {a})")
    sizes = {p.name: p.default for p in PrecomputedSky.parameters
             if p.name in ("transmittance_r_size", "transmittance_mu_size")}
    cols = transmittance_columns(medium_from_properties(p0), sizes)
    return {"sun_columns": np.ascontiguousarray(cols, dtype=np.float64),
            "sun_profiles": np.stack([np.asarray(p0.profile_code, dtype=np.float64),
                                      np.asarray(p0.profile_p0, dtype=np.float64),
                                      np.asarray(p0.profile_p1, dtype=np.float64)]),
            "sun_geometry": np.array([float(p0.planet_radius_m), float(p0.top_radius_m)])}


def extinction(c: dict, aod: float, wavelengths_nm) -> np.ndarray:
    """beta_c [per unit column] of the rows of ``sun_columns`` at ``wavelengths_nm``: (n_c,
    n), from the model's atmosphere at ``aod`` (:func:`._dataset.atmosphere`, absorbers
    folded as in the reference); ValueError if its profiles are not the file's."""
    from skydome.models.fitted._dataset import atmosphere

    p = atmosphere(aod, 0.0).optical_properties(wavelengths_nm, fold=True)
    prof = np.stack([np.asarray(p.profile_code, dtype=np.float64),
                     np.asarray(p.profile_p0, dtype=np.float64),
                     np.asarray(p.profile_p1, dtype=np.float64)])
    if prof.shape != c["sun_profiles"].shape or not np.array_equal(prof, c["sun_profiles"]):
        raise ValueError("the atmosphere's density profiles are not those of the coefficient "
                         "file's sun columns (rerun tools/fit_fitted.py --add-sun)")
    return np.asarray(p.extinction, dtype=np.float64)


def transmittance(c: dict, mu_s: float, altitude_m: float, beta) -> np.ndarray:
    """Transmittance along the ray from the observer (``altitude_m`` above the ground) to
    the top, zenith cosine ``mu_s``, for the extinction spectra ``beta`` (n_c, n) of
    :func:`extinction`: (n,), in [0, 1]."""
    from skydome.transport._tables import lookup_columns

    R, Rt = (float(x) for x in c["sun_geometry"])
    col = np.empty(c["sun_columns"].shape[0])
    lookup_columns(c["sun_columns"], R + float(altitude_m), float(mu_s), R, Rt, col)
    return np.exp(-(np.maximum(col, 0.0) @ beta))


def visible_fraction(c: dict, mu_s: float, altitude_m: float,
                     angular_radius_deg: float) -> float:
    """Fraction of the sun's disc above the horizon of an observer ``altitude_m`` above the
    ground, the rule of the reference ([Bru17] GetTransmittanceToSun, ``precomputed``'s
    ``_lookup.sun_visible_fraction``): with sin h = R / r and cos h = -sqrt(1 - sin^2 h)
    the horizon's zenith cosine, e = sin h x alpha (the disc's radius in mu_s at the
    horizon), x = (mu_s - cos h + e) / (2 e), v = smoothstep(x) = x^2 (3 - 2x) on [0, 1]."""
    R = float(c["sun_geometry"][0])
    sin_h = R / (R + float(altitude_m))
    cos_h = -math.sqrt(max(1.0 - sin_h * sin_h, 0.0))
    e = sin_h * math.radians(float(angular_radius_deg))
    x = (float(mu_s) - cos_h + e) / (2.0 * e)
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    return x * x * (3.0 - 2.0 * x)
