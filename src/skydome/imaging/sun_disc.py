"""The sun in an image: an energy-true, limb-darkened disc, or a separate light.

A model gives the sun's disc as one mean radiance ``L_sun`` (``sky.sun_radiance(wl)``,
W m^-2 sr^-1 nm^-1), whose product with the disc's solid angle is the model's direct
normal irradiance ``E_n = L_sun Omega_sun``. :func:`draw_sun_disc` adds the disc to the
sky pixels so that, in every projection and at every image size,

    sum over pixels of (L_pixel - L_sky) Omega_pixel = E_n x (visible part of the disc),

to round-off, and distributes the light over the pixels the disc covers by the fraction
of the disc's (limb-darkened) flux that falls into each of them:

* The disc is sampled in its own frame (angle theta from the sun's centre, position angle
  psi) on rings of equal width whose exact solid angles ``2 pi (cos theta_j -
  cos theta_j+1)`` sum to ``Omega_sun = 2 pi (1 - cos r)``; the ring width is at most a
  quarter of the smallest pixel side near the sun, so a pixel the disc touches gets
  many samples and a sun smaller than a pixel puts all its flux into the one or few
  pixels it overlaps.
* Each ring carries its exact mean of the limb-darkening law ([Nec05], normalised to a
  disc mean of 1 per wavelength), so the samples' weights sum to ``Omega_sun`` at every
  wavelength.
* A sample adds ``L_sun w / Omega_pixel`` to the pixel it falls into; samples below the
  horizon (the ground hides them), outside the image or in a masked pixel add nothing.

The sun is added to the sky, not painted over it: looking at the sun one receives the
transmitted beam and the light scattered into the same line of sight, and the models give
the two separately.

:class:`SunLight` is the alternative for renderers that take the sun as a light:
direction, angular radius and spectral normal irradiance, written as JSON.

References
----------
.. [Nec05] H. Neckel, "Analytical reference functions F(lambda) for the Sun's limb
   darkening and its absolute continuum intensities (lambda 300 to 1100 nm)", Solar
   Physics 229, 13-33, 2005 (the polynomial I(mu)/I(1) = sum_k A_k(lambda) mu^k, k = 0..5,
   with A_k = a_k0 + a_k1/lambda + a_k5/lambda^5, lambda in micrometres, and the
   coefficients of its three wavelength ranges).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["limb_darkening", "limb_darkening_mean", "SunLight", "sun_light",
           "sun_disc_radiance", "draw_sun_disc", "XYZ_CHANNEL_WAVELENGTHS_NM"]

#: Wavelengths [nm] whose limb darkening stands for the X, Y and Z channels of XYZ images
#: (near the peaks of x-bar (long lobe), y-bar and z-bar of the CIE 1931 observer).
XYZ_CHANNEL_WAVELENGTHS_NM = (600.0, 555.0, 450.0)

# [Nec05] coefficients (a00, a01, a20, a30, a40, a50, a25, a35, a45, a55) of the ranges
# 300-372.98 nm, 385-422.57 nm and 422.57-1100 nm; a10, a11 and a15 follow from
# I(1) = 1: a10 = 1 - (a00 + a20 + ... + a50), a11 = -a01, a15 = -(a25 + ... + a55).
# a55 of the third range is taken as -0.003347: with that sign the disc means agree with
# Neckel & Labs 1994 Table 1 (F/I(0)) to 0.3 % at 440-1050 nm, with +0.003347 (as some
# transcriptions print it) they fall 20 % short at 444 nm (docs/models.md).
_NECKEL_RANGES_NM = ((300.0, 372.98), (385.0, 422.57), (422.57, 1100.0))
_NECKEL_COEFFS = (
    (0.35601, -0.085217, -0.67237, 0.18696, 0.00038, 0.01373, 0.003589, -0.002415, 0.000897, -0.000200),
    (0.09900, 0.010643, -2.80511, 3.32780, -2.17878, 0.58825, 0.024873, -0.029317, 0.018273, -0.004663),
    (0.75267, -0.265577, -1.89287, 2.42234, -1.71150, 0.49062, 0.012582, -0.017117, 0.011977, -0.003347),
)


def _neckel_range(lam_um: np.ndarray, c) -> np.ndarray:
    """A_0..A_5 (..., 6) of one [Nec05] range at wavelengths lam_um [um]."""
    a00, a01, a20, a30, a40, a50, a25, a35, a45, a55 = c
    l1, l5 = 1.0 / lam_um, lam_um ** -5.0
    a10 = 1.0 - (a00 + a20 + a30 + a40 + a50)
    a11, a15 = -a01, -(a25 + a35 + a45 + a55)
    return np.stack([a00 + a01 * l1, a10 + a11 * l1 + a15 * l5, a20 + a25 * l5,
                     a30 + a35 * l5, a40 + a45 * l5, a50 + a55 * l5], axis=-1)


def _neckel_coefficients(wavelengths_nm) -> np.ndarray:
    """Polynomial coefficients A_0..A_5 of I(mu)/I(1) [Nec05], shape (n, 6).

    Outside 300-1100 nm the edge wavelength's law is used; in the gap 372.98-385 nm that
    [Nec05] leaves between its first two ranges, the coefficients are interpolated
    linearly between the two ranges' edge values (docs/models.md)."""
    w = np.clip(np.atleast_1d(np.asarray(wavelengths_nm, dtype=np.float64)), 300.0, 1100.0)
    out = np.empty(w.shape + (6,))
    (lo1, hi1), (lo2, hi2), (lo3, _) = _NECKEL_RANGES_NM
    r1, r2, r3 = w < hi1, (w >= lo2) & (w < hi2), w >= lo3
    gap = (w >= hi1) & (w < lo2)
    out[r1] = _neckel_range(w[r1] / 1e3, _NECKEL_COEFFS[0])
    out[r2] = _neckel_range(w[r2] / 1e3, _NECKEL_COEFFS[1])
    out[r3] = _neckel_range(w[r3] / 1e3, _NECKEL_COEFFS[2])
    if np.any(gap):
        t = ((w[gap] - hi1) / (lo2 - hi1))[:, None]
        a = _neckel_range(np.array([hi1 / 1e3]), _NECKEL_COEFFS[0])
        b = _neckel_range(np.array([lo2 / 1e3]), _NECKEL_COEFFS[1])
        out[gap] = (1.0 - t) * a + t * b
    return out


