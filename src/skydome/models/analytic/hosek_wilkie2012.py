"""Hosek & Wilkie (2012): "An Analytic Model for Full Spectral Sky-Dome Radiance", with the
solar radiance function of Hosek & Wilkie (2013).

The sky is an extended Perez form ([HW12] eq. 9) fitted to brute-force path-traced skies,

    L(theta, gamma) = F(theta, gamma) L_M,
    F = (1 + A exp(B / (cos theta + 0.01))) (C + D exp(E gamma) + F cos^2 gamma
        + G chi(H, gamma) + I cos^(1/2) theta),
    chi(g, alpha) = (1 + cos^2 alpha) / (1 + g^2 - 2 g cos alpha)^(3/2),

with theta the view zenith angle and gamma the angle to the sun. The nine coefficients and
the radiance scale L_M are stored per channel (eleven 40 nm bands 320-720 nm, or R, G, B,
or CIE X, Y, Z), ground albedo (0 and 1) and turbidity (1..10) as the six control points of
a quintic Bezier curve in x = (solar elevation / (pi / 2))^(1/3) ([HW12] section 5 and
eq. 11); a model instance interpolates linearly in turbidity and albedo.

The sun ([HW13]) is the direct radiance at the disc centre, a piecewise cubic in solar
elevation per band and turbidity (45 pieces with breakpoints (j / 45)^3 pi / 2), times a
fifth-order limb-darkening polynomial in mu = sqrt(1 - sin^2 g / sin^2 r).

Conventions: East-North-Up frame, azimuth from north towards east; wavelengths in nm;
spectral radiance in W m^-2 sr^-1 nm^-1; luminance in cd m^-2 (683 lm/W times the
authors' Y channel).

Valid range (the fits): turbidity in [1, 10], ground albedo in [0, 1], sun elevation in
[0, 90] deg, wavelengths in [320, 720] nm (320-780 nm accepted; zero above 720 nm, as in
the authors' implementation). Anything else raises ValueError. Directions below the
horizon get zero radiance.

References
----------
.. [HW12] L. Hosek, A. Wilkie, "An Analytic Model for Full Spectral Sky-Dome Radiance",
   ACM Transactions on Graphics 31(4), article 95 (SIGGRAPH 2012). Eq. 9 (the model),
   eq. 11 (the Bezier interpolation in elevation), section 5 (the fit and its parameters).
.. [HW13] L. Hosek, A. Wilkie, "Adding a Solar-Radiance Function to the Hosek-Wilkie
   Skylight Model", IEEE Computer Graphics and Applications 33(3), pp. 44-52 (2013).
.. [HWdata] L. Hosek, A. Wilkie, coefficient data of the reference implementation v1.4a
   (2013), 3-clause BSD licence; shipped as data/hosek_wilkie2012_sky.csv,
   data/hosek_wilkie2013_sun.csv and data/hosek_wilkie2013_limb_darkening.csv.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from skydome._validate import as_directions, as_wavelengths
from skydome.constants import K_M
from skydome.data import load_table
from skydome.models import Parameter, SkyModel, register

__all__ = ["HosekWilkie2012", "BANDS_NM", "WAVELENGTH_RANGE", "bezier_weights",
           "cooked_coefficients", "distribution", "solar_centre_radiance",
           "limb_darkening", "ACCEPTED_RANGE"]

#: Centres of the spectral dataset's bands [nm] ([HW12] section 5: 320-720 nm, 40 nm apart).
BANDS_NM = np.arange(320.0, 721.0, 40.0)
#: Wavelength range of the spectral dataset [nm].
WAVELENGTH_RANGE = (320.0, 720.0)
#: Wavelengths accepted by the model [nm]: the dataset's range plus 720-780 nm, where the
#: radiance is zero as in the authors' implementation and Mitsuba's (so that the model runs
#: in skydome's 380-780 nm colour pipeline; the CIE 1931 x-bar above 720 nm holds 0.2 % of
#: its integral, y-bar 0.01 %).
ACCEPTED_RANGE = (320.0, 780.0)
_CHANNEL_CODES = {"R": 1, "G": 2, "B": 3, "X": 4, "Y": 5, "Z": 6}
_N_PIECES = 45                                       # [HW13] pieces of the solar function


# --------------------------------------------------------------------------------------
# Tables
# --------------------------------------------------------------------------------------

@lru_cache(maxsize=1)
def _sky_table() -> dict[float, tuple[np.ndarray, np.ndarray]]:
    """{channel: (coefficients (2, 10, 6, 9), L_M (2, 10, 6))} keyed by wavelength [nm] or
    the tristimulus codes 1..6 (R, G, B, X, Y, Z)."""
    _, a = load_table("hosek_wilkie2012_sky")
    out = {}
    for ch in np.unique(a[:, 0]):
        rows = a[a[:, 0] == ch]
        rows = rows[np.lexsort((rows[:, 3], rows[:, 2], rows[:, 1]))]
        out[float(ch)] = (rows[:, 4:13].reshape(2, 10, 6, 9).copy(),
                          rows[:, 13].reshape(2, 10, 6).copy())
    return out


@lru_cache(maxsize=1)
def _sun_table() -> np.ndarray:
    """Solar polynomial coefficients (11 bands, 10 turbidities, 45 pieces, 4: c0..c3)."""
    _, a = load_table("hosek_wilkie2013_sun")
    a = a[np.lexsort((a[:, 2], a[:, 1], a[:, 0]))]
    return a[:, 3:7].reshape(BANDS_NM.size, 10, _N_PIECES, 4).copy()


@lru_cache(maxsize=1)
def _limb_table() -> np.ndarray:
    """Limb-darkening coefficients a0..a5 per band, (11, 6)."""
    _, a = load_table("hosek_wilkie2013_limb_darkening")
    return a[np.argsort(a[:, 0]), 1:7].copy()


# --------------------------------------------------------------------------------------
# Interpolation of the datasets
# --------------------------------------------------------------------------------------

def bezier_weights(elevation_rad: float) -> np.ndarray:
    """Weights of the six control points: the quintic Bernstein polynomials
    C(5, k) (1 - x)^(5 - k) x^k at x = (elevation / (pi / 2))^(1/3) ([HW12] eq. 11)."""
    x = (max(elevation_rad, 0.0) / (0.5 * np.pi)) ** (1.0 / 3.0)
    binom = np.array([1.0, 5.0, 10.0, 10.0, 5.0, 1.0])
    k = np.arange(6)
    return binom * (1.0 - x) ** (5 - k) * x ** k


def _turbidity_weights(turbidity: float) -> tuple[int, float]:
    """Index of the lower of the two tabulated turbidities 1..10 (0-based) and the weight
    of the upper one (linear interpolation)."""
    lo = min(int(np.floor(turbidity)), 9) - 1
    return lo, turbidity - (lo + 1)


def cooked_coefficients(channel: float, turbidity: float, albedo: float,
                        elevation_rad: float) -> tuple[np.ndarray, float]:
    """The nine coefficients A..I and L_M of one channel at (T, albedo, solar elevation):
    quintic Bezier in elevation ([HW12] eq. 11), then linear in turbidity and albedo."""
    cfg, rad = _sky_table()[float(channel)]
    b = bezier_weights(elevation_rad)
    lo, wt = _turbidity_weights(turbidity)
    coef = np.zeros(9)
    lm = 0.0
    for ia, wa in ((0, 1.0 - albedo), (1, albedo)):
        for it, w in ((lo, 1.0 - wt), (lo + 1, wt)):
            if w * wa == 0.0:
                continue
            coef += wa * w * (b @ cfg[ia, it])
            lm += wa * w * float(b @ rad[ia, it])
    return coef, lm


def distribution(cos_theta, cos_gamma, coef) -> np.ndarray:
    """F(theta, gamma) of [HW12] eq. 9 for coefficients A..I (numpy reference form)."""
    A, B, C, D, E, F, G, H, I = coef
    cos_theta = np.asarray(cos_theta, dtype=np.float64)
    cos_gamma = np.clip(cos_gamma, -1.0, 1.0)
    gamma = np.arccos(cos_gamma)
    chi = (1.0 + cos_gamma ** 2) / (1.0 + H * H - 2.0 * H * cos_gamma) ** 1.5
    return ((1.0 + A * np.exp(B / (cos_theta + 0.01)))
            * (C + D * np.exp(E * gamma) + F * cos_gamma ** 2 + G * chi
               + I * np.sqrt(np.maximum(cos_theta, 0.0))))


def _band_weights(w: np.ndarray) -> np.ndarray:
    """(n, 11) weights of the bands for linear interpolation in wavelength; zero rows above
    the last band (720 nm)."""
    pos = (w - BANDS_NM[0]) / 40.0
    lo = np.clip(np.floor(pos).astype(int), 0, BANDS_NM.size - 2)
    f = pos - lo
    out = np.zeros((w.size, BANDS_NM.size))
    out[np.arange(w.size), lo] = 1.0 - f
    out[np.arange(w.size), lo + 1] = f
    out[w > WAVELENGTH_RANGE[1]] = 0.0
    return out


def solar_centre_radiance(turbidity: float, elevation_rad) -> np.ndarray:
    """Direct radiance at the centre of the solar disc per band [W m^-2 sr^-1 nm^-1],
    (..., 11) for elevations (...,) [rad] ([HW13]: piecewise cubic in elevation, linear in
    turbidity)."""
    h = np.clip(np.asarray(elevation_rad, dtype=np.float64), 0.0, 0.5 * np.pi)
    j = np.minimum((np.cbrt(h / (0.5 * np.pi)) * _N_PIECES).astype(int), _N_PIECES - 1)
    x = h - (j / _N_PIECES) ** 3 * 0.5 * np.pi          # distance from the piece's start
    powers = x[..., None] ** np.arange(4)               # (..., 4)
    lo, wt = _turbidity_weights(turbidity)
    c = _sun_table()                                    # (11, 10, 45, 4)
    out = (1.0 - wt) * np.einsum("b...k,...k->...b", c[:, lo, j], powers)
    if wt > 0.0:
        out = out + wt * np.einsum("b...k,...k->...b", c[:, lo + 1, j], powers)
    return np.maximum(out, 0.0)


def limb_darkening(mu) -> np.ndarray:
    """Limb-darkening factor per band, (..., 11), at mu = cos of the angle between the
    solar surface normal and the ray ([HW13])."""
    mu = np.asarray(mu, dtype=np.float64)[..., None, None]
    return np.sum(_limb_table() * mu ** np.arange(6), axis=-1)


# --------------------------------------------------------------------------------------
# The model
# --------------------------------------------------------------------------------------

@register
class HosekWilkie2012(SkyModel):
    """Hosek & Wilkie (2012) analytic sky with the (2013) solar radiance function.

    Parameters
    ----------
    sun : skydome.Sun
        Sun position; elevation in [0, 90] deg. Its angular radius sets the disc size.
    turbidity : float
        Turbidity T [-], in [1, 10].
    albedo : float
        Ground albedo [-], in [0, 1] (grey, the same at every wavelength).

    Notes
    -----
    ``radiance`` uses the spectral dataset and interpolates linearly between its 40 nm
    bands, as the authors' implementation does; ``xyz`` uses the authors' CIE XYZ dataset
    (Y times 683 lm/W is luminance) and ``rgb`` their linear RGB dataset, each fitted
    separately, so they differ slightly from integrating ``radiance`` (which stops at
    720 nm). Negative values of the fit are clamped to zero.

    ``solar_radiance(directions, wavelengths_nm)`` is the disc itself, per ray (the
    solar function at the ray's elevation times limb darkening, as the authors' code).
    Deviation (docs/models.md): ``sun_radiance`` returns the disc average, the radiance at
    the sun's centre elevation times the mean limb darkening 2 sum_i a_i / (i + 2) (exact
    for the polynomial), so that times the disc's solid angle it is the direct irradiance;
    it ignores the change of the solar function across the disc's height (second order
    in the disc radius, under 0.1 % above 5 deg elevation).
    """

    name = "hosek_wilkie2012"
    reference = ("L. Hosek, A. Wilkie, 'An Analytic Model for Full Spectral Sky-Dome "
                 "Radiance', ACM TOG 31(4), 95 (2012); solar radiance: IEEE CG&A 33(3) (2013)")
    native = "spectral"
    summary = "extended Perez fit to path-traced skies, spectral / RGB / XYZ, with limb-darkened sun"
    parameters = (
        Parameter("turbidity", "", 3.0, 1.0, 10.0, "atmospheric turbidity T (Linke-like)"),
        Parameter("albedo", "", 0.2, 0.0, 1.0, "ground albedo (grey)"),
    )

    sun_elevation_range_deg = (0.0, 90.0)   # the fit has no twilight

    def _setup(self, vals, given):
        super()._setup(vals, given)
        self._elev = np.radians(self.sun.elevation_deg)
        self._cooked: dict[str, tuple[np.ndarray, np.ndarray]] = {}

    def _channels(self, which: str) -> tuple[np.ndarray, np.ndarray]:
        """Cooked (C, 9) coefficients and (C,) L_M of the spectral bands, 'rgb' or 'xyz'."""
        if which not in self._cooked:
            keys = {"spectral": BANDS_NM, "rgb": [1, 2, 3], "xyz": [4, 5, 6]}[which]
            cooked = [cooked_coefficients(k, self.turbidity, self.albedo, self._elev)
                      for k in keys]
            self._cooked[which] = (np.ascontiguousarray([c for c, _ in cooked]),
                                   np.array([m for _, m in cooked]))
        return self._cooked[which]

    def _eval(self, directions, which: str) -> np.ndarray:
        # [HW12] eq. 9 per channel in one parallel numba kernel; _eval_reference is the numpy
        # form of the same formula.
        from skydome.models.analytic import _kernels_analytic as K

        flat, lead = K.flat_directions(directions)
        cfg, lm = self._channels(which)
        s = np.asarray(self.sun.direction, dtype=np.float64)
        out = K.hosek_wilkie(flat, s, cfg, lm)
        return out.reshape(lead + (cfg.shape[0],))

    def _eval_reference(self, directions, which: str) -> np.ndarray:
        """numpy reference implementation of :meth:`_eval`."""
        d = as_directions(directions)
        cfg, lm = self._channels(which)
        cos_t = d[..., 2]
        cos_g = d @ self.sun.direction
        out = np.stack([distribution(cos_t, cos_g, c) * m for c, m in zip(cfg, lm)], axis=-1)
        return np.where(cos_t[..., None] < 0.0, 0.0, np.maximum(out, 0.0))

    def radiance(self, directions, wavelengths_nm) -> np.ndarray:
        """Spectral sky radiance [W m^-2 sr^-1 nm^-1], shape (..., n); wavelengths in
        [320, 780] nm, linear between the dataset's bands (320-720 nm), zero above 720 nm
        and below the horizon."""
        w = as_wavelengths(wavelengths_nm, *ACCEPTED_RANGE)
        return self._eval(directions, "spectral") @ _band_weights(w).T

    def _spectral_basis(self, wavelengths_nm):
        """(sample, B): ``radiance(d, wavelengths_nm) == sample(d) @ B`` with ``sample(d)``
        the (n, 11) band radiances and B the (11, n_wl) interpolation weights, so that a
        renderer can fold B into its spectrum -> XYZ weights (skydome.imaging.render)."""
        w = as_wavelengths(wavelengths_nm, *ACCEPTED_RANGE)
        return (lambda d: self._eval(d, "spectral")), _band_weights(w).T

    def xyz(self, directions) -> np.ndarray:
        """CIE 1931 XYZ of the sky from the authors' XYZ dataset, Y in cd m^-2, (..., 3)."""
        return K_M * self._eval(directions, "xyz")

    def rgb(self, directions) -> np.ndarray:
        """Linear RGB (Rec. 709 primaries) of the sky from the authors' RGB dataset, in the
        same photometric scale as :meth:`xyz` (683 lm/W), shape (..., 3)."""
        return K_M * self._eval(directions, "rgb")

    # -- the sun ([HW13]) --------------------------------------------------------------------
    def _sun_bands(self) -> np.ndarray:
        return solar_centre_radiance(self.turbidity, self._elev)

    def sun_radiance(self, wavelengths_nm) -> np.ndarray:
        """Disc-averaged spectral radiance of the sun at the ground [W m^-2 sr^-1 nm^-1],
        shape (n,), wavelengths in [320, 780] nm, zero above 720 nm (centre radiance times the mean limb
        darkening; see Notes of the class)."""
        w = as_wavelengths(wavelengths_nm, *ACCEPTED_RANGE)
        a = _limb_table()
        mean_dark = 2.0 * np.sum(a / (np.arange(6) + 2.0), axis=-1)      # 2 int D(mu) mu dmu
        return _band_weights(w) @ (self._sun_bands() * mean_dark)

    def solar_radiance(self, directions, wavelengths_nm) -> np.ndarray:
        """Radiance of the limb-darkened solar disc in each direction [W m^-2 sr^-1 nm^-1],
        (..., n): zero outside the disc. As in the authors' implementation the solar
        function is evaluated at each ray's own elevation ([HW13])."""
        d = as_directions(directions)
        w = as_wavelengths(wavelengths_nm, *ACCEPTED_RANGE)
        cos_g = np.clip(d @ self.sun.direction, -1.0, 1.0)
        sin2_g = 1.0 - cos_g * cos_g
        sin_r = np.sin(np.radians(self.sun.angular_radius_deg))
        inside = (cos_g > 0.0) & (sin2_g < sin_r * sin_r) & (d[..., 2] >= 0.0)
        mu = np.sqrt(np.clip(1.0 - sin2_g / (sin_r * sin_r), 0.0, 1.0))
        elev = np.arcsin(np.clip(d[..., 2], 0.0, 1.0))
        bw = _band_weights(w).T                                  # (11, n)
        # [HW13] as the authors' code: radiance and limb darkening each linear in wavelength
        value = (solar_centre_radiance(self.turbidity, elev) @ bw) * (limb_darkening(mu) @ bw)
        return np.maximum(np.where(inside[..., None], value, 0.0), 0.0)
