"""``kaneda1991``: sky colour over a spherical earth with exponential air and aerosols, and fog.

Kaneda, Okamoto, Nakamae & Nishita (1991) compute the sky by single scattering of
sunlight in a spherical atmosphere whose molecular and aerosol densities fall
exponentially with altitude, with Rayleigh scattering for molecules and Mie scattering
for aerosols, and add a fog layer near the ground for outdoor scenes (survey section 7.2).
The radiance arriving at the eye on the ground from direction v is

    L(lambda) = E_sun sum_c beta_s,c(lambda) P_c(theta)
                integral_0^{t_max} rho_c(h(t)) exp(-tau_view(t) - tau_sun(t)) dt

(the single-scattering integral of the survey, eqs. 15-16), with c running over
molecules, aerosols, ozone (absorbing only) and, when enabled, fog; tau_view is the optical
depth from the eye to the point t and tau_sun the optical depth from that point to the
sun (zero radiance contribution from points in the earth's shadow). ``t_max`` is the top
of the atmosphere for the sky, or an object's distance for :meth:`Kaneda1991.fog`.

Sample placement: the view ray is sampled where it crosses spherical shells whose
altitudes divide each exponential profile into intervals of equal density decrement
(``h_k = -H ln(1 - k/N (1 - exp(-h_top/H)))``), merged over the constituents (plus the
edges of the ozone and fog layers); each interval is integrated by Simpson's rule and cut
into equal pieces where it is optically thick. Optical depths towards the sun are read from
the transport engine's column table (fog: the chord of a uniform layer, or the Chapman
function of an exponential one).

References
----------
[KONN91] Kaneda, K., Okamoto, T., Nakamae, E., Nishita, T. 1991. Photorealistic image
    synthesis for outdoor scenery under various atmospheric conditions. The Visual
    Computer 7, 247-258.
[KRZ06] Kment, Rauter & Zotti, Modelling of Daylight for Computer Graphics (the survey),
    section 7.2, eqs. 3, 7, 10-12, 15-16.
[NMN87] Nishita, T., Miyawaki, Y., Nakamae, E. 1987. A shading model for atmospheric
    scattering considering luminous intensity distribution of light sources. SIGGRAPH 87
    (the "hazy" and "murky" Mie phase-function approximations).
"""

from __future__ import annotations

import math

import numpy as np

from skydome._validate import as_directions, as_wavelengths
from skydome.models import (ATMOSPHERE, TURBIDITY, GroundEyeAerialPerspective, Parameter, SkyModel,
                            register)

__all__ = ["Kaneda1991", "Kaneda1991Sky", "phase_hazy", "phase_murky"]

_INV_4PI = 1.0 / (4.0 * math.pi)


def phase_hazy(cos_theta):
    """[NMN87] "hazy" Mie approximation 1 + 9 ((1 + cos)/2)^8, normalised over the sphere
    [sr^-1]: the integral of ((1 + cos)/2)^n over the sphere is 4 pi / (n + 1), so the
    normalisation constant is 4 pi (1 + 9/9) = 8 pi."""
    c = np.asarray(cos_theta, dtype=np.float64)
    return (1.0 + 9.0 * ((1.0 + c) * 0.5) ** 8) / (8.0 * math.pi)


def phase_murky(cos_theta):
    """[NMN87] "murky" Mie approximation 1 + 50 ((1 + cos)/2)^32, normalised over the
    sphere [sr^-1] (constant 4 pi (1 + 50/33))."""
    c = np.asarray(cos_theta, dtype=np.float64)
    return (1.0 + 50.0 * ((1.0 + c) * 0.5) ** 32) / (4.0 * math.pi * (1.0 + 50.0 / 33.0))


def _horizon_clamp(d):
    """Directions below the horizon replaced by the horizontal direction of the same
    azimuth (straight down: north)."""
    d = np.array(d, dtype=np.float64)
    below = d[:, 2] < 0.0
    if np.any(below):
        h = np.hypot(d[below, 0], d[below, 1])
        flat = np.zeros((h.size, 3))
        ok = h > 1e-12
        flat[ok, 0] = d[below, 0][ok] / h[ok]
        flat[ok, 1] = d[below, 1][ok] / h[ok]
        flat[~ok, 1] = 1.0
        d[below] = flat
    return d