def limb_darkening(mu, wavelengths_nm) -> np.ndarray:
    """Centre-to-limb intensity ratio I(mu)/I(1) of the sun [Nec05], shape
    mu.shape + (n_wavelengths,); mu = cos of the heliocentric angle, in [0, 1]."""
    A = _neckel_coefficients(wavelengths_nm)
    mu = np.clip(np.asarray(mu, dtype=np.float64), 0.0, 1.0)[..., None]
    return sum(A[:, k] * mu ** k for k in range(6))


def limb_darkening_mean(wavelengths_nm) -> np.ndarray:
    """Disc-averaged I/I(1) [Nec05]: int_0^1 I(mu) 2 mu dmu = 2 sum_k A_k / (k + 2),
    shape (n_wavelengths,). The disc's mean radiance over its centre's."""
    A = _neckel_coefficients(wavelengths_nm)
    return 2.0 * sum(A[:, k] / (k + 2.0) for k in range(6))


def _ring_mean_profile(rho0: np.ndarray, rho1: np.ndarray, wavelengths_nm) -> np.ndarray:
    """Exact mean of I(mu)/I_mean over the annulus rho0..rho1 of the (flat) disc, rho the
    distance from the centre in disc radii, mu = sqrt(1 - rho^2): since 2 rho drho =
    -2 mu dmu, int I 2 rho drho = sum_k A_k 2 (mu0^(k+2) - mu1^(k+2)) / (k + 2)."""
    A = _neckel_coefficients(wavelengths_nm)
    mu0 = np.sqrt(np.clip(1.0 - rho0 * rho0, 0.0, 1.0))[:, None]
    mu1 = np.sqrt(np.clip(1.0 - rho1 * rho1, 0.0, 1.0))[:, None]
    num = sum(A[:, k] * 2.0 * (mu0 ** (k + 2) - mu1 ** (k + 2)) / (k + 2.0) for k in range(6))
    area = (rho1 * rho1 - rho0 * rho0)[:, None]
    return num / area / limb_darkening_mean(wavelengths_nm)


