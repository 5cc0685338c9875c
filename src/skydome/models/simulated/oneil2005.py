"""``oneil2005``: O'Neil's real-time single scattering (GPU Gems 2, chapter 16).

Nishita et al. (1993) single scattering, reduced by O'Neil (2005) to what a 2004 vertex
shader could afford: a few samples along the view ray, and the optical depth of every light
and view path taken from one fitted function instead of a lookup table,

    depth(P, cos) = exp(-h(P) / H0) * scale(cos)                                   [ONe05] 16.4
    scale(cos)    = scaleDepth * exp(-0.00287 + x (0.459 + x (3.83 + x (-6.80 + x 5.25)))),
    x = 1 - cos,

with h the altitude in units of the atmosphere's thickness (outer - inner radius), H0 =
scaleDepth = 0.25 and outer radius = 1.025 x inner radius. The polynomial was fitted to
that one atmosphere only; :func:`scale_polynomial_error` measures how well it does there and
elsewhere.

The chapter's equations ([ONe05] 16.2), lengths in units of the atmosphere's thickness:

    t(Pa, Pb, lambda) = 4 pi K(lambda) int_Pa^Pb exp(-h / H0) ds                       (out-scattering)
    I_v(lambda) = I_s(lambda) K(lambda) F(theta, g) int_Pa^Pb exp(-h / H0)
                  exp(-t(P, Pc, lambda) - t(P, Pa, lambda)) ds                         (in-scattering)
    F(theta, g) = 3 (1 - g^2) / (2 (2 + g^2)) (1 + cos^2 theta) / (1 + g^2 - 2 g cos theta)^(3/2)

with K = Kr / lambda^4 (lambda in um) for Rayleigh (g = 0) and K = Km for Mie. Both use the
same density scale depth (the chapter's shaders have one ``fScaleDepth``).

Physical units. The in-scattering integral is dimensionless (K per thickness times length in
thickness) and F / (4 pi) is a phase function per steradian, so I_v = I_s x (a number per
steradian): with I_s the spectral solar irradiance [W m^-2 nm^-1] the result is spectral
radiance [W m^-2 sr^-1 nm^-1]. :meth:`ONeil2005.radiance` evaluates the chapter's formulas
at any wavelength (1 / lambda^4 is defined everywhere) with I_s = the ASTM G173 solar
spectrum; :meth:`ONeil2005.shader_rgb` is the chapter's own three-channel result (white
I_s = ESun = 20 at 650, 570 and 475 nm, before its HDR exposure), in its display units.

References
----------
[ONe05] O'Neil, S. 2005. Accurate Atmospheric Scattering. In GPU Gems 2, M. Pharr (ed.),
    Addison-Wesley, chapter 16, 253-268.
[NSTN93] Nishita, T., Sirai, T., Tadamura, K., Nakamae, E. 1993. Display of the Earth
    Taking into Account Atmospheric Scattering. SIGGRAPH 93, 175-182.
[KRZ06] Kment, Rauter & Zotti, Modelling of Daylight for Computer Graphics, sec. 7.8.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from skydome._validate import as_directions, as_wavelengths, check_number
from skydome.models import Parameter, SkyModel, register

__all__ = ["ONeil2005", "ONeil2005Sky", "scale_polynomial", "exact_scale", "scale_polynomial_error",
           "parameters_from_atmosphere", "CHAPTER_WAVELENGTHS_NM"]

# [ONe05] demo (sec. 16.5 shaders' v3InvWavelength): wavelengths of the red, green and blue channels [nm]
CHAPTER_WAVELENGTHS_NM = np.array([650.0, 570.0, 475.0])


def scale_polynomial(cos_angle, scale_depth: float = 0.25) -> np.ndarray:
    """O'Neil's fitted optical-depth function scale(cos) [thickness units].

    scaleDepth exp(-0.00287 + x (0.459 + x (3.83 + x (-6.80 + x 5.25)))), x = 1 - cos
    ([ONe05] 16.4, the shaders' ``scale()``): the column of exp(-h/H0) from the ground
    to the top of the atmosphere along a ray at angle arccos(cos) from the vertical, in
    units of the atmosphere's thickness, for scaleDepth 0.25 and outer/inner radius 1.025.
    """
    x = 1.0 - np.asarray(cos_angle, dtype=np.float64)
    return scale_depth * np.exp(-0.00287 + x * (0.459 + x * (3.83 + x * (-6.80 + x * 5.25))))


@lru_cache(maxsize=8)
def _gauss_legendre(n: int):
    return np.polynomial.legendre.leggauss(n)


def exact_scale(cos_angle, scale_depth: float = 0.25, outer_ratio: float = 1.025,
                height: float = 0.0, samples: int = 512) -> np.ndarray:
    """The quantity the polynomial approximates, by quadrature [thickness units].

    exp(h/H0) int_0^L exp(-(r(s) - R) / H0) ds: the column of the relative density along the
    ray from altitude ``height`` (thickness units) to the top of the atmosphere, divided by
    the density at the start, all lengths in units of the thickness (R = 1 / (outer_ratio
    - 1)). Rays that hit the planet are integrated to the ground. Gauss-Legendre quadrature
    with ``samples`` nodes in the variable u = sqrt(s) (resolves the steep start of grazing
    rays).
    """
    mu = np.asarray(cos_angle, dtype=np.float64)
    R = 1.0 / (outer_ratio - 1.0)
    r0 = R + height
    disc_top = (R + 1.0) ** 2 - r0 * r0 * (1.0 - mu * mu)
    length = -r0 * mu + np.sqrt(np.maximum(disc_top, 0.0))
    disc_gr = R * R - r0 * r0 * (1.0 - mu * mu)
    hits = (mu < 0.0) & (disc_gr >= 0.0)
    length = np.where(hits, -r0 * mu - np.sqrt(np.maximum(disc_gr, 0.0)), length)
    x, w = _gauss_legendre(int(samples))
    u = 0.5 * (x + 1.0)[(None,) * mu.ndim] * np.sqrt(length)[..., None]
    s = u * u
    r = np.sqrt(np.maximum(r0 * r0 + s * s + 2.0 * r0 * s * mu[..., None], 0.0))
    f = np.exp(-(r - r0) / scale_depth) * 2.0 * u          # ds = 2 u du
    return (f * (0.5 * w)).sum(axis=-1) * np.sqrt(length)


def scale_polynomial_error(scale_depth: float = 0.25, outer_ratio: float = 1.025,
                           height: float = 0.0, n: int = 101) -> dict:
    """Relative error of :func:`scale_polynomial` against :func:`exact_scale` for upward
    rays (cos in [0, 1]) from altitude ``height`` (thickness units).

    Returns {"max_abs": max |rel|, "rms": rms rel, "at_cos": cos of the worst node,
    "zenith": rel at cos = 1, "horizon": rel at cos = 0}.
    """
    mu = np.linspace(0.0, 1.0, n)
    rel = scale_polynomial(mu, scale_depth) / exact_scale(mu, scale_depth, outer_ratio, height) - 1.0
    i = int(np.argmax(np.abs(rel)))
    return {"max_abs": float(np.abs(rel[i])), "rms": float(np.sqrt(np.mean(rel ** 2))),
            "at_cos": float(mu[i]), "zenith": float(rel[-1]), "horizon": float(rel[0])}


def parameters_from_atmosphere(atmosphere, reference_nm: float = 550.0) -> dict:
    """Map a :class:`skydome.Atmosphere` onto O'Neil's parameters (for comparisons).

    * outer_ratio = top radius / planet radius; scale_depth = Rayleigh scale height /
      thickness (the chapter has one scale depth for both constituents);
    * kr, km such that the vertical optical depths at ``reference_nm`` are kept:
      4 pi Kr / lambda^4 x scale_depth = tau_R(lambda), 4 pi Km x scale_depth = tau_aerosol
      (aerosol extinction is taken grey, as the chapter's Km is);
    * g = -(aerosol asymmetry): the shaders take cos between the sun and the reversed view
      direction, so the chapter's g = -0.99 is forward scattering.

    The atmosphere must have an exponential "rayleigh" constituent; an "aerosol" one is
    optional; ozone and the ground are ignored (the chapter has neither).
    """
    from skydome.atmosphere.profiles import ExponentialProfile

    ray = atmosphere.constituent("rayleigh")
    if not isinstance(ray.profile, ExponentialProfile):
        raise ValueError("atmosphere: the rayleigh constituent must have an exponential profile")
    thickness = atmosphere.top_altitude_m
    H = ray.profile.kernel_params()[1]
    scale_depth = H / thickness
    lam_um = reference_nm / 1000.0
    tau = atmosphere.vertical_optical_depth([reference_nm])
    kr = float(tau["rayleigh"][0]) * lam_um ** 4 / (4.0 * np.pi * scale_depth)
    km, g = 0.0, -0.76
    if any(c.name == "aerosol" for c in atmosphere.constituents):
        km = float(tau["aerosol"][0]) / (4.0 * np.pi * scale_depth)
        g = -atmosphere.constituent("aerosol").g
    return {"kr": kr, "km": km, "g": g, "scale_depth": scale_depth,
            "outer_ratio": atmosphere.top_radius_m / atmosphere.planet_radius_m}


def _phase(cos_theta, g):
    """[ONe05] 16.2 F(theta, g) (Cornette-Shanks form); averages to 1 over the sphere."""
    g2 = g * g
    c2 = cos_theta * cos_theta
    return 1.5 * ((1.0 - g2) / (2.0 + g2)) * (1.0 + c2) / (1.0 + g2 - 2.0 * g * cos_theta) ** 1.5


@register
class ONeil2005(SkyModel):
    """O'Neil's GPU single scattering (GPU Gems 2, ch. 16) with the chapter's constants.

    Parameters
    ----------
    sun : skydome.Sun
        Sun position; below the horizon the fitted depth function grows without bound for
        the light paths, which darkens the sky smoothly (no explicit earth shadow).
    atmosphere : skydome.Atmosphere, optional
        If given, kr, km, g, scale_depth and outer_ratio are derived from it with
        :func:`parameters_from_atmosphere` (then do not give them too).
    kr : float
        Rayleigh constant Kr, default 0.0025 ([ONe05] demo).
    km : float
        Mie constant Km, default 0.0010 ([ONe05] demo).
    esun : float
        Sun brightness ESun of :meth:`shader_rgb` (display units), default 20.
    g : float
        Mie asymmetry in the chapter's sign convention, default -0.990 (forward scattering).
    scale_depth : float
        Density scale depth as a fraction of the atmosphere's thickness, default 0.25.
    outer_ratio : float
        Outer (atmosphere) radius / inner (planet) radius, default 1.025.
    samples : int
        Sample points along each view ray, default 2 (the chapter's shaders).
    depth_function : {"polynomial", "exact"}
        "polynomial": the chapter's fitted scale(); "exact": the true normalised column
        (:func:`exact_scale`, tabulated), to separate the fit's error from the sampling's.

    Notes
    -----
    Native quantity: spectral. The chapter evaluates its formulas at three wavelengths and
    displays the three numbers as RGB; they are samples of a spectrum, not sRGB values, so
    instead of guessing a conversion we evaluate the same formulas on the requested
    wavelength grid (the base class integrates them against the CIE 1931 functions for
    xyz()). The observer is on the ground (the chapter's SkyFromAtmosphere shader with the
    camera at the inner radius); directions below the horizon return 0 (the view path is
    empty; the ground itself is not modelled).
    """

    name = "oneil2005"
    reference = ("O'Neil, S. 2005. Accurate Atmospheric Scattering. GPU Gems 2, ch. 16; "
                 "Kment, Rauter & Zotti, sec. 7.8")
    native = "spectral"
    viewer_shader = "oneil2005"
    viewer_parameters = ("kr", "km", "g", "scale_depth", "outer_ratio", "samples")
    summary = "O'Neil's real-time single scattering: fitted optical-depth polynomial, 2 samples."
    parameters = (
        Parameter("atmosphere", "", None, doc="derive kr, km, g, scale_depth, outer_ratio from it",
                  kind="object"),
        Parameter("kr", "", 0.0025, 0.0, 1.0, "Rayleigh constant Kr"),
        Parameter("km", "", 0.0010, 0.0, 1.0, "Mie constant Km"),
        Parameter("esun", "", 20.0, 0.0, 1e6, "sun brightness ESun of shader_rgb (display units)"),
        Parameter("g", "", -0.990, -0.999, 0.999, "Mie asymmetry (chapter sign: negative = forward)"),
        Parameter("scale_depth", "", 0.25, 0.001, 1.0, "scale depth / atmosphere thickness"),
        Parameter("outer_ratio", "", 1.025, 1.0001, 2.0, "outer radius / inner radius"),
        Parameter("samples", "", 2, 1, 4096, "sample points per view ray", kind="int"),
        Parameter("depth_function", "", "polynomial", kind="choice", choices=("polynomial", "exact"),
                  doc="optical depth from the fitted polynomial or exactly"),
    )

    _DERIVED = ("kr", "km", "g", "scale_depth", "outer_ratio")

    def _setup(self, p, params):
        from skydome.atmosphere import Atmosphere

        sun = self.sun
        atm = p["atmosphere"]
        if atm is not None:
            if not isinstance(atm, Atmosphere):
                raise TypeError(f"atmosphere must be a skydome.Atmosphere, not {type(atm).__name__}")
            clash = sorted(set(params) & set(self._DERIVED))
            if clash:
                raise ValueError(f"give either atmosphere or {', '.join(clash)}, not both")
            derived = parameters_from_atmosphere(atm)
            for k in self._DERIVED:
                par = next(q for q in self.parameters if q.name == k)
                p[k] = check_number(k, derived[k], par.low, par.high)
        self.sun = sun
        for k in ("atmosphere", "kr", "km", "esun", "g", "scale_depth", "outer_ratio", "samples",
                  "depth_function"):
            setattr(self, k, p[k])
        self._table = None

    # -- the depth function ------------------------------------------------------------------
    def _scale(self, cos_angle):
        if self.depth_function == "polynomial":
            return scale_polynomial(cos_angle, self.scale_depth)       # [ONe05] 16.4
        if self._table is None:
            # exact ground-level columns for upward rays; downward rays from the ground are
            # blocked by the planet (a depth of 1e30: no light)
            mu = np.concatenate([[-1.0, -1e-9], np.linspace(0.0, 1.0, 1001)])
            logs = np.log(exact_scale(np.clip(mu, 0.0, 1.0), self.scale_depth, self.outer_ratio))
            logs[:2] = np.log(1e30)
            self._table = (mu, logs)
        mu, logs = self._table
        c = np.clip(np.asarray(cos_angle, dtype=np.float64), -1.0, 1.0)
        return np.exp(np.interp(c, mu, logs))

    # -- the integral --------------------------------------------------------------------------
    def _integrals(self, d, inv_wl4):
        """Front-colour integrals of [ONe05]'s SkyFromAtmosphere shader for ground-level
        view directions d (n, 3): returns (rayleigh (n, nl), mie (n, nl), cos_theta (n,)),
        where radiance = I_s (Kr/lambda^4 F_R rayleigh + Km F_M mie)."""
        R = 1.0 / (self.outer_ratio - 1.0)            # inner radius in thickness units
        Ro = R + 1.0
        s = self.sun.direction
        mu = d[:, 2]
        up = mu > 0.0
        far = -R * mu + np.sqrt(Ro * Ro - R * R * (1.0 - mu * mu))   # camera at (0, 0, R)
        start_offset = self._scale(mu)                # depth at the camera is exp(0) = 1
        n_s = self.samples
        seg = far / n_s                               # fSampleLength (already in thickness units)
        k_ext = 4.0 * np.pi * (self.kr * inv_wl4 + self.km)            # (nl,) fKr4PI/lambda^4 + fKm4PI
        front = np.zeros((d.shape[0], inv_wl4.size))
        cam = np.array([0.0, 0.0, R])
        for i in range(n_s):
            t = (i + 0.5) * seg
            P = cam + d * t[:, None]
            height = np.linalg.norm(P, axis=1)
            depth = np.exp((R - height) / self.scale_depth)           # fScaleOverScaleDepth (inner - h)
            light_angle = P @ s / height
            camera_angle = np.einsum("ij,ij->i", d, P) / height
            scatter = start_offset + depth * (self._scale(light_angle) - self._scale(camera_angle))
            scatter = np.maximum(scatter, 0.0)
            atten = np.exp(-scatter[:, None] * k_ext)                  # v3Attenuate
            front += atten * (depth * seg)[:, None]
        front[~up] = 0.0
        cos_theta = d @ s
        return front, cos_theta

    def _colour(self, d, wl_nm, e_sun):
        inv_wl4 = (np.asarray(wl_nm, dtype=np.float64) / 1000.0) ** -4.0
        flat = d.reshape(-1, 3)
        front, cos_theta = self._integrals(flat, inv_wl4)
        # the shaders use fCos = dot(sun, -view) with g < 0 for forward scattering
        fr = 0.75 * (1.0 + cos_theta ** 2)                              # F(theta, 0)
        fm = _phase(-cos_theta, self.g)                                 # F(theta, g)
        c0 = front * (inv_wl4 * self.kr)                               # c0 / ESun
        c1 = front * self.km                                           # c1 / ESun
        out = e_sun * (fr[:, None] * c0 + fm[:, None] * c1)
        return np.maximum(out, 0.0).reshape(d.shape[:-1] + (inv_wl4.size,))

    def radiance(self, directions, wavelengths_nm) -> np.ndarray:
        """Spectral radiance [W m^-2 sr^-1 nm^-1] from ``directions`` (..., 3), shape
        (..., n_wavelengths): the chapter's formulas at each wavelength with I_s the solar
        spectral irradiance (ASTM G173 at the sun's distance). 0 below the horizon."""
        from skydome.spectra import solar_irradiance

        d = as_directions(directions)
        wl = as_wavelengths(wavelengths_nm)
        e = solar_irradiance(wl) * self.sun.irradiance_scale
        return self._colour(d, wl, e)

    def shader_rgb(self, directions) -> np.ndarray:
        """The chapter's own result: (R, G, B) = c0 F_R + c1 F_M at 650, 570, 475 nm with a
        white sun of brightness ``esun``, in its display units before the HDR exposure
        1 - exp(-exposure x colour); shape (..., 3)."""
        d = as_directions(directions)
        return self._colour(d, CHAPTER_WAVELENGTHS_NM, self.esun)

    def sun_radiance(self, wavelengths_nm) -> np.ndarray:
        """Radiance of the sun's disc [W m^-2 sr^-1 nm^-1]: E_sun / Omega x exp(-t), with t the
        chapter's out-scattering depth to the top, 4 pi (Kr/lambda^4 + Km) scale(cos z)."""
        from skydome.spectra import solar_irradiance

        wl = as_wavelengths(wavelengths_nm)
        mu = float(self.sun.direction[2])
        if mu < 0.0:
            return np.zeros(wl.shape)
        t = 4.0 * np.pi * (self.kr * (wl / 1000.0) ** -4.0 + self.km) * float(self._scale(mu))
        return solar_irradiance(wl) * self.sun.irradiance_scale / self.sun.solid_angle_sr * np.exp(-t)


#: The earlier name (class names follow the registry names, without a "Sky" suffix).
ONeil2005Sky = ONeil2005
