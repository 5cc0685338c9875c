"""The coefficient file of the ``fitted`` model and the angular tables built from it.

The representation (written by tools/fit_fitted.py from the data set of
tools/fitted_dataset.py):

For every node (AOD a_i, albedo b_j, sun elevation e_k, altitude h_l, wavelength w_m) the
reference's radiance per unit extraterrestrial irradiance L [sr^-1] on the view grid is
stored as

    y = ln(L / s + DELTA),   s = the mean of L over the sky part of the grid,

and y over the grid's directions is a low-rank expansion in an angular basis of its own
sun-elevation node,

    y(direction) = mean_k(direction) + sum_n c_n(a_i, b_j, e_k, h_l, w_m) B_kn(direction),

the basis B_k and mean_k from a truncated singular value decomposition of every y of that
elevation node (every atmosphere, altitude and wavelength), the sky and the ground apart
(``K_SKY`` and ``K_GROUND`` terms). A configuration between the nodes takes c and ln s
interpolated linearly in altitude at its two neighbouring elevation nodes, y interpolated
linearly in elevation, L per AOD node and albedo node, L linear in AOD; between the albedo
nodes 0,
1/2 and 1 the radiance follows the form of a Lambertian ground under a scattering
atmosphere,

    L(b) = L_0 + b G / (1 - b S)

(G: the light reflected once by a white ground and scattered to the eye; S: the share of
the ground's light that the atmosphere sends back down, the atmosphere's spherical albedo
seen from below), whose G and S the three nodes determine (S clamped to [0, 0.95]).

The sun: the transmittance T along the path to the sun's centre, ln T per (AOD, elevation,
altitude, wavelength); between the nodes ln T / m (m the relative air mass of Kasten &
Young 1989 at the sun's elevation) interpolated linearly in elevation and in the vertical
optical depth at 550 nm above the observer (air and aerosol, each exponential in
altitude), times m; then times the fraction of the disc above the horizon
(:func:`sun_visible_fraction`).
"""

from __future__ import annotations

import functools
import json
import math
from pathlib import Path

import numpy as np

from skydome.models.fitted import _grid

#: The coefficient file shipped with the package.
COEFFICIENT_FILE = Path(__file__).parent / "data" / "fitted_coefficients.npz"

#: Offset of the logarithm (relative to the mean sky radiance).
DELTA = 1e-3
#: Scale heights of ``Atmosphere.earth``'s aerosol and air [m] (survey section 4, eq. 7)
#: and the air's vertical optical depth at 550 nm (Atmosphere.earth().vertical_optical_depth).
AEROSOL_SCALE_HEIGHT_M = 1200.0
RAYLEIGH_SCALE_HEIGHT_M = 7994.0
RAYLEIGH_DEPTH_550 = 0.0878


@functools.lru_cache(maxsize=2)
def load(path: str | None = None) -> dict:
    """The coefficient arrays (loaded once, on first use)."""
    p = Path(path) if path is not None else COEFFICIENT_FILE
    if not p.is_file():
        raise FileNotFoundError(f"the fitted model's coefficient file {p.name} is missing "
                                "(make it with tools/fit_fitted.py)")
    with np.load(p, allow_pickle=False) as z:
        out = {k: z[k] for k in z.files}
    out["meta"] = json.loads(str(out["meta"]))
    return out


def bracket(nodes: np.ndarray, x: float) -> tuple[int, float]:
    """(i, f): x = (1 - f) nodes[i] + f nodes[i + 1], x clamped to the nodes' span."""
    n = nodes.size
    if n == 1:
        return 0, 0.0
    x = min(max(float(x), float(nodes[0])), float(nodes[-1]))
    i = int(np.clip(np.searchsorted(nodes, x, side="right") - 1, 0, n - 2))
    return i, (x - float(nodes[i])) / (float(nodes[i + 1]) - float(nodes[i]))


def sun_visible_fraction(elevation_deg: float, altitude_m: float,
                         angular_radius_deg: float) -> float:
    """Fraction of the sun's disc above the horizon of an observer at ``altitude_m``: the
    area of the disc (radius alpha) above a straight horizon at distance u from its
    centre, 1 - (acos(u/alpha) - (u/alpha) sqrt(1 - (u/alpha)^2)) / pi, with u the
    elevation of the centre above the horizon (which lies at -acos(R / (R + h)))."""
    dip = _grid.horizon_zenith_rad(altitude_m) - 0.5 * math.pi
    u = (math.radians(elevation_deg) + dip) / math.radians(angular_radius_deg)
    if u >= 1.0:
        return 1.0
    if u <= -1.0:
        return 0.0
    return 1.0 - (math.acos(u) - u * math.sqrt(1.0 - u * u)) / math.pi


def _part(c: dict, part: str, k: int, coef: np.ndarray) -> np.ndarray:
    """y on one part ("sky" or "ground") of the grid at elevation node k: (n_wl, n_dir)."""
    return c[f"{part}_mean"][k][None, :] + coef @ c[f"{part}_basis"][k]


