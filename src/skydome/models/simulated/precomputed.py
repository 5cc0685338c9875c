"""``precomputed``: a spectral sky from precomputed scattering tables (Bruneton 2017).

E. Bruneton's "Precomputed Atmospheric Scattering: a New Implementation" (2017; the
reworking of Bruneton & Neyret 2008) tabulates, for a spherical-shell atmosphere, the
transmittance T(r, mu), the in-scattered radiance S(r, mu, mu_s, nu) summed over N
scattering orders and the ground irradiance E(r, mu_s). Rendering any view is then a few
table lookups. This module computes the tables with numba on the CPU, per wavelength (20
by default over 380-780 nm), for any :class:`skydome.atmosphere.Atmosphere`; it keeps
each constituent's single scattering apart (the phase function is applied at render
time, so the aerosol forward peak stays sharp) and stores multiple scattering as full
radiance.

References
----------
[Bru17] E. Bruneton, Precomputed Atmospheric Scattering: a New Implementation, 2017,
    https://ebruneton.github.io/precomputed_atmospheric_scattering/ (atmosphere/functions.glsl).
[BN08] E. Bruneton, F. Neyret, Precomputed Atmospheric Scattering, EGSR 2008, eqs. 1-9.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
import time

import numpy as np

from skydome._validate import as_directions, as_wavelengths, check_number
from skydome.models import Parameter, SkyModel, check_sun, register, resolve_atmosphere

__all__ = ["PrecomputedSky", "Precomputed"]

_FORMAT = "skydome.precomputed/1"
_QUADRATURE_SCALE_M = 500.0
# the observer's sky map of orders 2..N: view zenith nodes below / above the horizon (uniform
# in angle) and azimuth nodes from the sun's over [0, 180] deg
_SLICE_GROUND, _SLICE_SKY, _SLICE_PHI = 48, 192, 96


@register
class PrecomputedSky(SkyModel):
    """Bruneton's (2017) precomputed multiple-scattering sky, spectral, built on the CPU.

    Parameters
    ----------
    sun : skydome.Sun
        Sun position. Sun elevations down to ``90 - max_sun_zenith_deg`` (-18 deg by
        default) are in the tables; below that the sky is night: radiance 0.
    atmosphere : skydome.Atmosphere, optional
        The medium. Default ``Atmosphere.earth(turbidity=turbidity)``.
    turbidity : float
        Preetham turbidity [1, 32] used when no atmosphere is given (default 2.5).
    observer_altitude_m : float
        Observer altitude above the ground [m], [0, top of the atmosphere).
    n_wavelengths : int
        Number of table wavelengths, evenly spaced over 380-780 nm (default 20).
    table_wavelengths_nm : array_like, optional
        Explicit table wavelength grid [nm] (instead of ``n_wavelengths``).
    orders : int
        Number of scattering orders, [1, 20] (default 4). Ground reflections count as
        orders.
    remaining_orders : {"none", "geometric"}
        "geometric" adds the orders beyond ``orders`` as a geometric series whose ratio is
        that of the last two computed orders' total radiance, per wavelength (clamped to 0.9;
        after Hillaire 2020, eq. 10); see the validated settings below.
    transmittance_mu_size, transmittance_r_size : int
        Transmittance (column) table size, default 256 x 64.
    scattering_r_size, scattering_mu_size, scattering_mu_s_size, scattering_nu_size : int
        4-D scattering table size, default 32 x 128 x 32 x 8 (Bruneton's; ``scattering_mu_size``
        even).
    irradiance_mu_s_size, irradiance_r_size : int
        Ground-irradiance table size, default 64 x 16.
    integration_samples : int
        Quadrature nodes per ray piece for single and multiple scattering (default 20).
    sphere_samples : int
        Zenith-angle samples of the incident directions in the scattering density
        (Bruneton's 16; azimuth gets twice as many over the full circle).
    density_mu_s_size : int, optional
        mu_s nodes of the scattering density J (default: ``scattering_mu_s_size``).

    The defaults are Bruneton's sizes. The settings validated against the Monte Carlo
    reference (docs/validation.md) are ``orders=6, remaining_orders="geometric",
    sphere_samples=32, scattering_nu_size=16, scattering_mu_s_size=64, density_mu_s_size=64``
    (several times the precomputation time and memory).
    max_sun_zenith_deg : float
        Largest sun zenith angle in the tables [deg], [90, 120] (default 108: astronomical
        twilight).
    """

    name = "precomputed"
    reference = ("Bruneton, Precomputed Atmospheric Scattering: a New Implementation (2017); "
                 "Bruneton & Neyret, Precomputed Atmospheric Scattering, EGSR 2008, eqs. 1-9")
    native = "spectral"
    summary = "Bruneton-style precomputed multiple scattering tables (spectral, any atmosphere)."
    parameters = (
        Parameter("atmosphere", "", None, doc="skydome.Atmosphere (default Atmosphere.earth(turbidity))",
                  kind="object"),
        Parameter("turbidity", "", 2.5, 1.0, 32.0, "Preetham turbidity when no atmosphere is given"),
        Parameter("observer_altitude_m", "m", 0.0, 0.0, 999_999.0, "observer altitude above the ground"),
        Parameter("n_wavelengths", "", 20, 1, 400, "table wavelengths over 380-780 nm", kind="int"),
        Parameter("table_wavelengths_nm", "nm", None, doc="explicit table wavelength grid",
                  kind="object"),
        Parameter("orders", "", 4, 1, 20, "scattering orders", kind="int"),
        Parameter("remaining_orders", "", "none", doc="orders beyond N: none, or geometric "
                  "(series with the ratio of the last two orders per table cell)",
                  kind="choice", choices=("none", "geometric")),
        Parameter("transmittance_mu_size", "", 256, 4, 4096, "transmittance table, mu axis", kind="int"),
        Parameter("transmittance_r_size", "", 64, 4, 4096, "transmittance table, r axis", kind="int"),
        Parameter("scattering_r_size", "", 32, 2, 512, "scattering table, r axis", kind="int"),
        Parameter("scattering_mu_size", "", 128, 4, 2048, "scattering table, mu axis (even)", kind="int"),
        Parameter("scattering_mu_s_size", "", 32, 2, 512, "scattering table, mu_s axis", kind="int"),
        Parameter("scattering_nu_size", "", 8, 2, 256, "scattering table, nu axis", kind="int"),
        Parameter("irradiance_mu_s_size", "", 64, 2, 4096, "irradiance table, mu_s axis", kind="int"),
        Parameter("irradiance_r_size", "", 16, 2, 4096, "irradiance table, r axis", kind="int"),
        Parameter("integration_samples", "", 20, 2, 1000, "quadrature nodes per ray piece", kind="int"),
        Parameter("sphere_samples", "", 16, 4, 256, "zenith samples of the scattering density",
                  kind="int"),
        Parameter("density_mu_s_size", "", None, 2, 512,
                  "mu_s nodes of the scattering density (default: scattering_mu_s_size)", kind="int"),
        Parameter("max_sun_zenith_deg", "deg", 108.0, 90.0, 120.0, "largest sun zenith in the tables"),
    )

    def __init__(self, sun, **params):

        check_sun(sun)
        p = self._validate_params(params)
        atm = resolve_atmosphere(p, params)
        if p["scattering_mu_size"] % 2:
            raise ValueError(f"scattering_mu_size = {p['scattering_mu_size']} is out of range: "
                             "it must be even, in [4, 2048]")
        if p["table_wavelengths_nm"] is not None:
            if "n_wavelengths" in params:
                raise ValueError("give either n_wavelengths or table_wavelengths_nm, not both")
            wl = as_wavelengths(p["table_wavelengths_nm"], 280.0, 4000.0, "table_wavelengths_nm")
            if wl.size > 1 and np.any(np.diff(wl) <= 0):
                raise ValueError("table_wavelengths_nm must be strictly increasing")
        else:
            n = p["n_wavelengths"]
            wl = np.array([550.0]) if n == 1 else np.linspace(380.0, 780.0, n)
        for k, v in p.items():
            setattr(self, k, v)
        self.sun = sun
        self.atmosphere = atm
        self.table_wavelengths_nm = wl
        self.n_wavelengths = wl.size
        self.precompute_seconds = None
        self._t = self._precompute(atm, wl, p)

    # -- precomputation ----------------------------------------------------------------------------
    @staticmethod
    def _precompute(atm, wl, p) -> dict:
        """Build every table ([Bru17] Model::Precompute) and return them as a dict of arrays."""
        from skydome._progress import report
        from skydome.models.simulated import _kernels_precomputed as KP
        from skydome.transport import _kernels as K

        t_start = time.perf_counter()
        props = atm.optical_properties(wl)
        R = float(props.planet_radius_m)
        Rt = float(props.top_radius_m)
        mu_s_min = float(np.cos(np.radians(p["max_sun_zenith_deg"])))
        alpha = float(np.radians(0.2666))  # sun angular radius used for the earth's shadow edge
        codes, p0s, p1s = props.profile_code, props.profile_p0, props.profile_p1
        beta_e = np.ascontiguousarray(props.extinction)
        sc_idx = np.nonzero(np.any(props.scattering > 0.0, axis=1))[0].astype(np.int64)
        if sc_idx.size == 0:
            sc_idx = np.array([0], dtype=np.int64)
        beta_s = np.ascontiguousarray(props.scattering[sc_idx])
        pc = np.ascontiguousarray(props.phase_code[sc_idx])
        pp = np.ascontiguousarray(props.phase_param[sc_idx])
        albedo = np.ascontiguousarray(props.ground_albedo)
        nl = wl.size
        n_r, n_mu = p["scattering_r_size"], p["scattering_mu_size"]
        n_ms, n_nu = p["scattering_mu_s_size"], p["scattering_nu_size"]
        n_q = p["integration_samples"]
        n_q_ms = max(4, (n_q + 1) // 2)   # the scattering density is smooth along the ray
        ts = _QUADRATURE_SCALE_M

        # 1. transmittance: column densities to the top on Bruneton's (r, mu) mapping
        col = K.build_column_table(codes, p0s, p1s, R, Rt, p["transmittance_r_size"],
                                   p["transmittance_mu_size"], 128, ts)
        # 2. single scattering per scattering constituent, no phase ([Bru17] eq. for S1)
        trans = np.exp(-np.einsum("cij,cl->ijl", col, beta_e)).astype(np.float32)
        ss = np.empty((sc_idx.size, n_r, n_mu, n_ms, n_nu, nl), dtype=np.float32)
        KP.single_scattering_table(col, trans, codes, p0s, p1s, beta_s, beta_e, sc_idx, R, Rt, mu_s_min,
                                   alpha, n_q, ts, ss)
        report("precomputing tables: scattering orders", 1, p["orders"])
        ms = np.zeros((n_r, n_mu, n_ms, n_nu, nl), dtype=np.float32)
        E = np.zeros((p["irradiance_r_size"], p["irradiance_mu_s_size"], nl))
        if p["orders"] >= 2:
            # incident directions: Bruneton's 16 x 32 over the sphere in the sun's frame (angle
            # from the sun, azimuth about it from its vertical plane), kept on phi in [0, pi]
            n_th = p["sphere_samples"]
            th_in = (np.arange(n_th) + 0.5) * np.pi / n_th
            ph_in = (np.arange(n_th) + 0.5) * np.pi / n_th
            d_omega = np.sin(th_in) * (np.pi / n_th) ** 2
            # outgoing grid of the scattering density, in the sun's frame: theta (angle from the
            # sun) and phi (azimuth about the sun) in [0, pi]
            th_out = np.linspace(0.0, np.pi, 2 * n_th + 1)
            ph_out = np.linspace(0.0, np.pi, n_th + 1)
            n_in = th_in.size * ph_in.size
            n_out = th_out.size * ph_out.size
            # phase matrices, factored where the phase function is a polynomial of degree
            # <= 2 in the cosine (Rayleigh, isotropic): P(o.i) = a0 + a1 o.i + a2 (o.i)^2 is
            # exactly left(o) . right(i) with 10 terms, so the Rayleigh part of the product
            # costs 10/256 of the full one (checked against the full matrix to 1e-9 of its
            # largest entry, else the full matrix is used):
            # J = sum_k P_k (L w_k) = [left_k | ...] [right_k (L w_k); ...]
            left, right = [], []
            for k in range(sc_idx.size):
                P = np.empty((n_out, n_in))
                KP.phase_matrix(int(pc[k]), float(pp[k]), th_out, ph_out, th_in, ph_in, d_omega,
                                P)
                fac = _quadratic_phase_factors(int(pc[k]), float(pp[k]), th_out, ph_out, th_in,
                                               ph_in, d_omega, P)
                if fac is not None:
                    left.append(fac[0])
                    right.append(fac[1])
                else:
                    left.append(P)
                    right.append(None)
            left_all = np.ascontiguousarray(np.hstack(left), dtype=np.float32)
            rows = np.cumsum([0] + [m.shape[1] for m in left])
            # irradiance quadrature ([Bru17] ComputeIndirectIrradiance: 16 x 64 over the
            # upper hemisphere; phi on [0, pi] doubled)
            n_ti = 16
            th_i = (np.arange(n_ti) + 0.5) * (0.5 * np.pi) / n_ti
            ph_i = (np.arange(2 * n_ti) + 0.5) * np.pi / (2 * n_ti)
            dom_i = np.sin(th_i) * (0.5 * np.pi / n_ti) * (np.pi / (2 * n_ti))
            r_nodes = np.array([KP.cell_r(i, n_r, R, Rt) for i in range(n_r)])
            dens = np.stack([[K.profile_density(codes[c], p0s[c], p1s[c], rr - R)
                              for rr in r_nodes] for c in sc_idx])          # (nsc, n_r)
            delta = np.zeros((1, 1, 1, 1, nl), dtype=np.float32)
            dE = np.zeros_like(E)
            # the scattering density's own mu_s axis (same mapping, its own node count)
            n_ms_j = p["density_mu_s_size"] or n_ms
            L_in = np.empty((n_in, n_r, n_ms_j, nl))
            rhs = np.empty((int(rows[-1]), n_r * n_ms_j * nl), dtype=np.float32)
            # weight of each constituent at every (r, mu_s, l) column of L_in: its scattering
            # coefficient at reference density (the density profile is applied exactly along
            # each ray in 3d: J_k / rho_k is smooth in r, rho_k J_k is not)
            w_col = [np.broadcast_to(np.ones_like(dens[k])[:, None, None] * beta_s[k][None, None, :],
                                     (n_r, n_ms_j, nl)).reshape(-1) for k in range(sc_idx.size)]
            dE_prev = prev_dE = prev_delta = None
            J_sum = None
            for order in range(2, p["orders"] + 1):
                first = order == 2
                # 3a. radiance of order-1 arriving at each node, + ground reflection of order-2
                KP.incident_radiance(first, ss, pc, pp, delta, dE, col, beta_e, albedo, R, Rt,
                                     mu_s_min, alpha, n_r, n_ms_j, th_in, ph_in, L_in)
                # 3b. scattering density J ([BN08] eq. 7) on the outgoing grid: one float32
                # matrix product (BLAS) over all (r, mu_s, l), laid out [k, theta, phi, r, mu_s, l]
                lin = L_in.reshape(n_in, -1)
                for k in range(sc_idx.size):
                    blk = lin if right[k] is None else right[k] @ lin
                    np.multiply(blk, w_col[k], out=rhs[rows[k]:rows[k + 1]], casting="unsafe")
                if J_sum is None:
                    J = np.empty((sc_idx.size, th_out.size, ph_out.size, n_r, n_ms_j, nl),
                                 dtype=np.float32)
                for k in range(sc_idx.size):
                    np.matmul(left_all[:, rows[k]:rows[k + 1]], rhs[rows[k]:rows[k + 1]],
                              out=J[k].reshape(n_out, -1))
                # the density of orders 2..N, kept for the observer's slice at render time
                if J_sum is None:
                    J_sum = J.copy()
                else:
                    J_sum += J
                # 3c. ground irradiance of order-1 ([BN08] eq. 9)
                dE_new = np.empty_like(E)
                KP.indirect_irradiance(first, ss, pc, pp, delta, R, Rt, mu_s_min, th_i, ph_i,
                                       dom_i, dE_new)
                E += dE_new
                dE = dE_new
                # 3d. scattering of this order along every ray ([BN08] eq. 8)
                if first:
                    delta = np.empty_like(ms)
                prev_delta = None if first else delta.copy()
                prev_dE = dE_prev
                dE_prev = dE_new.copy()
                KP.multiple_scattering_table(J, codes, p0s, p1s, sc_idx, col, beta_e, R, Rt, mu_s_min, n_q_ms, ts, delta)
                ms += delta
                report("precomputing tables: scattering orders", order, p["orders"])
            if p["remaining_orders"] == "geometric" and p["orders"] >= 3:
                # the orders beyond N as a geometric series whose ratio f is that of the
                # last two orders' total radiance, per wavelength (the idea of [Hil20] eq. 10):
                # L_N f / (1 - f). (A per-cell ratio was tried: it is unstable in cells where
                # the ground reflection enters.)
                axes = tuple(range(delta.ndim - 1))
                tot, tot_prev = delta.sum(axis=axes, dtype=np.float64), prev_delta.sum(axis=axes, dtype=np.float64)
                f = np.clip(np.where(tot_prev > 0, tot / np.where(tot_prev > 0, tot_prev, 1.0), 0.0), 0.0, 0.9)
                ms += (delta * (f / (1.0 - f))).astype(ms.dtype)
                J_sum += (J * (f / (1.0 - f))).astype(J_sum.dtype)
                ea = tuple(range(dE.ndim - 1))
                te, te_prev = dE.sum(axis=ea), prev_dE.sum(axis=ea)
                fe = np.clip(np.where(te_prev > 0, te / np.where(te_prev > 0, te_prev, 1.0), 0.0), 0.0, 0.9)
                E += dE * (fe / (1.0 - fe))
        extra = {}
        if p["orders"] >= 2:
            extra = {"scattering_density": np.ascontiguousarray(J_sum, dtype=np.float32),
                     "profile_code": np.asarray(codes), "profile_p0": np.asarray(p0s, dtype=np.float64),
                     "profile_p1": np.asarray(p1s, dtype=np.float64), "scattering_index": sc_idx}
        return {**extra, "table_wavelengths_nm": np.asarray(wl, dtype=np.float64),
                "columns": col, "beta_e": beta_e, "single_scattering": ss,
                "multiple_scattering": ms, "irradiance": E, "phase_code": pc, "phase_param": pp,
                "ground_albedo": albedo, "scattering_coefficient": beta_s,
                "geometry": np.array([R, Rt, mu_s_min, alpha]),
                "precompute_seconds": np.array(time.perf_counter() - t_start)}

    # -- tables helpers -----------------------------------------------------------------------------
    @property
    def _R(self):
        return float(self._t["geometry"][0])

    @property
    def _Rt(self):
        return float(self._t["geometry"][1])

    @property
    def _mu_s_min(self):
        return float(self._t["geometry"][2])

    @property
    def _alpha(self):
        return float(self._t["geometry"][3])

    @property
    def _r0(self):
        return self._R + self.observer_altitude_m

    def _night(self) -> bool:
        return self.sun.direction[2] < self._mu_s_min - 1e-12

    def _solar(self, wl):
        from skydome.spectra import solar_irradiance

        return solar_irradiance(wl) * self.sun.irradiance_scale

    def _to_wavelengths(self, values, wl):
        """Per-unit-solar-irradiance values on the table grid (..., n_table) -> radiometric
        values on ``wl``: linear interpolation in wavelength (end values held beyond the
        table), times the solar spectrum at ``wl``."""
        tw = self._t["table_wavelengths_nm"]
        if wl.shape == tw.shape and np.allclose(wl, tw, rtol=0, atol=1e-9):
            return values * self._solar(wl)
        W = np.zeros((wl.size, tw.size))
        if tw.size == 1:
            W[:, 0] = 1.0
        else:
            x = np.clip(wl, tw[0], tw[-1])
            j = np.clip(np.searchsorted(tw, x) - 1, 0, tw.size - 2)
            f = (x - tw[j]) / (tw[j + 1] - tw[j])
            W[np.arange(wl.size), j] = 1.0 - f
            W[np.arange(wl.size), j + 1] += f
        return (values @ W.T) * self._solar(wl)

    def _observer_slices(self, table_only=False):
        """The 4-D tables interpolated at the observer's r and the sun's mu_s."""
        from skydome.models.simulated import _kernels_precomputed as KP

        R, Rt = self._R, self._Rt
        ss, ms = self._t["single_scattering"], self._t["multiple_scattering"]
        n_r, n_ms = ms.shape[0], ms.shape[2]
        ir, a = KP.r_index(self._r0, n_r, R, Rt)
        x = KP.mu_s_unit(float(self.sun.direction[2]), R, Rt, self._mu_s_min)
        ims, c = KP._split(x * (n_ms - 1), n_ms)

        def sl(t):
            out = ((1 - a) * ((1 - c) * t[..., ir, :, ims, :, :] + c * t[..., ir, :, ims + 1, :, :])
                   + a * ((1 - c) * t[..., ir + 1, :, ims, :, :] + c * t[..., ir + 1, :, ims + 1, :, :]))
            return np.ascontiguousarray(out, dtype=np.float64)

        mu_s = float(self.sun.direction[2])
        if table_only or "scattering_density" not in self._t or mu_s < self._mu_s_min:
            return sl(ss), sl(ms)
        # orders 2..N integrated at the observer's own r and mu_s (the aureole of the
        # multiply scattered light is too sharp for the table's mu_s and nu nodes), cached
        cache = self.__dict__.setdefault("_slice_cache", {})
        key = (self._r0, mu_s)
        if key not in cache:
            t = self._t
            geom = self._slice_geometry()
            n_g, n_s, th_h = int(geom[0]), int(geom[1]), float(geom[2])
            th = np.concatenate([np.pi - (np.pi - th_h) * np.arange(n_g) / (n_g - 1.0),
                                 th_h * (1.0 - np.arange(n_s) / (n_s - 1.0))])
            ground = np.arange(n_g + n_s) < n_g
            cphi = np.cos(np.pi * np.arange(_SLICE_PHI) / (_SLICE_PHI - 1.0))
            out = np.empty((n_g + n_s, _SLICE_PHI, ms.shape[-1]))
            KP.multiple_scattering_slice(t["scattering_density"], t["profile_code"], t["profile_p0"],
                                         t["profile_p1"], t["scattering_index"], t["columns"],
                                         t["beta_e"], R, Rt, self._mu_s_min, self._r0, mu_s,
                                         int(self.integration_samples), _QUADRATURE_SCALE_M,
                                         np.cos(th), ground, cphi, out)
            if len(cache) > 8:
                cache.clear()
            cache[key] = out
        return sl(ss), cache[key]

    def _slice_geometry(self, table=False):
        """``geom`` of :func:`_kernels_precomputed.render_observer`: (n_ground, n_sky,
        horizon zenith angle [rad]) of the observer's sky map, or (0, 0, 0) for the table's
        own mu mapping."""
        if table or "scattering_density" not in self._t or float(self.sun.direction[2]) < self._mu_s_min:
            return np.zeros(3)
        mu_h = -math.sqrt(max(1.0 - (self._R / self._r0) ** 2, 0.0))
        return np.array([_SLICE_GROUND, _SLICE_SKY, math.acos(mu_h)])

    # -- public API ---------------------------------------------------------------------------------
    def radiance(self, directions, wavelengths_nm) -> np.ndarray:
        """Spectral radiance [W m^-2 sr^-1 nm^-1] arriving from ``directions`` (..., 3), shape
        (..., n_wavelengths).

        Directions below the horizon see the Lambertian ground (the atmosphere's albedo) lit
        by the transmitted sun and the sky irradiance table, through the air in front of it.
        Wavelengths between table wavelengths are interpolated linearly (relative to the
        solar spectrum); beyond the table's ends its end values are held. Sun below
        ``90 - max_sun_zenith_deg``: 0 (night)."""
        d = as_directions(directions)
        wl = as_wavelengths(wavelengths_nm)
        flat = np.ascontiguousarray(d.reshape(-1, 3))
        tw = self._t["table_wavelengths_nm"]
        if wl.shape == tw.shape and np.allclose(wl, tw, rtol=0, atol=1e-9):
            # fast path: the kernel applies the solar spectrum itself
            out = self._radiance_table(flat, self._solar(wl))
        else:
            out = self._to_wavelengths(self._radiance_table(flat), wl)
            np.maximum(out, 0.0, out=out)
        return out.reshape(d.shape[:-1] + (wl.size,))

    def radiance_table(self, directions) -> np.ndarray:
        """Radiance per unit extraterrestrial irradiance [sr^-1] on the table wavelengths,
        shape (..., n_table_wavelengths) (the fast path: no spectral interpolation)."""
        d = as_directions(directions)
        return self._radiance_table(np.ascontiguousarray(d.reshape(-1, 3))).reshape(
            d.shape[:-1] + (self.n_wavelengths,))

    def _radiance_table(self, flat, scale=None):
        from skydome.models.simulated import _kernels_precomputed as KP

        nl = self.n_wavelengths
        scale = np.ones(nl) if scale is None else np.ascontiguousarray(scale, dtype=np.float64)
        out = np.empty((flat.shape[0], nl))
        if self._night():
            out[:] = 0.0
            return out
        ss_s, ms_s = self._observer_slices()
        t = self._t
        KP.render_observer(flat, self._r0, np.ascontiguousarray(self.sun.direction), ss_s,
                           t["phase_code"], t["phase_param"], ms_s, t["columns"], t["beta_e"],
                           t["ground_albedo"], t["irradiance"], scale, self._R, self._Rt,
                           self._alpha, self._slice_geometry(), out)
        return out

    def _transmittance_table(self, r, mu):
        from skydome.models.simulated import _kernels_precomputed as KP

        cs = np.empty(self._t["columns"].shape[0])
        KP.columns_at(self._t["columns"], r, mu, self._R, self._Rt, cs)
        return np.exp(-(cs @ self._t["beta_e"]))

    def sun_radiance(self, wavelengths_nm) -> np.ndarray:
        """Radiance of the sun's disc [W m^-2 sr^-1 nm^-1]: E_sun / Omega_sun x T(observer ->
        top) x the fraction of the disc above the horizon; 0 when the planet hides it."""
        from skydome.models.simulated import _kernels_precomputed as KP

        wl = as_wavelengths(wavelengths_nm)
        mu_s = float(self.sun.direction[2])
        vis = KP.sun_visible_fraction(self._r0, mu_s, self._R, self._alpha)
        t = self._transmittance_table(self._r0, mu_s) * vis
        return self._to_wavelengths(t[None, :], wl)[0] / self.sun.solid_angle_sr

    def irradiance_components(self, wavelengths_nm):
        """(direct, diffuse) spectral irradiance on a horizontal surface at the observer
        [W m^-2 nm^-1]: the transmitted sun (averaged over the disc, [Bru17]
        ComputeDirectIrradiance) and the sky (the irradiance table, orders 1..N-1)."""
        from skydome.models.simulated import _kernels_precomputed as KP

        wl = as_wavelengths(wavelengths_nm)
        nl = self.n_wavelengths
        mu_s = float(self.sun.direction[2])
        direct = np.zeros(nl)
        diffuse = np.zeros(nl)
        if not self._night():
            cs = np.empty(self._t["columns"].shape[0])
            KP.direct_irradiance_acc(self._t["columns"], self._t["beta_e"], self._r0, mu_s, self._R,
                                     self._Rt, self._alpha, 1.0, cs, direct)
            KP.irradiance_lookup_acc(self._t["irradiance"], self._r0, mu_s, self._R, self._Rt, 1.0,
                                     diffuse)
        return (np.maximum(self._to_wavelengths(direct[None], wl)[0], 0.0),
                np.maximum(self._to_wavelengths(diffuse[None], wl)[0], 0.0))

    def ground_irradiance(self, wavelengths_nm) -> np.ndarray:
        """Global spectral irradiance on a horizontal surface at the observer
        [W m^-2 nm^-1] (direct + diffuse, see :meth:`irradiance_components`)."""
        direct, diffuse = self.irradiance_components(wavelengths_nm)
        return direct + diffuse

    def aerial_perspective(self, directions, distance_m, wavelengths_nm):
        """Transmittance and in-scattered radiance between the observer and the point at
        ``distance_m`` along each direction ([Bru17] GetSkyRadianceToPoint).

        Parameters
        ----------
        directions : array_like (..., 3)
        distance_m : float or array_like broadcastable to (...)
            Distance to the object [m], >= 0; clamped to the end of the ray (ground or top
            of the atmosphere).
        wavelengths_nm : array_like

        Returns
        -------
        transmittance : ndarray (..., n_wavelengths)
            Dimensionless.
        inscattered : ndarray (..., n_wavelengths)
            [W m^-2 sr^-1 nm^-1]. An object of radiance L0 appears as T L0 + inscattered.
        """
        from skydome.models.simulated import _kernels_precomputed as KP

        d = as_directions(directions)
        wl = as_wavelengths(wavelengths_nm)
        dist = np.asarray(distance_m, dtype=np.float64)
        if not np.all(np.isfinite(dist)) or np.any(dist < 0):
            raise ValueError("distance_m must be finite and >= 0 m")
        dist = np.ascontiguousarray(np.broadcast_to(dist, d.shape[:-1]).reshape(-1))
        flat = np.ascontiguousarray(d.reshape(-1, 3))
        nl = self.n_wavelengths
        tr = np.empty((flat.shape[0], nl))
        ins = np.zeros((flat.shape[0], nl))
        t = self._t
        KP.aerial_perspective(flat, dist, self._r0, np.ascontiguousarray(self.sun.direction),
                              t["single_scattering"], t["phase_code"], t["phase_param"],
                              t["multiple_scattering"], t["columns"], t["beta_e"], self._R,
                              self._Rt, self._mu_s_min, tr, ins)
        if self._night():
            ins[:] = 0.0
        elif "scattering_density" in t:
            # the observer's end of the path: orders 2..N from the observer's slice (as in
            # radiance()) instead of the 4-D table, so that an infinite distance gives the sky
            ss_s, ms_s = self._observer_slices()
            ms_tab = self._observer_slices(table_only=True)[1]
            zero = np.zeros_like(ss_s)
            no_ground = np.zeros_like(t["ground_albedo"])
            one = np.ones(nl)
            a_sl, a_tab = np.empty_like(ins), np.empty_like(ins)
            for ms_x, o, geom in ((ms_s, a_sl, self._slice_geometry()),
                                  (ms_tab, a_tab, self._slice_geometry(table=True))):
                KP.render_observer(flat, self._r0, np.ascontiguousarray(self.sun.direction), zero,
                                   t["phase_code"], t["phase_param"], ms_x, t["columns"], t["beta_e"],
                                   no_ground, t["irradiance"], one, self._R, self._Rt, self._alpha,
                                   geom, o)
            # applied in proportion to the path's share of the whole ray's extinction,
            # 1 - T(d) over 1 - T(end): 0 at distance 0, all of it at the end of the ray
            tr_end, ins_end = np.empty_like(tr), np.zeros_like(ins)
            KP.aerial_perspective(flat, np.full(flat.shape[0], 1e12), self._r0,
                                  np.ascontiguousarray(self.sun.direction), t["single_scattering"],
                                  t["phase_code"], t["phase_param"], t["multiple_scattering"],
                                  t["columns"], t["beta_e"], self._R, self._Rt, self._mu_s_min,
                                  tr_end, ins_end)
            share = np.clip((1.0 - tr) / np.maximum(1.0 - tr_end, 1e-300), 0.0, 1.0)
            np.maximum(ins + share * (a_sl - a_tab), 0.0, out=ins)
        tw = t["table_wavelengths_nm"]
        shape = d.shape[:-1] + (wl.size,)
        trans = np.stack([np.interp(wl, tw, row) for row in tr]) if tw.size > 1 else \
            np.repeat(tr, wl.size, axis=1)
        return (np.clip(trans, 0.0, 1.0).reshape(shape),
                np.maximum(self._to_wavelengths(ins, wl), 0.0).reshape(shape))

    def with_sun(self, sun=None, observer_altitude_m=None) -> "PrecomputedSky":
        """The same tables for another sun position and/or observer altitude [m] (no
        precomputation: the tables hold every altitude and sun zenith angle)."""
        import copy

        from skydome.sun import Sun

        new = copy.copy(self)
        if sun is not None:
            if not isinstance(sun, Sun):
                raise TypeError(f"sun must be a skydome.Sun, not {type(sun).__name__}")
            new.sun = sun
        if observer_altitude_m is not None:
            top = self._Rt - self._R
            new.observer_altitude_m = check_number("observer_altitude_m", observer_altitude_m,
                                                   0.0, top, "m", high_open=True)
        return new

    # -- persistence --------------------------------------------------------------------------------
    def _meta(self) -> dict:
        meta = {"format": _FORMAT, "model": self.name}
        for p in self.parameters:
            if p.name in ("atmosphere", "table_wavelengths_nm"):
                continue
            meta[p.name] = getattr(self, p.name)
        meta["atmosphere"] = (self.atmosphere.describe() if self.atmosphere is not None
                              else self._atmosphere_description)
        s = self.sun
        meta["sun"] = {"elevation_deg": s.elevation_deg, "azimuth_deg": s.azimuth_deg,
                       "angular_radius_deg": s.angular_radius_deg, "distance_au": s.distance_au}
        return meta

    _atmosphere_description = None

    def save(self, path) -> None:
        """Write the tables and parameters to an ``.npz`` file (atomically)."""
        path = os.fspath(path)
        folder = os.path.dirname(os.path.abspath(path))
        fd, tmp = tempfile.mkstemp(suffix=".npz", dir=folder)
        os.close(fd)
        try:
            np.savez(tmp, meta=np.array(json.dumps(self._meta(), default=_json_default)),
                     **self._t)
            os.replace(tmp, path)
        except BaseException:
            if os.path.exists(tmp):
                os.remove(tmp)
            raise

    @classmethod
    def load(cls, path, sun=None) -> "PrecomputedSky":
        """Read tables written by :meth:`save`. ``sun`` replaces the saved sun position.

        The loaded model has ``atmosphere = None`` (its description is kept in
        ``describe()``): it renders from the tables alone."""
        from skydome.sun import Sun

        with np.load(os.fspath(path), allow_pickle=False) as z:
            meta = json.loads(str(z["meta"]))
            if meta.get("format") != _FORMAT:
                raise ValueError(f"{path} is not a skydome precomputed-table file "
                                 f"(format {meta.get('format')!r}, expected {_FORMAT!r})")
            tables = {k: z[k] for k in z.files if k != "meta"}
        obj = cls.__new__(cls)
        for p in cls.parameters:
            if p.name in meta:
                setattr(obj, p.name, meta[p.name])
        obj.atmosphere = None
        obj._atmosphere_description = meta["atmosphere"]
        obj.table_wavelengths_nm = tables["table_wavelengths_nm"]
        obj.n_wavelengths = obj.table_wavelengths_nm.size
        obj.sun = sun if sun is not None else Sun(**meta["sun"])
        obj._t = tables
        return obj

    @property
    def precompute_time_s(self) -> float:
        """Wall time of the precomputation [s]."""
        return float(self._t["precompute_seconds"])

    def describe(self):
        out = super().describe()
        out["parameters"]["atmosphere"] = (self.atmosphere.describe() if self.atmosphere is not None
                                           else self._atmosphere_description)
        out["parameters"]["table_wavelengths_nm"] = [float(x) for x in self.table_wavelengths_nm]
        return out

    def export_textures(self, folder) -> list:
        """Write the tables as float32 textures (``.npy``, and ``.exr`` where OpenEXR is
        available) plus ``textures.json`` and ``textures.md`` describing axes, mappings and
        units. Returns the written paths."""
        folder = os.fspath(folder)
        os.makedirs(folder, exist_ok=True)
        t = self._t
        R, Rt, mu_s_min = self._R, self._Rt, self._mu_s_min
        trans = np.exp(-np.einsum("cij,cl->ijl", t["columns"], t["beta_e"])).astype(np.float32)
        tex = {
            "transmittance": (trans, ["r", "mu", "wavelength"],
                              "transmittance to the top of the atmosphere (dimensionless); "
                              "r: x_r = rho/H, mu: x_mu = (d - d_min)/(d_max - d_min), d the "
                              "distance to the top, d_min = Rt - r, d_max = rho + H; node i at "
                              "x = i/(n-1); rays that hit the ground are not in the table"),
            "single_scattering": (t["single_scattering"].astype(np.float32),
                                  ["constituent", "r", "mu", "mu_s", "nu", "wavelength"],
                                  "single scattering without phase function, per unit solar "
                                  "irradiance [sr^0 m^0: multiply by E_sun and the constituent's "
                                  "phase function P(nu) [sr^-1] to get radiance]"),
            "multiple_scattering": (t["multiple_scattering"].astype(np.float32),
                                    ["r", "mu", "mu_s", "nu", "wavelength"],
                                    "orders 2..N, radiance per unit solar irradiance [sr^-1]"),
            "irradiance": (t["irradiance"].astype(np.float32), ["r", "mu_s", "wavelength"],
                           "sky irradiance on a horizontal surface (orders 1..N-1) per unit "
                           "solar irradiance (dimensionless); x_r = (r - R)/(Rt - R), "
                           "x_mu_s = (mu_s + 1)/2, node i at x = i/(n-1)"),
        }
        desc = {
            "format": _FORMAT, "units": "lengths m; radiance per unit extraterrestrial solar "
            "spectral irradiance; multiply by E_sun(lambda) [W m^-2 nm^-1]",
            "planet_radius_m": R, "top_radius_m": Rt, "mu_s_min": mu_s_min,
            "wavelengths_nm": [float(x) for x in t["table_wavelengths_nm"]],
            "phase_code": [int(x) for x in t["phase_code"]],
            "phase_param": [float(x) for x in t["phase_param"]],
            "phase_codes": {"0": "rayleigh (param = rho/(2-rho))", "1": "henyey_greenstein (g)",
                            "2": "cornette_shanks (g)", "3": "isotropic"},
            "mappings": {
                "r": "x = rho/H, rho = sqrt(r^2 - R^2), H = sqrt(Rt^2 - R^2)",
                "mu": "first half: rays hitting the ground, node 0 = horizon .. n/2-1 = nadir, "
                      "x = (d - (r-R))/(rho - (r-R)), d the distance to the ground; second half: "
                      "node n/2 = zenith .. n-1 = horizon, x = (d - (Rt-r))/(rho + H - (Rt-r)), "
                      "d the distance to the top; node k of a half at x = k/(n/2-1)",
                "mu_s": "x = max(1 - a/A, 0)/(1 + a), a = (d - (Rt-R))/(H - (Rt-R)), d the distance "
                        "to the top from the ground towards the sun, A = a(mu_s_min); node i at "
                        "x = i/(n-1)",
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


Precomputed = PrecomputedSky


def _quadratic_phase_factors(code, param, th_out, ph_out, th_in, ph_in, d_omega, P):
    """(left, right) with left @ right == P (the phase matrix of
    :func:`_kernels_precomputed.phase_matrix`) when the phase function is a polynomial of
    degree <= 2 in the cosine (Rayleigh, isotropic); None otherwise.

    P[o, i] = dOmega_i (p(o.w_i) + p(o.w_i')), w_i' the mirror image of w_i (y -> -y), and
    p(c) = a0 + a1 c + a2 c^2 with (o.w)^2 = sum_m o_m^2 w_m^2 + 2 sum_{m<n} o_m o_n w_m w_n."""
    from skydome.transport._kernels import phase_value

    if code not in (0, 3):
        return None
    fm, f0, fp = (phase_value(code, param, c) for c in (-1.0, 0.0, 1.0))
    a0, a1, a2 = f0, 0.5 * (fp - fm), 0.5 * (fp + fm) - f0

    def unit(th, ph):
        T, F = np.meshgrid(th, ph, indexing="ij")
        return np.stack([np.sin(T) * np.cos(F), np.sin(T) * np.sin(F), np.cos(T)], -1).reshape(-1, 3)

    o = unit(th_out, ph_out)
    w = unit(th_in, ph_in)
    ox, oy, oz = o.T
    left = np.stack([np.ones_like(ox), ox, oy, oz, ox * ox, oy * oy, oz * oz, ox * oy, ox * oz,
                     oy * oz], axis=1)

    def feats(x, y, z):
        return np.stack([np.full_like(x, a0), a1 * x, a1 * y, a1 * z, a2 * x * x, a2 * y * y,
                         a2 * z * z, 2 * a2 * x * y, 2 * a2 * x * z, 2 * a2 * y * z])

    wx, wy, wz = w.T
    right = (feats(wx, wy, wz) + feats(wx, -wy, wz)) * np.repeat(d_omega, ph_in.size)[None, :]
    if np.abs(left @ right - P).max() > 1e-9 * np.abs(P).max():
        return None
    return left, right


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