# --------------------------------------------------------------------------------------
# The sun's radiance, whichever quantity the model gives
# --------------------------------------------------------------------------------------

def sun_disc_radiance(sky, wavelengths_nm=None) -> np.ndarray | None:
    """Mean radiance of the sun's disc: spectral [W m^-2 sr^-1 nm^-1] at
    ``wavelengths_nm``, or XYZ (Y in cd m^-2) when ``wavelengths_nm`` is None; None if the
    model has no sun.

    Models with ``sun_radiance(wl)`` give it directly. Luminance-only models that give
    their disc's mean luminance (``sun_luminance()`` [cd m^-2], e.g. ``perez1993``: the
    direct normal illuminance over Omega_sun) get a disc of that luminance with the D65
    chromaticity that :meth:`SkyModel.xyz` gives their sky.
    """
    sun = getattr(sky, "sun", None)
    if sun is None:
        return None
    fn = getattr(sky, "sun_radiance", None)
    L = None
    if callable(fn) and getattr(sky, "native", "spectral") != "luminance":
        if wavelengths_nm is not None:
            L = fn(wavelengths_nm)
            if L is not None:
                L = np.asarray(L, dtype=np.float64).reshape(-1)
        else:
            from skydome.spectra import default_wavelengths, spectrum_to_xyz

            w = default_wavelengths()
            Ls = fn(w)
            if Ls is not None:
                L = spectrum_to_xyz(np.asarray(Ls, dtype=np.float64).reshape(-1), w)
    lum = getattr(sky, "sun_luminance", None)
    Y = lum() if (L is None and wavelengths_nm is None and callable(lum)) else None
    if Y is not None:   # None: a luminance-only model without a sun (CIE skies with no DNI)
        Y = float(Y)
        x, y = 0.31271, 0.32902  # CIE D65, as SkyModel.xyz for luminance-only models
        L = np.array([Y * x / y, Y, Y * (1.0 - x - y) / y])
    if L is None:
        return None
    if not np.all(np.isfinite(L)) or np.any(L < 0.0):
        raise ValueError(f"sun radiance of model {getattr(sky, 'name', sky)!r} has "
                         "non-finite or negative values")
    # Models whose sun_radiance is the disc's flux over Omega_sun (the mean radiance x the
    # fraction of the disc above their own horizon: precomputed, fitted) say so through
    # sun_visible_fraction(); the disc's pixels carry the visible part's radiance, and
    # draw_sun_disc / sun_light take the fraction above the horizon themselves.
    vis_fn = getattr(sky, "sun_visible_fraction", None)
    if callable(vis_fn):
        vis = float(vis_fn())
        L = L / vis if vis > 0.0 else np.zeros_like(L)
    return L


# --------------------------------------------------------------------------------------
# Drawing the disc
# --------------------------------------------------------------------------------------