def radiance_grid(c: dict, aod: float, albedo: float, elevation_deg: float,
                  altitude_m: float) -> np.ndarray:
    """The radiance per unit extraterrestrial irradiance [sr^-1] of a configuration on the
    view grid at the table wavelengths: (N_SKY + N_GROUND, N_PHI, n_wl), >= 0."""
    ia, fa = bracket(c["aod_nodes"], aod)
    ie, fe = bracket(c["elevation_nodes_deg"], elevation_deg)
    ih, fh = bracket(c["altitude_nodes_m"], altitude_m)
    n_wl = c["wavelengths_nm"].size
    n_sky = _grid.N_SKY * _grid.N_PHI
    per_albedo = []
    for j in range(c["albedo_nodes"].size):
        L = 0.0
        for i, wi in ((ia, 1.0 - fa), (ia + 1, fa)):
            if wi == 0.0:
                continue
            y = np.zeros((n_wl, n_sky + _grid.N_GROUND * _grid.N_PHI))
            log_s = np.zeros(n_wl)
            for k, wk in ((ie, 1.0 - fe), (ie + 1, fe)):
                if wk == 0.0:
                    continue
                cs = np.zeros((n_wl, c["coef_sky"].shape[-1]))
                cg = np.zeros((n_wl, c["coef_ground"].shape[-1]))
                for h, wh in ((ih, 1.0 - fh), (ih + 1, fh)):
                    if wh == 0.0:
                        continue
                    cs += wh * c["coef_sky"][i, j, k, h]
                    cg += wh * c["coef_ground"][i, j, k, h]
                    log_s += wk * wh * c["log_scale"][i, j, k, h]
                y[:, :n_sky] += wk * _part(c, "sky", k, cs)
                y[:, n_sky:] += wk * _part(c, "ground", k, cg)
            # linear in AOD: the aerosol's light (its aureole above all) grows in proportion
            # to its optical depth in a thin haze, which ln L would turn into a geometric mean
            L = L + wi * np.exp(log_s)[:, None] * np.maximum(np.exp(y) - DELTA, 0.0)
        per_albedo.append(L)
    L = albedo_form(c["albedo_nodes"], per_albedo, albedo)
    return np.ascontiguousarray(
        L.T.reshape(_grid.N_SKY + _grid.N_GROUND, _grid.N_PHI, n_wl))


def albedo_form(nodes, values, albedo: float) -> np.ndarray:
    """The radiance at ground albedo ``albedo`` from its values at the albedo nodes 0, 1/2,
    1: L(b) = L_0 + b G / (1 - b S) (module docstring), solved for G and S per element."""
    if not (len(nodes) == 3 and np.allclose(nodes, [0.0, 0.5, 1.0])):
        raise ValueError("the albedo form needs the albedo nodes 0, 0.5, 1")
    L0, Lh, L1 = values
    d1 = Lh - L0                     # = G / (2 - S)
    d2 = L1 - L0                     # = G / (1 - S)
    # d2 / d1 = (2 - S) / (1 - S) = r  ->  S = (r - 2) / (r - 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(d1 > 0.0, d2 / np.where(d1 > 0.0, d1, 1.0), 2.0)
        S = np.clip(np.where(r > 2.0, (r - 2.0) / (r - 1.0), 0.0), 0.0, 0.95)
    G = d2 * (1.0 - S)
    b = float(albedo)
    return np.maximum(L0 + b * G / (1.0 - b * S), 0.0)


def sun_transmittance(c: dict, aod: float, elevation_deg: float,
                      altitude_m: float) -> np.ndarray:
    """Transmittance along the path to the sun's centre at the table wavelengths, (n_wl,),
    in [0, 1] (the visible fraction of the disc not included)."""
    ia, fa = bracket(c["aod_nodes"], aod)
    ie, fe = bracket(c["elevation_nodes_deg"], elevation_deg)
    # in altitude, linear in the optical depth at 550 nm above the observer: air (0.088,
    # scale height 8 km) and aerosol (AOD, 1.2 km), each exponential in altitude
    def depth(h):
        return (RAYLEIGH_DEPTH_550 * np.exp(-h / RAYLEIGH_SCALE_HEIGHT_M)
                + max(aod, 0.005) * np.exp(-h / AEROSOL_SCALE_HEIGHT_M))

    g = depth(np.asarray(c["altitude_nodes_m"], dtype=np.float64))
    ih, fh = bracket(-g, -float(depth(min(max(altitude_m, 0.0), 15000.0))))
    e_nodes = c["elevation_nodes_deg"]
    lt = np.zeros(c["wavelengths_nm"].size)
    for i, wi in ((ia, 1.0 - fa), (ia + 1, fa)):
        for k, wk in ((ie, 1.0 - fe), (ie + 1, fe)):
            for h, wh in ((ih, 1.0 - fh), (ih + 1, fh)):
                if wi * wk * wh != 0.0:
                    # ln T per unit air mass: nearly constant in elevation, where ln T
                    # itself grows steeply towards the horizon
                    lt += wi * wk * wh * c["log_sun_transmittance"][i, k, h] / air_mass(
                        float(e_nodes[k]))
    return np.clip(np.exp(lt * air_mass(elevation_deg)), 0.0, 1.0)


def air_mass(elevation_deg: float) -> float:
    """Relative optical air mass of Kasten & Young 1989 (eq. 3: m = 1 / (cos z + 0.50572
    (96.07995 deg - z)^-1.6364), z the zenith angle), the scale of ln T in elevation; valid
    to z = 96.08 deg, so elevations in [-2, 90] deg."""
    z = 90.0 - float(elevation_deg)
    return 1.0 / (math.cos(math.radians(z)) + 0.50572 * (96.07995 - z) ** -1.6364)
