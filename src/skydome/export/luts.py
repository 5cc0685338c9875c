"""LUT bakes for real-time renderers: the precomputed model's tables in Bruneton's
texture layout, reduced to CIE XYZ the way Bruneton reduces his spectral tables.

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
description, with its ``table_format``): r, mu and nu are [Bru17]'s, mu_s is the model's own
zenith-angle mapping (``precomputed._mapping.mu_s_unit``; table format 2), not [Bru17]'s
distance-to-the-top mapping:

    x = (u(theta_max) - u(theta_s)) / (u(theta_max) - u(0)),
    u(theta) = asinh((theta - 92 deg) / 6 deg),

theta_s = acos(mu_s), theta_max = acos(mu_s_min), 0 at mu_s_min (clamped below), 1 at
the zenith, node i at x = i / (n_mu_s - 1); it does not depend on the planet radius.
Bake format 2 (``LUT_FORMAT``) is the one with this mu_s axis; format 1 had [Bru17]'s.

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

__all__ = ["xyz_weights_for_table", "bake_precomputed", "write_precomputed_luts", "LUT_FORMAT"]

#: version 2: the mu_s axis is the model's zenith-angle mapping (table format
#: skydome.precomputed/2), no longer [Bru17]'s
LUT_FORMAT = "skydome.luts.bruneton-xyz/2"
#: the model's table format whose axes this bake describes
TABLE_FORMAT = "skydome.precomputed/2"


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


def bake_precomputed(sky) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """(textures, description) of a :class:`PrecomputedSky` in Bruneton's layout, XYZ."""
    with tempfile.TemporaryDirectory() as tmp:
        sky.export_textures(tmp)
        with open(os.path.join(tmp, "textures.json")) as f:
            src = json.load(f)
        arrays = {name: np.load(os.path.join(tmp, t["file"]))
                  for name, t in src["textures"].items()}
    if src.get("format") != TABLE_FORMAT:
        raise ValueError(f"textures.json format = {src.get('format')!r} is not supported; "
                         f"valid: {TABLE_FORMAT!r} (the mu_s mapping this bake describes)")
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
        "textures": {n: {"file": f"{n}.bin", "shape": list(a.shape), "dtype": "float32"}
                     for n, a in tex.items()},
    }
    return tex, desc


def _npy_bytes(arr: np.ndarray) -> bytes:
    import io

    buf = io.BytesIO()
    np.save(buf, arr)
    return buf.getvalue()


def write_precomputed_luts(sky, folder) -> list[str]:
    """Write :func:`bake_precomputed` as ``<name>.bin`` (raw little-endian float32),
    ``<name>.npy`` and ``luts.json`` into ``folder`` (created; files written to temporary
    names and renamed, so no partial file is left). Returns the paths."""
    from skydome.render.image import _atomic_write

    folder = os.fspath(folder)
    tex, desc = bake_precomputed(sky)
    os.makedirs(folder, exist_ok=True)
    written = []

    def atomic(path, write):
        _atomic_write(Path(path), write)
        written.append(path)

    for name, a in tex.items():
        arr = np.ascontiguousarray(a, dtype="<f4")
        atomic(os.path.join(folder, f"{name}.bin"), lambda tmp, arr=arr: arr.tofile(tmp))
        atomic(os.path.join(folder, f"{name}.npy"),
               lambda tmp, arr=arr: Path(tmp).write_bytes(_npy_bytes(arr)))
    atomic(os.path.join(folder, "luts.json"),
           lambda tmp: Path(tmp).write_text(json.dumps(desc, indent=2)))
    return written
