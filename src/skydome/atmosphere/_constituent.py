"""The constituents of an atmosphere and their optical properties on a wavelength grid:
:class:`SpectralCoefficient`, :class:`TabulatedPhase`, :class:`Constituent`,
:class:`OpticalProperties` and :func:`fold_absorbers`, re-exported by
:mod:`skydome.atmosphere`.

The modules that build constituents (:mod:`~skydome.atmosphere.gases`,
:mod:`~skydome.atmosphere.mie`, :mod:`~skydome.atmosphere.blender`) import them from here,
so that none of them imports the package that calls them back (no import cycle).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, NamedTuple

import numpy as np

from skydome._validate import as_wavelengths, check_choice, check_number
from skydome.atmosphere.profiles import DensityProfile, ExponentialProfile
from skydome.constants import H_RAYLEIGH

__all__ = ["PHASE_CODES", "PHASE_TABLE_ANGLES", "SpectralCoefficient", "TabulatedPhase",
           "Constituent", "OpticalProperties", "fold_absorbers"]

# phase-function codes shared with the kernels (transport/_phase.py)
PHASE_CODES = {"rayleigh": 0, "henyey_greenstein": 1, "cornette_shanks": 2, "isotropic": 3,
               "tabulated": 4}

#: nodes of the kernels' tabulated phase functions: uniform in scattering angle over
#: [0, 180] deg, 0.125 deg apart (the grid of skydome.atmosphere.mie.MieAerosol)
PHASE_TABLE_ANGLES = 1441


# ---------------------------------------------------------------------------------------------
class SpectralCoefficient:
    """A non-negative coefficient as a function of wavelength [m^-1] (or dimensionless for an
    albedo).

    Build it from a constant, a power law ``value * (lambda / ref)^-exponent``, a table
    (linear interpolation, constant beyond the ends) or any callable of wavelength in nm.
    """

    def __init__(self, func: Callable[[np.ndarray], np.ndarray], description: str):
        self._func = func
        self.description = description

    @classmethod
    def make(cls, value: Any, name: str) -> "SpectralCoefficient":
        """Coerce a float, a (wavelengths_nm, values) pair, a callable or a
        SpectralCoefficient into a SpectralCoefficient; ``name`` is used in errors."""
        if isinstance(value, SpectralCoefficient):
            return value
        if isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool):
            return cls.constant(check_number(name, value, 0.0, None), name)
        if callable(value):
            return cls(lambda wl: np.asarray(value(wl), dtype=np.float64), f"{name}: callable")
        if isinstance(value, (tuple, list)) and len(value) == 2:
            return cls.table(value[0], value[1], name)
        raise TypeError(f"{name} must be a number, a (wavelengths_nm, values) pair, a callable "
                        f"or a SpectralCoefficient, got {type(value).__name__}")

    @classmethod
    def constant(cls, value: float, name: str = "coefficient") -> "SpectralCoefficient":
        v = check_number(name, value, 0.0, None)
        return cls(lambda wl: np.full(np.shape(wl), v), f"{v:g}")

    @classmethod
    def power_law(cls, value_at_ref: float, ref_nm: float, exponent: float,
                  name: str = "coefficient") -> "SpectralCoefficient":
        v = check_number(name, value_at_ref, 0.0, None)
        ref = check_number("ref_nm", ref_nm, 1.0, None, "nm")
        e = check_number("exponent", exponent, -10.0, 10.0)
        return cls(lambda wl: v * (np.asarray(wl, dtype=np.float64) / ref) ** (-e),
                   f"{v:g} (lambda/{ref:g} nm)^-{e:g}")

    @classmethod
    def table(cls, wavelengths_nm, values, name: str = "coefficient") -> "SpectralCoefficient":
        wl = as_wavelengths(wavelengths_nm, 1.0, 1e5, name=f"{name} wavelengths")
        v = np.asarray(values, dtype=np.float64)
        if v.shape != wl.shape:
            raise ValueError(f"{name}: values shape {v.shape} does not match wavelengths shape {wl.shape}")
        if not np.all(np.isfinite(v)) or np.any(v < 0):
            raise ValueError(f"{name}: values must be finite and non-negative")
        if np.any(np.diff(wl) <= 0):
            raise ValueError(f"{name}: wavelengths must be strictly increasing")
        wl, v = wl.copy(), v.copy()
        return cls(lambda x: np.interp(np.asarray(x, dtype=np.float64), wl, v),
                   f"table {wl[0]:g}-{wl[-1]:g} nm ({wl.size} values)")

    def __call__(self, wavelengths_nm) -> np.ndarray:
        out = np.asarray(self._func(np.asarray(wavelengths_nm, dtype=np.float64)), dtype=np.float64)
        out = np.broadcast_to(out, np.shape(wavelengths_nm)).astype(np.float64)
        if not np.all(np.isfinite(out)) or np.any(out < 0):
            raise ValueError(f"coefficient {self.description} gave NaN or negative values")
        return out

    def __repr__(self) -> str:
        return f"SpectralCoefficient({self.description})"


# ---------------------------------------------------------------------------------------------
class TabulatedPhase:
    """A phase function given as a table in scattering angle, per wavelength [sr^-1].

    Build it from measured values (``theta_deg`` (na,), ``values`` (na,) for a grey phase
    function or (na, nw) at ``wavelengths_nm`` (nw,)) or from a function of wavelength
    (:meth:`from_function`, e.g. Lorenz-Mie from :class:`skydome.atmosphere.mie.MieAerosol`).
    The kernels see it on a uniform grid of scattering angle (:meth:`on_grid`): linear
    interpolation in angle, and in wavelength between measured wavelengths (the end
    values held beyond them).

    Parameters
    ----------
    theta_deg : array_like (na,)
        Scattering angles [deg], strictly increasing, from 0 to 180.
    values : array_like (na,) or (na, nw)
        Phase function values, finite and non-negative.
    wavelengths_nm : array_like (nw,), optional
        Wavelengths of the columns of ``values`` [nm], strictly increasing.
    normalise : bool
        Scale each wavelength's table to 1 over the sphere (trapezoidal rule in angle on
        the kernels' grid); default True, so that measured relative values may be given.
    """

    def __init__(self, theta_deg, values, wavelengths_nm=None, *, normalise: bool = True,
                 description: str = "table"):
        th = np.asarray(theta_deg, dtype=np.float64)
        v = np.asarray(values, dtype=np.float64)
        if th.ndim != 1 or th.size < 2:
            raise ValueError(f"theta_deg must be 1-D with at least 2 angles, got shape {th.shape}")
        if not np.all(np.isfinite(th)) or abs(th[0]) > 1e-9 or abs(th[-1] - 180.0) > 1e-9 \
                or np.any(np.diff(th) <= 0):
            raise ValueError("theta_deg must increase strictly from 0 to 180 deg")
        if v.ndim == 1:
            v = v[:, None]
        if v.ndim != 2 or v.shape[0] != th.size:
            raise ValueError(f"values shape {np.shape(values)} does not match theta_deg shape {th.shape}")
        if not np.all(np.isfinite(v)) or np.any(v < 0):
            raise ValueError("values must be finite and non-negative")
        if wavelengths_nm is None:
            if v.shape[1] != 1:
                raise ValueError("wavelengths_nm is required for a table with several columns")
            wl = None
        else:
            wl = as_wavelengths(wavelengths_nm, 1.0, 1e5, name="phase table wavelengths_nm").reshape(-1)
            if wl.size != v.shape[1]:
                raise ValueError(f"values has {v.shape[1]} columns for {wl.size} wavelengths")
            if np.any(np.diff(wl) <= 0):
                raise ValueError("phase table wavelengths_nm must be strictly increasing")
        self._theta, self._values, self._wl = th.copy(), v.copy(), wl
        self._func = None
        self.normalise = bool(normalise)
        self.description = description

    @classmethod
    def from_function(cls, func: Callable[[np.ndarray], tuple], description: str = "function",
                      *, normalise: bool = False) -> "TabulatedPhase":
        """A phase function computed per wavelength grid: ``func(wavelengths_nm (nl,))``
        returns ``(theta_deg (na,), values (na, nl))``."""
        obj = cls.__new__(cls)
        obj._theta = obj._values = obj._wl = None
        obj._func = func
        obj.normalise = bool(normalise)
        obj.description = description
        return obj

    def _raw(self, wl: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if self._func is not None:
            th, v = self._func(wl)
            return np.asarray(th, dtype=np.float64), np.asarray(v, dtype=np.float64).reshape(len(th), wl.size)
        if self._wl is None:
            return self._theta, np.repeat(self._values, wl.size, axis=1)
        cols = np.stack([np.interp(wl, self._wl, row) for row in self._values])
        return self._theta, cols

    def on_grid(self, wavelengths_nm, n_angles: int = PHASE_TABLE_ANGLES) -> np.ndarray:
        """Values [sr^-1] on the kernels' grid, theta_k = 180 k / (n_angles - 1) deg, at the
        given wavelengths: shape (n_angles, nl)."""
        wl = np.asarray(wavelengths_nm, dtype=np.float64).reshape(-1)
        th, v = self._raw(wl)
        grid = np.linspace(0.0, 180.0, n_angles)
        if th.size == n_angles and np.allclose(th, grid, rtol=0, atol=1e-9):
            out = np.array(v, dtype=np.float64)
        else:
            out = np.stack([np.interp(grid, th, v[:, j]) for j in range(wl.size)], axis=-1)
        if not np.all(np.isfinite(out)) or np.any(out < 0):
            raise ValueError(f"phase table {self.description} gave NaN or negative values")
        if self.normalise:
            t = np.radians(grid)
            norm = 2.0 * np.pi * np.trapezoid(out * np.sin(t)[:, None], t, axis=0)
            if np.any(norm <= 0):
                raise ValueError(f"phase table {self.description} integrates to zero")
            out = out / norm
        return out

    def __repr__(self) -> str:
        return f"TabulatedPhase({self.description})"


# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Constituent:
    """One scattering and/or absorbing component of the atmosphere.

    Parameters
    ----------
    name : str
        Label ("rayleigh", "aerosol", "ozone", ...).
    scattering : SpectralCoefficient or number or (wl, values) or callable
        Scattering coefficient at reference density [m^-1].
    absorption : same
        Absorption coefficient at reference density [m^-1].
    profile : DensityProfile
        Density relative to the reference density as a function of altitude.
    phase : {"rayleigh", "henyey_greenstein", "cornette_shanks", "isotropic", "tabulated"}
        Phase function of the scattering; "tabulated" takes ``phase_table``.
    g : float
        Asymmetry parameter of HG / Cornette-Shanks, in (-1, 1).
    depolarisation : float
        Depolarisation ratio for the Rayleigh phase function, in [0, 0.5].
    phase_table : TabulatedPhase, optional
        The tabulated phase function (Lorenz-Mie or measured), required with
        ``phase="tabulated"``.
    """

    name: str
    scattering: Any = 0.0
    absorption: Any = 0.0
    profile: DensityProfile = field(default_factory=lambda: ExponentialProfile(H_RAYLEIGH))
    phase: str = "rayleigh"
    g: float = 0.0
    depolarisation: float = 0.0
    phase_table: Any = None

    def __post_init__(self):
        object.__setattr__(self, "scattering", SpectralCoefficient.make(self.scattering, f"{self.name}.scattering"))
        object.__setattr__(self, "absorption", SpectralCoefficient.make(self.absorption, f"{self.name}.absorption"))
        if not isinstance(self.profile, DensityProfile):
            raise TypeError(f"{self.name}.profile must be a DensityProfile, got {type(self.profile).__name__}")
        check_choice(f"{self.name}.phase", self.phase, tuple(PHASE_CODES))
        object.__setattr__(self, "g", check_number(f"{self.name}.g", self.g, -1.0, 1.0,
                                                   low_open=True, high_open=True))
        object.__setattr__(self, "depolarisation",
                           check_number(f"{self.name}.depolarisation", self.depolarisation, 0.0, 0.5))
        if self.phase_table is not None and not isinstance(self.phase_table, TabulatedPhase):
            raise TypeError(f"{self.name}.phase_table must be a TabulatedPhase, "
                            f"got {type(self.phase_table).__name__}")
        if self.phase == "tabulated" and self.phase_table is None:
            raise ValueError(f"{self.name}.phase = 'tabulated' needs a phase_table")

    def phase_param(self) -> float:
        """The kernel's phase parameter: g for HG/CS; rho/(2 - rho) for Rayleigh."""
        if self.phase == "rayleigh":
            return self.depolarisation / (2.0 - self.depolarisation)
        return self.g


