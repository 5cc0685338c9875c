"""Warm what a new user's first commands need: compile the numba kernels of the default
render path and build the default ``precomputed`` tables into the on-disk cache.

Run once by ``./scripts/demo``'s set-up (``python -m skydome.apps.warmup``), so that the
first ``skydome render`` starts from compiled kernels and cached tables instead of paying
the compilation (about 10 s) and the precomputation (about 7 s on 2 cores).
"""

from __future__ import annotations

import time


#: Table sizes of the precomputation that compiles its kernels when the default tables
#: are cached already (:func:`warm`): small grids, the default 20 wavelengths (so that the
#: orders >= 3 run at a subset of them, as at the defaults).
PRECOMPUTE_WARM_SIZES = dict(scattering_r_size=8, scattering_mu_size=32, scattering_mu_s_size=16,
                             scattering_nu_size=8, transmittance_mu_size=64,
                             transmittance_r_size=16, irradiance_mu_s_size=16,
                             irradiance_r_size=8, sphere_samples=8, high_order_sphere_samples=8)


def warm_kernels(verbose: bool = True) -> float:
    """Compile the kernels of the default render path into numba's on-disk cache without
    touching the table cache: a small precomputation of the default atmosphere and
    wavelengths (:data:`PRECOMPUTE_WARM_SIZES`: the default tables' kernel specialisations,
    table sizes aside), a tiny fisheye from it and its display transform, and the fitted
    model's lookup (a tiny fisheye, luminance, spectral radiance). Run by the
    package build (``setup.py``) and by :func:`warm`; returns the seconds it took."""
    import skydome as sd
    from skydome.imaging import make_projection

    t0 = time.perf_counter()
    sun = sd.Sun(elevation_deg=30.0, azimuth_deg=180.0)
    model = sd.model("precomputed", sun=sun, cache=False, **PRECOMPUTE_WARM_SIZES)
    sd.render(model, make_projection("fisheye", "16"), output="xyz").to_srgb()
    # the fitted model: its lookup kernel (issue 29: no multi-second compilation on first
    # use; 1.8-3.8 s otherwise on 2 cores), in its luminance, XYZ and spectral forms
    fitted = sd.model("fitted", sun=sun)
    sd.render(fitted, make_projection("fisheye", "16"), output="xyz")
    fitted.luminance([[0.0, 0.6, 0.8]])
    fitted.radiance([[0.0, 0.6, 0.8]], [450.0, 550.0])
    if verbose:
        print(f"warm: default render path compiled ({time.perf_counter() - t0:.1f} s)",
              flush=True)
    return time.perf_counter() - t0


def warm(verbose: bool = True) -> float:
    """Build the default precomputed tables (cached), render a tiny image with the default
    model and the analytic models' kernels, and compile the sky-matrix kernel (``skydome
    skymatrix``); returns the seconds it took."""
    import skydome as sd
    from skydome.imaging import make_projection

    t0 = time.perf_counter()
    sun = sd.Sun(elevation_deg=30.0, azimuth_deg=180.0)
    proj = make_projection("fisheye", "16")
    for name, params in (("precomputed", {}), ("fitted", {}), ("single_scattering", {}),
                         ("preetham1999", {}),
                         ("perez1993", {"dni": 650.0, "dhi": 120.0}), ("cie2003", {"sky_type": 12})):
        t = time.perf_counter()
        model = sd.model(name, sun=sun, **params)
        image = sd.render(model, proj, output="xyz")
        if name == "precomputed":
            image.to_srgb()    # the picture's display path (the Hunt-gain kernel)
            if model.from_cache:
                # the default tables came from the cache, so the precomputation's kernels
                # were not compiled: a small precomputation of the default atmosphere and
                # wavelengths (the same kernel specialisations, table sizes aside) compiles
                # them, so that a first new atmosphere (turbidity, AOD, ...) does not pay
                # 1-1.5 min of compilation on top of its precomputation
                sd.model(name, sun=sun, cache=False, **PRECOMPUTE_WARM_SIZES)
        if verbose:
            print(f"warm: {name} ready ({time.perf_counter() - t:.1f} s)", flush=True)
    t = time.perf_counter()
    from skydome.daylighting.skymatrix import warm_kernels

    warm_kernels()
    if verbose:
        print(f"warm: sky matrices ready ({time.perf_counter() - t:.1f} s)", flush=True)
    return time.perf_counter() - t0


if __name__ == "__main__":
    import sys

    if sys.argv[1:] == ["--kernels"]:
        print(f"warm: kernels done in {warm_kernels():.1f} s")
    elif sys.argv[1:]:
        sys.exit("usage: python -m skydome.apps.warmup [--kernels]")
    else:
        print(f"warm: done in {warm():.1f} s")
