"""``montecarlo``: spectral, optionally polarised, Monte Carlo reference sky.

Backward path tracing from the observer through the spherical-shell atmosphere of an
:class:`skydome.atmosphere.Atmosphere`, with every order of scattering (Russian roulette, no
cut-off), next-event estimation towards the sun's disc, a Lambertian ground and, in polarised
mode, Stokes vectors with Rayleigh scattering matrices including depolarisation. It returns
the radiance with its standard error, so that other models can be judged against it within
a stated uncertainty. The kernels are in :mod:`skydome.models.simulated._kernels_montecarlo`.
"""

from __future__ import annotations

import numpy as np

from skydome._validate import as_directions, as_wavelengths
from skydome.models import ATMOSPHERE_PARAMETERS, Parameter, SkyModel, register

__all__ = ["MonteCarlo", "MonteCarloSky", "degree_of_polarisation", "angle_of_polarisation", "stokes_frame"]


def degree_of_polarisation(stokes) -> np.ndarray:
    """Degree of polarisation sqrt(Q^2 + U^2 + V^2) / I of Stokes vectors (..., 4), in [0, 1]
    (0 where I = 0)."""
    s = np.asarray(stokes, dtype=np.float64)
    i = s[..., 0]
    p = np.sqrt(s[..., 1] ** 2 + s[..., 2] ** 2 + s[..., 3] ** 2)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(i > 0, p / np.where(i > 0, i, 1.0), 0.0)
    return np.clip(out, 0.0, 1.0)


def angle_of_polarisation(stokes) -> np.ndarray:
    """Angle of linear polarisation [deg] in (-90, 90]: 0.5 atan2(U, Q), measured from the
    parallel axis of :func:`stokes_frame` (the local meridian, towards the zenith) towards the
    perpendicular axis."""
    s = np.asarray(stokes, dtype=np.float64)
    a = 0.5 * np.degrees(np.arctan2(s[..., 2], s[..., 1]))
    return np.where(a <= -90.0, a + 180.0, a)


def stokes_frame(directions) -> tuple[np.ndarray, np.ndarray]:
    """Reference frame of the Stokes vectors for light arriving from ``directions`` (..., 3).

    Returns (e_par, e_perp), unit vectors perpendicular to the ray. e_par lies in the local
    meridian plane (the vertical plane through the direction) and points towards increasing
    elevation, d(direction)/d(elevation) = (-sin e sin a, -sin e cos a, cos e) in
    East-North-Up; e_perp = k x e_par with k = -direction the propagation direction of the
    light (at the zenith, the limit from azimuth 0: e_par = south, (0, -1, 0)). Q > 0 means
    the electric field vibrates preferentially in the meridian plane.
    """
    d = as_directions(directions)
    z = np.array([0.0, 0.0, 1.0])
    a = z - d[..., 2:3] * d
    n = np.linalg.norm(a, axis=-1, keepdims=True)
    fallback = np.broadcast_to(np.array([0.0, -1.0, 0.0]), a.shape)
    a = np.where(n > 1e-12, a / np.where(n > 1e-12, n, 1.0), fallback)
    # a is z projected perpendicular to d: increasing elevation (also for d below the horizon)
    b = np.cross(-d, a)
    return a, b


#: Paths per progress block (direction x wavelength x sample): runs shorter than this go in
#: one block; longer ones in up to PROGRESS_BLOCKS blocks of whole directions.
PROGRESS_PATHS_PER_BLOCK = 20_000_000
PROGRESS_BLOCKS = 200


