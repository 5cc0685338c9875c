"""What a viewer shader needs for one model, computed by skydome's own CPU code.

:func:`shader_scene` validates a request (model name, sun, model parameters: the same
checks and messages as the CLI and the model constructors), builds the model with
:func:`skydome.model` and returns a JSON-ready dict of the numbers its shader uses.
Nothing physical is computed in the page that is not also computed here or in the model:

* ``preetham1999``: the Perez coefficients A..E of x, y and Y ([PSS99] Appendix A.2) and
  the zenith values divided by F(0, theta_s) ([PSS99] eq. 3), as the CPU kernel
  ``_kernels_analytic.preetham`` takes them.
* ``hoffman_preetham2002``: beta_R, beta_M and the attenuated sun's irradiance E_sun per
  wavelength of skydome's default grid ([HP02], [PSS99] A.1, A.3), plus the CIE 1931
  weights that turn a spectrum on that grid into XYZ (:func:`skydome.spectra.integration_weights`,
  the map :meth:`SkyModel.xyz` applies).
* ``oneil2005``: 1 / lambda^4 and the solar irradiance per wavelength, the chapter's
  constants ([ONe05] 16.2-16.5) and the same CIE weights.
* ``dobashi2002``: the synthetic mountain scene's heightmap with its shadow-volume top and
  Lambert term on the grid, and the [DYN02] tables J_c, D_c of
  :func:`skydome.effects.dobashi2002.build_tables` reduced to XYZ per constituent (the
  phase functions do not depend on the wavelength, so the reduction is exact), for the
  effect's fixed extent (the scene's march range) and every view cosine.
* ``fitted``: the configuration's angular table in XYZ (``FittedSky.xyz_table``, the
  table the model's ``xyz()`` looks up) and the constants of its view grid's mappings.

References
----------
[PSS99] Preetham, Shirley & Smits, SIGGRAPH 99. [HP02] Hoffman & Preetham, GDC 2002.
[ONe05] O'Neil, GPU Gems 2, ch. 16. [DYN02] Dobashi, Yamamoto & Nishita, Graphics
Hardware 2002.
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np

__all__ = ["VIEWER_MODELS", "SUN_KEYS", "parse_request", "shader_scene", "build_model",
           "viewer_models", "VIEWS"]


def viewer_models() -> dict[str, tuple[str, ...]]:
    """Models the viewer renders with a shader, and the model parameters it exposes: every
    registered model that declares a ``viewer_shader`` (with its ``viewer_parameters``;
    skydome.models, capabilities), by the year in its name (names without one last), then
    the viewer's own scenes (:data:`VIEWS`). ``VIEWER_MODELS`` is the same dict, read when
    asked for."""
    import re

    from skydome.models import available

    def year(name):
        m = re.search(r"(\d{4})$", name)
        return (int(m.group(1)) if m else 10_000, name)

    found = {n: cls for n, cls in available().items() if cls.viewer_shader is not None}
    out = {n: tuple(found[n].viewer_parameters) for n in sorted(found, key=year)}
    out.update({n: tuple(v.viewer_parameters) for n, v in VIEWS.items()})
    return out


def __getattr__(name):
    if name == "VIEWER_MODELS":
        return viewer_models()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

#: Table sizes of the viewer's precomputed model: smaller than the model's defaults so that
#: a turbidity change bakes in about 10 s on two cores (the sun and the observer altitude
#: never need a new bake: the tables hold every r and mu_s).
PRECOMPUTED_VIEWER_SIZES = {"n_wavelengths": 8, "scattering_r_size": 16, "scattering_mu_size": 64,
                            "scattering_mu_s_size": 16, "scattering_nu_size": 8, "orders": 4,
                            # the viewer's tables stay in memory: a request can never write
                            # to (or evict entries from) the user's on-disk table cache
                            "cache": False}

#: Request keys that place the sun (by angles, or by place and time).
SUN_KEYS = ("sun_elevation", "sun_azimuth", "lat", "lon", "time")

#: Largest number of view-ray samples the oneil2005 shader loops over (a shader loop
#: needs a constant bound).
ONEIL_MAX_SAMPLES = 16


def _number(key: str, text: str, kind: str = "float"):
    try:
        return int(text) if kind == "int" else float(text)
    except (TypeError, ValueError):
        raise ValueError(f"{key} = {text!r} is not a valid {kind}") from None


class Dobashi2002View:
    """The viewer's dobashi2002 scene: the aerial perspective and light shafts of
    :mod:`skydome.effects.dobashi2002` over :func:`synthetic_mountains` (seed 0, camera
    ``DEFAULT_CAMERA``'s position; the page turns the view). Not a sky model: the sky
    behind the terrain is not rendered."""

    name = "dobashi2002"
    viewer_shader = "dobashi2002"
    viewer_parameters = ("turbidity", "shafts", "n_planes")
    reference = "Dobashi, Yamamoto & Nishita 2002"
    summary = ("light shafts and aerial perspective over a synthetic mountain scene: sampling "
               "planes, 2D look-up tables, shadow volume from a heightmap")
    #: table sizes: distance nodes over the scene's march range, view cosines over [-1, 1]
    N_DISTANCE, N_ANGLE, N_WAVELENGTHS = 64, 256, 21

    @staticmethod
    def _parameters():
        from skydome.models import Parameter

        return (Parameter("turbidity", "", 2.5, 1.0, 32.0, "Preetham turbidity of the air"),
                Parameter("shafts", "", True, doc="shadow test at the sampling planes (light shafts)",
                          kind="bool"),
                Parameter("n_planes", "", 48, 1, 128, "sampling planes", kind="int"))

    parameters = property(lambda self: self._parameters())

    def __init__(self, sun, turbidity=2.5, shafts=True, n_planes=48):
        pars = {p.name: p for p in self._parameters()}
        self.sun = sun
        self.turbidity = pars["turbidity"].validate(turbidity)
        self.shafts = pars["shafts"].validate(shafts)
        self.n_planes = pars["n_planes"].validate(n_planes)

    def describe(self) -> dict:
        return {"model": self.name, "turbidity": self.turbidity, "shafts": self.shafts,
                "n_planes": self.n_planes, "sun_elevation_deg": self.sun.elevation_deg,
                "sun_azimuth_deg": self.sun.azimuth_deg}


#: The viewer's own scenes that are not sky models, by name (the page lists them after
#: the models; each class declares ``viewer_shader`` and ``viewer_parameters``).
VIEWS = {Dobashi2002View.name: Dobashi2002View}


def viewer_class(name: str):
    """The class whose ``parameters`` the page shows for model ``name``."""
    if name in VIEWS:
        return VIEWS[name]
    from skydome.models import get_model_class

    return get_model_class(name)


def _bool(key: str, text: str) -> bool:
    words = {"true": True, "1": True, "yes": True, "false": False, "0": False, "no": False}
    if text.lower() not in words:
        raise ValueError(f"{key} = {text!r} is not a boolean: give true, false, yes, no, 1 or 0")
    return words[text.lower()]


def parse_request(query: Mapping[str, str]) -> tuple[str, dict[str, Any], dict[str, Any]]:
    """Split a request's query into (model name, sun keywords, model keywords).

    Every value arrives as text; numbers are converted with a message naming the key.
    Unknown keys raise ValueError naming the valid ones.
    """
    model = query.get("model")
    models = viewer_models()
    if model is None:
        raise ValueError(f"model is missing; valid: {', '.join(models)}")
    if model not in models:
        raise ValueError(f"model = {model!r} is not one of {', '.join(models)}")
    cls = viewer_class(model)
    params_of = cls._parameters() if model in VIEWS else cls.parameters
    pars = {p.name: p for p in params_of if p.name in models[model]}
    sun: dict[str, Any] = {}
    params: dict[str, Any] = {}
    for key, text in query.items():
        if key == "model":
            continue
        if key in SUN_KEYS:
            sun[key] = text if key == "time" else _number(key, text)
        elif key in pars:
            p = pars[key]
            if p.kind == "choice":
                params[key] = text
            elif p.kind == "bool":
                params[key] = _bool(key, text)
            else:
                params[key] = _number(key, text, p.kind)
        else:
            valid = ", ".join(("model",) + SUN_KEYS + tuple(pars))
            raise ValueError(f"unknown parameter {key!r} for model {model!r}; valid: {valid}")
    return model, sun, params


def build_model(model: str, sun_kw: Mapping[str, Any], params: Mapping[str, Any]):
    """The skydome model the page renders (its constructor validates the parameters)."""
    import skydome

    from skydome.sun import sun_from_options

    sun = sun_from_options(**sun_kw)
    if model in VIEWS:
        return VIEWS[model](sun, **params)
    shader = viewer_class(model).viewer_shader
    if shader == "precomputed":
        return _precomputed_model(sun, dict(params))
    if shader == "oneil2005" and params.get("samples", 2) > ONEIL_MAX_SAMPLES:
        raise ValueError(f"samples = {params['samples']} is out of range [1, "
                         f"{ONEIL_MAX_SAMPLES}] in the viewer")
    return skydome.model(model, sun=sun, **params)


_PRECOMPUTED_MODELS: dict = {}
_LUTS: dict = {}


def _precomputed_model(sun, params: dict):
    """The precomputed model for ``sun``: tables built once per turbidity (viewer sizes),
    then :meth:`PrecomputedSky.with_sun` for each sun and observer altitude."""
    import skydome
    from skydome.models import get_model_class

    cls = get_model_class("precomputed")
    pars = {p.name: p for p in cls.parameters}
    T = pars["turbidity"].validate(params.get("turbidity", pars["turbidity"].default))
    h = params.get("observer_altitude_m", 0.0)
    key = round(float(T), 9)
    if key not in _PRECOMPUTED_MODELS:
        if len(_PRECOMPUTED_MODELS) >= 2:
            _PRECOMPUTED_MODELS.clear()
        # the shader reads single scattering from the 4-D table in twilight too: its CPU
        # twin does the same (the CPU default integrates it at the observer; the shader
        # against that default: docs/viewer.md)
        _PRECOMPUTED_MODELS[key] = skydome.model("precomputed", sun=sun, turbidity=T,
                                                 twilight_single_scattering=False,
                                                 **PRECOMPUTED_VIEWER_SIZES)
    return _PRECOMPUTED_MODELS[key].with_sun(sun, observer_altitude_m=h)


def lut_bytes(key: str, name: str) -> bytes:
    """The float32 bytes of baked texture ``name`` of bake ``key`` (ValueError if unknown)."""
    if key not in _LUTS:
        raise ValueError(f"key = {key!r} is not a baked table set; valid: {', '.join(_LUTS) or 'none'}")
    tex = _LUTS[key][0]
    if name not in tex:
        raise ValueError(f"name = {name!r} is not a texture of {key}; valid: {', '.join(tex)}")
    return np.ascontiguousarray(tex[name], dtype="<f4").tobytes()


def _precomputed(sky) -> dict[str, Any]:
    from skydome.export.luts import bake_precomputed

    key = f"precomputed/T={sky.turbidity:.9g}"
    if key not in _LUTS:
        if len(_LUTS) >= 2:
            _LUTS.clear()
        _LUTS[key] = bake_precomputed(sky, ground=True)
    tex, desc = _LUTS[key]
    sz = desc["sizes"]
    if len(desc["phase_code"]) > 2:
        raise ValueError("the viewer's precomputed shader takes at most 2 scattering constituents")
    pc = (desc["phase_code"] + [3])[:2]
    pp = (desc["phase_param"] + [0.0])[:2]
    return {"lut_key": key, "textures": {n: v["shape"] for n, v in desc["textures"].items()},
            "sizes": [sz["r"], sz["mu"], sz["mu_s"], sz["nu"]], "R": desc["planet_radius_m"],
            "Rt": desc["top_radius_m"], "mu_s_min": desc["mu_s_min"],
            "h0": sky.observer_altitude_m, "irradiance_scale": sky.sun.irradiance_scale,
            "nsc": len(desc["phase_code"]), "pc": pc, "pp": pp,
            # the ground ([Bru17] GetSkyRadianceToPoint + GetSunAndSkyIrradiance), spectral
            "nl": len(desc["table_wavelengths_nm"]), "albedo": desc["ground_albedo"],
            "K": np.asarray(desc["xyz_weights"]).ravel().tolist(),
            "sun_alpha": float(np.radians(sky.sun.angular_radius_deg))}


def _xyz_weights(wl: np.ndarray) -> np.ndarray:
    """(n, 3) weights with XYZ = L @ W: K_m times the CIE 1931 integration weights, the
    linear map that :meth:`SkyModel.xyz` applies to a spectrum on grid ``wl``."""
    from skydome.constants import K_M
    from skydome.spectra import integration_weights

    return K_M * np.asarray(integration_weights(wl))


def _sun_block(sky) -> dict[str, Any]:
    s = sky.sun
    return {"elevation_deg": float(s.elevation_deg), "azimuth_deg": float(s.azimuth_deg),
            "direction": [float(v) for v in s.direction]}


def _preetham(sky) -> dict[str, Any]:
    from skydome.models.analytic import preetham1999 as p99

    T = sky.turbidity
    theta_s = float(np.radians(sky.sun.zenith_deg))
    coef = p99.perez_coefficients(T)                                   # [PSS99] A.2
    Yz = float(p99.zenith_luminance(T, theta_s))                        # [PSS99] A.2
    xz, yz = (float(v) for v in p99.zenith_chromaticity(T, theta_s))    # [PSS99] A.2
    zval = {"x": xz, "y": yz, "Y": Yz}
    # F(0, theta_s): the Perez function at the zenith ([PSS99] eq. 3 denominator)
    zen = [zval[k] / float(p99.perez_function(1.0, theta_s, coef[k])) for k in ("x", "y", "Y")]
    return {"coef": [[float(v) for v in coef[k]] for k in ("x", "y", "Y")],
            "zenith": zen, "cos_floor": 1e-6}


def _hoffman(sky) -> dict[str, Any]:
    from skydome.models.analytic import hoffman_preetham2002 as hp
    from skydome.models.analytic import preetham1999 as p99
    from skydome.spectra import default_wavelengths

    wl = default_wavelengths()
    beta_r = p99.rayleigh_coefficient(wl)                               # [PSS99] A.3
    # the sky view's haze column factor (1200 m / 8803 m), as HoffmanPreetham2002.radiance
    beta_m = p99.mie_coefficient(wl, sky.turbidity) * (p99.ALPHA_MOLECULES / p99.ALPHA_HAZE)
    e_sun = p99.sun_radiance(wl, sky.sun, sky.turbidity) * sky.sun.solid_angle_sr
    return {"wavelengths_nm": wl.tolist(), "beta_r": beta_r.tolist(), "beta_m": beta_m.tolist(),
            "e_sun": e_sun.tolist(), "xyz_weights": _xyz_weights(wl).tolist(),
            "g": sky.g, "hp_phase": 1 if sky.phase == "hoffman_preetham" else 0,
            "shell_m": sky.sky_distance_m, "earth_radius_m": hp.EARTH_RADIUS_M}


def _oneil(sky) -> dict[str, Any]:
    from skydome.spectra import default_wavelengths, solar_irradiance

    if sky.depth_function != "polynomial":
        raise ValueError("depth_function = 'exact' is not available in the viewer "
                         "(the shader uses the chapter's polynomial)")
    wl = default_wavelengths()
    inv_wl4 = (wl / 1000.0) ** -4.0                                     # [ONe05] v3InvWavelength
    e_sun = solar_irradiance(wl) * sky.sun.irradiance_scale
    return {"wavelengths_nm": wl.tolist(), "inv_wl4": inv_wl4.tolist(), "e_sun": e_sun.tolist(),
            "xyz_weights": _xyz_weights(wl).tolist(), "kr": sky.kr, "km": sky.km, "g": sky.g,
            "scale_depth": sky.scale_depth, "outer_ratio": sky.outer_ratio,
            "samples": int(sky.samples)}


def _b64(a: np.ndarray) -> str:
    import base64

    return base64.b64encode(np.ascontiguousarray(a, dtype="<f4").tobytes()).decode("ascii")


def _layers(tab: np.ndarray, n4: int) -> np.ndarray:
    """(ny, nx, nl) table -> (n4, ny, nx, 4): texture layers of four wavelengths each
    (zero-padded), the layout of a WebGL2 RGBA32F 2-D array texture."""
    ny, nx, nl = tab.shape
    out = np.zeros((ny, nx, 4 * n4))
    out[..., :nl] = tab
    return out.reshape(ny, nx, n4, 4).transpose(2, 0, 1, 3)


def _hillaire_weights(grid: np.ndarray, wl: np.ndarray, solar: np.ndarray,
                      lam4: bool = True) -> np.ndarray:
    """(n_grid, 3): XYZ = sum_g K_g L_g for radiance per unit irradiance L on the table
    grid, the linear map of Hillaire2020Sky.radiance (values on the grid taken to ``wl``
    linearly in L lambda^4, times the solar spectrum) followed by SkyModel.xyz's CIE
    weights. With ``lam4`` False, linear in the value itself: the map of
    Hillaire2020Sky.aerial_perspective's transmittance (np.interp), times the solar
    spectrum (the XYZ of sunlight seen through the air)."""
    if grid.shape == wl.shape and np.array_equal(grid, wl):
        M = np.eye(wl.size)
    else:
        idx = np.clip(np.searchsorted(grid, wl) - 1, 0, grid.size - 2)
        a = (wl - grid[idx]) / (grid[idx + 1] - grid[idx])
        M = np.zeros((wl.size, grid.size))
        rows = np.arange(wl.size)
        p = 4.0 if lam4 else 0.0
        M[rows, idx] += (1.0 - a) * grid[idx] ** p / wl ** p
        M[rows, idx + 1] += a * grid[idx + 1] ** p / wl ** p
    return (M * solar[:, None]).T @ _xyz_weights(wl)


_HILLAIRE_CACHE: dict = {}


def _hillaire(sky) -> dict[str, Any]:
    from skydome.spectra import default_wavelengths, solar_irradiance

    wl = default_wavelengths()
    key = (round(sky.turbidity, 9), round(sky.observer_altitude_m, 6), sky.n_wavelengths)
    if key not in _HILLAIRE_CACHE:
        from skydome.atmosphere import fold_absorbers

        tb = sky.tables(wl)                   # [Hil20] 4.1 transmittance, 5.5 Psi_ms (eqs. 5-10)
        p, _ = fold_absorbers(tb.props)       # mixed gases into Rayleigh: 4 constituents (exact)
        nl = tb.grid.size
        n4 = (nl + 3) // 4
        nc = int(p.profile_code.size)
        if nc > 4:
            raise ValueError(f"the atmosphere has {nc} constituents; the viewer's hillaire2020 "
                             "shader takes at most 4")

        def per_c(x):
            out = np.zeros((4, 4 * n4))
            out[:nc, :nl] = x
            return out.reshape(4 * n4 * 4).tolist()

        def pad4(x, fill=0.0):
            out = np.full(4, fill)
            out[:nc] = x
            return out.tolist()

        alb = np.zeros(4 * n4)
        alb[:nl] = p.ground_albedo
        _HILLAIRE_CACHE.clear()
        _HILLAIRE_CACHE[key] = {
            "lut_key": f"hillaire2020/{key}", "grid_nm": tb.grid.tolist(), "ng": n4, "nc": nc,
            "tlut_size": [int(tb.tlut.shape[1]), int(tb.tlut.shape[0])],
            "mslut_size": [int(tb.mslut.shape[1]), int(tb.mslut.shape[0])],
            "tlut_b64": _b64(_layers(tb.tlut, n4)), "mslut_b64": _b64(_layers(tb.mslut, n4)),
            "R": tb.R, "Rt": tb.Rt, "ts": tb.ts, "codes": pad4(p.profile_code, 0),
            "p0": pad4(p.profile_p0, 1.0), "p1": pad4(p.profile_p1, 1.0),
            "phase_codes": pad4(p.phase_code, 3), "phase_params": pad4(p.phase_param),
            "beta_s": per_c(p.scattering), "beta_e": per_c(p.extinction),
            "albedo": alb.tolist()}
    out = dict(_HILLAIRE_CACHE[key])
    grid = np.asarray(out["grid_nm"])
    K = np.zeros((4 * out["ng"], 3))
    KT = np.zeros((4 * out["ng"], 3))
    solar = solar_irradiance(wl) * sky.sun.irradiance_scale
    K[:grid.size] = _hillaire_weights(grid, wl, solar)
    KT[:grid.size] = _hillaire_weights(grid, wl, solar, lam4=False)
    out.update({"K": K.tolist(), "KT": KT.tolist(), "sun_xyz": KT.sum(axis=0).tolist(), "h0": sky.observer_altitude_m,
                "ap_size": sky.ap_size, "ap_km_per_slice": sky.ap_km_per_slice,
                "ap_samples": sky.ap_samples,
                "sv_size": [sky.skyview_width, sky.skyview_height], "n_steps": sky.view_samples,
                "use_ms": 1 if sky.multiple_scattering else 0})
    return out


_DOBASHI_CACHE: dict = {}


def _dobashi(view) -> dict[str, Any]:
    """Heightmap, shadow volume and [DYN02] tables for the page's dobashi2002 shader."""
    from skydome.atmosphere import Atmosphere
    from skydome.constants import EARTH_RADIUS
    from skydome.effects import dobashi2002 as dy
    from skydome.spectra import _M_SRGB_TO_XYZ, _M_XYZ_TO_SRGB

    sun = view.sun
    key = (round(view.turbidity, 9), tuple(round(float(v), 12) for v in sun.direction))
    if key not in _DOBASHI_CACHE:
        cam = dy.DEFAULT_CAMERA
        _, _, hm = dy.synthetic_mountains(8, 8, seed=0, camera=cam, sun=sun)
        far = 1000.0 * 35.0 * dy.MARCH_RANGE        # synthetic_mountains' march range (ranges_km)
        atm = Atmosphere.earth(turbidity=view.turbidity)
        wl = np.linspace(380.0, 780.0, view.N_WAVELENGTHS)
        tb = dy.build_tables(atm, wl, sun, cam.altitude_m, far, (-1.0, 1.0), view.N_DISTANCE,
                             view.N_ANGLE)                                       # eqs. (2)-(3)
        from skydome.atmosphere import fold_absorbers
        from skydome.transport._medium import medium_from_properties

        props, keep = fold_absorbers(atm.optical_properties(wl))   # exact; see its docstring
        med = medium_from_properties(props)
        nc = int(med.phase_code.size)
        if nc > 4:
            raise ValueError(f"the atmosphere has {nc} constituents; the viewer takes at most 4")
        pp = np.asarray(med.phase_param, dtype=np.float64).reshape(nc, -1)
        if not np.allclose(pp, pp[:, :1]):
            raise ValueError("the viewer's dobashi2002 shader needs phase functions that do not "
                             "depend on the wavelength")
        W = _xyz_weights(wl)                                                    # (nl, 3)
        # J~_c = sum_l W_l E_sun,l beta_c,l J_c,l: eq. (1) per constituent, in XYZ
        # (a folded absorber does not scatter, and its column densities are those of the
        # constituent it joined: its J term is 0 and its optical depth is in ext below)
        JX = np.einsum("dacl,cl,l,lk->cdak", tb.J[:, :, keep], tb.scattering[keep], tb.e_sun, W)
        tex = np.concatenate([JX, np.transpose(tb.D[:, :, keep], (2, 0, 1))[..., None]], axis=-1)   # (nc, nd, na, 4)
        ref = dy.reference_sunlight(atm, sun, cam.altitude_m, wl)
        top = dy.shadow_volume_top(hm, sun.direction)
        # channel 3: the highest of the four heights that a bilinear sample in cell (j, i)
        # reads, so that the page's march skips the sample where the ray is above them all
        Hm = hm.heights_m
        cell = np.zeros_like(Hm)
        cell[:-1, :-1] = np.maximum(np.maximum(Hm[:-1, :-1], Hm[:-1, 1:]), np.maximum(Hm[1:, :-1], Hm[1:, 1:]))
        grid = np.stack([Hm, np.minimum(top, 1e30), dy.terrain_lambert(hm, sun.direction), cell], axis=-1)
        ext = np.zeros((4, wl.size))
        ext[:nc] = props.extinction
        _DOBASHI_CACHE.clear()
        _DOBASHI_CACHE[key] = {
            "lut_key": f"dobashi2002/{key}", "nc": nc, "nl": int(wl.size),
            "wavelengths_nm": wl.tolist(), "tables_b64": _b64(tex), "table_size": [tb.mu.size, tb.t_m.size],
            "mu_range": [float(tb.mu[0]), float(tb.mu[-1])], "extent_m": far,
            "grid_b64": _b64(grid), "grid_size": [hm.x_m.size, hm.y_m.size],
            "grid_origin": [float(hm.x_m[0]), float(hm.y_m[0])],
            "grid_step": [float(hm.x_m[1] - hm.x_m[0]), float(hm.y_m[1] - hm.y_m[0])],
            "hmax": float(hm.heights_m.max()),
            "eye": [cam.east_m, cam.north_m, cam.altitude_m],
            "planet_radius_m": atm.planet_radius_m, "datum_radius_m": EARTH_RADIUS,
            "march_steps": dy.MARCH_STEPS,
            "phase_codes": [int(v) for v in med.phase_code] + [3] * (4 - nc),
            "phase_params": [float(v) for v in pp[:, 0]] + [0.0] * (4 - nc),
            "ext": ext.T.reshape(-1).tolist(),                                   # (nl, 4)
            "t_weights": (W * (ref / np.pi)[:, None]).tolist(),                  # (nl, 3)
            "albedo": dy.TERRAIN_ALBEDO.tolist(), "fill": dy.TERRAIN_FILL,
            "srgb_to_xyz": np.asarray(_M_SRGB_TO_XYZ).T.reshape(-1).tolist(),   # column-major
            "xyz_to_srgb": np.asarray(_M_XYZ_TO_SRGB).T.reshape(-1).tolist()}
    out = dict(_DOBASHI_CACHE[key])
    out.update({"shafts": 1 if view.shafts else 0, "n_planes": view.n_planes})
    return out


def _fitted(sky) -> dict[str, Any]:
    """The fitted model's angular table of this configuration in XYZ (FittedSky.xyz_table,
    the table its xyz() looks up; built on the CPU in milliseconds) as an RGBA32F texture,
    rows = the view grid's zenith-angle nodes, columns = its azimuth nodes, and the
    constants of the inverse mappings (skydome.models.fitted._grid, _kernels.lookup)."""
    import math

    from skydome.models.fitted import _grid

    tab = sky.xyz_table()                                   # (rows, N_PHI, 3) [cd m^-2]
    rgba = np.zeros(tab.shape[:2] + (4,))
    rgba[..., :3] = tab
    th_h = _grid.horizon_zenith_rad(sky.observer_altitude_m)
    az = math.radians(float(sky.sun.azimuth_deg))
    return {"table_b64": _b64(rgba), "n": [_grid.N_SKY, _grid.N_GROUND, _grid.N_PHI],
            "theta_h": th_h, "inv_sky": 1.0 / (th_h - _grid.EPS),
            "inv_ground": 1.0 / (math.pi - th_h - _grid.EPS), "eps": _grid.EPS,
            "a_phi": _grid.A_PHI, "sun_az": [math.sin(az), math.cos(az)]}


#: The numbers of each shader (``viewer_shader``), by shader.
_BUILDERS = {"preetham1999": _preetham, "hoffman_preetham2002": _hoffman, "oneil2005": _oneil,
             "hillaire2020": _hillaire, "precomputed": _precomputed, "dobashi2002": _dobashi,
             "fitted": _fitted}


def shader_scene(query: Mapping[str, str]) -> dict[str, Any]:
    """Validate ``query`` (text values, as from a URL) and return the shader's numbers.

    Raises ValueError or TypeError with the CLI's message on bad input.
    """
    model, sun_kw, params = parse_request(query)
    sky = build_model(model, sun_kw, params)
    shader = viewer_class(model).viewer_shader
    out = {"model": model, "shader": shader, "sun": _sun_block(sky),
           "describe": _jsonable(sky.describe())}
    out.update(_BUILDERS[shader](sky))
    out["sun_disc"] = _sun_disc(sky)
    return out


def _sun_disc(sky) -> dict[str, Any] | None:
    """The sun's disc as ``skydome.imaging.render`` draws it into an XYZ image: the model's
    mean disc radiance (``sun_disc_radiance`` on the default grid, reduced to XYZ with the
    render's CIE weights; Y in cd/m^2), the angular radius [rad] and [Nec05]'s
    limb-darkening polynomial I(mu) / I_mean at the X, Y and Z channels' wavelengths
    (``XYZ_CHANNEL_WAVELENGTHS_NM``; coefficients of mu^0..mu^5 per channel, divided by the
    disc mean so that the disc averages to 1). None for a scene without a sun (dobashi2002)
    or where the render draws none (sun below minus its angular radius)."""
    from skydome.imaging import sun_disc as sd
    from skydome.spectra import default_wavelengths

    sun = getattr(sky, "sun", None)
    if sun is None or not callable(getattr(sky, "sun_radiance", None)):
        return None
    if not sun.elevation_deg > -sun.angular_radius_deg:
        return None
    wl = default_wavelengths()
    L = sd.sun_disc_radiance(sky, wl)
    if L is None:
        return None
    xyz = np.asarray(L, dtype=np.float64) @ _xyz_weights(wl)
    ch = np.asarray(sd.XYZ_CHANNEL_WAVELENGTHS_NM)
    A = sd._neckel_coefficients(ch) / sd.limb_darkening_mean(ch)[:, None]     # (3, 6)
    return {"xyz": [float(v) for v in xyz], "alpha": float(np.radians(sun.angular_radius_deg)),
            "limb": A.T.ravel().tolist()}                                     # (6, 3): mu^k rows


def _jsonable(obj):
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, (bool, int, float, str)) or obj is None:
        return obj
    if isinstance(obj, np.generic):
        return obj.item()
    return str(obj)
