"""Lorenz-Mie aerosols: log-normal size distributions of homogeneous spheres.

For a population of spheres with complex refractive index m and a log-normal number
distribution of radii,

    n(ln r) = 1 / (sqrt(2 pi) ln sigma_g) exp(-(ln r - ln r_m)^2 / (2 ln^2 sigma_g))   [Sei06] eq. 8.34

(r_m the median radius, sigma_g >= 1 the geometric standard deviation), the mean cross
sections per particle are

    <C_ext,sca>(lambda) = integral C_ext,sca(r, lambda) n(ln r) d ln r,

with C = Q pi r^2 and Q the Lorenz-Mie efficiencies of a sphere of size parameter
x = 2 pi r / lambda ([BH83] eqs. 4.61, 4.62). The phase function of the population is the
scattering-weighted mean of the particles' phase functions

    p(theta, lambda) = integral C_sca(r) p_r(theta) n d ln r / <C_sca>,
    p_r(theta) = (|S1|^2 + |S2|^2) / (2 pi x^2 Q_sca)      [BH83] eqs. 3.16, 4.74

(normalised to 1 over the sphere, [sr^-1]). The integrals over size are done by the
trapezoidal rule in ln r over r_m sigma_g^(+-4) (the tails beyond carry 6e-5 of the
particles).

Where the numbers come from
---------------------------
Q_ext, Q_sca and the asymmetry parameter g come from ``miepython`` (Prahl; imported
lazily, vectorised over size). The amplitude functions S1, S2 (the tabulated phase
function) come from :func:`mie_series`, a vectorised implementation of the Bohren &
Huffman series written here from [BH83] ch. 4 (miepython evaluates them one size at a
time, which is 50x slower for a size distribution). Both are tested against Wiscombe's
published MIEV0 test cases [Wis79] and against each other (tests/test_mie.py).

The transport kernels know only analytic phase functions (Rayleigh, Henyey-Greenstein,
Cornette-Shanks, isotropic), with one asymmetry parameter per constituent. A
:class:`MieConstituent` therefore carries, besides its Mie coefficients, the Mie
asymmetry parameter g at 550 nm for the kernels (Henyey-Greenstein by default), and the
:class:`MieAerosol` itself so that effects that need the true phase function (Bishop's
ring, the aureole: :mod:`skydome.effects.aureole`) can use it.

Sign convention: absorption is a positive imaginary part in [BH83] (time factor
exp(-i omega t)) and a negative one in Wiscombe's and miepython's convention. Here a
refractive index may be given either way: only |Im m| is used, as absorption.

References
----------
.. [BH83] Bohren, C. F. & Huffman, D. R. (1983), *Absorption and Scattering of Light by
   Small Particles*, Wiley; ch. 4 (series, eqs. 4.53, 4.56, 4.61, 4.62, 4.74, 4.89) and
   appendix A (BHMIE: logarithmic derivative by downward recurrence).
.. [Wis79] Wiscombe, W. J. (1979, revised 1996), *Mie scattering calculations: advances in
   technique and fast, vector-speed computer codes*, NCAR/TN-140+STR (test cases of MIEV0);
   Wiscombe (1980), Improved Mie scattering algorithms, Appl. Opt. 19, 1505-1509 (number
   of terms x + 4.05 x^(1/3) + 2).
.. [Sei06] Seinfeld, J. H. & Pandis, S. N. (2006), *Atmospheric Chemistry and Physics*,
   2nd ed., Wiley, section 8.1.4 (the log-normal distribution).
.. [Pra] Prahl, S., miepython, https://github.com/scottprahl/miepython (Mie efficiencies).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, NamedTuple

import numpy as np

from skydome._validate import as_wavelengths, check_int, check_number
from skydome.atmosphere._constituent import Constituent
from skydome.atmosphere.profiles import DensityProfile

__all__ = ["mie_series", "lognormal_nodes", "MieOptics", "MieAerosol", "MieConstituent",
           "mie_constituent"]

REFERENCE_WAVELENGTH_NM = 550.0


# ---------------------------------------------------------------------------------------------
def _n_terms(x: np.ndarray) -> np.ndarray:
    """Number of series terms: x + 4.05 x^(1/3) + 2 ([Wis79]; Wiscombe 1980 eq. 4)."""
    return np.floor(x + 4.05 * np.cbrt(x) + 2.0).astype(np.int64)


def mie_series(m: complex, x, mu=None):
    """Lorenz-Mie series for homogeneous spheres, vectorised over size parameter.

    Parameters
    ----------
    m : complex
        Refractive index of the sphere relative to the medium; absorption is |Im m|
        (either sign convention is accepted).
    x : array_like (nx,)
        Size parameters 2 pi r / lambda, in (0, 1e4].
    mu : array_like (nmu,), optional
        Cosines of the scattering angles at which S1, S2 are wanted.

    Returns
    -------
    qext, qsca, g : ndarray (nx,)
        Extinction and scattering efficiencies ([BH83] eqs. 4.61, 4.62) and asymmetry
        parameter ([BH83] eq. 4.89 / p. 120).
    s1, s2 : ndarray (nx, nmu) complex, only when ``mu`` is given
        Scattering amplitudes ([BH83] eq. 4.74), normalised as in [BH83] (their
        integral (|S1|^2 + |S2|^2)/2 over the sphere is pi x^2 Q_sca).
    """
    m = complex(m)
    if not np.isfinite(m.real) or m.real <= 0:
        raise ValueError(f"refractive index real part = {m.real:g} is out of range (0, inf)")
    m = complex(m.real, abs(m.imag))       # [BH83] convention: exp(-i omega t), Im m >= 0
    x = np.atleast_1d(np.asarray(x, dtype=np.float64))
    if np.any(~np.isfinite(x)) or np.any(x <= 0) or np.any(x > 1e4):
        raise ValueError("size parameter x is out of range (0, 10000]")
    nx = x.size
    nstop = _n_terms(x)
    nmax = int(nstop.max())
    mx = m * x
    # logarithmic derivative D_n(mx) by downward recurrence ([BH83] eq. 4.89, appendix A)
    amx = float(np.abs(mx).max())
    nmx = int(max(nmax, amx + 4.05 * amx ** (1.0 / 3.0))) + 16
    D = np.zeros((nmx + 1, nx), dtype=np.complex128)
    for n in range(nmx, 0, -1):
        D[n - 1] = n / mx - 1.0 / (D[n] + n / mx)
    with_angles = mu is not None
    if with_angles:
        mu = np.atleast_1d(np.asarray(mu, dtype=np.float64))
        s1 = np.zeros((nx, mu.size), dtype=np.complex128)
        s2 = np.zeros((nx, mu.size), dtype=np.complex128)
        pi_prev = np.zeros(mu.size)      # pi_0
        pi_n = np.ones(mu.size)          # pi_1
    # Riccati-Bessel functions by upward recurrence ([BH83] eq. 4.88)
    psi_prev, psi = np.cos(x), np.sin(x)             # psi_-1, psi_0
    chi_prev, chi = -np.sin(x), np.cos(x)            # chi_-1, chi_0
    xi = psi - 1j * chi
    qext = np.zeros(nx)
    qsca = np.zeros(nx)
    gq = np.zeros(nx)
    a_prev = np.zeros(nx, dtype=np.complex128)
    b_prev = np.zeros(nx, dtype=np.complex128)
    for n in range(1, nmax + 1):
        active = n <= nstop
        fn = (2.0 * n + 1.0) / (n * (n + 1.0))
        psi_new = np.where(active, (2.0 * n - 1.0) / x * psi - psi_prev, psi)
        chi_new = np.where(active, (2.0 * n - 1.0) / x * chi - chi_prev, chi)
        psi_prev, psi = psi, psi_new
        chi_prev, chi = chi, chi_new
        xi_prev, xi = xi, psi - 1j * chi
        Dn = D[n]
        ta = Dn / m + n / x
        tb = Dn * m + n / x
        with np.errstate(all="ignore"):
            a = (ta * psi - psi_prev) / (ta * xi - xi_prev)     # [BH83] eq. 4.88
            b = (tb * psi - psi_prev) / (tb * xi - xi_prev)
        a = np.where(active, a, 0.0)
        b = np.where(active, b, 0.0)
        qext += (2.0 * n + 1.0) * (a.real + b.real)                       # eq. 4.62
        qsca += (2.0 * n + 1.0) * (np.abs(a) ** 2 + np.abs(b) ** 2)       # eq. 4.61
        if n > 1:   # asymmetry parameter ([BH83] p. 120)
            nm = n - 1.0
            gq += (nm * (nm + 2.0) / (nm + 1.0) * (a_prev * np.conj(a) + b_prev * np.conj(b)).real)
        gq += fn * (a * np.conj(b)).real
        a_prev, b_prev = a, b
        if with_angles:
            tau_n = n * mu * pi_n - (n + 1.0) * pi_prev                   # eq. 4.47
            s1 += fn * (a[:, None] * pi_n + b[:, None] * tau_n)           # eq. 4.74
            s2 += fn * (a[:, None] * tau_n + b[:, None] * pi_n)
            pi_next = ((2.0 * n + 1.0) / n * mu * pi_n - (n + 1.0) / n * pi_prev)
            pi_prev, pi_n = pi_n, pi_next
    qext *= 2.0 / x ** 2
    qsca *= 2.0 / x ** 2
    g = 4.0 / (x ** 2 * qsca) * gq
    if with_angles:
        return qext, qsca, g, s1, s2
    return qext, qsca, g


# ---------------------------------------------------------------------------------------------
def lognormal_nodes(median_radius_um: float, geometric_std: float, n: int = 41):
    """Quadrature nodes and weights for a log-normal number distribution.

    Parameters
    ----------
    median_radius_um : float
        Median radius r_m [um], in [1e-3, 100].
    geometric_std : float
        Geometric standard deviation sigma_g, in [1, 5]; 1 is a single size.
    n : int
        Number of nodes (trapezoidal rule in ln r over r_m sigma_g^(+-4)), in [3, 2001].

    Returns
    -------
    radii_um, weights : ndarray (n,)
        Radii [um] and number fractions (summing to 1).
    """
    rm = check_number("median_radius_um", median_radius_um, 1e-3, 100.0, "um")
    sg = check_number("geometric_std", geometric_std, 1.0, 5.0)
    n = check_int("n_radii", n, 3, 2001)
    if sg == 1.0:
        return np.array([rm]), np.array([1.0])
    s = np.log(sg)
    z = np.linspace(-4.0, 4.0, n)
    w = np.exp(-0.5 * z * z)                           # [Sei06] eq. 8.34 in ln r
    w[[0, -1]] *= 0.5                                  # trapezoidal end weights
    return rm * np.exp(z * s), w / w.sum()


class MieOptics(NamedTuple):
    """Mean optical properties per particle of a size distribution on a wavelength grid."""

    wavelengths_nm: np.ndarray   # (nl,)
    c_ext_m2: np.ndarray         # (nl,) mean extinction cross section [m^2]
    c_sca_m2: np.ndarray         # (nl,) mean scattering cross section [m^2]
    g: np.ndarray                # (nl,) asymmetry parameter <cos theta>
    single_scattering_albedo: np.ndarray   # (nl,)


def _refractive_index(value: Any) -> Callable[[float], complex]:
    if callable(value):
        return lambda wl: complex(value(wl))
    if isinstance(value, bool) or not isinstance(value, (int, float, complex, np.number)):
        raise TypeError(f"refractive_index must be a complex number or a callable of wavelength "
                        f"in nm, got {type(value).__name__}")
    m = complex(value)
    if not (np.isfinite(m.real) and np.isfinite(m.imag)) or not (1.0 <= m.real <= 4.0) \
            or abs(m.imag) > 10.0:
        raise ValueError(f"refractive_index = {m} is out of range: real part [1, 4], "
                         f"|imaginary part| [0, 10]")
    return lambda wl: m


class MieAerosol:
    """A log-normal population of homogeneous spheres and its Lorenz-Mie optics.

    Parameters
    ----------
    median_radius_um : float
        Median radius r_m of the number distribution [um], in [1e-3, 100].
    geometric_std : float
        Geometric standard deviation sigma_g, in [1, 5] (1: a single size).
    refractive_index : complex or callable
        Complex refractive index relative to air, e.g. 1.5 - 0.001j for volcanic ash
        (absorption is |Im m|), or a callable of wavelength [nm] returning one.
    n_radii : int
        Quadrature nodes over size (default 41; 3 to 2001).
    n_angles : int
        Nodes of the tabulated phase function in scattering angle (default 1441: 0.125 deg).

    Notes
    -----
    Optical properties are cached per wavelength. Size parameters above 1e4 (radius
    above ~ 600 um in the visible) are refused.
    """

    def __init__(self, median_radius_um: float = 0.5, geometric_std: float = 1.1,
                 refractive_index: Any = 1.5 - 0.001j, *, n_radii: int = 41,
                 n_angles: int = 1441):
        self.median_radius_um = check_number("median_radius_um", median_radius_um, 1e-3, 100.0, "um")
        self.geometric_std = check_number("geometric_std", geometric_std, 1.0, 5.0)
        self.n_radii = check_int("n_radii", n_radii, 3, 2001)
        self.n_angles = check_int("n_angles", n_angles, 19, 100_001)
        self.refractive_index = refractive_index
        self._m = _refractive_index(refractive_index)
        self.radii_um, self.weights = lognormal_nodes(self.median_radius_um, self.geometric_std,
                                                      self.n_radii)
        self.theta_deg = np.linspace(0.0, 180.0, self.n_angles)
        self._cache: dict[float, tuple] = {}

    def __repr__(self) -> str:
        return (f"MieAerosol(median_radius_um={self.median_radius_um:g}, "
                f"geometric_std={self.geometric_std:g}, refractive_index={self.refractive_index!r})")

    # -- one wavelength -------------------------------------------------------------------
    def _one(self, wl: float) -> tuple:
        key = round(float(wl), 6)
        hit = self._cache.get(key)
        if hit is not None:
            return hit
        import miepython

        m = self._m(wl)
        if not (np.isfinite(m.real) and m.real > 0):
            raise ValueError(f"refractive_index({wl:g} nm) = {m} has a non-positive real part")
        r_m = self.radii_um * 1e-6
        x = 2.0 * np.pi * self.radii_um * 1e3 / wl
        if x.max() > 1e4:
            raise ValueError(f"size parameter {x.max():.4g} at {wl:g} nm is out of range (0, 10000]")
        qext, qsca, _, g = miepython.efficiencies_mx(complex(m.real, -abs(m.imag)), x)   # [Pra]
        qext, qsca, g = (np.atleast_1d(np.asarray(v, dtype=np.float64)) for v in (qext, qsca, g))
        area = np.pi * r_m ** 2
        c_ext = float(np.sum(self.weights * qext * area))
        c_sca_i = self.weights * qsca * area
        c_sca = float(np.sum(c_sca_i))
        g_mean = float(np.sum(c_sca_i * g) / c_sca) if c_sca > 0 else 0.0
        # tabulated phase function: scattering-weighted mean over size ([BH83] eq. 3.16)
        mu = np.cos(np.radians(self.theta_deg))
        _, qs2, _, s1, s2 = mie_series(m, x, mu)
        with np.errstate(all="ignore"):
            p_r = (np.abs(s1) ** 2 + np.abs(s2) ** 2) / (2.0 * np.pi * x[:, None] ** 2 * qs2[:, None])
        p_r = np.where(np.isfinite(p_r), p_r, 0.0)
        phase = (c_sca_i[:, None] * p_r).sum(axis=0) / c_sca if c_sca > 0 else np.full(mu.size, 1 / (4 * np.pi))
        out = (c_ext, c_sca, g_mean, phase)
        if len(self._cache) > 512:
            self._cache.clear()
        self._cache[key] = out
        return out

    # -- public ---------------------------------------------------------------------------
    def optics(self, wavelengths_nm) -> MieOptics:
        """Mean cross sections per particle [m^2], asymmetry parameter and single-scattering
        albedo on a wavelength grid [nm] (1-D, in [100, 1e5])."""
        wl = as_wavelengths(wavelengths_nm, 100.0, 1e5).reshape(-1)
        rows = [self._one(w) for w in wl]
        c_ext = np.array([r[0] for r in rows])
        c_sca = np.array([r[1] for r in rows])
        g = np.array([r[2] for r in rows])
        with np.errstate(invalid="ignore", divide="ignore"):
            ssa = np.where(c_ext > 0, c_sca / c_ext, 1.0)
        return MieOptics(wl, c_ext, c_sca, g, ssa)

    def phase_table(self, wavelengths_nm) -> tuple[np.ndarray, np.ndarray]:
        """The tabulated phase function: (theta_deg (na,), p (na, nl) [sr^-1]), normalised
        to 1 over the sphere."""
        wl = as_wavelengths(wavelengths_nm, 100.0, 1e5).reshape(-1)
        return self.theta_deg.copy(), np.stack([self._one(w)[3] for w in wl], axis=-1)

    def phase_function(self, cos_theta, wavelengths_nm) -> np.ndarray:
        """Phase function [sr^-1] of the population at scattering angles with cosines
        ``cos_theta`` (...), shape (..., nl): linear interpolation in angle of the
        tabulated values (ln p interpolated, so the forward peak is followed closely)."""
        c = np.clip(np.asarray(cos_theta, dtype=np.float64), -1.0, 1.0)
        th = np.degrees(np.arccos(c))
        theta, table = self.phase_table(wavelengths_nm)
        logt = np.log(np.maximum(table, 1e-300))
        out = np.empty(th.shape + (table.shape[1],))
        for j in range(table.shape[1]):
            out[..., j] = np.exp(np.interp(th, theta, logt[:, j]))
        return out


# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class MieConstituent(Constituent):
    """A :class:`~skydome.atmosphere.Constituent` whose coefficients come from Lorenz-Mie
    theory. ``aerosol`` gives the true phase function, which the kernels use as a
    :class:`~skydome.atmosphere.TabulatedPhase` when ``phase`` is "tabulated" (the
    default of :func:`mie_constituent`); ``g`` is the Mie asymmetry parameter at 550 nm,
    the parameter of an analytic stand-in ("henyey_greenstein", "cornette_shanks")."""

    aerosol: Any = None
    number_density_m3: float = 0.0

    def __post_init__(self):
        if self.phase_table is None and isinstance(self.aerosol, MieAerosol):
            object.__setattr__(self, "phase_table", mie_phase_table(self.aerosol))
        super().__post_init__()


def mie_phase_table(aerosol: "MieAerosol"):
    """The aerosol's Lorenz-Mie phase function as a :class:`~skydome.atmosphere.TabulatedPhase`
    (computed per wavelength grid, normalised by construction, [BH83] eq. 3.16)."""
    from skydome.atmosphere._constituent import TabulatedPhase

    return TabulatedPhase.from_function(aerosol.phase_table, f"Lorenz-Mie {aerosol!r}",
                                        normalise=False)


def mie_constituent(aerosol: MieAerosol, profile: DensityProfile, *,
                    number_density_m3: float | None = None,
                    optical_depth_550: float | None = None,
                    top_altitude_m: float = 100e3, kernel_phase: str = "tabulated",
                    name: str = "mie_aerosol") -> MieConstituent:
    """Build a Mie constituent from an aerosol population and a density profile.

    Parameters
    ----------
    aerosol : MieAerosol
    profile : DensityProfile
        Density relative to the reference (peak or sea-level) number density.
    number_density_m3 : float, optional
        Reference number density [m^-3], in (0, 1e15].
    optical_depth_550 : float, optional
        Instead of ``number_density_m3``: the vertical extinction optical depth of the
        layer at 550 nm, in (0, 20]; N = tau / (<C_ext(550)> column(profile)).
    top_altitude_m : float
        Top of the atmosphere [m] (for the column of ``profile``).
    kernel_phase : {"tabulated", "henyey_greenstein", "cornette_shanks"}
        Phase function the transport kernels use: the tabulated Lorenz-Mie phase function
        (default), or an analytic stand-in with g = Mie g at 550 nm (faster to tabulate,
        but it misses the diffraction peak and the rainbow/glory structure).
    name : str
    """
    if not isinstance(aerosol, MieAerosol):
        raise TypeError(f"aerosol must be a MieAerosol, got {type(aerosol).__name__}")
    if not isinstance(profile, DensityProfile):
        raise TypeError(f"profile must be a DensityProfile, got {type(profile).__name__}")
    if (number_density_m3 is None) == (optical_depth_550 is None):
        raise ValueError("give exactly one of number_density_m3 and optical_depth_550")
    top = check_number("top_altitude_m", top_altitude_m, 100.0, 1e6, "m")
    ref = aerosol.optics([REFERENCE_WAVELENGTH_NM])
    if number_density_m3 is not None:
        n0 = check_number("number_density_m3", number_density_m3, 0.0, 1e15, "m^-3", low_open=True)
    else:
        tau = check_number("optical_depth_550", optical_depth_550, 0.0, 20.0, low_open=True)
        n0 = tau / (float(ref.c_ext_m2[0]) * profile.column(top))
    g550 = float(np.clip(ref.g[0], -0.999, 0.999))

    def sca(wl):
        wl = np.asarray(wl, dtype=np.float64)
        return n0 * aerosol.optics(wl.reshape(-1)).c_sca_m2.reshape(wl.shape)

    def absorption(wl):
        wl = np.asarray(wl, dtype=np.float64)
        o = aerosol.optics(wl.reshape(-1))
        return n0 * np.maximum(o.c_ext_m2 - o.c_sca_m2, 0.0).reshape(wl.shape)

    return MieConstituent(name, scattering=sca, absorption=absorption, profile=profile,
                          phase=kernel_phase, g=g550, aerosol=aerosol, number_density_m3=n0)


# ---------------------------------------------------------------------------------------------
def layered_mie_atmosphere(atmosphere_cls, kind: str, *, optical_depth_550: float, median_radius_um: float,
                           geometric_std: float, refractive_index: Any, layer_altitude_m: float,
                           layer_width_m: float, background_turbidity: float,
                           n_radii: int = 41, **earth_kwargs):
    """Atmosphere.earth(turbidity=background_turbidity, ...) plus an elevated Gaussian
    layer of Mie particles (the body of :meth:`Atmosphere.volcanic_ash` and
    :meth:`Atmosphere.forest_fire_smoke`, which pass their class as ``atmosphere_cls``: this
    module builds constituents and does not import the package that calls it)."""
    from skydome.atmosphere.profiles import GaussianLayerProfile

    Atmosphere = atmosphere_cls

    z = check_number("layer_altitude_m", layer_altitude_m, 0.0, 80e3, "m")
    w = check_number("layer_width_m", layer_width_m, 10.0, 20e3, "m")
    aero = MieAerosol(median_radius_um, geometric_std, refractive_index, n_radii=n_radii)
    base = Atmosphere.earth(turbidity=background_turbidity, **earth_kwargs)
    layer = mie_constituent(aero, GaussianLayerProfile(z, w), optical_depth_550=optical_depth_550,
                            top_altitude_m=base.top_altitude_m, name=kind)
    return Atmosphere(base.constituents + (layer,), planet_radius_m=base.planet_radius_m,
                      top_altitude_m=base.top_altitude_m, ground_albedo=base.ground_albedo,
                      name=(f"{kind}(tau550={optical_depth_550:g}, r_m={median_radius_um:g} um, "
                            f"sigma_g={geometric_std:g}, m={refractive_index}) + {base.name}"))
