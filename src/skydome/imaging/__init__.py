"""Rendering: sample any sky model through a projection into a :class:`SkyImage`.

>>> import skydome as sd
>>> sky = sd.model("single_scattering", sun=sd.Sun(elevation_deg=30, azimuth_deg=135))
>>> image = sd.render(sky, sd.Fisheye(256))
>>> image.save("sky.exr")

Nothing heavy is imported here (OpenEXR, Pillow and matplotlib load when used).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from skydome.imaging.image import SkyImage
from skydome.imaging.projections import AngularMap, Equirect, Fisheye, Projection, make_projection

__all__ = ["render", "Equirect", "Fisheye", "AngularMap", "make_projection", "SkyImage",
           "Projection"]


def _one_blas_thread(fn):
    """Run ``fn`` with BLAS limited to one thread and numpy's new arrays on small pages.

    The render path's products are skinny (a chunk of pixels times an (n x 3) matrix):
    OpenBLAS's thread pool, spin-waiting against numba's between the kernels, made them
    cost 0.3-3.3 s of CPU for the 8 M pixels of a 4096 x 2048 map against 0.04-0.1 s on
    one thread; one thread gives the same values. numpy advises transparent huge pages for
    large arrays, and on the 2-core EPYC virtual machine of docs/performance.md the first
    touch of a 2 MiB page is slow: a fresh process's first 4096 x 2048 map of
    preetham1999 took 4.7 s (3.2 s CPU) with them, 1.7 s (1.1 s) without. The previous
    advice is restored on return (the command line sets NUMPY_MADVISE_HUGEPAGE=0)."""
    import functools

    @functools.wraps(fn)
    def wrapped(*args, **kwargs):
        from threadpoolctl import threadpool_limits

        try:
            from numpy._core.multiarray import _set_madvise_hugepage
        except ImportError:                                    # numpy < 2
            try:
                from numpy.core.multiarray import _set_madvise_hugepage
            except ImportError:
                _set_madvise_hugepage = None
        prev = None if _set_madvise_hugepage is None else _set_madvise_hugepage(False)
        try:
            with threadpool_limits(limits=1, user_api="blas"):
                return fn(*args, **kwargs)
        finally:
            if prev is not None:
                _set_madvise_hugepage(prev)
    return wrapped


@_one_blas_thread
def render(sky, projection: Projection, wavelengths_nm=None, *,
           progress: Callable[[int, int], None] | None = None, draw_sun: bool = True,
           chunk: int = 262144, limb_darkening: bool = True, ground="model",
           output: str = "native") -> SkyImage:
    """Render a sky model into an image.

    Parameters
    ----------
    sky : SkyModel
        Any model. Spectral models (``native == "spectral"``) are sampled with
        ``sky.radiance(directions, wavelengths_nm)`` and give a spectral image; XYZ and
        luminance models with ``sky.xyz(directions)`` and give an XYZ image.
    projection : Projection
        Pixel layout (:class:`Fisheye`, :class:`Equirect`, :class:`AngularMap`).
    wavelengths_nm : array_like, optional
        Wavelengths [nm] for spectral models; default 16 samples 380-780 nm. Ignored for
        XYZ and luminance models.
    progress : callable, optional
        ``progress(done_pixels, total_pixels)``, called after every chunk.
    draw_sun : bool
        Draw the solar disc where the model has a sun with a radiance (see Notes). If
        False the image has no disc and ``image.sun_light`` holds the sun as a separate
        :class:`~skydome.imaging.sun_disc.SunLight` (direction, angular radius, spectral
        normal irradiance) for renderers that take it that way.
    chunk : int
        Directions per model call (>= 1), bounding memory use.
    limb_darkening : bool
        Give the disc the sun's centre-to-limb darkening (Neckel 2005; default) or, if
        False, a uniform radiance. Either way its flux is the model's.
    ground : {"model", "black", "lambertian"} or float
        What the pixels below the horizon show (:mod:`skydome.imaging.ground`): "model"
        (default) the model's own ground where it traces ground-hit rays, else a
        Lambertian ground of the model's albedo (0.2 without one) lit by its sky and sun;
        "black"; "lambertian", that Lambertian ground on every model; or an albedo in
        [0, 1] for a Lambertian ground of that albedo on every model.
    output : {"native", "xyz"}
        "native" (default): a spectral image for spectral models, XYZ for the others.
        "xyz": an XYZ image for every model, by the fused path: each chunk of the model's
        spectra goes straight to XYZ through one (n_model_wavelengths x 3) matrix (for
        models with a wavelength table, e.g. ``precomputed``, the table -> ``wavelengths_nm``
        resampling, the solar spectrum and the CMF integration weights of
        ``wavelengths_nm`` in one), so no spectral image is ever held: the same XYZ as
        ``render(...).xyz()`` to rounding, in a fraction of the time and memory. What
        PNG, HDR and EXR files need.

    Returns
    -------
    SkyImage
        Spectral radiance [W m^-2 sr^-1 nm^-1] or XYZ (Y in cd m^-2); masked pixels 0.

    Notes
    -----
    The sun: if ``draw_sun``, ``sky.sun`` is set, the model gives a sun radiance
    (:func:`~skydome.imaging.sun_disc.sun_disc_radiance`) and the sun's elevation exceeds
    minus its angular radius, the disc is drawn by
    :func:`~skydome.imaging.sun_disc.draw_sun_disc`: its limb-darkened radiance is
    distributed over the pixels it covers in proportion to the flux falling into each, so
    that the drawn flux sum (L - L_sky) Omega_pix equals the model's direct normal
    irradiance L_sun Omega_sun (times the part of the disc above the horizon) in any
    projection and for a disc of any size, smaller than a pixel included. The disc
    replaces the sky it covers. For XYZ images the sun's spectrum is converted to XYZ.
    """
    from skydome._validate import as_wavelengths, check_int

    if isinstance(sky, str):
        raise TypeError(f"sky must be a sky model, got the string {sky!r}: build the model first, "
                        f"e.g. skydome.model({sky!r}, sun=skydome.Sun(elevation_deg=30, azimuth_deg=180))")
    if not (callable(getattr(sky, "radiance", None)) or callable(getattr(sky, "xyz", None))):
        raise TypeError(f"sky must be a sky model (with radiance() or xyz()), got {type(sky).__name__}")
    if not isinstance(projection, Projection):
        raise TypeError(f"projection must be a skydome Projection, got {type(projection).__name__}")
    chunk = check_int("chunk", chunk, 1, None)
    from skydome.imaging.ground import apply_ground, check_ground

    ground = check_ground(ground)
    if progress is not None and not callable(progress):
        raise TypeError(f"progress must be callable or None, got {progress!r}")
    from skydome._validate import check_choice

    check_choice("output", output, ("native", "xyz"))
    native = getattr(sky, "native", "spectral")
    spectral = native == "spectral"
    fused = spectral and output == "xyz"
    if spectral:
        if wavelengths_nm is None:
            from skydome.spectra import wavelength_grid

            wl = wavelength_grid(380.0, 780.0, n=16)
        else:
            wl = as_wavelengths(wavelengths_nm)
        n_ch = wl.size
    else:
        wl = None
        n_ch = 3

    dirs, mask = projection.directions()
    H, W = projection.shape
    if fused:
        sample, to_xyz = _fused_sampler(sky, wl)
        n_ch = 3
    flat_dirs = dirs.reshape(-1, 3)
    on_ground = not np.any(np.asarray(getattr(projection, "position", (0.0, 0.0, 0.0))) != 0.0)
    # the pixels the model is sampled at: all the mask's, but those below the horizon where
    # the ground replaces them (black or Lambertian: apply_ground overwrites every one)
    sampled = mask
    if on_ground and ground != "model":
        sampled = mask & ~(dirs[..., 2] < 0.0)
    flat_s = sampled.reshape(-1)
    total = int(np.count_nonzero(flat_s))
    first = int(np.argmax(flat_s)) if total else 0
    # one run of pixels (a lat-long map's sky, cube faces): contiguous chunks, no gather
    # and scatter through an index array
    idx = None if bool(flat_s[first:first + total].all()) else np.flatnonzero(flat_s)
    data = np.zeros((H, W, n_ch), dtype=np.float64)
    flat_data = data.reshape(-1, n_ch)
    for start in range(0, total, chunk):
        rows = (slice(first + start, first + min(start + chunk, total)) if idx is None
                else idx[start:start + chunk])
        d = flat_dirs[rows]
        direct = False
        if fused and to_xyz is None:
            v = np.asarray(sample(d), dtype=np.float64)
        elif fused:
            s = np.asarray(sample(d), dtype=np.float64)
            direct = idx is None and s.shape == (d.shape[0], to_xyz.shape[0])
            if direct:
                # straight into the image's run of pixels (the same product, no copy)
                v = np.matmul(s, to_xyz, out=flat_data[rows])
            else:
                v = s @ to_xyz
        else:
            v = np.asarray(sky.radiance(d, wl) if spectral else sky.xyz(d), dtype=np.float64)
        if v.shape != (d.shape[0], n_ch):
            raise ValueError(f"model {getattr(sky, 'name', sky)!r} returned shape {v.shape}, "
                             f"expected {(d.shape[0], n_ch)}")
        if not np.all(np.isfinite(v)):
            raise ValueError(f"model {getattr(sky, 'name', sky)!r} returned NaN or infinite values")
        if not direct:
            flat_data[rows] = v
        if progress is not None:
            progress(min(start + chunk, total), total)
    if fused:
        spectral = False
    ground_info = None
    if on_ground:
        # an observer on the ground (a camera away from the origin sees no "horizon")
        ground_info = apply_ground(sky, data, dirs, mask, wl, ground,
                                   to_xyz=_xyz_weights(wl) if fused else None)

    sun = getattr(sky, "sun", None)
    sun_info = None
    if sun is not None:
        sun_info = {"elevation_deg": sun.elevation_deg, "azimuth_deg": sun.azimuth_deg,
                    "angular_radius_deg": sun.angular_radius_deg}
    sun_light = None
    if sun is not None and sun.elevation_deg > -sun.angular_radius_deg:
        from skydome.imaging import sun_disc

        if draw_sun:
            L_sun = sun_disc.sun_disc_radiance(sky, wl)
            if L_sun is not None and fused:
                L_sun = L_sun @ _xyz_weights(wl)
            if L_sun is not None:
                if L_sun.shape[0] != n_ch:
                    raise ValueError(f"sun radiance of model {getattr(sky, 'name', sky)!r} has "
                                     f"shape {L_sun.shape}, expected ({n_ch},)")
                ch_wl = wl if spectral else sun_disc.XYZ_CHANNEL_WAVELENGTHS_NM
                sun_disc.draw_sun_disc(data, projection, mask, sun, L_sun, ch_wl,
                                       limb_darkening=limb_darkening)
                sun_info["drawn"] = "limb-darkened disc" if limb_darkening else "uniform disc"
        else:
            sun_light = sun_disc.sun_light(sky, wl if spectral or fused else None)
            if sun_light is not None:
                sun_info["drawn"] = "left out (see the sun light)"

    meta = {}
    describe = getattr(sky, "describe", None)
    if callable(describe):
        desc = describe()
        meta["model"] = desc.get("model", getattr(sky, "name", ""))
        meta["reference"] = desc.get("reference", "")
        meta["parameters"] = desc.get("parameters", {})
    else:
        meta["model"] = getattr(sky, "name", type(sky).__name__)
    if sun_info is not None:
        meta["sun"] = sun_info
    if ground_info is not None:
        meta["ground"] = ground_info
    meta["projection"] = projection.describe()
    meta["quantity"] = ("spectral radiance [W m^-2 sr^-1 nm^-1]" if spectral
                        else "CIE 1931 XYZ, Y = luminance [cd m^-2]")
    if fused:
        meta["spectral_sampling"] = {"wavelengths_nm": [float(w) for w in wl],
                                     "path": "fused spectrum -> XYZ"}
    image = SkyImage(data, "spectral" if spectral else "xyz", wl if spectral else None, mask,
                     projection, meta)
    image.sun_light = sun_light
    # for the exposure's adapting luminance: not the projection's directions a second time
    image._above_horizon = (projection, dirs[..., 2] > 0.0)
    return image


def _xyz_weights(wl) -> np.ndarray:
    """(n_wl x 3) matrix: XYZ = L @ M, 683 lm/W times the CMF integration weights."""
    from skydome.constants import K_M
    from skydome.spectra import integration_weights

    return K_M * np.asarray(integration_weights(wl))


def _fused_sampler(sky, wl):
    """(sample(d) -> (n, n_model), M (n_model x 3)) with XYZ = sample(d) @ M; M None where
    sample(d) is XYZ itself.

    Models with ``_fused_xyz(wl, M)`` (a lookup linear in its table's values) return the
    XYZ sampler of their table times M.

    Models with a wavelength table (``radiance_table`` per unit solar irradiance on the
    table wavelengths and the linear ``_to_wavelengths`` resampling) are sampled on their
    table and the resampling folded into M: it is linear, so its matrix is its image of the
    identity. Models with ``_spectral_basis(wl)`` -> (sample, B), radiance = sample(d) @ B,
    are sampled on their basis and B folded into M. Other spectral models are sampled at
    ``wl``."""
    M = _xyz_weights(wl)
    # models whose value is a linear lookup in a table of their own (fitted): the table
    # times the spectrum's map to XYZ, looked up once per direction in three channels
    fused = getattr(sky, "_fused_xyz", None)
    if callable(fused):
        return fused(wl, M), None
    table = getattr(sky, "radiance_table", None)
    resample = getattr(sky, "_to_wavelengths", None)
    n_t = getattr(sky, "n_wavelengths", None)
    if callable(table) and callable(resample) and isinstance(n_t, (int, np.integer)):
        R = np.asarray(resample(np.eye(int(n_t)), wl), dtype=np.float64)  # (n_table, n_wl)
        if R.shape == (int(n_t), wl.size) and np.all(R >= 0.0):
            return table, R @ M
    # models whose spectrum is a fixed linear map of a few basis values per direction
    # (hosek_wilkie2012: 11 bands interpolated in wavelength): the map folded into M
    basis = getattr(sky, "_spectral_basis", None)
    if callable(basis):
        sample, B = basis(wl)
        B = np.asarray(B, dtype=np.float64)                  # (n_basis, n_wl)
        if B.ndim == 2 and B.shape[1] == wl.size:
            return sample, B @ M
    return (lambda d: sky.radiance(d, wl)), M
