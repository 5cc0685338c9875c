"""LUT bakes for real-time renderers: the precomputed model's tables in Bruneton's
texture layout and the hillaire2020 model's tables in Hillaire's, reduced to CIE XYZ the
way Bruneton reduces his spectral tables (:func:`bake`, :func:`write_luts`; the command
``skydome export luts``). The hillaire2020 bake is described in :func:`bake_hillaire2020`;
its shader-side lookups are in ``export/glsl/hillaire2020.glsl``.

Bruneton (2017) stores the 4-D scattering function S(r, mu, mu_s, nu) in a 3-D texture:
x = nu and mu_s together (``x = (i_nu + u_mu_s) / NU_SIZE``: blocks of mu_s, one per nu
node), y = mu, z = r (``GetScatteringTextureUvwzFromRMuMuSNu`` and the 4-D -> 3-D packing
of ``GetScattering``). He precomputes spectrally and stores RGB, converting with
"luminance from radiance" coefficients, which is exact because everything after the
table look-up is linear. :func:`bake_precomputed` does the same for skydome's tables
(read through the model's public :meth:`PrecomputedSky.export_textures`): each table
wavelength j gets the XYZ weight

    K_j = sum_l 683 w_l E_sun(l) W_lj

with W the model's interpolation from the table grid to the output grid (linear in
wavelength, end values held), E_sun the ASTM G173 solar spectrum and w_l the CIE 1931
integration weights of the output grid (skydome's default 41 wavelengths), the map that
``PrecomputedSky.xyz`` applies. Multiply the baked values by the sun's 1/d^2 factor
(``Sun.irradiance_scale``) at render time.

Textures (float32, C order, RGBA with A = 0, i.e. (z, y, x, 4)):

* ``multiple_scattering``: XYZ of orders 2..N, shape (n_r, n_mu, n_nu * n_mu_s, 4);
* ``single_scattering_<k>``: XYZ of single scattering of constituent k without its phase
  function, same shape; multiply by the constituent's phase function P_k(nu) [sr^-1].

The axis mappings are those of the model's ``textures.json`` (copied into the
description, with its ``table_format``): r and nu are [Bru17]'s; mu is the model's own
mapping of the angle from the local horizon (``precomputed._mapping.mu_unit``, table format
3): on each half of the axis (ground rays, sky rays) x = asinh(e / 2 deg) / asinh(e_max /
2 deg), e the angle from the horizon of radius r; mu_s is the model's own zenith-angle
mapping (``precomputed._mapping.mu_s_unit``; table format 2), not [Bru17]'s
distance-to-the-top mapping:

    x = (u(theta_max) - u(theta_s)) / (u(theta_max) - u(0)),
    u(theta) = asinh((theta - 92 deg) / 6 deg),

theta_s = acos(mu_s), theta_max = acos(mu_s_min), 0 at mu_s_min (clamped below), 1 at
the zenith, node i at x = i / (n_mu_s - 1); it does not depend on the planet radius.
Bake format 3 (``LUT_FORMAT``) is the one with these mu and mu_s axes; format 2 had
[Bru17]'s mu axis, format 1 [Bru17]'s mu and mu_s axes.

References
----------
[Bru17] E. Bruneton, Precomputed Atmospheric Scattering: a New Implementation (2017),
    atmosphere/functions.glsl and model.cc (luminance_from_radiance).
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["xyz_weights_for_table", "bake_precomputed", "bake_hillaire2020", "bake",
           "write_luts", "write_precomputed_luts", "check_luts_options", "LUT_FORMAT",
           "HILLAIRE_FORMAT", "LUT_MODELS", "LUT_LAYOUTS", "LUT_FILE_FORMATS", "lut_models"]

#: version 2: the mu_s axis is the model's zenith-angle mapping (table format
#: skydome.precomputed/2), no longer [Bru17]'s; version 3: the mu axis too is the model's
#: (angle from the local horizon, table format skydome.precomputed/3)
LUT_FORMAT = "skydome.luts.bruneton-xyz/3"
#: the hillaire2020 bake (Hillaire's layout, XYZ)
HILLAIRE_FORMAT = "skydome.luts.hillaire-xyz/1"
#: the bakes by layout: a model declares its layout as ``lut_layout`` (skydome.models,
#: capabilities), so that :func:`lut_models` lists it and :func:`bake` bakes it
LUT_LAYOUTS = ("bruneton", "hillaire")
#: file formats of :func:`write_luts`
LUT_FILE_FORMATS = ("exr", "npy", "bin")
#: the model's table format whose axes this bake describes
TABLE_FORMAT = "skydome.precomputed/3"


def xyz_weights_for_table(table_wavelengths_nm, wavelengths_nm=None) -> np.ndarray:
    """(n_table, 3) weights K with XYZ = sum_j K_j S_j for radiance per unit solar
    irradiance S on the table grid (see the module docstring)."""
    from skydome.constants import K_M
    from skydome.spectra import default_wavelengths, integration_weights, solar_irradiance

    tw = np.asarray(table_wavelengths_nm, dtype=np.float64)
    wl = default_wavelengths() if wavelengths_nm is None else np.asarray(wavelengths_nm, float)
    # the model's table -> output interpolation (linear, end values held), column by column
    if tw.size == 1:
        W = np.ones((wl.size, 1))
    else:
        W = np.stack([np.interp(wl, tw, e) for e in np.eye(tw.size)], axis=1)
    cmf = K_M * np.asarray(integration_weights(wl))                       # (n_out, 3)
    return (W * solar_irradiance(wl)[:, None]).T @ cmf


def _bruneton_3d(tab: np.ndarray) -> np.ndarray:
    """(r, mu, mu_s, nu, 3) -> (r, mu, nu * mu_s, 4): Bruneton's 4-D -> 3-D packing."""
    n_r, n_mu, n_ms, n_nu, _ = tab.shape
    out = np.zeros((n_r, n_mu, n_nu, n_ms, 4), dtype=np.float32)
    out[..., :3] = tab.transpose(0, 1, 3, 2, 4)
    return out.reshape(n_r, n_mu, n_nu * n_ms, 4)


