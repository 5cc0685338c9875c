"""Sky matrices: one row of sky-patch values per hour (and a sun matrix), from perez1993.

A sky matrix holds, for every hour h and patch p, the mean radiance of the patch. Its units
follow Radiance: "visible radiance" [W sr^-1 m^-2] = luminance / 179 lm W^-1 (WHTEFFICACY),
so that rcontrib/dctimestep results times 179 are illuminances in lux. Components:

- ``rgb``: Radiance's three channels; the sky patches are tinted by gendaymtx's default sky
  colour (0.96, 1.004, 1.118) (Y-weighted brightness 0.99975), the sun is white and the
  ground grey, as gendaymtx does;
- ``luminance``: one component, luminance [cd m^-2] (no tint).

Perez skies are computed as gendaymtx does them ([PSM93] distribution, [PISMS90] sky
parameters and efficacies, normalised so that the patches' horizontal illuminance equals the
diffuse horizontal illuminance), for all hours in one call of a numba kernel over
(hours x quadrature nodes), with the node set of the patches computed once.

The sun, three ways (``sun=``):

- ``"spread"`` (gendaymtx's default): the direct normal illuminance goes into the 4 patches
  whose centres are nearest the sun, weighted by 1 / (1.002 - cos angle), as radiance over
  each patch's solid angle; ``"spread:N"`` uses N patches (1..4);
- ``"disc:ANGLE"`` (gendaymtx -5 ANGLE): all of it into the nearest patch, as the radiance of
  a disc of full angle ANGLE [deg] (for a five-phase run's sun-patch separation);
- ``"separate"``: not in the sky matrix; a sun matrix (hours x components) holds the radiance
  of the solar disc (full angle 0.533 deg) and ``sun_directions`` its direction each hour,
  nothing blurred (gendaymtx -D);
- ``"none"``: sky only (gendaymtx -s).

Ground patch 0: reflectance x (Dh + Dn sin a) / pi / 179 (gendaymtx).

References
----------
[PSM93], [PISMS90] as in :mod:`skydome.models.analytic.perez1993`; G. Ward, ``gendaymtx``
(Radiance 5.4): the treatment of the sun, the ground, and the sky's colour.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from skydome.constants import RADIANCE_SUN_ANGLE_DEG, RADIANCE_WHITE_EFFICACY
from skydome.daylighting.patches import AdaptiveRule, PatchSet, patches as _patches

__all__ = ["SkyMatrix", "perez_sky_matrix", "model_sky_matrix", "parse_sun_option",
           "weather_model_sky_matrix", "parse_components", "weather_aod",
           "GENDAYMTX_SKY_COLOR", "start_numba_without_blas",
           "SUN_ANGLE_DEG", "DEFAULT_ORDER", "PEREZ_DEFAULT_ORDER", "quadrature_rule",
           "warm_kernels", "perez_sky_matrix_file"]

#: gendaymtx's default sky colour (its -c default, Radiance 5.4).
GENDAYMTX_SKY_COLOR = (0.96, 1.004, 1.118)
#: Radiance's luminous efficacy of white light [lm W^-1] (color.h WHTEFFICACY).
WHITE_EFFICACY = RADIANCE_WHITE_EFFICACY
#: Full angle of the solar disc in gendaymtx (SUN_ANG_DEG) [deg].
SUN_ANGLE_DEG = RADIANCE_SUN_ANGLE_DEG  # Radiance's disc, full angle [deg]
#: Default quadrature order per patch of a model's sky matrix (q x q Gauss-Legendre nodes;
#: see patches).
DEFAULT_ORDER = 4
#: Default patch quadrature of the Perez sky matrices: the adaptive rule (AdaptiveRule()).
PEREZ_DEFAULT_ORDER = "adaptive"
_NSUNPATCH = 4


@dataclass
class SkyMatrix:
    """A sky matrix and, with ``sun="separate"``, its sun matrix.

    Attributes
    ----------
    patches : PatchSet
    sky : numpy.ndarray
        (n_hours, n_patches, n_components) [W sr^-1 m^-2] (``rgb``) or [cd m^-2]
        (``luminance``); from :func:`perez_sky_matrix` a view of an array stored in
        Radiance's file order (patches, hours, components).
    components : str
    sun : numpy.ndarray or None
        (n_hours, n_components) radiance of the solar disc, same units (``sun="separate"``).
    sun_directions : numpy.ndarray
        (n_hours, 3) unit vectors towards the sun (ENU).
    sun_solid_angle_sr : float
        Solid angle of the disc the sun matrix's radiance is spread over [sr].
    """

    patches: PatchSet
    sky: np.ndarray
    components: str
    sun: np.ndarray | None
    sun_directions: np.ndarray
    sun_solid_angle_sr: float

    def radiance_layout(self) -> np.ndarray:
        """The sky matrix in Radiance's file order: (n_patches, n_hours, n_components) (no
        copy for a matrix from :func:`perez_sky_matrix`, which is stored in that order)."""
        return np.ascontiguousarray(np.swapaxes(self.sky, 0, 1))


def parse_sun_option(sun: str) -> tuple[str, int, float]:
    """("spread", n, 0) / ("disc", 1, angle_deg) / ("separate", 0, 0) / ("none", 0, 0)."""
    if not isinstance(sun, str):
        raise TypeError(f"sun must be a string, got {sun!r}")
    s = sun.strip().lower()
    if s in ("separate", "none"):
        return s, 0, 0.0
    if s == "spread":
        return "spread", _NSUNPATCH, 0.0
    if s.startswith("spread:") and s[7:].isdigit() and 1 <= int(s[7:]) <= _NSUNPATCH:
        return "spread", int(s[7:]), 0.0
    if s.startswith("disc:"):
        try:
            ang = float(s[5:])
        except ValueError:
            ang = float("nan")
        if math.isfinite(ang) and 0.0 < ang <= 20.0:
            return "disc", 1, ang
    raise ValueError(f"sun = {sun!r} is unknown; use 'spread', 'spread:N' (N in 1..4), "
                     "'disc:ANGLE' (full angle in (0, 20] deg), 'separate' or 'none'")


def quadrature_rule(ps: PatchSet, order):
    """The node sets the Perez kernel takes for ``order``: an int 0..16 (q x q nodes on every
    patch, 0 = the centre), "adaptive" (``AdaptiveRule.default_for(ps)``, see
    :class:`~skydome.daylighting.patches.AdaptiveRule`) or an AdaptiveRule. Returns (nodes, weights, offsets (T, n_sky + 1), cos_tier
    (T, n_sky)); a fixed order is one rule (T = 1)."""
    from skydome._validate import check_int

    if isinstance(order, str) and order.strip().lower() == "adaptive":
        order = AdaptiveRule.default_for(ps)
    if isinstance(order, AdaptiveRule):
        return order.nodes(ps)
    if isinstance(order, str):
        raise ValueError(f"order = {order!r} is unknown; use an integer in [0, 16] or "
                         "'adaptive'")
    order = check_int("order", order, 0, 16)
    nodes, weights, offsets = ps.nodes(order)
    cos_tier = np.full((1, ps.n_sky), -2.0)
    cos_tier.setflags(write=False)  # read-only as the tiered rules': one compiled kernel
    return nodes, weights, offsets[None, :], cos_tier


def perez_sky_matrix(dni, dhi, sun_directions, day_of_year, *, patches="tregenza",
                     order=PEREZ_DEFAULT_ORDER, sun: str = "spread", components: str = "rgb",
                     dew_point_c=11.0, ground_reflectance=0.2,
                     sky_color=GENDAYMTX_SKY_COLOR, dtype=np.float64,
                     out=None, backend: str = "auto") -> SkyMatrix:
    """Perez (1993) sky matrix of many hours in one vectorised pass.

    Parameters
    ----------
    dni, dhi : array_like
        (n,) direct normal and diffuse horizontal irradiance [W m^-2].
    sun_directions : array_like
        (n, 3) unit vectors towards the sun (ENU), e.g. ``Weather.sun_directions``.
    day_of_year : array_like
        (n,) 1..366 (sun-earth distance).
    patches : str or PatchSet
        "tregenza" or "reinhart:MF".
    order : int, "adaptive" or AdaptiveRule
        Patch quadrature: an int 0..16 takes q x q Gauss-Legendre nodes on every patch (0 =
        gendaymtx's point sample at each patch centre); "adaptive" (default) takes
        ``AdaptiveRule.default_for(patches)``: at MF >= 2 order 8 on the patches within 5 deg
        of the sun, 3 within 10 deg, 2 elsewhere (4 in altitude below 6 deg); over every
        lit hour of the sample year (Greensboro TMY3) every patch mean is within 0.07 % of
        order 16 at Tregenza and MF:4 for 1/3 (MF:4) to 1 (Tregenza) times order 4's nodes
        (docs/daylighting.md, section 2); point sampling (order 0) errs by up to 41 % (Tregenza) and 10 % (MF:4), in
        the circumsolar patches.
    sun : str
        "spread" (default, gendaymtx), "spread:N", "disc:ANGLE", "separate" or "none".
    components : {"rgb", "luminance"}
    dew_point_c : array_like
        Surface dew point [deg C] per hour or one value (gendaymtx: 11 for .wea input).
    ground_reflectance : float or array_like
        Ground albedo per hour or one value, in [0, 1] (default 0.2, gendaymtx's -g).
    sky_color : 3 floats
        RGB tint of the sky patches (``rgb`` only; default gendaymtx's).
    dtype : numpy.float64 or numpy.float32
        Storage of the matrix (computed in float64 either way); float32 halves the memory
        of an annual MF:4 RGB matrix (485 MB -> 242 MB) and is what a "float" file holds.
    out : numpy.ndarray, optional
        A zero-filled C-contiguous (patches, hours, components) array of ``dtype`` in
        Radiance's file order, e.g. the memory map of the output file's body
        (:func:`~skydome.daylighting.radiance_io.matrix_file`): the matrix is filled into it
        and ``sky`` is its (hours, patches, components) view, so that writing the file needs
        no transposed copy (1.7 s for an annual MF:4 matrix on a 2-core EPYC). Without it the
        matrix is allocated in the same order.
    backend : {"auto", "numpy", "numba"}
        "numba": the parallel kernel of :mod:`skydome.daylighting._kernels` (every rule);
        "numpy": the same arithmetic vectorised with numpy over blocks of hours
        (:mod:`skydome.daylighting._numpy_sky`; every rule: the adaptive one as its far rule
        for every patch-hour, then the patch-hours nearer the sun with their finer rule),
        which needs no numba (its import is 0.4-0.5 s of a run's start-up); "auto" (the
        default) takes numpy. Both give the same float64 matrix to rounding (relative
        1e-12; 1.2e-14 measured for the adaptive rule over the sample year), not bit for
        bit; a float32 matrix from "numpy" is the float32 product of the float32-rounded
        patch mean and hour factor, within 2.4e-7 relative of the kernel's once-rounded
        value (docs/daylighting.md, "Backends and the fast command line"), and "numpy"
        raises ValueError on a value that is not finite in ``dtype``. "numba" reproduces
        the bits of results made before "auto" became the default.

    Returns
    -------
    SkyMatrix
    """
    from skydome._validate import check_choice
    from skydome.models.analytic.perez1993 import (COS_ZETA_MIN,
                                                    perez1993_coefficients_many,
                                                    perez1993_sky_parameters)

    ps = patches if isinstance(patches, PatchSet) else _patches(patches)
    rule = quadrature_rule(ps, order)
    use_numpy = _numpy_backend(backend, rule, order)
    mode, nsuns, disc_deg = parse_sun_option(sun)
    check_choice("components", components, ("rgb", "luminance"))
    dni = np.atleast_1d(np.asarray(dni, dtype=np.float64))
    dhi = np.atleast_1d(np.asarray(dhi, dtype=np.float64))
    # Own (writable) copies of what reaches the kernel: a read-only argument (a broadcast,
    # an array from a Dask worker) would make numba compile another specialisation.
    sd = np.array(sun_directions, dtype=np.float64).reshape(-1, 3)
    n = dni.shape[0]
    if dni.shape != (n,) or dhi.shape != (n,) or sd.shape != (n, 3):
        raise ValueError(f"dni {dni.shape}, dhi {dhi.shape} and sun_directions {sd.shape} "
                         "must be (n,), (n,) and (n, 3)")
    for name, v in (("dni", dni), ("dhi", dhi)):
        if np.any(~np.isfinite(v)) or np.any(v < 0.0):
            k = int(np.argmax(~np.isfinite(v) | (v < 0.0)))
            raise ValueError(f"{name}[{k}] = {v[k]:g} W/m^2 is out of range [0, inf)")
    if not np.all(np.isfinite(sd)):
        raise ValueError("sun_directions holds non-finite values")
    norm = np.linalg.norm(sd, axis=-1)
    if np.any(np.abs(norm - 1.0) > 1e-6):
        raise ValueError("sun_directions must be unit vectors")
    doy = np.broadcast_to(np.asarray(day_of_year), (n,)).astype(np.int64)
    if np.any(doy < 1) or np.any(doy > 366):
        raise ValueError(f"day_of_year = {doy.min()}..{doy.max()} is out of range [1, 366]")
    td = np.broadcast_to(np.asarray(dew_point_c, dtype=np.float64), (n,))
    if np.any(~np.isfinite(td)) or np.any(td < -70.0) or np.any(td > 40.0):
        raise ValueError("dew_point_c must be finite, in [-70, 40] degC")
    rho = np.array(np.broadcast_to(np.asarray(ground_reflectance, dtype=np.float64), (n,)))
    if np.any(~np.isfinite(rho)) or np.any(rho < 0.0) or np.any(rho > 1.0):
        raise ValueError("ground_reflectance must be in [0, 1]")
    tint = np.asarray(sky_color, dtype=np.float64)
    if tint.shape != (3,) or np.any(~np.isfinite(tint)) or np.any(tint < 0.0):
        raise ValueError(f"sky_color = {sky_color!r} must be 3 numbers >= 0")

    ncomp = 3 if components == "rgb" else 1
    sky_tint = tint if components == "rgb" else np.ones(1)
    out_scale = 1.0 / WHITE_EFFICACY if components == "rgb" else 1.0  # lm -> Radiance units
    grey = np.ones(ncomp)

    # -- per hour: sky parameters (vectorised), sun vector of the distribution ------------------
    alt = np.arcsin(np.clip(sd[:, 2], -1.0, 1.0))  # true altitude
    zen_true = np.degrees(0.5 * np.pi - alt)
    par = perez1993_sky_parameters(dni, dhi, zen_true, doy, td)
    zc = np.radians(par.sun_zenith_deg)
    azi = np.arctan2(sd[:, 0], sd[:, 1])
    s_dist = np.stack([np.sin(zc) * np.sin(azi), np.sin(zc) * np.cos(azi), np.cos(zc)], axis=-1)
    coef = perez1993_coefficients_many(zc, par.epsilon, par.delta)
    e_diff = np.maximum(par.diffuse_illuminance, 0.0)
    e_dir = np.maximum(par.direct_illuminance, 0.0)
    day = (dni + dhi) > 1e-4  # gendaymtx: "effectively nighttime" below

    npatch = len(ps)
    dtype = np.dtype(dtype)
    if dtype not in (np.dtype(np.float64), np.dtype(np.float32)):
        raise ValueError(f"dtype = {dtype} must be float64 or float32")
    # Both backends fill a zero-filled C-contiguous (P, H, C) array in Radiance's file order
    # (unlit hours stay zero); ``sky`` is its (H, P, C) view.
    if out is not None:
        if not isinstance(out, np.ndarray) or out.shape != (npatch, n, ncomp) or \
                out.dtype != dtype or not out.flags.c_contiguous or not out.flags.writeable:
            raise ValueError(f"out must be a writeable C-contiguous ({npatch}, {n}, {ncomp}) "
                             f"{dtype} array, got {getattr(out, 'shape', None)} "
                             f"{getattr(out, 'dtype', None)}")
        file_order = out
    else:
        file_order = np.zeros((npatch, n, ncomp), dtype=dtype)
    sun_sa = math.pi * math.radians(SUN_ANGLE_DEG / 2.0) ** 2
    fixed_sa = math.pi * math.radians(disc_deg / 2.0) ** 2 if mode == "disc" else 0.0
    n_sun_patches = nsuns if mode in ("spread", "disc") else 0
    tints = np.ascontiguousarray(sky_tint * np.ones(ncomp))
    if use_numpy:
        from skydome.daylighting import _numpy_sky as NS

        tiers = None if rule[2].shape[0] == 1 else (rule[2], rule[3], ps.centres[1:])
        NS.fill_perez_sky(file_order, day, rule[0], rule[1], rule[2][-1], s_dist, coef, e_diff,
                          COS_ZETA_MIN, ps.centres[1:], ps.solid_angle_sr[1:], sd, e_dir, rho,
                          tints, grey, out_scale, n_sun_patches, fixed_sa, tiers)
    else:
        import numba

        from skydome.daylighting import _kernels as DK

        DK.fill_perez_sky(file_order, np.ascontiguousarray(day), *rule,
                          np.ascontiguousarray(ps.centres[1:]), ps.solid_angle_sr[1:],
                          np.ascontiguousarray(s_dist), np.ascontiguousarray(sd),
                          np.ascontiguousarray(coef), e_diff, e_dir, np.ascontiguousarray(rho),
                          tints, grey, out_scale, n_sun_patches, fixed_sa, COS_ZETA_MIN,
                          numba.get_num_threads())
    sky = np.swapaxes(file_order, 0, 1)
    sun_mat = None
    if mode == "separate":
        up = day & (alt > -math.radians(SUN_ANGLE_DEG / 2.0))  # gendaymtx -D: sun in the sky
        sun_mat = (np.where(up, e_dir, 0.0) * out_scale / sun_sa)[:, None] * grey[None, :]
    return SkyMatrix(ps, sky, components, sun_mat, sd.copy(),
                     sun_sa if mode == "separate" else fixed_sa)


def _numpy_backend(backend, rule, order) -> bool:
    """Whether ``backend`` ("auto", "numpy" or "numba") computes with the numpy backend for the
    quadrature ``rule`` (of :func:`quadrature_rule`, a fixed order or the tiered adaptive
    rule): "numpy" and "auto" do (numpy's block-vectorised ``arccos``/``exp`` beat the strict
    IEEE kernel's scalar libm calls, and a process that needs no numba skips its 0.5-0.7 s
    start-up), "numba" does not."""
    from skydome._validate import check_choice

    backend = check_choice("backend", backend, ("auto", "numpy", "numba"))
    return backend in ("numpy", "auto")


def start_numba_without_blas() -> bool:
    """Initialise numba's CPU target without importing SciPy's BLAS bindings (for a process
    that only runs the sky-matrix kernels, e.g. ``skydome skymatrix``); True if it did.
    The Perez kernels use no BLAS. See :func:`skydome._numba_start.start_numba_without_blas`."""
    from skydome._numba_start import start_numba_without_blas as start

    return start()


def warm_kernels() -> None:
    """Compile (or load from numba's on-disk cache) the sky-matrix kernel in both storage
    types, float32 (a "float" matrix file, filled in place) and float64 (the default), on
    two hours of a tiny patch set, so that a first ``skydome skymatrix`` loads compiled code
    instead of compiling it (about 4 s per type on a 2-core EPYC)."""
    sd = np.array([[0.0, -0.5, math.sqrt(0.75)]] * 2)
    for dtype in (np.float32, np.float64):
        ps = _patches("tregenza")
        out = np.zeros((len(ps), 2, 3), dtype=dtype)
        perez_sky_matrix([600.0, 0.0], [100.0, 0.0], sd, [172, 172], patches=ps, order=0,
                         dtype=dtype, out=out)


def perez_sky_matrix_from_weather(weather, sun_position: str = "spa", **kwargs) -> SkyMatrix:
    """:func:`perez_sky_matrix` of every hour of a :class:`~skydome.daylighting.weather.Weather`
    (its sun at the hours' midpoints, its dew point where the file has one).

    ``sun_position``: "spa" (NREL SPA, default) or "radiance" (Radiance's approximate
    formulas, to reproduce gendaymtx; up to 0.9 deg off)."""
    from skydome._validate import check_choice

    check_choice("sun_position", sun_position, ("spa", "radiance"))
    sd = weather.spa_sun_directions() if sun_position == "spa" else weather.radiance_sun_directions()
    kw = dict(kwargs)
    if "dew_point_c" not in kw and weather.dew_point_c is not None:
        td = np.where(np.isfinite(weather.dew_point_c), weather.dew_point_c, 11.0)
        kw["dew_point_c"] = td
    _note_beyond_clear_sky(weather, sd)
    return perez_sky_matrix(weather.dni, weather.dhi, sd, weather.day_of_year, **kw)


class ClearSkyNote(UserWarning):
    """One-line note: hours whose direct beam is beyond the clear-sky limit (gendaylit's
    rule), kept as gendaymtx keeps them."""


def _note_beyond_clear_sky(weather, sun_directions) -> np.ndarray:
    """Flag the hours (sun up) whose DNI/DHI are beyond the clear-sky limit by gendaylit's
    rule (:func:`~skydome.models.analytic.perez1993.clear_sky_limit_exceeded`) with one
    :class:`ClearSkyNote` counting them; the matrix keeps them as gendaymtx does (it has no
    such check). Returns the mask."""
    from skydome.models.analytic.perez1993 import clear_sky_limit_exceeded

    zen = np.degrees(np.arccos(np.clip(np.asarray(sun_directions)[:, 2], -1.0, 1.0)))
    bad = (zen < 90.0) & clear_sky_limit_exceeded(weather.dni, weather.dhi, zen,
                                                   weather.day_of_year)
    n = int(np.sum(bad))
    if n:
        import warnings

        k = int(np.argmax(bad))
        warnings.warn(f"weather = {weather.path!r}: {n} hour(s) beyond the clear-sky limit "
                      f"(gendaylit's rule; first: record {k + 1}, {weather.time[k]}, DNI "
                      f"{weather.dni[k]:g} W/m^2, DHI {weather.dhi[k]:g} W/m^2), kept as "
                      "gendaymtx keeps them", ClearSkyNote, stacklevel=3)
    return bad


def perez_sky_matrix_file(path, weather, *, sun_position: str = "spa", fmt: str = "float",
                          info=(), overwrite: bool = False, **kwargs) -> SkyMatrix:
    """:func:`perez_sky_matrix_from_weather` written to a binary Radiance matrix file
    (``fmt`` "float" or "double"), without holding a second copy of it: either backend fills
    the memory map of the file's zero-filled body
    (:func:`~skydome.daylighting.radiance_io.matrix_file`) in place. The file appears only
    when complete. ``kwargs`` as :func:`perez_sky_matrix` (not ``dtype``/``out``: the format
    gives the type). Returns the SkyMatrix; its ``sky`` is a read-only memory map of the
    written file."""
    from skydome._validate import check_choice
    from skydome.daylighting.radiance_io import matrix_file

    check_choice("fmt", fmt, ("float", "double"))
    for k in ("dtype", "out"):
        if k in kwargs:
            raise TypeError(f"perez_sky_matrix_file() takes no {k!r}")
    dtype = np.float32 if fmt == "float" else np.float64
    ps = kwargs.get("patches", "tregenza")
    ps = kwargs["patches"] = ps if isinstance(ps, PatchSet) else _patches(ps)
    ncomp = 3 if kwargs.get("components", "rgb") == "rgb" else 1
    shape = (len(ps), len(weather), ncomp)
    order = kwargs.get("order", PEREZ_DEFAULT_ORDER)
    # the numpy backend checks every value it writes (and raises): no second reading of the map
    backend = kwargs.get("backend", "auto")
    checked = backend != "numba" and _numpy_backend(backend, quadrature_rule(ps, order), order)
    with matrix_file(path, *shape, fmt=fmt, info=info, overwrite=overwrite,
                     check_finite=not checked) as body:
        m = perez_sky_matrix_from_weather(weather, sun_position=sun_position, dtype=dtype,
                                          out=body, **kwargs)
    body = np.memmap(path, dtype=dtype, mode="r", shape=shape, offset=_data_offset(path))
    m.sky = np.swapaxes(body, 0, 1)
    return m


def _data_offset(path) -> int:
    """Offset of a binary Radiance matrix file's data: after its header's blank line."""
    with open(path, "rb") as f:
        head = f.read(1 << 16)
    k = head.find(b"\n\n")
    if k < 0:
        raise ValueError(f"{str(path)!r}: no end of header in its first 64 KiB")
    return k + 2


def model_sky_matrix(make_model, n_hours: int, *, patches="tregenza",
                     order: int = DEFAULT_ORDER, components: str = "luminance",
                     wavelengths_nm=None, zarr_path=None, chunk_hours: int = 168):
    """Sky matrix of any skydome model: patch means of its luminance or spectral radiance.

    Parameters
    ----------
    make_model : callable
        ``make_model(h)`` -> the SkyModel of hour ``h`` (e.g. a precomputed sky with that
        hour's aerosol optical depth), or None for a black hour (night).
    n_hours : int
    patches, order : the patch quadrature (see :mod:`skydome.daylighting.patches`).
    components : {"luminance", "spectral"}
        Luminance [cd m^-2] (1 component) or spectral radiance [W m^-2 sr^-1 nm^-1] at
        ``wavelengths_nm`` (default: skydome's 41-sample grid).
    zarr_path : str or Path, optional
        Write a Zarr array (hours, patches, components) instead of returning the matrix,
        one chunk of ``chunk_hours`` hours at a time: memory holds one chunk, never the whole
        matrix (MF:6 spectral over a year is 8760 x 5186 x 41 x 8 bytes = 15 GB). The ground
        patch 0 is left 0 (the models' ground is not modelled here). The folder must not
        exist; it is removed again on any exception, Ctrl-C or SIGTERM before the call
        returns (a full disk: OSError ENOSPC), so nothing partial is left.

    Returns
    -------
    numpy.ndarray (hours, patches, components), or the zarr array when ``zarr_path`` is given.
    """
    from skydome._validate import check_choice, check_int

    ps = patches if isinstance(patches, PatchSet) else _patches(patches)
    order = check_int("order", order, 0, 16)
    n_hours = check_int("n_hours", n_hours, 1, None)
    chunk_hours = check_int("chunk_hours", chunk_hours, 1, None)
    check_choice("components", components, ("luminance", "spectral"))
    if components == "spectral":
        from skydome.spectra import default_wavelengths

        wl = default_wavelengths() if wavelengths_nm is None else np.asarray(
            wavelengths_nm, dtype=np.float64)
        ncomp = int(wl.size)
    else:
        wl, ncomp = None, 1
    nodes, weights, offsets = ps.nodes(order)
    starts = offsets[:-1]
    dom = np.add.reduceat(weights, starts)
    shape = (n_hours, len(ps), ncomp)
    if zarr_path is None:
        return _fill_matrix(None, make_model, n_hours, chunk_hours, ps, ncomp, wl, nodes,
                            weights, starts, dom)
    import os
    import shutil
    from pathlib import Path

    import zarr

    from skydome._io import temporary

    zp = Path(zarr_path)
    if zp.exists():
        raise ValueError(f"out = {str(zp)!r} exists")
    # the folder is this call's until it returns: removed on an exception, Ctrl-C or SIGTERM
    with temporary(zp, is_dir=True):
        try:
            store = zarr.open_array(str(zp), mode="w-", shape=shape,
                                    chunks=(min(chunk_hours, n_hours), len(ps), ncomp),
                                    dtype="f8", fill_value=0.0)
            return _fill_matrix(store, make_model, n_hours, chunk_hours, ps, ncomp, wl,
                                nodes, weights, starts, dom)
        except OSError as exc:
            shutil.rmtree(zp, ignore_errors=True)
            if exc.errno is None or exc.filename is not None:
                raise
            raise OSError(exc.errno, exc.strerror or os.strerror(exc.errno), str(zp)) from exc
        except BaseException:
            shutil.rmtree(zp, ignore_errors=True)
            raise


def _fill_matrix(store, make_model, n_hours, chunk_hours, ps, ncomp, wl, nodes, weights,
                 starts, dom):
    """The loop of :func:`model_sky_matrix`: into the Zarr array ``store``, or a new array."""
    shape = (n_hours, len(ps), ncomp)
    out = None if store is not None else np.zeros(shape)
    for a in range(0, n_hours, chunk_hours):
        b = min(n_hours, a + chunk_hours)
        block = np.zeros((b - a, len(ps), ncomp))
        for h in range(a, b):
            m = make_model(h)
            if m is None:
                continue
            if wl is None:
                v = np.asarray(m.luminance(nodes), dtype=np.float64)[:, None]
            else:
                v = np.asarray(m.radiance(nodes, wl), dtype=np.float64)
            if not np.all(np.isfinite(v)) or np.any(v < 0.0):
                raise ValueError(f"model of hour {h} returned a negative or non-finite value")
            block[h - a, 1:, :] = np.add.reduceat(weights[:, None] * v, starts, axis=0) / dom[
                :, None]
        if store is not None:
            store[a:b] = block
        else:
            out[a:b] = block
    return store if store is not None else out


def parse_components(spec: str) -> tuple[str, np.ndarray | None]:
    """"luminance" -> ("luminance", None); "spectral:N" -> ("spectral", N wavelengths evenly
    over 380-780 nm [nm]), N in 1..401; "spectral" -> skydome's default grid."""
    if not isinstance(spec, str):
        raise TypeError(f"components must be a string, got {spec!r}")
    s = spec.strip().lower()
    if s == "luminance":
        return "luminance", None
    if s == "spectral":
        from skydome.spectra import default_wavelengths

        return "spectral", np.asarray(default_wavelengths(), dtype=np.float64)
    if s.startswith("spectral:") and s[9:].isdigit() and 1 <= int(s[9:]) <= 401:
        n = int(s[9:])
        return "spectral", (np.array([550.0]) if n == 1 else np.linspace(380.0, 780.0, n))
    raise ValueError(f"components = {spec!r} is unknown for a model's sky matrix; use "
                     "'luminance', 'spectral' or 'spectral:N' (N in 1..401)")


def weather_aod(weather, aod_from) -> np.ndarray:
    """Aerosol optical depth of every hour: ``"weather"`` (the file's AOD column, taken as the
    vertical AOD at 550 nm; every lit hour must have one) or one number in [0, 10]."""
    n = len(weather)
    if isinstance(aod_from, str) and aod_from.strip().lower() == "weather":
        if weather.aod is None:
            raise ValueError(f"aod-from = 'weather': {weather.path!r} holds no aerosol optical "
                             "depth (give a number instead, e.g. 0.1)")
        aod = np.asarray(weather.aod, dtype=np.float64)
        lit = (weather.dni + weather.dhi) > 1e-4
        bad = lit & ~(np.isfinite(aod) & (aod >= 0.0) & (aod <= 10.0))
        if np.any(bad):
            k = int(np.argmax(bad))
            raise ValueError(f"aod-from = 'weather': aerosol optical depth missing or out of "
                             f"range [0, 10] at record {k + 1} ({weather.time[k]})")
        return np.where(lit, aod, 0.0)
    try:
        v = float(aod_from)
    except (TypeError, ValueError):
        v = float("nan")
    if not (math.isfinite(v) and 0.0 <= v <= 10.0):
        raise ValueError(f"aod-from = {aod_from!r} must be 'weather' or a number in [0, 10]")
    return np.full(n, v)


class SunRangeNote(UserWarning):
    """One-line note: lit hours whose sun lies outside the model's range were left 0."""


def _hours_outside_sun_range(cls, params: dict, elevation_deg, lit) -> np.ndarray:
    """Lit hours whose sun elevation lies outside the range the model declares
    (``sun_elevation_range_deg``, for models that refuse a sun outside it; dobashi1995's
    ``min_sun_elevation_deg`` lowers its bound). They get a zero row, as the night hours do,
    and one :class:`SunRangeNote` counts them. Models declared black outside their range
    (perez1993, the CIE skies) or covering every elevation keep their own handling."""
    el = np.asarray(elevation_deg, dtype=np.float64)
    if getattr(cls, "sun_outside_range", "raise") != "raise":
        return np.zeros(el.shape, dtype=bool)
    lo, hi = cls.sun_elevation_range_deg
    if "min_sun_elevation_deg" in params:
        lo = float(params["min_sun_elevation_deg"])
    elif "min_sun_elevation_deg" in {p.name for p in getattr(cls, "parameters", ())}:
        lo = next(p.default for p in cls.parameters if p.name == "min_sun_elevation_deg")
    outside = lit & ((el < lo) | (el > hi))
    n = int(np.sum(outside))
    if n:
        import warnings

        warnings.warn(f"model {cls.name!r} covers sun elevations [{lo:g}, {hi:g}] deg: {n} lit "
                      f"hour(s) with the sun outside it (lowest {el[outside].min():.2f} deg) "
                      "are left 0, as the night hours", SunRangeNote, stacklevel=3)
    return outside


def weather_model_sky_matrix(weather, model: str = "precomputed", *, aod_from=None,
                             aod_step: float = 0.02, params=None, patches="tregenza",
                             order: int = DEFAULT_ORDER, components: str = "spectral:16",
                             sun_position: str = "spa", zarr_path=None,
                             chunk_hours: int = 168):
    """Sky matrix of any skydome model over a weather file's hours (e.g. the precomputed
    physically based spectral sky with each hour's aerosol optical depth).

    Each lit hour (DNI + DHI > 1e-4 W m^-2, gendaymtx's rule; other hours are 0) gets the
    model with the sun of the hour's midpoint. A lit hour whose sun lies outside the sun
    elevations the model declares (``sun_elevation_range_deg`` of a model that refuses a sun
    outside it: preetham1999, hosek_wilkie2012, cie2003's skies, ... e.g. the twilight hours
    of a sun just below the horizon) gets a zero row too, as a night hour, and one
    :class:`SunRangeNote` warning counts them; models with their own handling (black outside
    the range, or a twilight extension) get those hours as they define them. The weather's
    irradiances only select the lit hours (a physically based model computes its own clear
    sky). With ``aod_from`` the model's
    atmosphere is ``Atmosphere.earth(aerosol_optical_depth=AOD)`` per hour, the AOD rounded
    to the nearest multiple of ``aod_step`` so that hours share one set of tables (each
    distinct AOD costs one table build, ~35 s on a 2-core EPYC with the default settings; the
    tables are kept in the on-disk cache); models with ``with_sun`` (precomputed) are built
    once per AOD and moved to each hour's sun, without recomputing.

    Parameters
    ----------
    weather : Weather
    model : str
        A registered model name (default "precomputed").
    aod_from : "weather", float or None
        None: the model's own atmosphere (``params``).
    aod_step : float
        Rounding of the AOD, in (0, 1] (default 0.02).
    params : dict, optional
        Further model parameters (e.g. table sizes).
    patches, order : the patch quadrature (:mod:`skydome.daylighting.patches`).
    components : "luminance", "spectral" or "spectral:N"
        Luminance [cd m^-2] or spectral radiance [W m^-2 sr^-1 nm^-1] at N wavelengths evenly
        over 380-780 nm (for precomputed the model's table wavelengths default to the same N).
    sun_position : "spa" or "radiance"
    zarr_path, chunk_hours : see :func:`model_sky_matrix` (the Zarr array is written one
        chunk of hours at a time, never held whole).

    Returns
    -------
    numpy.ndarray (hours, patches, components) or the zarr array (``zarr_path``); the ground
    patch 0 is 0, and the sun's direct beam is not in the matrix (sky only).
    """
    import skydome as sd
    from skydome._validate import check_choice, check_number

    check_choice("sun_position", sun_position, ("spa", "radiance"))
    kind, wl = parse_components(components)
    from skydome.models import get_model_class

    params = dict(params or {})
    cls = get_model_class(model)
    names = {p.name for p in getattr(cls, "parameters", ())}
    if aod_from is not None:
        if "atmosphere" not in names:
            raise ValueError(f"aod-from: model {model!r} has no atmosphere parameter")
        if "atmosphere" in params or "turbidity" in params:
            raise ValueError("give aod-from or an atmosphere/turbidity parameter, not both")
        step = check_number("aod_step", aod_step, 0.0, 1.0, low_open=True)
        aod = np.round(weather_aod(weather, aod_from) / step) * step
    else:
        aod = None
    if kind == "spectral" and model == "precomputed" and "n_wavelengths" not in params \
            and "table_wavelengths_nm" not in params:
        params["table_wavelengths_nm"] = wl
    sd_dirs = weather.spa_sun_directions() if sun_position == "spa" else \
        weather.radiance_sun_directions()
    el = np.degrees(np.arcsin(np.clip(sd_dirs[:, 2], -1.0, 1.0)))
    az = np.degrees(np.arctan2(sd_dirs[:, 0], sd_dirs[:, 1])) % 360.0
    lit = (weather.dni + weather.dhi) > 1e-4
    lit = lit & ~_hours_outside_sun_range(cls, params, el, lit)
    base: dict = {}  # AOD -> model built once (tables), moved to each hour's sun

    def make(h):
        if not lit[h]:
            return None
        sun = sd.Sun(elevation_deg=float(el[h]), azimuth_deg=float(az[h]))
        kw = dict(params)
        key = None
        if aod is not None:
            key = float(aod[h])
            kw["atmosphere"] = sd.Atmosphere.earth(aerosol_optical_depth=key)
        if hasattr(cls, "with_sun"):
            m = base.get(key)
            if m is None:
                if len(base) >= 4:  # bound the tables held in memory
                    base.pop(next(iter(base)))
                m = base[key] = sd.model(model, sun=sun, **kw)
            return m.with_sun(sun)
        return sd.model(model, sun=sun, **kw)

    # validate the parameters on the first lit hour before any file is made
    first = int(np.argmax(lit)) if np.any(lit) else None
    if first is not None:
        make(first)
    return model_sky_matrix(make, len(weather), patches=patches, order=order,
                            components=kind, wavelengths_nm=wl, zarr_path=zarr_path,
                            chunk_hours=chunk_hours)
