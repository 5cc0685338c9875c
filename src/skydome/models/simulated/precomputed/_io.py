"""Persistence of the precomputed model: ``save``/``load`` (one ``.npz`` file: the tables
and a JSON description of the parameters) and ``export_textures`` (float32 textures with
their axes, mappings and units, for a shader)."""

from __future__ import annotations

import json
import os

import numpy as np

# version 2: the mu_s axis of [Bru17] replaced by the zenith-angle mapping of _mapping.mu_s_unit;
# version 3: the mu axis of [Bru17] replaced by the horizon-angle mapping of _mapping.mu_unit;
# version 4: the irradiance table's mu_s axis on _mapping.mu_s_unit too (read geometrically
# between its nodes), no longer [Bru17]'s (mu_s + 1) / 2
FORMAT = "skydome.precomputed/4"


def meta(model) -> dict:
    """The parameters and sun of ``model`` as a JSON-able dict."""
    out = {"format": FORMAT, "model": model.name}
    for p in model.parameters:
        if p.name in ("atmosphere", "table_wavelengths_nm"):
            continue
        out[p.name] = getattr(model, p.name)
    out["atmosphere"] = (model.atmosphere.describe() if model.atmosphere is not None
                         else model._atmosphere_description)
    s = model.sun
    out["sun"] = {"elevation_deg": s.elevation_deg, "azimuth_deg": s.azimuth_deg,
                  "angular_radius_deg": s.angular_radius_deg, "distance_au": s.distance_au}
    return out


def save(model, path) -> None:
    """Write the tables and parameters to an ``.npz`` file (atomically); the stored table of
    orders 2..N is built first where it is not yet, so that the file holds every table."""
    from skydome._io import atomic_write

    model._t.build_multiple_scattering()
    model._t.build_single_scattering()
    atomic_write(path, lambda tmp: np.savez(
        tmp, meta=np.array(json.dumps(meta(model), default=_json_default)), **model._t.arrays()),
        suffix=".npz")


def load(cls, path, sun=None):
    """Read tables written by :func:`save` into a new ``cls`` (see ``PrecomputedSky.load``).

    The file's content is checked as it is read: every member of the ``.npz`` (a zip file)
    against its CRC-32 (by :mod:`zipfile`), and every table for finite values. A damaged
    file raises ValueError naming it (flipped bytes, a truncated file, NaN in a table)."""
    import zipfile

    from skydome.models.simulated.precomputed._tables import Tables
    from skydome.sun import Sun

    try:
        with np.load(os.fspath(path), allow_pickle=False) as z:
            m = json.loads(str(z["meta"]))
            if m.get("format") != FORMAT:
                raise ValueError(f"{path} is not a skydome precomputed-table file of this "
                                 f"version (format {m.get('format')!r}, expected {FORMAT!r})")
            arrays = {k: z[k] for k in z.files if k != "meta"}
    except (zipfile.BadZipFile, KeyError, EOFError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path} is damaged or not a skydome precomputed-table file "
                         f"({' '.join(str(exc).split())})") from None
    for k, a in arrays.items():
        if np.issubdtype(a.dtype, np.floating) and not np.all(np.isfinite(a)):
            raise ValueError(f"{path} is damaged: table {k!r} holds NaN or infinite values")
    tables = Tables.from_arrays(arrays)
    from skydome.models.simulated.precomputed._precompute import attach_stored_table_builder

    attach_stored_table_builder(tables)
    obj = cls.__new__(cls)
    for p in cls.parameters:
        if p.name in m:
            setattr(obj, p.name, m[p.name])
    obj.atmosphere = None
    obj._atmosphere_description = m["atmosphere"]
    obj.table_wavelengths_nm = tables.table_wavelengths_nm
    obj.n_wavelengths = obj.table_wavelengths_nm.size
    obj.sun = sun if sun is not None else Sun(**m["sun"])
    obj.precompute_seconds = tables.precompute_seconds
    obj.from_cache = False
    obj._t = tables
    return obj