def _spectral_layers(tab: np.ndarray) -> np.ndarray:
    """(a, b, nl) -> (ceil(nl / 4), a, b, 4): four table wavelengths per RGBA texel, layer k
    channel c holding wavelength 4 k + c (zeros past the last)."""
    a, b, nl = tab.shape
    n4 = -(-nl // 4)
    out = np.zeros((a, b, 4 * n4), dtype=np.float32)
    out[..., :nl] = tab
    return np.ascontiguousarray(out.reshape(a, b, n4, 4).transpose(2, 0, 1, 3))


def bake_precomputed(sky, ground: bool = False) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """(textures, description) of a :class:`PrecomputedSky` in Bruneton's layout, XYZ.

    ``ground``: also the tables of [Bru17]'s ground radiance (GetSunAndSkyIrradiance and
    GetTransmittance of GetSkyRadianceToPoint), which is a product of spectra and so is
    kept on the table wavelengths: ``transmittance_spectral`` (to the top, (r, mu) in the
    transmittance mapping) and ``irradiance_spectral`` (the sky irradiance E(r, mu_s)),
    both (ceil(nl / 4), n_r, n_mu, 4) with four wavelengths per texel; the description gets
    the ground albedo on the table wavelengths and their XYZ weights K_j (above)."""
    with tempfile.TemporaryDirectory() as tmp:
        sky.export_textures(tmp)
        with open(os.path.join(tmp, "textures.json")) as f:
            src = json.load(f)
        arrays = {name: np.load(os.path.join(tmp, t["file"]))
                  for name, t in src["textures"].items()}
    if src.get("format") != TABLE_FORMAT:
        raise ValueError(f"textures.json format = {src.get('format')!r} is not supported; "
                         f"valid: {TABLE_FORMAT!r} (the mu and mu_s mappings this bake describes)")
    if 4 in src["phase_code"]:
        raise ValueError("the sky has a tabulated phase function (phase code 4): the LUT bake "
                         "stores XYZ single scattering for an analytic phase only; give the "
                         "constituents an analytic phase (henyey_greenstein, cornette_shanks)")
    K = xyz_weights_for_table(src["wavelengths_nm"])
    ss = arrays["single_scattering"].astype(np.float64)       # (k, r, mu, mu_s, nu, l)
    ms = arrays["multiple_scattering"].astype(np.float64)     # (r, mu, mu_s, nu, l)
    tex = {"multiple_scattering": _bruneton_3d(ms @ K)}
    for k in range(ss.shape[0]):
        tex[f"single_scattering_{k}"] = _bruneton_3d(ss[k] @ K)
    n_r, n_mu, n_ms, n_nu = ms.shape[:4]
    desc = {
        "format": LUT_FORMAT, "units": "CIE 1931 XYZ with Y in cd m^-2 for a sun at 1 au "
        "(multiply by Sun.irradiance_scale); single scattering without its phase function",
        "planet_radius_m": src["planet_radius_m"], "top_radius_m": src["top_radius_m"],
        "mu_s_min": src["mu_s_min"], "sizes": {"r": n_r, "mu": n_mu, "mu_s": n_ms, "nu": n_nu},
        "layout": "float32 (r, mu, nu * mu_s, 4): x = i_nu * n_mu_s + i_mu_s, y = i_mu, "
                  "z = i_r; RGBA = X, Y, Z, 0",
        "phase_code": src["phase_code"], "phase_param": src["phase_param"],
        "phase_codes": src["phase_codes"], "table_format": src["format"],
        "mappings": src["mappings"],
        "table_wavelengths_nm": src["wavelengths_nm"],
        "xyz_weights": K.tolist(),
    }
    if ground:
        tex["transmittance_spectral"] = _spectral_layers(arrays["transmittance"].astype(np.float32))
        tex["irradiance_spectral"] = _spectral_layers(arrays["irradiance"].astype(np.float32))
        props = sky.atmosphere.optical_properties(np.asarray(src["wavelengths_nm"]))
        desc["ground_albedo"] = np.asarray(props.ground_albedo, dtype=np.float64).tolist()
        desc["ground_layout"] = ("*_spectral: float32 (ceil(nl / 4), n_r, n_mu or n_mu_s, 4), "
                                 "layer k channel c = table wavelength 4 k + c; transmittance: "
                                 "x_r = rho / H, x_mu = (d - d_min) / (d_max - d_min); "
                                 "irradiance: x_r = (r - R) / (Rt - R), x_mu_s = (mu_s + 1) / 2")
    desc["textures"] = {n: {"file": f"{n}.bin", "shape": list(a.shape), "dtype": "float32"}
                        for n, a in tex.items()}
    return tex, desc


def _solar_xyz_weights(grid_nm, wavelengths_nm=None, to_request=None) -> np.ndarray:
    """(n_grid, 3) weights K: XYZ [Y in cd m^-2] = sum_j K_j x_j of a spectrum per unit solar
    irradiance x given on ``grid_nm``, mapped to the output wavelengths by ``to_request``
    (a linear map (..., n_grid) -> (..., n_out); default linear interpolation)."""
    from skydome.constants import K_M
    from skydome.spectra import default_wavelengths, integration_weights, solar_irradiance

    grid = np.asarray(grid_nm, dtype=np.float64)
    wl = default_wavelengths() if wavelengths_nm is None else np.asarray(wavelengths_nm, float)
    if to_request is None:
        return xyz_weights_for_table(grid, wl)
    W = to_request(np.eye(grid.size), grid, wl)                      # (n_grid, n_out)
    cmf = K_M * np.asarray(integration_weights(wl))                  # (n_out, 3)
    return (W * solar_irradiance(wl)[None, :]) @ cmf


def _rgba(xyz: np.ndarray, alpha=None) -> np.ndarray:
    out = np.zeros(xyz.shape[:-1] + (4,), dtype=np.float32)
    out[..., :3] = xyz
    if alpha is not None:
        out[..., 3] = alpha
    return out


def bake_hillaire2020(sky, wavelengths_nm=None) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """(textures, description) of a :class:`~skydome.models.simulated.hillaire2020.Hillaire2020`
    sky in Hillaire's (2020) layout, CIE XYZ.

    The four tables of the model ([Hil20] secs. 4.1, 5.3-5.5), for the sky's atmosphere,
    observer and sun, built on its internal wavelength grid for ``wavelengths_nm`` (default
    skydome's 41 wavelengths, i.e. the grid ``sky.xyz`` uses) and reduced to XYZ with the
    model's own grid -> output map (linear in L lambda^4), the ASTM G173 sun and the CIE
    1931 functions. Textures (float32 RGBA, C order; 2-D (height, width, 4), 3-D
    (depth, height, width, 4)):

    * ``transmittance`` (64, 256): [Bru17]'s (r, mu) mapping, x = mu unit, y = r unit;
      RGB = the sun's XYZ through the air over its XYZ above it (per channel, exact for
      the solar disc's colour), A = 0.
    * ``multiple_scattering`` (32, 32): Psi_ms, x = mu_s = 2 u - 1, y = altitude / (top -
      ground); RGB = the XYZ of Psi_ms times the sun (the source term of [Hil20] eq. 11 is
      sigma_s x this), A = 0.
    * ``sky_view`` (108, 192): XYZ radiance of the sky [cd m^-2] (sun at 1 au) in the
      paper's latitude mapping (two halves, above and below the horizon, squared towards
      the horizon) and azimuth from the sun, cos(phi) = 1 - 2 x^2; A = 0.
    * ``aerial_perspective`` (32, 32, 32): in-scattered XYZ [cd m^-2] from the observer to
      slice k (depth ``km_per_slice n ((k + 0.5)/n)^2`` km), rows elevation
      90 deg s|s| with s = 2 y - 1, columns as the sky view; A = the sun-luminance-weighted
      transmittance (Y channel of the next texture).
    * ``aerial_transmittance`` (32, 32, 32): per-channel sun-weighted transmittance, A = 0.

    Sky view and in-scatter are linear in the spectral tables, so these XYZ textures give
    exactly what ``sky.xyz`` gives after the same bilinear / trilinear lookup. The
    transmittance and Psi_ms textures reduce a spectrum to three channels, the usual RGB
    approximation of real-time engines; the spectral tables themselves come with the bake
    (``*_spectral``, wavelength last, in ``.npy`` / ``.bin``) for engines that march per
    wavelength.
    """
    from skydome.spectra import default_wavelengths

    if getattr(sky, "name", None) != "hillaire2020":
        raise ValueError(f"model = {getattr(sky, 'name', type(sky).__name__)!r}: the Hillaire "
                         "bake needs a hillaire2020 sky")
    wl = default_wavelengths() if wavelengths_nm is None else np.asarray(wavelengths_nm, float)
    tb = sky.tables(wl)
    grid = tb.grid
    K = _solar_xyz_weights(grid, wl, to_request=type(sky)._to_request)       # radiance
    Ks = _solar_xyz_weights(grid, wl)                                          # transmittance
    Ks_norm = Ks / Ks.sum(axis=0)
    vl, vt = tb.aerial
    ap_l = (vl @ K).transpose(2, 0, 1, 3)                                      # (s, v, u, 3)
    ap_t = (vt @ Ks_norm).transpose(2, 0, 1, 3)
    tex = {
        "transmittance": _rgba(tb.tlut @ Ks_norm),
        "multiple_scattering": _rgba(tb.mslut @ K),
        "sky_view": _rgba(tb.skyview @ K),
        "aerial_perspective": _rgba(ap_l, ap_t[..., 1]),
        "aerial_transmittance": _rgba(ap_t),
    }
    spectral = {"transmittance_spectral": tb.tlut, "multiple_scattering_spectral": tb.mslut,
                "sky_view_spectral": tb.skyview,
                "aerial_perspective_spectral": vl.transpose(2, 0, 1, 3),
                "aerial_transmittance_spectral": vt.transpose(2, 0, 1, 3)}
    tex.update({k: np.ascontiguousarray(v, dtype=np.float32) for k, v in spectral.items()})
    s = sky.sun
    desc = {
        "format": HILLAIRE_FORMAT, "model": "hillaire2020",
        "reference": "S. Hillaire, A Scalable and Production Ready Sky and Atmosphere "
                     "Rendering Technique, CGF 39(4), EGSR 2020",
        "units": "XYZ textures: CIE 1931 XYZ, Y in cd m^-2, for a sun at 1 au (multiply by "
                 "Sun.irradiance_scale); transmittance unitless; *_spectral: radiance per "
                 "unit solar irradiance [sr^-1 nm^-1 per W m^-2 nm^-1 = sr^-1] on "
                 "grid_wavelengths_nm, wavelength last",
        "planet_radius_m": tb.R, "top_radius_m": tb.Rt,
        "observer_radius_m": tb.r0, "observer_altitude_m": float(sky.observer_altitude_m),
        "sun": {"elevation_deg": s.elevation_deg, "azimuth_deg": s.azimuth_deg,
                "direction_enu": [float(x) for x in s.direction],
                "note": "sky_view and aerial_* hold this sun and observer; transmittance and "
                        "multiple_scattering do not depend on them"},
        "ap_km_per_slice": float(sky.ap_km_per_slice),
        "multiple_scattering_on": bool(sky.multiple_scattering),
        "grid_wavelengths_nm": grid.tolist(),
        "output_wavelengths_nm": np.asarray(wl).tolist(),
        "xyz_weights_radiance": K.tolist(),
        "xyz_weights_transmittance": Ks_norm.tolist(),
        "texel_convention": "node i of n at unit coordinate x = i / (n - 1); a GPU texture "
                            "coordinate is u = (x (n - 1) + 0.5) / n (texel centres)",
        "mappings": {
            "transmittance": "x_r = rho / H, x_mu = (d - d_min) / (d_max - d_min), "
                             "rho = sqrt(r^2 - R^2), H = sqrt(Rt^2 - R^2), d = distance to "
                             "the top along mu, d_min = Rt - r, d_max = rho + H ([Bru17] "
                             "GetTransmittanceTextureUvFromRMu; [Hil20] sec. 4.1)",
            "multiple_scattering": "x = (mu_s + 1) / 2, y = (r - R) / (Rt - R) ([Hil20] sec. "
                                   "5.5: a linear 32 x 32 grid)",
            "sky_view": "rows 0..H/2-1 above the horizon: theta = Z_h (1 - (1 - c)^2), "
                        "c = row / (H/2 - 1); rows H/2..H-1 below: theta = Z_h + beta c^2; "
                        "beta = acos(sqrt(r0^2 - R^2) / r0), Z_h = pi - beta; the halves are "
                        "interpolated apart (never across the horizon); columns: "
                        "cos(phi_rel) = 1 - 2 x^2, x = col / (W - 1), phi_rel the azimuth "
                        "from the sun ([Hil20] sec. 5.3)",
            "aerial_perspective": "row: elevation = 90 deg s |s|, s = 2 row / (n - 1) - 1; "
                                  "column: as sky_view; slice k at depth km_per_slice n "
                                  "((k + 0.5) / n)^2 km, looked up at w = sqrt(d / "
                                  "km_per_slice / n); below half a slice the in-scatter "
                                  "fades to 0 at d = 0 ([Hil20] sec. 5.4)",
        },
        "glsl": "export/glsl/hillaire2020.glsl (the lookups of this bake)",
        "textures": {n: {"file": f"{n}.bin", "shape": list(a.shape), "dtype": "float32"}
                     for n, a in tex.items()},
    }
    return tex, desc


def lut_models() -> tuple[str, ...]:
    """The registered models that have a bake: those declaring a ``lut_layout``
    (``precomputed`` first, the default, then by name). ``LUT_MODELS`` is the same tuple,
    read when asked for."""
    from skydome.models import available

    return tuple(sorted((n for n, cls in available().items() if cls.lut_layout is not None),
                        key=lambda n: (n != "precomputed", n)))


def __getattr__(name):
    if name == "LUT_MODELS":
        return lut_models()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def bake(sky, wavelengths_nm=None) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """The bake of ``sky`` in its model's layout (``lut_layout``): Bruneton's
    (``"bruneton"``, e.g. ``precomputed``) or Hillaire's (``"hillaire"``, e.g.
    ``hillaire2020``; any object with the precomputed model's ``export_textures``
    is baked in Bruneton's); ValueError for other models."""
    name = getattr(sky, "name", type(sky).__name__)
    layout = getattr(sky, "lut_layout", None)
    if layout is None and hasattr(sky, "export_textures"):
        layout = "bruneton"         # an object that exports the precomputed model's tables
    if layout == "hillaire":
        return bake_hillaire2020(sky, wavelengths_nm)
    if layout == "bruneton":
        return bake_precomputed(sky)
    if layout is not None:
        raise ValueError(f"model {name!r}: lut_layout = {layout!r} is not one of "
                         f"{', '.join(LUT_LAYOUTS)}")
    raise ValueError(f"model = {name!r} has no LUT bake; valid: {', '.join(lut_models())}")


def _npy_bytes(arr: np.ndarray) -> bytes:
    import io

    buf = io.BytesIO()
    np.save(buf, arr)
    return buf.getvalue()


def check_luts_options(formats=("npy", "bin"), half: bool = False) -> tuple[str, ...]:
    """Validate the file formats of :func:`write_luts` before any work."""
    if isinstance(formats, str):
        formats = tuple(f.strip() for f in formats.split(",") if f.strip())
    formats = tuple(formats)
    bad = [f for f in formats if f not in LUT_FILE_FORMATS]
    if bad or not formats:
        raise ValueError(f"formats = {','.join(formats)!r} is not a list of "
                         f"{', '.join(LUT_FILE_FORMATS)}")
    if half and "exr" not in formats:
        raise ValueError("half = True needs the exr format (half floats are for EXR files)")
    return formats


def _exr_2d(arr: np.ndarray) -> np.ndarray:
    """A 2-D or 3-D RGBA texture as one image: 3-D slices stacked top to bottom."""
    return arr if arr.ndim == 3 else arr.reshape(-1, arr.shape[-2], arr.shape[-1])


def _write_exr(tmp: str, arr: np.ndarray, half: bool, desc_name: str) -> None:
    import OpenEXR

    from skydome._io import write_exr

    img = _exr_2d(arr)
    dtype = np.float16 if half else np.float32
    names = "RGBA" if img.shape[-1] == 4 else None
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
              "skydome:texture": desc_name}
    if names is None:
        ch = {f"C{i:03d}": np.ascontiguousarray(img[..., i].astype(dtype))
              for i in range(img.shape[-1])}
    else:
        ch = {c: np.ascontiguousarray(img[..., i].astype(dtype)) for i, c in enumerate(names)}
    write_exr(tmp, header, ch)     # a full disk: OSError ENOSPC, not OpenEXR's RuntimeError