def _progress_blocks(n: int, nl: int, samples: int) -> np.ndarray:
    """Direction indices where the progress blocks start, and ``n`` at the end."""
    work = n * nl * samples
    k = int(min(n, PROGRESS_BLOCKS, max(1, work // PROGRESS_PATHS_PER_BLOCK)))
    return np.unique(np.linspace(0, n, k + 1).round().astype(np.int64))


@register
class MonteCarlo(SkyModel):
    """Monte Carlo sky: every order of scattering, with standard errors, optionally polarised.

    Parameters
    ----------
    sun : skydome.Sun
        Sun position, any elevation in [-90, 90] deg (below the horizon only light that
        reaches the air above the earth's shadow contributes, by any number of scatterings).
    {atmosphere_parameters}
    samples : int
        Paths per direction per wavelength (default 256); the standard error falls as
        1/sqrt(samples).
    seed : int
        Seed of the random streams (default 0). Every (direction index, wavelength index)
        has its own stream derived from the seed, so results do not depend on the number of
        threads.
    polarised : bool
        Carry Stokes vectors (I, Q, U, V) with scattering matrices (default False).
    max_order : int or None
        Highest scattering order (ground reflections count as orders); None: unbounded,
        terminated by Russian roulette (unbiased).
    next_event : {"vertex", "segment"}
        Next-event estimation towards the sun. "vertex" (default): at every collision.
        "segment" (unpolarised only): the expected value of the next collision's next
        event, integrated along each segment of the path before it is tracked (the segment
        cut at its lowest point and at the earth's shadow, 48 nodes per piece); the paths
        are the same, the estimate unbiased up to that quadrature. In deep twilight, where
        nearly every collision lies in the earth's shadow, it gathers the sunlit air of
        every segment instead of waiting for a collision there (docs/models.md, montecarlo,
        "Deep twilight: the segment estimate"); it costs more per path.

    Notes
    -----
    ``radiance`` excludes the directly visible sun: its disc is in :meth:`sun_radiance`.
    Directions below the horizon see the ground (Lambertian, the atmosphere's albedo, lit by
    the sun and the sky) through the air in front of it. See ``docs/sections/montecarlo.md``.

    References
    ----------
    Woodcock et al. 1965 (delta tracking); Hansen & Travis 1974, Space Sci. Rev. 16, eq. 2.15
    (Rayleigh scattering matrix with depolarisation); Chandrasekhar 1950, Radiative Transfer;
    Kment, Rauter & Zotti, Modelling of Daylight for Computer Graphics, eqs. 3, 10-12.
    """

    name = "montecarlo"
    reference = ("Backward Monte Carlo path tracing: Woodcock et al. 1965 (delta tracking); "
                 "Hansen & Travis 1974, Space Sci. Rev. 16, 527, eq. 2.15 (Rayleigh matrix); "
                 "Kment, Rauter & Zotti, Modelling of Daylight for Computer Graphics, eqs. 3, 10-12")
    native = "spectral"
    own_ground = "sun_and_sky"            # measured: rho E_h / pi at the nadir within 2 %
    summary = "Polarised multiple-scattering Monte Carlo reference with standard errors."
    parameters = (
        *ATMOSPHERE_PARAMETERS,
        Parameter("samples", "", 256, 2, 100_000_000, "paths per direction per wavelength", kind="int"),
        Parameter("seed", "", 0, 0, 2 ** 63 - 1, "seed of the random streams", kind="int"),
        Parameter("polarised", "", False, doc="carry Stokes vectors (I, Q, U, V)", kind="bool"),
        Parameter("max_order", "", None, 1, 100_000, "highest scattering order (None: unbounded)",
                  kind="int"),
        Parameter("next_event", "", "vertex", doc="next-event estimation towards the sun: "
                  "vertex (at each collision), or segment (its expected value integrated along "
                  "each segment, the earth's shadow cut out; unpolarised only; for deep twilight)",
                  kind="choice", choices=("vertex", "segment")),
    )

    def _setup(self, p, given):
        self.atmosphere = p["atmosphere"]
        self.turbidity = p["turbidity"]
        self.observer_altitude_m = p["observer_altitude_m"]
        self.samples = p["samples"]
        self.seed = p["seed"]
        self.polarised = bool(p["polarised"])
        self.max_order = p["max_order"]
        self.next_event = p["next_event"]
        if self.next_event == "segment" and self.polarised:
            raise ValueError("next_event = 'segment' is out of range with polarised = True: "
                             "the segment estimate is unpolarised; use next_event = 'vertex'")
        self._last = None

    # -- engine --------------------------------------------------------------------------
    def _run(self, d, wl):
        """(mean, stderr), each (n, nl, 4), for flat directions d (n, 3)."""
        key = (d.tobytes(), wl.tobytes(), self.samples, self.seed, self.polarised, self.max_order,
               self.next_event)
        if self._last is not None and self._last[0] == key:
            return self._last[1]
        from skydome.models.simulated import _kernels_montecarlo as K
        from skydome.spectra import solar_irradiance
        from skydome.transport._medium import medium_from_properties
        from skydome.transport.optical_depth import DEFAULT_QUADRATURE_SCALE_M, ColumnTable

        props = self.atmosphere.optical_properties(wl, fold=True)
        table = ColumnTable.cached(props, 256, 512, 128, DEFAULT_QUADRATURE_SCALE_M)
        e_sun = solar_irradiance(wl) * self.sun.irradiance_scale
        zen_ref, _ = stokes_frame(d)
        n, nl = d.shape[0], wl.size
        mean = np.zeros((n, nl, 4))
        err = np.zeros((n, nl, 4))
        medium = medium_from_properties(props)
        args = (np.ascontiguousarray(d), np.ascontiguousarray(zen_ref),
                medium.R + self.observer_altitude_m,
                np.ascontiguousarray(self.sun.direction, dtype=np.float64),
                float(np.cos(np.radians(self.sun.angular_radius_deg))), medium,
                np.ascontiguousarray(e_sun, dtype=np.float64), table.table, int(self.samples),
                int(self.seed), self.polarised,
                -1 if self.max_order is None else int(self.max_order), mean, err)
        # Long runs in blocks of directions, reporting progress (skydome._progress) after
        # each; every (direction, wavelength) keeps its own random stream, so the numbers do
        # not depend on the blocks.
        from skydome._progress import report

        blocks = _progress_blocks(n, nl, int(self.samples))
        total = n * nl * int(self.samples)
        for a, b in zip(blocks[:-1], blocks[1:]):
            K.trace_rows(*args, int(a), int(b), self.next_event == "segment")
            report("montecarlo paths", b * nl * int(self.samples), total)
        mean[..., 0] = np.maximum(mean[..., 0], 0.0)
        self._last = (key, (mean, err))
        return mean, err

    def _inputs(self, directions, wavelengths_nm):
        d = as_directions(directions)
        wl = as_wavelengths(wavelengths_nm)
        return d, np.ascontiguousarray(d.reshape(-1, 3)), wl

    # -- public API ----------------------------------------------------------------------
    def radiance_with_error(self, directions, wavelengths_nm):
        """Spectral radiance and its standard error [W m^-2 sr^-1 nm^-1], each
        (..., n_wavelengths). The directly visible sun is excluded (see sun_radiance)."""
        d, flat, wl = self._inputs(directions, wavelengths_nm)
        mean, err = self._run(flat, wl)
        shape = d.shape[:-1] + (wl.size,)
        return mean[..., 0].reshape(shape).copy(), err[..., 0].reshape(shape).copy()

    def radiance(self, directions, wavelengths_nm) -> np.ndarray:
        """Spectral radiance [W m^-2 sr^-1 nm^-1] arriving from ``directions`` (..., 3),
        shape (..., n_wavelengths), without the directly visible sun."""
        return self.radiance_with_error(directions, wavelengths_nm)[0]

    def stokes_with_error(self, directions, wavelengths_nm):
        """Stokes vectors (I, Q, U, V) [W m^-2 sr^-1 nm^-1] and their standard errors, each
        (..., n_wavelengths, 4), in the frame of :func:`stokes_frame` (Q > 0 along the local
        meridian plane). Requires ``polarised=True``."""
        if not self.polarised:
            raise ValueError("polarised = False: build the model with polarised=True for Stokes vectors")
        d, flat, wl = self._inputs(directions, wavelengths_nm)
        mean, err = self._run(flat, wl)
        shape = d.shape[:-1] + (wl.size, 4)
        return mean.reshape(shape).copy(), err.reshape(shape).copy()

    def stokes(self, directions, wavelengths_nm) -> np.ndarray:
        """Stokes vectors (..., n_wavelengths, 4); see :meth:`stokes_with_error`."""
        return self.stokes_with_error(directions, wavelengths_nm)[0]

    def degree_of_polarisation(self, directions, wavelengths_nm) -> np.ndarray:
        """Degree of polarisation in [0, 1], (..., n_wavelengths)."""
        return degree_of_polarisation(self.stokes(directions, wavelengths_nm))

    def angle_of_polarisation(self, directions, wavelengths_nm) -> np.ndarray:
        """Angle of polarisation [deg] from the local meridian, (..., n_wavelengths)."""
        return angle_of_polarisation(self.stokes(directions, wavelengths_nm))

    def sun_radiance(self, wavelengths_nm) -> np.ndarray:
        """Radiance of the sun's disc seen through the atmosphere [W m^-2 sr^-1 nm^-1]:
        E_sun / Omega_sun x T(observer -> top) (column table); 0 when the planet hides the
        sun. Uniform disc (no limb darkening)."""
        from skydome.transport.single import SingleScattering

        wl = as_wavelengths(wavelengths_nm)
        ss = SingleScattering(self.atmosphere, wl, self.observer_altitude_m)
        from skydome.spectra import solar_irradiance

        t = ss.transmittance(self.sun.direction)
        return solar_irradiance(wl) * self.sun.irradiance_scale / self.sun.solid_angle_sr * t


#: The earlier name (class names follow the registry names, without a "Sky" suffix).
MonteCarloSky = MonteCarlo