def export_textures(model, folder) -> list:
    """Write the tables as float32 textures (``.npy``, and ``.exr`` where OpenEXR is
    available) plus ``textures.json`` and ``textures.md`` describing axes, mappings and
    units. Returns the written paths."""
    folder = os.fspath(folder)
    os.makedirs(folder, exist_ok=True)
    t = model._t
    R, Rt, mu_s_min = t.planet_radius_m, t.top_radius_m, t.mu_s_min
    trans = np.exp(-np.einsum("cij,cl->ijl", t.columns, t.beta_e)).astype(np.float32)
    tex = {
        "transmittance": (trans, ["r", "mu", "wavelength"],
                          "transmittance to the top of the atmosphere (dimensionless); "
                          "r: x_r = rho/H, mu: x_mu = (d - d_min)/(d_max - d_min), d the "
                          "distance to the top, d_min = Rt - r, d_max = rho + H; node i at "
                          "x = i/(n-1); rays that hit the ground are not in the table"),
        "single_scattering": (t.single_scattering.astype(np.float32),
                              ["constituent", "r", "mu", "mu_s", "nu", "wavelength"],
                              "single scattering without phase function, per unit solar "
                              "irradiance [sr^0 m^0: multiply by E_sun and the constituent's "
                              "phase function P(nu) [sr^-1] to get radiance]"),
        "multiple_scattering": (t.multiple_scattering.astype(np.float32),
                                ["r", "mu", "mu_s", "nu", "wavelength"],
                                "orders 2..N, radiance per unit solar irradiance [sr^-1]"),
        "irradiance": (t.irradiance.astype(np.float32), ["r", "mu_s", "wavelength"],
                       "sky irradiance on a horizontal surface (orders 1..N and the "
                       "remainder) per unit solar irradiance (dimensionless); x_r = (r - R)/(Rt - R), "
                       "x_mu_s on the mu_s mapping (mappings.mu_s), node i at x = i/(n-1); "
                       "linear in r, geometric in mu_s between two nodes, E0 (E1/E0)^f "
                       "where both are positive (linear otherwise)"),
    }
    if t.phase_table is not None:
        tex["phase_table"] = (t.phase_table.astype(np.float32),
                              ["constituent", "angle", "wavelength"],
                              "tabulated phase function [sr^-1] of the constituents with phase "
                              "code 4 (zeros for the others), scattering angle node k at "
                              "pi k/(n-1), linear in angle")
    desc = {
        "format": FORMAT, "units": "lengths m; radiance per unit extraterrestrial solar "
        "spectral irradiance; multiply by E_sun(lambda) [W m^-2 nm^-1]",
        "planet_radius_m": R, "top_radius_m": Rt, "mu_s_min": mu_s_min,
        "wavelengths_nm": [float(x) for x in t.table_wavelengths_nm],
        "phase_code": [int(x) for x in t.phase_code],
        "phase_param": [float(x) for x in t.phase_param],
        "phase_codes": {"0": "rayleigh (param = rho/(2-rho))", "1": "henyey_greenstein (g)",
                        "2": "cornette_shanks (g)", "3": "isotropic",
                        "4": "tabulated (texture phase_table)"},
        "mappings": {
            "r": "x = rho/H, rho = sqrt(r^2 - R^2), H = sqrt(Rt^2 - R^2)",
            "mu": "x = asinh(e/w)/asinh(e_max/w), w = 2 deg, e the angle of the ray from the "
                  "local horizon, whose dip below the horizontal is atan(rho/R): e = asin(mu) "
                  "+ dip, e_max = 90 deg + dip for rays that do not hit the ground, e = -dip - "
                  "asin(mu), e_max = 90 deg - dip for rays that do; first half: rays hitting "
                  "the ground, node k = x (n/2-1) (node 0 = horizon .. n/2-1 = nadir); second "
                  "half: node n/2 + (1 - x)(n/2-1) (node n/2 = zenith .. n-1 = horizon)",
            "mu_s": "x = (u(theta_max) - u(theta_s))/(u(theta_max) - u(0)), u(theta) = "
                    "asinh((theta - 92 deg)/6 deg), theta_s = acos(mu_s), theta_max = "
                    "acos(mu_s_min) (0 at mu_s_min, 1 at the zenith); node i at x = i/(n-1)",
            "nu": "x = (nu + 1)/2, node i at x = i/(n-1)",
        },
        "textures": {},
    }
    written = []
    for name, (arr, axes, meaning) in tex.items():
        p = os.path.join(folder, f"{name}.npy")
        np.save(p, np.ascontiguousarray(arr, dtype=np.float32))
        written.append(p)
        desc["textures"][name] = {"file": f"{name}.npy", "shape": list(arr.shape),
                                  "axes": axes, "dtype": "float32", "meaning": meaning}
        exr = _write_exr(os.path.join(folder, f"{name}.exr"), arr)
        if exr:
            written.append(exr)
            desc["textures"][name]["exr"] = os.path.basename(exr)
    jp = os.path.join(folder, "textures.json")
    with open(jp, "w") as f:
        json.dump(desc, f, indent=2)
    written.append(jp)
    mp = os.path.join(folder, "textures.md")
    with open(mp, "w") as f:
        f.write("# skydome precomputed tables\n\n" + desc["units"] + ".\n\n")
        f.write(f"R = {R} m, Rt = {Rt} m, mu_s_min = {mu_s_min:.6f}\n\n")
        f.write("| texture | shape | axes | meaning |\n|---|---|---|---|\n")
        for name, v in desc["textures"].items():
            f.write(f"| {v['file']} | {tuple(v['shape'])} | {', '.join(v['axes'])} | "
                    f"{v['meaning']} |\n")
        f.write("\n## Axis mappings\n\n")
        for k, v in desc["mappings"].items():
            f.write(f"- **{k}**: {v}\n")
        f.write("\nEXR files hold the same arrays flattened to 2-D: rows = product of all "
                "axes but the last two, columns = product of the last two (wavelength "
                "fastest), one channel Y.\n")
    written.append(mp)
    return written


def _json_default(o):
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    return str(o)


def _write_exr(path, arr):
    """Single-channel float32 EXR of arr flattened to 2-D; None when OpenEXR is missing."""
    try:
        import OpenEXR
    except ImportError:
        return None
    a = np.ascontiguousarray(arr, dtype=np.float32)
    if a.ndim >= 2:
        a = a.reshape(int(np.prod(a.shape[:-2])), a.shape[-2] * a.shape[-1]) if a.ndim > 2 else a
    try:
        header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
        with OpenEXR.File(header, {"Y": a}) as f:
            f.write(path)
    except Exception:
        return None
    return path