def write_luts(sky, folder, formats=("npy", "bin"), half: bool = False,
               wavelengths_nm=None, progress=None) -> list[Path]:
    """Write :func:`bake` of ``sky`` into ``folder``: each texture as ``<name>.bin`` (raw
    little-endian float32), ``<name>.npy`` and/or ``<name>.exr`` (float32, or half with
    ``half``; 3-D textures as their slices stacked top to bottom), and ``luts.json``
    describing axes, mappings, units and the XYZ conversion. The folder appears at once,
    complete (:func:`skydome._io.atomic_folder`); into an existing folder each file is
    renamed into place. ``progress(done, total)`` is called per file. Returns the paths."""
    from skydome._io import atomic_folder, check_output_folder

    formats = check_luts_options(formats, half)
    folder = check_output_folder(folder)
    tex, desc = bake(sky, wavelengths_nm)
    if half:
        big = max(float(np.max(a)) for n, a in tex.items() if a.shape[-1] == 4)
        from skydome.export.envmap import HALF_MAX

        if big > HALF_MAX:
            raise ValueError(f"half = True: the largest texel {big:.4g} exceeds the half-float "
                             f"range ({HALF_MAX:g}); write float32")
    desc["files"] = {n: [f"{n}.{f}" for f in formats if f != "exr" or a.shape[-1] == 4]
                     for n, a in tex.items()}
    if "exr" in formats:
        desc["exr"] = {"dtype": "float16" if half else "float32", "channels": "RGBA",
                       "3-D textures": "slices stacked top to bottom: image row = "
                                       "slice * height + row",
                       "spectral textures": "not in EXR (.npy / .bin only)"}
    names = [(n, f) for n, a in tex.items() for f in formats if f != "exr" or a.shape[-1] == 4]
    total = len(names) + 1
    written = []
    with atomic_folder(folder) as tmp:
        for k, (n, f) in enumerate(names):
            arr = np.ascontiguousarray(tex[n], dtype="<f4")
            target = tmp / f"{n}.{f}"
            if f == "bin":     # Python's writes: a full disk raises OSError ENOSPC
                with open(target, "wb") as fh:
                    fh.write(memoryview(arr.reshape(-1)).cast("B"))
            elif f == "npy":
                target.write_bytes(_npy_bytes(arr))
            else:
                _write_exr(str(target), arr, half, n)
            written.append(folder / target.name)
            if progress is not None:
                progress(k + 1, total)
        (tmp / "luts.json").write_text(json.dumps(desc, indent=2))
        written.append(folder / "luts.json")
    if progress is not None:
        progress(total, total)
    return written


def write_precomputed_luts(sky, folder) -> list[str]:
    """Write :func:`bake_precomputed` as ``<name>.bin`` (raw little-endian float32),
    ``<name>.npy`` and ``luts.json`` into ``folder`` (:func:`write_luts`). Returns the
    paths."""
    if not hasattr(sky, "export_textures"):
        raise ValueError("write_precomputed_luts needs a precomputed sky")
    return [str(p) for p in write_luts(sky, folder, ("bin", "npy"))]