def _tangent_frame(s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    a = np.array([0.0, 0.0, 1.0]) if abs(s[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    e1 = np.cross(a, s)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(s, e1)


def _pixel_scale(projection, s: np.ndarray, r: float) -> float:
    """Smallest angular pixel side [rad] near the disc (probed at its centre and rim)."""
    e1, e2 = _tangent_frame(s)
    psi = np.linspace(0.0, 2.0 * np.pi, 16, endpoint=False)
    probes = np.concatenate([s[None], np.cos(r) * s + np.sin(r) * (
        np.cos(psi)[:, None] * e1 + np.sin(psi)[:, None] * e2)])
    row, col = projection.pixel_from_direction(probes)
    ok = np.isfinite(row) & np.isfinite(col)
    if not np.any(ok):
        return np.inf
    row, col = row[ok], col[ok]
    best = np.inf
    for dr, dc in ((0.5, 0.0), (0.0, 0.5)):
        a = projection.direction_from_pixel(row - dr, col - dc)
        b = projection.direction_from_pixel(row + dr, col + dc)
        ang = np.arccos(np.clip(np.sum(a * b, axis=-1), -1.0, 1.0))
        ang = ang[np.isfinite(ang) & (ang > 0.0)]
        if ang.size:
            best = min(best, float(ang.min()))
    return best


def _disc_samples(s: np.ndarray, r: float, n_rings: int, channel_wl) -> tuple[np.ndarray, np.ndarray]:
    """Directions (n, 3) and weights (n, C) [sr] of the limb-darkened disc: the weights
    of each ring sum to its exact solid angle times its mean normalised intensity, so all
    weights sum to Omega_sun per channel."""
    e1, e2 = _tangent_frame(s)
    edges = r * np.arange(n_rings + 1) / n_rings                  # ring edges theta_j [rad]
    omega = 2.0 * np.pi * (np.cos(edges[:-1]) - np.cos(edges[1:]))  # exact ring solid angles
    rho = np.sin(edges) / np.sin(r)                                # position on the disc [radii]
    prof = _ring_mean_profile(rho[:-1], rho[1:], channel_wl)       # (n_rings, C)
    # the flat-disc ring areas differ from the spherical ones by O(r^2): renormalise so
    # that the weights sum to Omega_sun exactly
    prof = prof * (omega.sum() / (omega @ prof))
    golden = np.pi * (3.0 - np.sqrt(5.0))
    dirs, wts = [], []
    for j in range(n_rings):
        n_psi = _ring_count(j)
        theta = np.arccos(0.5 * (np.cos(edges[j]) + np.cos(edges[j + 1])))  # equal-area middle
        psi = golden * j + 2.0 * np.pi * np.arange(n_psi) / n_psi
        d = np.cos(theta) * s + np.sin(theta) * (np.cos(psi)[:, None] * e1 + np.sin(psi)[:, None] * e2)
        dirs.append(d)
        wts.append(np.repeat((omega[j] / n_psi * prof[j])[None], n_psi, axis=0))
    return np.concatenate(dirs), np.concatenate(wts)


def _geometric_weights(s: np.ndarray, r: float, n_rings: int) -> np.ndarray:
    """Solid angle [sr] of each sample of :func:`_disc_samples` (no limb darkening)."""
    edges = r * np.arange(n_rings + 1) / n_rings
    omega = 2.0 * np.pi * (np.cos(edges[:-1]) - np.cos(edges[1:]))
    return np.concatenate([np.full(_ring_count(j), omega[j] / _ring_count(j)) for j in range(n_rings)])


def _ring_count(j: int) -> int:
    """Samples on ring j of the disc: about one per ring width along its circumference."""
    return max(1 if j == 0 else 6, int(np.ceil(2.0 * np.pi * (j + 0.5))))


def draw_sun_disc(data: np.ndarray, projection, mask: np.ndarray, sun, L_sun,
                  channel_wavelengths_nm, *, limb_darkening: bool = True,
                  max_rings: int = 1024) -> float:
    """Draw the sun's disc into ``data`` (H, W, C) in place (module docstring).

    Parameters
    ----------
    data : numpy.ndarray
        Pixel radiances (H, W, C), modified in place.
    projection : Projection
        The image's projection (``pixel_from_direction``, ``solid_angles``).
    mask : numpy.ndarray
        (H, W) bool, True where the pixel shows the sky.
    sun : Sun
        Direction and angular radius of the disc.
    L_sun : array_like
        Mean radiance of the disc per channel, shape (C,).
    channel_wavelengths_nm : array_like
        Wavelength [nm] of each channel's limb-darkening law, shape (C,).
    limb_darkening : bool
        Apply [Nec05]'s centre-to-limb law (default); False: a uniform disc.
    max_rings : int
        Upper bound on the rings that sample the disc (memory and time bound).

    Returns
    -------
    float
        The fraction of the disc's solid angle drawn (above the horizon, inside the image).

    Notes
    -----
    A pixel of solid angle Omega_p that the samples cover with solid angle
    Omega_c = sum w_geom and limb-weighted solid angle sum w (per channel) becomes
    ``L_p (1 - min(Omega_c / Omega_p, 1)) + L_sun sum w / Omega_p``: the sun replaces the
    sky it covers, and the image gains exactly ``(L_sun - L_sky) Omega_sun`` (to the
    sampling of the sky it hides) for a fully visible disc.
    """
    L_sun = np.asarray(L_sun, dtype=np.float64).reshape(-1)
    s = np.asarray(sun.direction, dtype=np.float64)
    r = float(np.radians(sun.angular_radius_deg))
    p = _pixel_scale(projection, s, r)
    # ring width <= 1/8 of the smallest pixel side: >= ~50 samples in a covered pixel
    n_rings = int(min(max_rings, max(16, np.ceil(8.0 * r / p)))) if np.isfinite(p) else 16
    wl = np.asarray(channel_wavelengths_nm, dtype=np.float64).reshape(-1)
    dirs, w = _disc_samples(s, r, n_rings, wl)
    geom = _geometric_weights(s, r, n_rings)
    if not limb_darkening:
        w = np.repeat(geom[:, None], w.shape[1], axis=1)
    H, W = projection.shape
    row, col = projection.pixel_from_direction(dirs)
    ok = np.isfinite(row) & np.isfinite(col) & (dirs[:, 2] >= 0.0)
    i = np.clip(np.floor(np.where(ok, row, 0.0)).astype(np.int64), 0, H - 1)
    j = np.clip(np.floor(np.where(ok, col, 0.0)).astype(np.int64), 0, W - 1)
    ok &= mask[i, j]
    if not np.any(ok):
        return 0.0
    geom = geom[ok]
    cells, inv = np.unique(i[ok] * W + j[ok], return_inverse=True)
    acc = np.zeros((cells.size, L_sun.size))
    np.add.at(acc, inv, w[ok])
    cov = np.bincount(inv, weights=geom, minlength=cells.size)
    omega_pix = _solid_angles_at(projection, cells)
    good = omega_pix > 0.0
    cells, acc, cov, omega_pix = cells[good], acc[good], cov[good], omega_pix[good]
    view = data.reshape(-1, data.shape[-1])
    keep = 1.0 - np.minimum(cov / omega_pix, 1.0)
    view[cells] = view[cells] * keep[:, None] + acc * L_sun / omega_pix[:, None]
    return float(cov.sum() / (2.0 * np.pi * (1.0 - np.cos(r))))


def _solid_angles_at(projection, cells) -> np.ndarray:
    """Solid angles [sr] of the pixels ``cells`` (flat indices): those pixels' alone where
    the projection can (the disc covers a few of a picture's pixels), else the whole
    image's."""
    at = getattr(projection, "solid_angles_at", None)
    if callable(at):
        return np.asarray(at(cells), dtype=np.float64)
    return projection.solid_angles().reshape(-1)[cells]


# --------------------------------------------------------------------------------------
# The sun as a separate light
# --------------------------------------------------------------------------------------

@dataclass(frozen=True)
class SunLight:
    """The sun as a light for renderers that take it apart from the sky image.

    Attributes
    ----------
    direction : tuple of float
        Unit vector towards the sun, East-North-Up (x east, y north, z up).
    angular_radius_deg : float
        Apparent radius of the disc [deg].
    wavelengths_nm : tuple of float or None
        Wavelengths [nm] of ``irradiance``; None when it is XYZ.
    irradiance : tuple of float
        Normal irradiance of the visible part of the disc: spectral [W m^-2 nm^-1] at
        ``wavelengths_nm``, or XYZ with Y the normal illuminance [lx].
    visible_fraction : float
        Fraction of the disc's flux above the horizon (already applied to ``irradiance``).
    limb_darkening : str
        The law of the disc's radiance profile (for renderers that draw the disc).
    """

    direction: tuple
    angular_radius_deg: float
    wavelengths_nm: tuple | None
    irradiance: tuple
    visible_fraction: float = 1.0
    limb_darkening: str = "Neckel 2005 (I(mu)/I(1) polynomial of degree 5 per wavelength)"
    quantity: str = field(default="")

    def to_dict(self) -> dict:
        """Plain JSON-ready dictionary, units in the keys."""
        return {"direction_enu": list(self.direction),
                "angular_radius_deg": self.angular_radius_deg,
                "wavelengths_nm": None if self.wavelengths_nm is None else list(self.wavelengths_nm),
                "irradiance": list(self.irradiance),
                "irradiance_quantity": self.quantity,
                "visible_fraction": self.visible_fraction,
                "limb_darkening": self.limb_darkening,
                "frame": "East-North-Up: x east, y north, z up"}

    def write_json(self, path) -> Path:
        """Write :meth:`to_dict` as JSON (atomically); returns the path."""
        from skydome._io import atomic_file, check_output_file

        p = check_output_file(path, (".json",), name="sun light file")
        with atomic_file(p) as tmp, open(tmp, "w") as fh:
            json.dump(self.to_dict(), fh, indent=2)
        return p


def _visible_fraction(elevation_deg: float, radius_deg: float, channel_wl) -> np.ndarray:
    """Fraction of the limb-darkened disc's flux above a flat horizon, per channel, from
    a fine sampling of the disc (the sun's height over the horizon along the disc)."""
    if elevation_deg >= radius_deg:
        return np.ones(len(channel_wl))
    if elevation_deg <= -radius_deg:
        return np.zeros(len(channel_wl))
    from skydome.transport.geometry import direction_from_angles

    s = direction_from_angles(elevation_deg, 0.0)
    dirs, w = _disc_samples(np.asarray(s, dtype=np.float64), np.radians(radius_deg), 256, channel_wl)
    return w[dirs[:, 2] >= 0.0].sum(axis=0) / w.sum(axis=0)


def sun_light(sky, wavelengths_nm=None) -> SunLight | None:
    """The model's sun as a :class:`SunLight` (None if it has no sun or the sun is below
    the horizon); spectral at ``wavelengths_nm`` or XYZ when it is None."""
    sun = getattr(sky, "sun", None)
    if sun is None or sun.elevation_deg <= -sun.angular_radius_deg:
        return None
    L = sun_disc_radiance(sky, wavelengths_nm)
    if L is None:
        return None
    ch = XYZ_CHANNEL_WAVELENGTHS_NM if wavelengths_nm is None else np.asarray(wavelengths_nm, float)
    vis = _visible_fraction(sun.elevation_deg, sun.angular_radius_deg, ch)
    E = L * sun.solid_angle_sr * vis
    return SunLight(direction=tuple(float(v) for v in sun.direction),
                    angular_radius_deg=float(sun.angular_radius_deg),
                    wavelengths_nm=None if wavelengths_nm is None else tuple(float(v) for v in ch),
                    irradiance=tuple(float(v) for v in E),
                    visible_fraction=float(np.mean(vis)),
                    quantity=("spectral normal irradiance [W m^-2 nm^-1]" if wavelengths_nm is not None
                              else "CIE 1931 XYZ normal irradiance, Y = illuminance [lx]"))