class OpticalProperties(NamedTuple):
    """Plain arrays describing an atmosphere on a wavelength grid, ready for the kernels.

    nc constituents, nl wavelengths. Coefficients are at reference density [m^-1].
    """

    wavelengths_nm: np.ndarray   # (nl,)
    planet_radius_m: float
    top_radius_m: float
    profile_code: np.ndarray     # (nc,) int64
    profile_p0: np.ndarray       # (nc,)
    profile_p1: np.ndarray       # (nc,)
    scattering: np.ndarray       # (nc, nl)
    extinction: np.ndarray       # (nc, nl) scattering + absorption
    phase_code: np.ndarray       # (nc,) int64
    phase_param: np.ndarray      # (nc,)
    ground_albedo: np.ndarray    # (nl,)
    phase_table: np.ndarray | None = None   # (nc, na, nl) [sr^-1] where any is tabulated


def fold_absorbers(props: OpticalProperties) -> tuple[OpticalProperties, np.ndarray]:
    """The same medium with fewer constituents: every purely absorbing constituent whose
    density profile is identical to an earlier constituent's is folded into it.

    Exact: constituents with one density profile n(h) add their extinction coefficients
    (tau = integral of n(h) ds x sum of their extinctions), and a constituent that does
    not scatter adds nothing to the scattering or the phase function. Used where a
    fixed number of constituents is all there is room for (the viewer's shaders, which
    pack four in a vec4): the uniformly mixed gases follow the air density, so they fold
    into Rayleigh's constituent.

    Returns the folded properties and the indices (into ``props``) of the constituents
    kept, in order.
    """
    nc = int(props.profile_code.size)
    target = np.arange(nc)
    for j in range(nc):
        if np.any(props.scattering[j] != 0.0):
            continue
        for i in range(j):
            if (target[i] == i and props.profile_code[i] == props.profile_code[j]
                    and props.profile_p0[i] == props.profile_p0[j]
                    and props.profile_p1[i] == props.profile_p1[j]):
                target[j] = i
                break
    keep = np.flatnonzero(target == np.arange(nc))
    extinction = np.zeros((keep.size, props.extinction.shape[1]))
    for k, i in enumerate(keep):
        extinction[k] = props.extinction[target == i].sum(axis=0)
    table = None if props.phase_table is None else props.phase_table[keep]
    return props._replace(profile_code=props.profile_code[keep], profile_p0=props.profile_p0[keep],
                          profile_p1=props.profile_p1[keep], scattering=props.scattering[keep],
                          extinction=extinction, phase_code=props.phase_code[keep],
                          phase_param=props.phase_param[keep], phase_table=table), keep