def _piece_extinction(full, keep) -> np.ndarray:
    """Largest extinction coefficient [m^-1] of each row of the folded properties (``keep``:
    the rows of ``full`` that :func:`skydome.atmosphere.fold_absorbers` kept): for a row that
    absorbers were folded into, the sum of its members' own maxima (an absorber joins the
    first kept row on its density profile), so that the kernel cuts the pieces of the
    unfolded medium."""
    own = full.extinction.max(axis=1)
    out = np.zeros(keep.size)
    for j in range(full.profile_code.size):
        profile = (full.profile_code[j], full.profile_p0[j], full.profile_p1[j])
        k = next(k for k, i in enumerate(keep)
                 if i == j or (i < j and profile == (full.profile_code[i], full.profile_p0[i],
                                                     full.profile_p1[i])))
        out[k] += own[j]
    return np.ascontiguousarray(out)


def _shell_altitudes(props, top, n_shells, fog):
    """Sample-shell altitudes [m]: equal density decrements of each exponential profile
    (with at most H/2 between shells up to 14 H), the edges of bounded layers (ozone tent,
    uniform fog), 0 and the top."""
    hs = [np.array([0.0, top])]
    codes = list(props.profile_code) + ([fog[0]] if fog else [])
    p0s = list(props.profile_p0) + ([fog[1]] if fog else [])
    p1s = list(props.profile_p1) + ([0.0] if fog else [])
    k = np.arange(1, n_shells) / n_shells
    for code, p0, p1 in zip(codes, p0s, p1s):
        if code == 0:          # exponential, scale height p0
            hs.append(-p0 * np.log1p(-k * -np.expm1(-top / p0)))
            # the equal-decrement shells leave the thin upper part in one interval: keep
            # the spacing below H/2 up to where the density has fallen to 1e-6
            hs.append(np.arange(0.0, min(top, 14.0 * p0), 0.5 * p0))
        elif code == 1:        # tent centred at p0, half width p1
            hs.append(np.linspace(p0 - p1, p0 + p1, 9))
        elif code == 2:        # uniform below p0
            hs.append(np.array([p0]))
            hs.append(p0 * k[::max(1, n_shells // 8)])
        elif code == 3:        # Gaussian
            hs.append(p0 + p1 * np.linspace(-4.0, 4.0, 17))
    h = np.concatenate(hs)
    h = np.unique(np.clip(h, 0.0, top))
    return np.ascontiguousarray(h)


@register
class Kaneda1991(GroundEyeAerialPerspective, SkyModel):
    """Kaneda et al. (1991): single scattering over a spherical earth, with optional fog.

    Parameters
    ----------
    sun : skydome.Sun
        Sun position; any elevation in [-90, 90] deg (below the horizon the sky is lit
        only above the earth's shadow; accuracy is verified from 5 deg up).
    atmosphere : skydome.Atmosphere, optional
        The medium. Default ``Atmosphere.earth(turbidity=turbidity)``.
    turbidity : float
        Preetham turbidity [1, 32] used when no atmosphere is given (default 2.5).
    mie_phase : {"atmosphere", "hazy", "murky"}
        Aerosol phase function: the atmosphere's own (default), or the [NMN87] hazy or
        murky approximation of Mie scattering used by Nishita's and Kaneda's group.
    fog_density : float
        Fog extinction (= scattering) coefficient at the ground [m^-1], [0, 0.1]
        (0 disables fog; 0.01 m^-1 is a meteorological visibility of 3.912/0.01 = 391 m).
    fog_height_m : float
        Scale height of an exponential fog, or thickness of a uniform fog [m], [1, 5000]
        (default 100).
    fog_profile : {"exponential", "uniform"}
        Fog density distribution (default exponential).
    fog_phase : {"murky", "hazy", "isotropic"}
        Fog phase function (default murky).
    shells : int
        Sample shells per density profile along each view ray [4, 1024] (default 12).
    max_dtau : float
        Largest optical thickness of one Simpson piece [0.001, 1] (default 0.2).
    """

    name = "kaneda1991"
    reference = ("Kaneda, Okamoto, Nakamae, Nishita 1991. Photorealistic image synthesis for "
                 "outdoor scenery under various atmospheric conditions. The Visual Computer 7, "
                 "247-258; survey section 7.2")
    native = "spectral"
    own_ground = "own"                    # measured against rho E_h / pi: docs/models.md
    summary = "Spherical earth, exponential air and aerosols, single scattering, fog layer."
    parameters = (
        ATMOSPHERE,
        TURBIDITY,
        Parameter("mie_phase", "", "atmosphere", kind="choice", choices=("atmosphere", "hazy", "murky"),
                  doc="aerosol phase function"),
        Parameter("fog_density", "m^-1", 0.0, 0.0, 0.1, "fog extinction at the ground (0: no fog)"),
        Parameter("fog_height_m", "m", 100.0, 1.0, 5000.0, "fog scale height or layer thickness"),
        Parameter("fog_profile", "", "exponential", kind="choice", choices=("exponential", "uniform"),
                  doc="fog density distribution"),
        Parameter("fog_phase", "", "murky", kind="choice", choices=("murky", "hazy", "isotropic"),
                  doc="fog phase function"),
        Parameter("shells", "", 12, 4, 1024, "sample shells per density profile", kind="int"),
        Parameter("max_dtau", "", 0.2, 0.001, 1.0, "largest optical thickness of a Simpson piece"),
    )

    def __init__(self, sun, **params):
        # (the common checks of the protocol; ``_setup`` is this model's table builder)
        p = self._begin(sun, params)
        atm = p["atmosphere"]
        self.atmosphere = atm
        for k, v in p.items():
            if k != "atmosphere":
                setattr(self, k, v)
        self._cache: dict = {}

    # -- set-up ----------------------------------------------------------------------------
    @property
    def fog_enabled(self) -> bool:
        return self.fog_density > 0.0

    def _setup(self, wl):
        """Optical properties (+ fog row), shells and column table for a wavelength grid."""
        from skydome.atmosphere import fold_absorbers
        from skydome.transport._medium import medium_from_properties, phase_cdf_table
        from skydome.transport.optical_depth import ColumnTable

        key = tuple(np.round(wl, 9))
        if key in self._cache:
            return self._cache[key]
        if len(self._cache) > 4:
            self._cache.clear()
        full = self.atmosphere.optical_properties(wl)
        props, keep = fold_absorbers(full)  # absorbers folded (exact), as in every kernel
        table = ColumnTable.cached(props)   # the reference model's table (shared)
        nc_a = props.profile_code.size
        bmax = _piece_extinction(full, keep)
        codes, p0s, p1s = props.profile_code, props.profile_p0, props.profile_p1
        beta_s, beta_e = props.scattering, props.extinction
        fog = None
        fog_code = -1
        if self.fog_enabled:
            fog_code = 0 if self.fog_profile == "exponential" else 2
            fog = (fog_code, self.fog_height_m)
            codes = np.append(codes, fog_code).astype(np.int64)
            p0s = np.append(p0s, self.fog_height_m)
            p1s = np.append(p1s, 0.0)
            row = np.full((1, wl.size), self.fog_density)
            bmax = np.append(bmax, self.fog_density)
            beta_s = np.vstack([beta_s, row])
            beta_e = np.vstack([beta_e, row])
        top = props.top_radius_m - props.planet_radius_m
        shells = _shell_altitudes(props, top, self.shells, fog)
        base = medium_from_properties(props)
        n_fog = codes.size - nc_a
        table_ph = base.phase_table
        if n_fog:
            table_ph = np.concatenate([table_ph, np.zeros((n_fog,) + table_ph.shape[1:])])
        medium = base._replace(
            profile_code=np.ascontiguousarray(codes, dtype=np.int64),
            profile_p0=np.ascontiguousarray(p0s, dtype=np.float64),
            profile_p1=np.ascontiguousarray(p1s, dtype=np.float64),
            scattering=np.ascontiguousarray(beta_s), extinction=np.ascontiguousarray(beta_e),
            phase_code=np.ascontiguousarray(np.append(base.phase_code, [3] * n_fog), dtype=np.int64),
            phase_param=np.ascontiguousarray(np.append(base.phase_param, [0.0] * n_fog)),
            phase_table=np.ascontiguousarray(table_ph),
            phase_cdf=np.ascontiguousarray(phase_cdf_table(table_ph)))
        setup = dict(props=props, table=table.table, nc_a=nc_a, medium=medium, bmax=bmax,
                     beta_s=medium.scattering, fog_code=fog_code, shells=shells)
        self._cache[key] = setup
        return setup

    def _phases(self, setup, nu):
        """Phase function of every constituent at scattering-angle cosines nu, (n, nc, nl)
        (the atmosphere's own, tabulated included, from the kernels' core; the NMN87
        approximations where chosen)."""
        from skydome.transport._phase import phase_values_many

        m = setup["medium"]
        nu = np.ascontiguousarray(nu, dtype=np.float64)
        out = np.empty((nu.size, m.phase_code.size, m.extinction.shape[1]))
        phase_values_many(m, nu, out)
        if self.mie_phase != "atmosphere":
            for c, code in enumerate(setup["props"].phase_code):
                if code in (1, 2, 4):
                    out[:, c, :] = (phase_hazy(nu) if self.mie_phase == "hazy" else phase_murky(nu))[:, None]
        if setup["fog_code"] >= 0:
            out[:, -1, :] = {"murky": phase_murky, "hazy": phase_hazy}.get(
                self.fog_phase, lambda c: np.full_like(c, _INV_4PI))(nu)[:, None]
        return out

    def _solar(self, wl):
        from skydome.spectra import solar_irradiance

        return solar_irradiance(wl) * self.sun.irradiance_scale

    def _trace(self, dirs, t_end, wl):
        """(transmittance (n, nl), in-scattered radiance (n, nl)) along rays from the eye."""
        from skydome.models.simulated import _kernels_kaneda as KK

        s = self._setup(wl)
        # the eye is on the ground: directions below the horizon are taken as horizontal
        d = np.ascontiguousarray(_horizon_clamp(dirs))
        n = d.shape[0]
        nc = s["medium"].profile_code.size
        acc = np.empty((n, nc, wl.size))
        trans = np.empty((n, wl.size))
        KK.kaneda_rays(d, np.ascontiguousarray(t_end, dtype=np.float64), self.sun.direction,
                       s["medium"], s["shells"], s["table"], s["nc_a"], s["fog_code"],
                       float(self.fog_height_m), float(self.max_dtau), 4096, s["bmax"], acc,
                       trans)
        nu = np.clip(d @ self.sun.direction, -1.0, 1.0)
        ph = self._phases(s, nu)                                     # (n, nc, nl)
        L = self._solar(wl) * np.einsum("ncl,cl,ncl->nl", ph, s["beta_s"], acc)
        return trans, np.maximum(L, 0.0)

    #: the rays of ``aerial_perspective`` (air, aerosols, ozone and fog)
    _aerial_rays = _trace

    # -- public API -----------------------------------------------------------------------
    def radiance(self, directions, wavelengths_nm) -> np.ndarray:
        """Single-scattered sky radiance (fog included when enabled) [W m^-2 sr^-1 nm^-1],
        shape (..., n_wavelengths). The eye is on the ground; directions below the horizon
        are evaluated as the horizon."""
        d = as_directions(directions)
        wl = as_wavelengths(wavelengths_nm)
        flat = d.reshape(-1, 3)
        _, L = self._trace(flat, np.full(flat.shape[0], np.inf), wl)
        return L.reshape(d.shape[:-1] + (wl.size,))

    def sun_radiance(self, wavelengths_nm) -> np.ndarray:
        """Radiance of the sun's disc [W m^-2 sr^-1 nm^-1]: E_sun / Omega_sun x T(ground ->
        top), fog included; 0 when the sun is below the horizon."""
        from skydome.models.simulated import _kernels_kaneda as KK

        wl = as_wavelengths(wavelengths_nm)
        s = self._setup(wl)
        t = np.empty(wl.size)
        KK.sun_transmittance(s["medium"], float(self.sun.direction[2]), s["table"], s["nc_a"],
                             s["fog_code"], float(self.fog_height_m), t)
        return self._solar(wl) / self.sun.solid_angle_sr * t


#: The earlier name (class names follow the registry names, without a "Sky" suffix).
Kaneda1991Sky = Kaneda1991
