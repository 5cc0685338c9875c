"""LUT bakes for real-time renderers: the precomputed model's tables in Bruneton's
texture layout and the hillaire2020 model's tables in Hillaire's, reduced to CIE XYZ the
way Bruneton reduces his spectral tables (:func:`bake`, :func:`write_luts`; the command
``skydome export luts``). The hillaire2020 bake is described in :func:`bake_hillaire2020`;
its shader-side lookups are in ``export/glsl/hillaire2020.glsl``. The ``fitted`` model's
bake (its XYZ tables over sun elevation, for ``export/glsl/fitted.glsl``) is in
:mod:`skydome.export.fitted_luts`.

Bruneton (2017) stores the 4-D scattering function S(r, mu, mu_s, nu) in a 3-D texture:
x = nu and mu_s together (``x = (i_nu + u_mu_s) / NU_SIZE``: blocks of mu_s, one per nu
node), y = mu, z = r (``GetScatteringTextureUvwzFromRMuMuSNu`` and the 4-D -> 3-D packing
of ``GetScattering``). He precomputes spectrally and stores RGB, converting with
"luminance from radiance" coefficients, which is exact because everything after the
table look-up is linear. :func:`bake_precomputed` does the same for skydome's tables
(the model's :class:`~skydome.models.simulated.precomputed.Tables`): each table wavelength
j gets the XYZ weight

    K_j = sum_l 683 w_l E_sun(l) W_lj

with W the model's interpolation from the table grid to the output grid (linear in
wavelength, end values held), E_sun the ASTM G173 solar spectrum and w_l the CIE 1931
integration weights of the output grid (skydome's default 41 wavelengths), the map that
``PrecomputedSky.xyz`` applies. Multiply the baked values by the sun's 1/d^2 factor
(``Sun.irradiance_scale``) at render time. The textures (scattering, single Mie, orders
2..N, transmittance, optical depths, irradiance, the scattering density of orders 2..N)
and the atmosphere's constants are described in :func:`bake_precomputed`;
``export/glsl/precomputed.glsl`` renders the sky, the sun, the ground and aerial
perspective from them, orders 2..N either from the stored 4-D table (one look-up) or, as
the model renders its observer's sky, integrated along the view ray from the scattering
density on a sky map (the ``skydome*Mapped`` functions; [BN08] eq. 8).

The axis mappings: r and nu are [Bru17]'s; mu is the model's own mapping of the angle
from the local horizon (``precomputed._mapping.mu_unit``, table format 3): on each half
of the axis (ground rays, sky rays) x = asinh(e / 2 deg) / asinh(e_max / 2 deg), e the
angle from the horizon of radius r; mu_s is the model's own zenith-angle mapping
(``precomputed._mapping.mu_s_unit``; table format 2), not [Bru17]'s distance-to-the-top
mapping:

    x = (u(theta_max) - u(theta_s)) / (u(theta_max) - u(0)),
    u(theta) = asinh((theta - 92 deg) / 6 deg),

theta_s = acos(mu_s), theta_max = acos(mu_s_min), 0 at mu_s_min (clamped below), 1 at
the zenith, node i at x = i / (n_mu_s - 1); it does not depend on the planet radius.
Bake format 5 (``LUT_FORMAT``) adds the scattering density of orders 2..N, which the
shader integrates along the view ray as the model does; format 4 had the reference's
texture set and the constants; format 3 had these axes and per-constituent single
scattering only, format 2 [Bru17]'s mu axis, format 1 [Bru17]'s mu and mu_s axes. Format 6
puts the irradiance textures' mu_s axis on the same mapping (no longer [Bru17]'s
(mu_s + 1) / 2), read geometrically between its two nodes.

References
----------
[Bru17] E. Bruneton, Precomputed Atmospheric Scattering: a New Implementation (2017),
    atmosphere/functions.glsl and model.cc (luminance_from_radiance).
[BN08] E. Bruneton, F. Neyret, Precomputed Atmospheric Scattering, EGSR 2008.
[Hil20] S. Hillaire, A Scalable and Production Ready Sky and Atmosphere Rendering
    Technique, CGF 39(4), EGSR 2020.
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["xyz_weights_for_table", "bake_precomputed", "bake_hillaire2020", "bake",
           "write_luts", "write_precomputed_luts", "atmosphere_from_luts",
           "check_luts_options", "LUT_FORMAT", "HILLAIRE_FORMAT", "LUT_MODELS", "LUT_LAYOUTS",
           "LUT_FILE_FORMATS", "lut_models"]

#: version 2: the mu_s axis is the model's zenith-angle mapping (table format
#: skydome.precomputed/2), no longer [Bru17]'s; version 3: the mu axis too is the model's
#: (angle from the local horizon, table format skydome.precomputed/3); version 4: the
#: reference's texture set (Rayleigh and single Mie scattering, orders 2..N apart,
#: transmittance, optical depths, irradiance) and the atmosphere's constants; version 5:
#: the scattering density of orders 2..N (texture scattering_density, luts.json
#: scattering_density) for the observer's sky as the model renders it; version 6: the
#: irradiance textures' mu_s axis on the model's mapping too, geometric between two nodes
#: (table format skydome.precomputed/4)
LUT_FORMAT = "skydome.luts.bruneton-xyz/6"
#: the hillaire2020 bake (Hillaire's layout, XYZ); version 2: the atmosphere's parameters,
#: the sun's disc and EXR channels named X, Y, Z (A)
HILLAIRE_FORMAT = "skydome.luts.hillaire-xyz/2"
#: the bakes by layout: a model declares its layout as ``lut_layout`` (skydome.models,
#: capabilities), so that :func:`lut_models` lists it and :func:`bake` bakes it
LUT_LAYOUTS = ("bruneton", "hillaire", "fitted")
#: file formats of :func:`write_luts`
LUT_FILE_FORMATS = ("exr", "npy", "bin")
#: the model's table format whose axes this bake describes
TABLE_FORMAT = "skydome.precomputed/4"


def xyz_weights_for_table(table_wavelengths_nm, wavelengths_nm=None) -> np.ndarray:
    """(n_table, 3) weights K with XYZ = sum_j K_j S_j for radiance per unit solar
    irradiance S on the table grid (see the module docstring):
    :func:`skydome.spectra.solar_xyz_matrix`, through ``wavelengths_nm`` (default the
    default wavelengths)."""
    from skydome.spectra import solar_xyz_matrix

    return solar_xyz_matrix(table_wavelengths_nm, wavelengths_nm)


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


def _precomputed_tables(sky):
    """The model's tables (:class:`skydome.models.simulated.precomputed.Tables`) of a
    :class:`PrecomputedSky`, after the table format check."""
    from skydome.models.simulated.precomputed import _io
    from skydome.models.simulated.precomputed._tables import Tables

    t = getattr(sky, "_t", None)
    if not isinstance(t, Tables):
        # not a PrecomputedSky: its own export says which table format it has
        with tempfile.TemporaryDirectory() as tmp:
            sky.export_textures(tmp)
            with open(os.path.join(tmp, "textures.json")) as f:
                fmt = json.load(f).get("format")
        if fmt != TABLE_FORMAT:
            raise ValueError(f"textures.json format = {fmt!r} is not supported; valid: "
                             f"{TABLE_FORMAT!r} (the mu and mu_s mappings this bake describes)")
        raise ValueError("the precomputed LUT bake needs a PrecomputedSky (its tables)")
    if _io.FORMAT != TABLE_FORMAT:       # pragma: no cover - a guard for the next format
        raise ValueError(f"table format = {_io.FORMAT!r} is not supported; valid: "
                         f"{TABLE_FORMAT!r}")
    if np.any(t.phase_code == 4):
        raise ValueError("the sky has a tabulated phase function (phase code 4): the LUT bake "
                         "stores XYZ single scattering for an analytic phase only; give the "
                         "constituents an analytic phase (henyey_greenstein, cornette_shanks)")
    return t


def _phase_groups(t) -> tuple[list[int], list[int], tuple[int, float]]:
    """(Rayleigh constituents, Mie constituents, (Mie phase code, parameter)): [Bru17]'s two
    phase functions. The scattering constituents with the Rayleigh phase (code 0) must share
    one depolarisation, the others one analytic phase function; ValueError otherwise."""
    codes = [int(c) for c in t.phase_code]
    params = [float(p) for p in t.phase_param]
    ray = [k for k, c in enumerate(codes) if c == 0]
    mie = [k for k, c in enumerate(codes) if c != 0]
    if not ray:
        raise ValueError("phase codes = %s: the Bruneton bake needs a constituent with the "
                         "Rayleigh phase function (code 0)" % codes)
    if len({params[k] for k in ray}) > 1:
        raise ValueError(f"Rayleigh phase parameters = {[params[k] for k in ray]}: the "
                         "Bruneton bake holds one Rayleigh phase function (one depolarisation)")
    if len({(codes[k], params[k]) for k in mie}) > 1:
        raise ValueError(f"phase codes = {codes}, parameters = {params}: the Bruneton bake "
                         "holds one Mie phase function; these constituents have "
                         f"{len({(codes[k], params[k]) for k in mie})} different ones")
    return ray, mie, ((codes[mie[0]], params[mie[0]]) if mie else (3, 0.0))


def _xyz_4d(tab: np.ndarray, K: np.ndarray) -> np.ndarray:
    """(r, mu, mu_s, nu, l) float32 @ K (l, 3) -> (r, mu, mu_s, nu, 3) float64, an r slab at
    a time (the 4-D tables are large)."""
    out = np.empty(tab.shape[:-1] + (3,))
    for i in range(tab.shape[0]):
        out[i] = tab[i].astype(np.float64) @ K
    return out


def _zeros(shape) -> np.ndarray:
    """A zeroed float32 texture in memory."""
    return np.zeros(shape, dtype=np.float32)


def _in_memory(name: str, shape) -> np.ndarray:
    """The default ``alloc(name, shape)`` of the bakes below: :func:`_zeros`."""
    return _zeros(shape)


def _xyz_bruneton_3d(tabs, K: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """sum_k tabs[k] @ K packed as :func:`_bruneton_3d` packs it, one r slab at a time:
    ``tabs`` (r, mu, mu_s, nu, l) float32 tables summed in float64 per slab and stored once
    in the float32 texture (r, mu, nu * mu_s, 4). The same values as ``_bruneton_3d(sum_k
    _xyz_4d(tabs[k], K))`` without the float64 (r, mu, mu_s, nu, 3) temporaries of the whole
    table (each as large as the texture itself, twice over). ``out``: the zeroed float32
    texture to fill (its final shape), else a new one."""
    n_r, n_mu, n_ms, n_nu, _ = tabs[0].shape
    tex = _zeros((n_r, n_mu, n_nu * n_ms, 4)) if out is None else out
    out5 = tex.reshape(n_r, n_mu, n_nu, n_ms, 4)          # a view: tex is C-contiguous
    for i in range(n_r):
        acc = np.zeros((n_mu, n_ms, n_nu, 3))
        for tab in tabs:
            acc += tab[i].astype(np.float64) @ K
        out5[i, ..., :3] = acc.transpose(0, 2, 1, 3)
    return tex


#: r nodes of single scattering per slab of the bake's pass over it (8: 126 MB at the
#: default sizes instead of the whole table's 503 MB)
SINGLE_SLAB_ROWS = 8


def _single_xyz(t, K: np.ndarray, ray, mie, ground: bool, shape,
                alloc=_in_memory) -> dict[str, np.ndarray]:
    """The XYZ textures of single scattering (:func:`_bruneton_3d`'s packing): ``scattering``
    (the Rayleigh group), ``single_mie_scattering`` (the Mie group; zeros without one) and,
    with ``ground``, ``single_scattering_<k>`` per scatterer; reduced in one pass over the
    table's r nodes, a slab of :data:`SINGLE_SLAB_ROWS` at a time
    (``Tables.single_scattering_slabs``: the table is not held whole where it is not
    already there). Each r node's values are those of :func:`_xyz_bruneton_3d` of the
    whole table (the same float64 sums in the same order). ``alloc(name, shape)``: the
    zeroed float32 texture of that name to fill."""
    n_r, n_mu, n_ms, n_nu = shape
    out: dict[str, np.ndarray] = {}
    tex: dict[str, np.ndarray] = {}
    groups: dict[str, list[int]] = {}
    for first, end, rows in t.single_scattering_slabs(SINGLE_SLAB_ROWS):
        if not groups:
            groups = {"scattering": list(ray), "single_mie_scattering": list(mie)}
            if ground:
                groups.update({f"single_scattering_{k}": [k] for k in range(rows.shape[0])})
            tex = {n: alloc(n, (n_r, n_mu, n_nu * n_ms, 4)) for n in groups}
            out = {n: a.reshape(n_r, n_mu, n_nu, n_ms, 4) for n, a in tex.items()}
        for i in range(first, end):
            for n, ks in groups.items():
                if not ks:
                    continue
                acc = np.zeros((n_mu, n_ms, n_nu, 3))
                for k in ks:
                    acc += rows[k, i - first].astype(np.float64) @ K
                out[n][i, ..., :3] = acc.transpose(0, 2, 1, 3)
    return tex


def bake_precomputed(sky, ground: bool = False, density: bool = False,
                     alloc=None) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """(textures, description) of a :class:`PrecomputedSky`: [Bru17]'s textures in CIE XYZ,
    everything an engine needs to draw the sky, the sun, the ground and aerial perspective
    (``export/glsl/precomputed.glsl``).

    Textures (float32, C order, RGBA; 2-D (height, width, 4), 3-D (depth, height, width, 4)):

    * ``scattering`` (n_r, n_mu, n_nu n_mu_s, 4): [Bru17]'s scattering texture, XYZ of
      Rayleigh single scattering without its phase function; A = 0.
    * ``single_mie_scattering``: the same shape, XYZ of single Mie scattering without its
      phase function: the reference's separate single-Mie texture, not its red channel in
      the scattering texture's A, whose extrapolation to the other channels ([BN08] eq. 9,
      GetExtrapolatedSingleMieScattering) assumes the Mie-to-Rayleigh ratio is the same in
      every channel up to the ratio of the scattering coefficients, which the XYZ channels
      of a spectral table do not satisfy (default model: that ratio in Y over X varies by
      6.4 % RMS about its median, in Z by 37 %); A = 0.
    * ``multiple_scattering``: the same shape, XYZ of orders 2..N (full radiance, no phase
      function to apply). The reference adds orders 2..N divided by the Rayleigh phase
      function at the node's nu into the scattering texture; with 16 nu nodes that costs up
      to 2.3 % of the sky's luminance (the quotient interpolates worse in nu than either
      factor), so the bake keeps them apart (the look-up then equals the model's own look-up
      of the same table to float32).
    * ``transmittance`` (n_tr_r, n_tr_mu, 4): to the top of the atmosphere, per XYZ channel
      weighted by the sun's spectrum (sum_j K_jc T_j / sum_j K_jc; exact for the sun's disc,
      the usual three-channel approximation for anything else); A = 0.
    * ``optical_depth`` (n_tr_r, n_tr_mu, 4): the column of each constituent (up to four, in
      the channels) from (r, mu) to the top [km at reference density]; the spectral
      transmittance is exp(-sum_c beta_e[c, j] column_c), the model's own (beta_e in
      km^-1: ``extinction_per_km``; km so that half floats hold the columns).
    * ``irradiance`` (n_irr_r, n_irr_mu_s, 4): XYZ of the sky's irradiance on a horizontal
      surface (orders 1..N), Y in lx for a sun at 1 au; A = 0.
    * ``irradiance_spectral`` (ceil(nl / 4), n_irr_r, n_irr_mu_s, 4): the same per unit
      solar irradiance on the table wavelengths, layer k channel c = wavelength 4 k + c.

    * ``scattering_density`` (with ``density``; :func:`bake` and :func:`write_luts` set
      it): the scattering density J of orders 2..N per table wavelength (four per texel),
      packed as luts.json ``scattering_density`` describes (545 MB in float32 at the
      default sizes): what the model integrates along each view ray for its observer's
      sky (``skydomeMultipleScatteringAlong``, ``skydomeSkyMapTexel``); the shader's
      sky and ground from it are the model's to float32 (docs/rendering.md).

    ``ground``: also the per-constituent layout that the viewer's shader reads
    (``skydome.viewer``): ``single_scattering_<k>`` (XYZ of constituent k's single
    scattering without its phase function, the scattering textures' shape) and
    ``transmittance_spectral`` ((ceil(nl / 4), n_tr_r, n_tr_mu, 4), four table wavelengths
    per texel).

    ``alloc(name, shape)``: where the large textures (the 4-D tables' and the scattering
    density) are built, a zeroed float32 C-contiguous array of that shape (default: a new
    one in memory; :func:`write_luts` gives the ``.npy`` file's own pages).

    XYZ values (Y in cd m^-2 or lx) are for a sun at 1 au: multiply by
    ``Sun.irradiance_scale``. The description holds the parametrisation (mappings, sizes,
    texel convention) and the atmosphere's constants (radii, mu_s_min, the sun, the
    Rayleigh and Mie coefficients and phase functions, each constituent's extinction, the
    ground albedo, the luminance conversion K).
    """
    from skydome.spectra import solar_irradiance

    t = _precomputed_tables(sky)
    ray, mie, (mie_code, mie_g) = _phase_groups(t)
    gamma = float(t.phase_param[ray[0]])        # P_R's, the description's "rayleigh"
    wl = np.asarray(t.table_wavelengths_nm, dtype=np.float64)
    nl = wl.size
    K = xyz_weights_for_table(wl)
    Kn = K / K.sum(axis=0)
    ms = t.multiple_scattering                                 # built on first read
    n_r, n_mu, n_ms, n_nu = ms.shape[:4]
    if len(t.beta_e) > 4:
        raise ValueError(f"constituents = {len(t.beta_e)}: the optical_depth texture holds at "
                         "most 4 (after folding the absorbers)")
    cols = np.asarray(t.columns, dtype=np.float64)             # (c, r, mu)
    trans = np.exp(-np.einsum("cij,cl->ijl", cols, t.beta_e))  # (r, mu, l)
    od = np.zeros(cols.shape[1:] + (4,), dtype=np.float32)
    od[..., :cols.shape[0]] = cols.transpose(1, 2, 0) * 1e-3      # km: half floats hold it
    irr = np.asarray(t.irradiance, dtype=np.float64)           # (r, mu_s, l)
    if alloc is None:
        alloc = _in_memory
    single = _single_xyz(t, K, ray, mie, ground, (n_r, n_mu, n_ms, n_nu), alloc)
    n_sc = sum(1 for n in single if n.startswith("single_scattering_"))
    tex = {
        "scattering": single.pop("scattering"),
        "single_mie_scattering": single.pop("single_mie_scattering"),
        "multiple_scattering": _xyz_bruneton_3d(
            [ms], K, alloc("multiple_scattering", (n_r, n_mu, n_nu * n_ms, 4))),
        "transmittance": _rgba(trans @ Kn),
        "optical_depth": od,
        "irradiance": _rgba(irr @ K),
        "irradiance_spectral": _spectral_layers(irr.astype(np.float32)),
    }
    dens = _density_description(sky, t) if density else None
    if dens is not None:
        J = t.scattering_density
        tex["scattering_density"] = _density_texture(
            J, dens["block_columns"],
            alloc("scattering_density", _density_shape(J.shape, dens["block_columns"])))
    if ground:
        tex.update(single)
        tex["transmittance_spectral"] = _spectral_layers(trans.astype(np.float32))
    names = _constituent_names(sky, cols.shape[0])
    sca = np.asarray(t.scattering_coefficient, dtype=np.float64)   # (k, l)
    idx = (np.asarray(t.scattering_index) if t.scattering_index is not None
           else np.arange(sca.shape[0]))
    e_sun = solar_irradiance(wl)
    # the disc's solid angle is the sky's sun's (PrecomputedSky.sun_radiance divides by it);
    # the tables' own angular radius sets the penumbra (visible fraction, ground cosine)
    omega = float(sky.sun.solid_angle_sr)
    xyz_sun = K.sum(axis=0)
    channels = {"scattering": "XYZ", "single_mie_scattering": "XYZ",
                "multiple_scattering": "XYZ", "transmittance": "XYZ",
                "irradiance": "XYZ", "optical_depth": names,
                "irradiance_spectral": None, "transmittance_spectral": None,
                "scattering_density": None}
    channels.update({f"single_scattering_{k}": "XYZ" for k in range(n_sc)})
    desc = {
        "format": LUT_FORMAT, "model": "precomputed",
        "reference": "E. Bruneton, Precomputed Atmospheric Scattering: a New Implementation "
                     "(2017), atmosphere/functions.glsl",
        "units": "XYZ textures: CIE 1931 XYZ, Y in cd m^-2 (radiance) or lx (irradiance) for "
                 "a sun at 1 au (multiply by Sun.irradiance_scale); scattering and "
                 "single_mie_scattering without their phase functions [sr^-1]; "
                 "irradiance_spectral per unit solar irradiance; optical_depth: columns in "
                 "km at reference density (times extinction_per_km gives the optical "
                 "depth)",
        "bottom_radius_m": t.planet_radius_m, "top_radius_m": t.top_radius_m,
        "planet_radius_m": t.planet_radius_m, "mu_s_min": t.mu_s_min,
        "sizes": {"r": n_r, "mu": n_mu, "mu_s": n_ms, "nu": n_nu},
        "transmittance_size": {"r": int(cols.shape[1]), "mu": int(cols.shape[2])},
        "irradiance_size": {"r": int(irr.shape[0]), "mu_s": int(irr.shape[1])},
        "n_wavelengths": nl,
        "layout": "scattering textures float32 (n_r, n_mu, n_nu * n_mu_s, 4): x = i_nu * "
                  "n_mu_s + i_mu_s, y = i_mu, z = i_r ([Bru17] GetScattering's 4-D -> 3-D "
                  "packing); RGBA = X, Y, Z, 0",
        "table_format": TABLE_FORMAT,
        "texel_convention": "node i of n at unit coordinate x = i / (n - 1); a GPU texture "
                            "coordinate is u = (x (n - 1) + 0.5) / n (texel centres); LINEAR "
                            "filtering, CLAMP_TO_EDGE",
        "mappings": {
            "r": "x = rho / H, rho = sqrt(r^2 - R^2), H = sqrt(Rt^2 - R^2) ([Bru17])",
            "mu": "x = asinh(e/w)/asinh(e_max/w), w = 2 deg, e the angle of the ray from the "
                  "local horizon, whose dip below the horizontal is atan(rho/R): e = asin(mu) "
                  "+ dip, e_max = 90 deg + dip for rays that do not hit the ground, e = -dip - "
                  "asin(mu), e_max = 90 deg - dip for rays that do; first half: rays hitting "
                  "the ground, node k = x (n/2-1) (node 0 = horizon .. n/2-1 = nadir); second "
                  "half: node n/2 + (1 - x)(n/2-1) (node n/2 = zenith .. n-1 = horizon); a "
                  "look-up stays in the half of its ray",
            "mu_s": "x = (u(theta_max) - u(theta_s))/(u(theta_max) - u(0)), u(theta) = "
                    "asinh((theta - 92 deg)/6 deg), theta_s = acos(mu_s), theta_max = "
                    "acos(mu_s_min) (0 at mu_s_min, 1 at the zenith); node i at x = i/(n-1)",
            "nu": "x = (nu + 1)/2, node i at x = i/(n-1); the 4-D look-up interpolates "
                  "between two nu blocks by hand and filters (mu_s, mu, r) in hardware",
            "transmittance": "x_r = rho / H, x_mu = (d - d_min) / (d_max - d_min), d the "
                             "distance to the top along mu, d_min = Rt - r, d_max = rho + H "
                             "([Bru17] GetTransmittanceTextureUvFromRMu); rows r, columns mu",
            "irradiance": "x_r = (r - R) / (Rt - R) ([Bru17] GetIrradianceTextureUvFromRMuS), "
                          "x_mu_s on the mu_s mapping above (not [Bru17]'s (mu_s + 1) / 2); "
                          "rows r, columns mu_s; LINEAR in r, and between the two mu_s "
                          "nodes (read at their texel centres) geometric, E0 (E1 / E0)^f, "
                          "where both are positive, linear otherwise (skydomeIrradianceUv, "
                          "skydomeGeometricMix)",
        },
        "sun": {"angular_radius_rad": t.sun_angular_radius_rad, "solid_angle_sr": omega,
                "disc_angular_radius_deg": float(sky.sun.angular_radius_deg),
                "solar_irradiance_xyz": xyz_sun.tolist(),
                "radiance_top_of_atmosphere_xyz": (xyz_sun / omega).tolist(),
                "solar_irradiance_w_m2_nm": e_sun.tolist(),
                "note": "XYZ illuminance [lx] and disc radiance [cd m^-2] above the "
                        "atmosphere at 1 au; angular_radius_rad: the tables' (the penumbra "
                        "of the visible fraction and of the ground's cosine), "
                        "solid_angle_sr: the disc's (of disc_angular_radius_deg); the "
                        "sun's disc seen through the air is "
                        "radiance_top_of_atmosphere_xyz x transmittance(r, mu_s) x the "
                        "fraction of the disc above the horizon"},
        "rayleigh": {"constituents": [int(idx[k]) for k in ray],
                     "scattering_per_m": sca[ray].sum(axis=0).tolist(),
                     "phase": "3 / (16 pi) ((1 + 3 gamma) + (1 - gamma) nu^2) / (1 + 2 gamma)",
                     "gamma": gamma},
        "mie": {"constituents": [int(idx[k]) for k in mie],
                "scattering_per_m": (sca[mie].sum(axis=0) if mie else np.zeros(nl)).tolist(),
                "phase_code": int(mie_code), "g": float(mie_g),
                "phase": {1: "Henyey-Greenstein", 2: "Cornette-Shanks",
                          3: "isotropic"}[int(mie_code)]},
        "constituents": names,
        "extinction_per_km": (np.asarray(t.beta_e, dtype=np.float64) * 1e3).tolist(),
        "ground_albedo": np.asarray(t.ground_albedo, dtype=np.float64).tolist(),
        "table_wavelengths_nm": wl.tolist(),
        "xyz_weights": K.tolist(),
        "xyz_weights_transmittance": Kn.tolist(),
        "luminance_conversion": "XYZ = sum_j K_j S_j for a quantity per unit solar irradiance "
                                "S_j on the table wavelengths: K_j = sum_l 683 w_l E_sun(l) "
                                "W_lj (xyz_weights; W the model's linear interpolation to 41 "
                                "wavelengths 380-780 nm, w_l the CIE 1931 weights); linear "
                                "sRGB = M XYZ",
        "xyz_to_linear_srgb": [[3.2404542, -1.5371385, -0.4985314],
                               [-0.9692660, 1.8760108, 0.0415560],
                               [0.0556434, -0.2040259, 1.0572252]],
        "phase_code": [int(x) for x in t.phase_code],
        "phase_param": [float(x) for x in t.phase_param],
        "scattering_density": dens,
        "glsl": "export/glsl/precomputed.glsl",
    }
    desc["textures"] = {n: {"file": f"{n}.bin", "shape": list(a.shape), "dtype": "float32",
                            "channels": (list(channels[n]) if channels[n] is not None
                                         else None)}
                        for n, a in tex.items()}
    return tex, desc


#: the largest side of a 3-D texture the packed scattering density may have (the common
#: GL_MAX_3D_TEXTURE_SIZE of desktop GPUs and WebGL2)
DENSITY_MAX_SIDE = 2048


def _density_description(sky, t) -> dict[str, Any] | None:
    """luts.json's ``scattering_density``: what ``skydomeMultipleScatteringAlong`` needs to
    integrate the scattering density J of orders 2..N along a view ray as the model does
    for its observer (its axes, the constituents' density profiles, the quadrature, the
    observer's sky map); None where the tables hold no J (one scattering order)."""
    from skydome.models.simulated import precomputed as P
    from skydome.models.simulated.precomputed._precompute import QUADRATURE_SCALE_M

    J = t.scattering_density
    if J is None:
        return None
    nsc, n_th, n_ph, n_r, n_ms, nl = J.shape
    layers = -(-nl // 4)
    blocks = n_th * nsc * layers
    cols = max(1, min(blocks, DENSITY_MAX_SIDE // n_ms))
    if -(-blocks // cols) * n_ph > DENSITY_MAX_SIDE or n_r > DENSITY_MAX_SIDE:
        raise ValueError(f"scattering density shape = {J.shape}: packed, it exceeds "
                         f"{DENSITY_MAX_SIDE} texels on a side")
    if len(t.profile_code) > 4 or nsc > 4:
        raise ValueError(f"constituents = {len(t.profile_code)}, scatterers = {nsc}: the "
                         "scattering density's description holds at most 4 of each")
    return {
        "theta": int(n_th), "phi": int(n_ph), "r": int(n_r), "mu_s": int(n_ms),
        "scatterers": int(nsc), "layers": int(layers), "block_columns": int(cols),
        "scatterer_constituent": [int(c) for c in t.scattering_index],
        "constituents": len(t.profile_code),
        "column_nodes": P.OBSERVER_COLUMN_NODES if sky.observer_columns else 0,
        "profile_code": [int(c) for c in t.profile_code],
        "profile_p0_m": [float(x) for x in t.profile_p0],
        "profile_p1_m": [float(x) for x in t.profile_p1],
        "quadrature": {"samples": int(sky.integration_samples),
                       "scale_m": float(QUADRATURE_SCALE_M)},
        "sky_map": {"ground": int(P._SLICE_GROUND), "sky": int(P._SLICE_SKY),
                    "phi": int(P._SLICE_PHI), "ground_linear": float(P._SLICE_GROUND_LINEAR),
                    "sky_linear": float(P._SLICE_SKY_LINEAR)},
        "layout": "float32 (n_slabs n_phi, n_r, block_columns n_mu_s, 4): block b = "
                  "((i_theta n_scatterers) + k) layers + layer, four table wavelengths "
                  "4 layer .. 4 layer + 3 in RGBA (zeros past the last), at x = (b mod "
                  "block_columns) n_mu_s + i_mu_s, y = i_r, z = (b div block_columns) n_phi "
                  "+ i_phi",
        "note": "J_k of orders 2..N per unit number density and solar irradiance "
                "[m^-1 sr^-1] of scatterer k (constituent scatterer_constituent[k], density "
                "profile profile_code: 0 exponential exp(-h / p0), 1 tent max(0, 1 - |h - "
                "p0| / p1), 2 uniform (1 below p0), 3 gaussian exp(-((h - p0) / p1)^2 / 2)); "
                "axes: theta the angle from the sun and phi the azimuth about the sun from "
                "its vertical plane (zenith side), both uniform over [0, pi], r and mu_s on "
                "the 4-D table's mappings; quadrature: samples midpoint nodes per piece of "
                "a ray split at its lowest point, uniform in ln(1 + u / scale_m), u the "
                "distance from the piece's dense end; column_nodes: 6 where the columns "
                "from the observer to each node are integrated along the ray itself (the "
                "6-point Gauss-Legendre rule from node to node in order of distance, over "
                "the constituents' profiles, constituents of them), 0 where they are the "
                "difference of two columns to the top read from optical_depth; sky_map: "
                "the observer's map of orders 2..N (zenith nodes nadir .. horizon for rays to the ground, horizon .. "
                "zenith for the others, each part at x uniform over [0, 1] from the horizon "
                "and the angle from the horizon u(x) = a x + (1 - a) x^2 of the part's "
                "whole, a = ground_linear, sky_linear; azimuth nodes over [0, pi] from the "
                "sun's)",
    }


def _density_shape(shape, cols: int) -> tuple[int, int, int, int]:
    """The packed texture's shape (n_slabs n_phi, n_r, cols n_mu_s, 4) of a J of ``shape``
    (k, theta, phi, r, mu_s, l)."""
    nsc, n_th, n_ph, n_r, n_ms, nl = shape
    slabs = -(-(n_th * nsc * -(-nl // 4)) // cols)
    return (slabs * n_ph, n_r, cols * n_ms, 4)


def _density_texture(J: np.ndarray, cols: int, out: np.ndarray | None = None) -> np.ndarray:
    """J (k, theta, phi, r, mu_s, l) -> the packed 3-D texture of ``_density_description``:
    (n_slabs n_phi, n_r, cols n_mu_s, 4), float32; ``out``: the zeroed texture to fill (that
    shape), else a new one."""
    nsc, n_th, n_ph, n_r, n_ms, nl = J.shape
    layers = -(-nl // 4)
    blocks = n_th * nsc * layers
    slabs = -(-blocks // cols)
    tex = _zeros(_density_shape(J.shape, cols)) if out is None else out
    out = tex.reshape(slabs, n_ph, n_r, cols, n_ms, 4)       # a view: tex is C-contiguous
    # a layer's four float32 moved as one 16-byte item (complex128: numpy copies its bytes
    # as they are), so that numpy's inner loop runs over the n_mu_s texels, not over four
    # channels: 0.22-0.31 s against 0.36-0.45 s of CPU for the default J (same bytes)
    full = nl // 4
    out16 = out.view(np.complex128)[..., 0]                  # (slabs, phi, r, cols, mu_s)
    for it in range(n_th):
        for k in range(nsc):
            src = np.asarray(J[k, it], dtype=np.float32)              # (phi, r, mu_s, l)
            src16 = src[..., :4 * full].view(np.complex128)           # (phi, r, mu_s, full)
            for lay in range(layers):
                b = (it * nsc + k) * layers + lay
                if lay < full:
                    out16[b // cols, :, :, b % cols, :] = src16[..., lay]
                else:                                       # the last, partial layer
                    n4 = nl - 4 * lay
                    out[b // cols, :, :, b % cols, :, :n4] = src[..., 4 * lay:4 * lay + n4]
    return tex


def _constituent_names(sky, n: int) -> list[str]:
    """Names of the model's constituents after folding the absorbers (``column<c>`` where the
    atmosphere is not known, e.g. a model read from a file)."""
    atm = getattr(sky, "atmosphere", None)
    if atm is not None:
        try:
            from skydome.atmosphere import fold_absorbers

            keep = fold_absorbers(atm.optical_properties(np.array([550.0])))[1]
            names = [atm.constituents[int(i)].name for i in keep]
            if len(names) == n:
                return names
        except Exception:       # noqa: BLE001 - names are a label, the columns do not need them
            pass
    return [f"column{c}" for c in range(n)]


def _solar_xyz_weights(grid_nm, wavelengths_nm=None, to_request=None) -> np.ndarray:
    """(n_grid, 3) weights K: XYZ [Y in cd m^-2] = sum_j K_j x_j of a spectrum per unit solar
    irradiance x given on ``grid_nm``, mapped to the output wavelengths by ``to_request``
    (a linear map (..., n_grid) -> (..., n_out); default linear interpolation)."""
    from skydome.spectra import default_wavelengths, solar_xyz_matrix

    grid = np.asarray(grid_nm, dtype=np.float64)
    wl = default_wavelengths() if wavelengths_nm is None else np.asarray(wavelengths_nm, float)
    W = None if to_request is None else to_request(np.eye(grid.size), grid, wl)  # (n_grid, n_out)
    return solar_xyz_matrix(grid, wl, interpolation=W)


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
        "atmosphere": _hillaire_atmosphere(sky, tb),
        "model_parameters": {p.name: getattr(sky, p.name) for p in sky.parameters
                             if p.name not in ("atmosphere", "turbidity")},
        "sun_disc": _sun_disc(sky, grid, wl, Ks),
        "textures": {n: {"file": f"{n}.bin", "shape": list(a.shape), "dtype": "float32",
                         "channels": _HILLAIRE_CHANNELS.get(n)}
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


#: EXR channel names of the hillaire2020 bake's XYZ textures (the spectral ones: none)
_HILLAIRE_CHANNELS = {"transmittance": "XYZ", "multiple_scattering": "XYZ", "sky_view": "XYZ",
                      "aerial_perspective": "XYZA", "aerial_transmittance": "XYZ"}


def _hillaire_atmosphere(sky, tb) -> dict[str, Any]:
    """The medium the hillaire2020 tables were built from, on their wavelength grid: what an
    engine needs to rebuild the per-frame tables (sky view, aerial perspective) for another
    sun or observer ([Hil20] secs. 5.3-5.4 read the coefficients, the density profiles, the
    phase functions, the radii, the ground albedo and the sun); :func:`atmosphere_from_luts`
    turns it back into an :class:`~skydome.atmosphere.Atmosphere`."""
    from skydome.atmosphere import PHASE_CODES, fold_absorbers
    from skydome.atmosphere.profiles import PROFILE_CODES
    from skydome.spectra import solar_irradiance

    p = tb.props                                      # optical_properties(grid, fold=True)
    atm = sky.atmosphere
    keep = fold_absorbers(atm.optical_properties(tb.grid))[1]
    names = [atm.constituents[int(i)].name for i in keep]
    if len(names) != p.profile_code.size:           # pragma: no cover - fold is deterministic
        names = [f"constituent{c}" for c in range(p.profile_code.size)]
    if p.phase_table is not None:
        raise ValueError("the sky has a tabulated phase function: the hillaire2020 bake "
                         "describes analytic phase functions only")
    profile_names = {v: k for k, v in PROFILE_CODES.items()}
    phase_names = {v: k for k, v in PHASE_CODES.items()}
    profile_params = {"exponential": ("scale_height_m", None), "tent": ("center_m",
                      "half_width_m"), "uniform": ("thickness_m", None),
                      "gaussian": ("center_m", "width_m")}
    cons = []
    for c, name in enumerate(names):
        kind = profile_names[int(p.profile_code[c])]
        a, b = profile_params[kind]
        prof = {"type": kind, a: float(p.profile_p0[c])}
        if b is not None:
            prof[b] = float(p.profile_p1[c])
        phase = phase_names[int(p.phase_code[c])]
        param = float(p.phase_param[c])
        entry = {"name": name, "profile": prof, "phase": phase,
                 "scattering_per_m": p.scattering[c].tolist(),
                 "absorption_per_m": (p.extinction[c] - p.scattering[c]).tolist()}
        if phase == "rayleigh":
            entry["depolarisation"] = 2.0 * param / (1.0 + param)    # rho of gamma
        elif phase in ("henyey_greenstein", "cornette_shanks"):
            entry["g"] = param
        cons.append(entry)
    return {
        "note": "coefficients at reference density on wavelengths_nm (the tables' grid), "
                "absorbers that share a density profile folded into one constituent; "
                "density profiles relative to the reference density as in "
                "skydome.atmosphere.profiles (exponential exp(-h / H); tent max(0, 1 - "
                "|h - c| / w); uniform 1 below the thickness; gaussian exp(-((h - c) / "
                "w)^2 / 2)); phase functions as in skydome.transport._phase",
        "planet_radius_m": float(p.planet_radius_m), "top_radius_m": float(p.top_radius_m),
        "wavelengths_nm": np.asarray(tb.grid, dtype=np.float64).tolist(),
        "ground_albedo": np.asarray(p.ground_albedo, dtype=np.float64).tolist(),
        "solar_irradiance_w_m2_nm": solar_irradiance(tb.grid).tolist(),
        "constituents": cons,
    }


def _sun_disc(sky, grid, wl, Ks) -> dict[str, Any]:
    """The sun's disc for an engine: its angular radius, its radiance above the atmosphere
    (XYZ, cd m^-2, at 1 au) and the baked sun's radiance through the atmosphere."""
    from skydome.spectra import spectrum_to_xyz

    s = sky.sun
    top = Ks.sum(axis=0) / s.solid_angle_sr
    seen = spectrum_to_xyz(sky.sun_radiance(wl), wl) / s.irradiance_scale
    return {"angular_radius_deg": float(s.angular_radius_deg),
            "solid_angle_sr": float(s.solid_angle_sr),
            "radiance_top_of_atmosphere_xyz": [float(x) for x in top],
            "radiance_xyz": [float(x) for x in seen],
            "note": "uniform disc (the model draws no limb darkening); radiance_xyz is the "
                    "baked sun's, through the air: for another sun multiply "
                    "radiance_top_of_atmosphere_xyz by the transmittance texture at "
                    "(observer radius, mu_s) (exact per XYZ channel); XYZ at 1 au, multiply "
                    "by Sun.irradiance_scale"}


def atmosphere_from_luts(desc: dict[str, Any]):
    """The :class:`~skydome.atmosphere.Atmosphere` described by a hillaire2020 bake's
    ``luts.json`` (``desc["atmosphere"]``): each coefficient a table on the bake's wavelength
    grid (exact there, linear between), the density profiles and phase functions as
    given. ValueError where the description lacks it."""
    from skydome.atmosphere import Atmosphere, Constituent
    from skydome.atmosphere import profiles as P

    a = desc.get("atmosphere") if isinstance(desc, dict) else None
    if not isinstance(a, dict) or "constituents" not in a:
        raise ValueError("desc has no 'atmosphere' with 'constituents' (a hillaire2020 "
                         f"bake of format {HILLAIRE_FORMAT!r} has them)")
    wl = np.asarray(a["wavelengths_nm"], dtype=np.float64)
    make = {"exponential": lambda q: P.ExponentialProfile(q["scale_height_m"]),
            "tent": lambda q: P.TentProfile(q["center_m"], q["half_width_m"]),
            "uniform": lambda q: P.UniformProfile(q["thickness_m"]),
            "gaussian": lambda q: P.GaussianLayerProfile(q["center_m"], q["width_m"])}

    def coefficient(values):
        v = np.asarray(values, dtype=np.float64)
        return float(v[0]) if wl.size == 1 else (wl, v)

    cons = []
    for c in a["constituents"]:
        kw = {"phase": c["phase"]}
        if "g" in c:
            kw["g"] = c["g"]
        if "depolarisation" in c:
            kw["depolarisation"] = c["depolarisation"]
        cons.append(Constituent(c["name"], scattering=coefficient(c["scattering_per_m"]),
                                absorption=coefficient(c["absorption_per_m"]),
                                profile=make[c["profile"]["type"]](c["profile"]), **kw))
    return Atmosphere(tuple(cons), planet_radius_m=a["planet_radius_m"],
                      top_altitude_m=a["top_radius_m"] - a["planet_radius_m"],
                      ground_albedo=coefficient(a["ground_albedo"]), name="from-luts")


def bake(sky, wavelengths_nm=None, density: bool = True,
         alloc=None) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """The bake of ``sky`` in its model's layout (``lut_layout``): Bruneton's
    (``"bruneton"``, e.g. ``precomputed``, with its scattering density unless ``density``
    is false), Hillaire's (``"hillaire"``, e.g. ``hillaire2020``; any object with the
    precomputed model's ``export_textures`` is baked in Bruneton's) or the fitted model's
    (``"fitted"``: its XYZ tables over sun elevation, :mod:`skydome.export.fitted_luts`);
    ValueError for other models. ``alloc``: where Bruneton's large textures are built
    (:func:`bake_precomputed`)."""
    name = getattr(sky, "name", type(sky).__name__)
    layout = getattr(sky, "lut_layout", None)
    if layout is None and hasattr(sky, "export_textures"):
        layout = "bruneton"         # an object that exports the precomputed model's tables
    if layout == "hillaire":
        return bake_hillaire2020(sky, wavelengths_nm)
    if layout == "fitted":          # the fitted model's XYZ tables over sun elevation
        from skydome.export.fitted_luts import bake_fitted

        return bake_fitted(sky)
    if layout == "bruneton":
        return bake_precomputed(sky, density=bool(density), alloc=alloc)
    if layout is not None:
        raise ValueError(f"model {name!r}: lut_layout = {layout!r} is not one of "
                         f"{', '.join(LUT_LAYOUTS)}")
    raise ValueError(f"model = {name!r} has no LUT bake; valid: {', '.join(lut_models())}")


def _write_npy(target, arr: np.ndarray) -> None:
    """``np.save``'s bytes straight into the file: no in-memory copy of the whole file (an
    io.BytesIO and its getvalue() were two copies of each texture, 545 MB apiece for the
    scattering density)."""
    with open(target, "wb") as fh:
        # through a plain ``write`` (numpy then writes buffered chunks of about 16 MiB) rather
        # than the file itself, for which numpy calls ``tofile``: its OSError on a full disk
        # ("N requested and M written") carries no errno, where ``write``'s is ENOSPC
        np.lib.format.write_array(_PlainWriter(fh), arr, allow_pickle=False)


def _npy_file_allocator(folder: Path, written: dict):
    """``alloc(name, shape)`` of :func:`bake_precomputed` that builds each texture in the
    pages of its own ``<folder>/<name>.npy`` (``numpy.lib.format.open_memmap``: the header
    :func:`_write_npy` writes, then the data, zeros until filled), recorded in ``written``.

    The bake then fills the file's page cache itself, instead of anonymous memory that
    ``write`` copies into the page cache afterwards: on the 2-core virtual machine of
    docs/performance.md the first touch of fresh anonymous pages costs about 2.7 us per
    4 KiB page, and the 545 MB scattering density, filled in memory and written to a new
    file, cost 0.5-1.6 s of system time where filled in its file's mapping it cost 0.25 s
    (with the ``.bin`` copy). The file's blocks are reserved first (``posix_fallocate``),
    so that a full disk is an OSError ENOSPC naming the file before any work rather than
    a SIGBUS on a page of the mapping. None where the platform has no ``posix_fallocate``
    (the textures are then built in memory and written as before)."""
    if not hasattr(os, "posix_fallocate"):
        return None

    def alloc(name: str, shape) -> np.ndarray:
        path = folder / f"{name}.npy"
        arr = np.lib.format.open_memmap(path, mode="w+", dtype="<f4", shape=tuple(shape))
        try:
            with open(path, "r+b") as fh:
                os.posix_fallocate(fh.fileno(), 0, arr.offset + arr.nbytes)
        except OSError as exc:
            raise OSError(exc.errno, exc.strerror, str(path)) from None
        written[name] = arr
        return arr
    return alloc


class _PlainWriter:
    """A file seen only through its ``write`` (see :func:`_write_npy`)."""

    def __init__(self, fh):
        self.write = fh.write


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


def _exr_channels(names) -> list[str]:
    """EXR channel names of a texture's channels: "XYZ" -> X, Y, Z; "XYZA" -> X, Y, Z, A; a
    list -> its names (one per channel)."""
    return list(names)


def _write_exr(tmp: str, arr: np.ndarray, half: bool, desc_name: str, channels) -> None:
    """One EXR image of ``arr`` with the channels named ``channels`` (the first
    len(channels) components of each texel; the unused A of an XYZ texture is left out)."""
    import OpenEXR

    from skydome._io import write_exr

    img = _exr_2d(arr)
    dtype = np.float16 if half else np.float32
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
              "skydome:texture": desc_name}
    ch = {c: np.ascontiguousarray(img[..., i].astype(dtype))
          for i, c in enumerate(_exr_channels(channels))}
    write_exr(tmp, header, ch)     # a full disk: OSError ENOSPC, not OpenEXR's RuntimeError


def write_luts(sky, folder, formats=("npy", "bin"), half: bool = False,
               wavelengths_nm=None, progress=None, density: bool = True) -> list[Path]:
    """Write :func:`bake` of ``sky`` into ``folder``: each texture as ``<name>.bin`` (raw
    little-endian float32), ``<name>.npy`` and/or ``<name>.exr`` (float32, or half with
    ``half``; 3-D textures as their slices stacked top to bottom), and ``luts.json``
    describing axes, mappings, units and the XYZ conversion. The folder appears at once,
    complete (:func:`skydome._io.atomic_folder`); into an existing folder each file is
    renamed into place. ``progress(done, total)`` is called per file. ``density=False``
    leaves out the precomputed bake's scattering density (545 MB in float32 at the default
    sizes; the shader's table path does not need it). Returns the paths."""
    from skydome._io import atomic_folder, check_output_folder

    formats = check_luts_options(formats, half)
    folder = check_output_folder(folder)
    with atomic_folder(folder) as tmp:
        mapped: dict[str, np.ndarray] = {}     # textures built in their .npy file's pages
        alloc = _npy_file_allocator(tmp, mapped) if "npy" in formats else None
        tex, desc = bake(sky, wavelengths_nm, density, alloc=alloc)
        written = _write_baked(tex, desc, folder, tmp, formats, half, mapped, progress)
        del tex, mapped                 # the mappings: the files are complete
    if progress is not None:
        progress(len(written), len(written))
    return written


def _write_baked(tex, desc, folder, tmp, formats, half, mapped, progress) -> list[Path]:
    """:func:`write_luts`'s files of a bake into the temporary folder ``tmp`` (those in
    ``mapped`` are their .npy files' mappings: already written)."""
    chans = {n: (desc["textures"].get(n) or {}).get("channels") for n in tex}
    exr_scale = {n: 1.0 for n in tex}
    if half:
        from skydome.export.envmap import HALF_MAX

        for n in tex:
            if chans[n]:
                big = float(np.max(tex[n]))
                # a texture beyond the half-float range in kcd m^-2 (half floats keep 11
                # bits: the precomputed sky through them within 0.034 % at sun 60 to -4
                # deg, 0.2 % at -10 deg)
                exr_scale[n] = 1e-3 if big > HALF_MAX else 1.0
                if big * exr_scale[n] > HALF_MAX:
                    raise ValueError(f"half = True: the largest texel of {n}, {big:.4g}, "
                                     f"exceeds the half-float range ({HALF_MAX:g}) even "
                                     "scaled by 1e-3; write float32")
                if exr_scale[n] != 1.0:
                    desc["textures"][n]["exr_scale"] = exr_scale[n]
    desc["files"] = {n: [f"{n}.{f}" for f in formats if f != "exr" or chans[n]]
                     for n in tex}
    if "exr" in formats:
        desc["exr"] = {"dtype": "float16" if half else "float32",
                       "channels": "named for what they hold (textures.<name>.channels): X, "
                                   "Y, Z for CIE XYZ, A where the alpha channel holds "
                                   "something; an unused A is not written",
                       "3-D textures": "slices stacked top to bottom: image row = "
                                       "slice * height + row",
                       "spectral textures": "not in EXR (.npy / .bin only)",
                       "scale": "EXR value = texture value x textures.<name>.exr_scale "
                                "(1 where absent; 1e-3, i.e. kcd m^-2, for a half-float "
                                "texture beyond the half-float range, 65504)"}
    names = [(n, f) for n in tex for f in formats if f != "exr" or chans[n]]
    total = len(names) + 1
    written = []
    for k, (n, f) in enumerate(names):
        arr = np.ascontiguousarray(tex[n], dtype="<f4")
        target = tmp / f"{n}.{f}"
        if f == "bin":     # Python's writes: a full disk raises OSError ENOSPC
            with open(target, "wb") as fh:
                fh.write(memoryview(arr.reshape(-1)).cast("B"))
        elif f == "npy":
            if n not in mapped:         # else built in the file's own pages
                _write_npy(target, arr)
        else:
            _write_exr(str(target), arr * np.float32(exr_scale[n]) if exr_scale[n] != 1.0
                       else arr, half, n, chans[n])
        written.append(folder / target.name)
        if progress is not None:
            progress(k + 1, total)
    (tmp / "luts.json").write_text(json.dumps(desc, indent=2))
    written.append(folder / "luts.json")
    return written


def write_precomputed_luts(sky, folder) -> list[str]:
    """Write :func:`bake_precomputed` as ``<name>.bin`` (raw little-endian float32),
    ``<name>.npy`` and ``luts.json`` into ``folder`` (:func:`write_luts`). Returns the
    paths."""
    if not hasattr(sky, "export_textures"):
        raise ValueError("write_precomputed_luts needs a precomputed sky")
    return [str(p) for p in write_luts(sky, folder, ("bin", "npy"))]
