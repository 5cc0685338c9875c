"""The grids of the ``fitted`` model: its parameter nodes, its view directions, its
wavelengths.

One definition, read by the data-set generator (tools/fitted_dataset.py), the fit
(tools/fit_fitted.py) and the evaluator, so that a node means the same everywhere.

View directions
---------------
A direction is given by its zenith angle theta and its azimuth from the sun's vertical
plane phi in [0, 180] deg (the sky is symmetric about that plane). The horizon of an
observer at altitude h lies at theta_h = 90 deg + dip, dip = acos(R / (R + h)) (a spherical
earth of radius R, :data:`skydome.constants.EARTH_RADIUS`): 0 at the ground, 3.93 deg at
15 km. The sky (theta < theta_h) and the ground (theta > theta_h) are two grids, so that
the step of brightness at the horizon is never interpolated across, and both follow the
horizon as the observer climbs:

* sky, ``N_SKY`` nodes: theta = (theta_h - EPS) (1 - x^2), x uniform in [0, 1] (x = 0
  just above the horizon): nodes densest at the horizon (first cell 0.02 deg), 2.9 deg
  apart at the zenith;
* ground, ``N_GROUND`` nodes: theta = theta_h + EPS + (180 deg - theta_h - EPS) x^2,
  densest at the horizon (first cell 0.35-0.39 deg);
* azimuth, ``N_PHI`` nodes: phi = 180 deg (A t + (1 - A) t^2), t uniform in [0, 1]:
  0.86 deg apart next to the sun's vertical, 4.9 deg on the side opposite it.
"""

from __future__ import annotations

import math

import numpy as np

from skydome.constants import EARTH_RADIUS

#: Sky, ground and azimuth nodes of the view grid.
N_SKY, N_GROUND, N_PHI = 64, 16, 64
#: The linear share of the azimuth mapping.
A_PHI = 0.3
#: The first sky and ground nodes lie this far [rad] (0.005 deg) above and below the
#: horizon, which belongs to neither. (The data set of the shipped coefficients was
#: computed with the nodes theta_h (1 - x^2) and theta_h + (180 deg - theta_h) x^2 but for
#: those two end nodes: within 0.005 deg of the nodes of these mappings.)
EPS = math.radians(0.005)

#: Table wavelengths of the data set [nm]: 300-1100 nm every 20 nm (the reference's table
#: grid; values between them are interpolated linearly, relative to the solar spectrum).
WAVELENGTHS_NM = np.arange(300.0, 1100.0 + 1e-9, 20.0)
#: Table wavelengths of their own between the 20-nm ones, where the gases absorb so that no
#: interpolation from the 20-nm values holds the spectrum: the 10-nm wavelengths whose
#: in-between error, measured against the reference computed there (the held-out grid at
#: 10 nm, docs/models.md "fitted", "Wavelengths"), was 5-8 % RMS by day or more: ozone's
#: Huggins band (310, 330 nm), water vapour (690, 710, 730, 890, 930 nm) and the O2 A band's
#: edge (770 nm); and ozone's Chappuis band (570, 590, 610 nm, its peaks near 575 and 603
#: nm), where interpolating the reference's own 20-nm values put the luminance of clear
#: skies up to 2.8 % low by day (3.5 % at 0.4-4.5 km) and 5.9 % in twilight (the
#: luminance's "interpolation alone", docs/models.md). A supplement data set holds them
#: (``tools/fitted_dataset.py --gas-bands``, or ``--wavelengths`` for some of them).
GAS_BAND_WAVELENGTHS_NM = np.array([310.0, 330.0, 570.0, 590.0, 610.0, 690.0, 710.0, 730.0,
                                    770.0, 890.0, 930.0])
#: The table wavelengths of a file fitted with that supplement (52 wavelengths).
TABLE_WAVELENGTHS_NM = np.union1d(WAVELENGTHS_NM, GAS_BAND_WAVELENGTHS_NM)
#: The Chappuis band's wavelengths: the supplement that the seventh file's data set (49
#: wavelengths) lacks (``tools/fitted_dataset.py --wavelengths 570,590,610``).
CHAPPUIS_WAVELENGTHS_NM = np.array([570.0, 590.0, 610.0])
#: The gas bands' and table wavelengths of the first to seventh files (8 and 49: without
#: the Chappuis band's).
V7_GAS_BAND_WAVELENGTHS_NM = np.setdiff1d(GAS_BAND_WAVELENGTHS_NM, CHAPPUIS_WAVELENGTHS_NM)
V7_TABLE_WAVELENGTHS_NM = np.union1d(WAVELENGTHS_NM, V7_GAS_BAND_WAVELENGTHS_NM)

#: The model's parameter range (inclusive).
SUN_ELEVATION_RANGE_DEG = (-12.0, 90.0)
ALTITUDE_RANGE_M = (0.0, 15000.0)
AOD_RANGE = (0.0, 1.0)
ALBEDO_RANGE = (0.0, 1.0)

#: The fitting nodes (the data set's parameter grid) of the shipped coefficient file. They
#: refine the grid of the first file (``V1_*`` below): an AOD node at 0.025, altitude nodes
#: at 0.35, 1.1 and 2 km, sun nodes at -11 and -9 deg, where the first file's errors between
#: its nodes were largest (docs/models.md "fitted", "The refit").
SUN_ELEVATION_NODES_DEG = np.array([-12.0, -11.0, -10.0, -9.0, -8.0, -7.0, -6.0, -5.0, -4.0,
                                    -3.0, -2.0, -1.0, 0.0, 0.5, 1.0, 2.0, 3.5, 5.0, 7.0, 10.0,
                                    14.0, 19.0, 25.0, 32.0, 40.0, 50.0, 62.0, 75.0, 90.0])
#: The sun node added to the sixth file's (``tools/fitted_dataset.py --elevations 0.5``):
#: with the sun between the nodes 0 and 1 deg, the reference's own values interpolated in
#: sun elevation alone were 4.4 % off in the hazy aureole near the horizon (AOD 0.6 at
#: 2.2 km, sun 0.5 deg: docs/models.md, "fitted", "The sun node at 0.5 deg").
SUPPLEMENT_SUN_ELEVATIONS_DEG = np.array([0.5])
#: The sun nodes of the sixth file (``--grid fit-v6``): the present ones without 0.5 deg.
V6_SUN_ELEVATION_NODES_DEG = np.setdiff1d(SUN_ELEVATION_NODES_DEG,
                                          SUPPLEMENT_SUN_ELEVATIONS_DEG)
#: Altitude nodes: denser in the aerosol's first scale heights (1.2 km), where the
#: radiance changes fastest with altitude (0.35-0.5 km apart up to 2 km), then 1-3 km
#: apart. The nodes at 4, 5, 8 and 12 km were added to the second file's (3-6 km and 6-10-15
#: km apart there): the reference computed every 500 m showed that gap's interpolation in
#: altitude alone to be up to 29 % off in haze with a low sun (docs/models.md, "fitted",
#: "The altitude nodes from 3 to 15 km").
ALTITUDE_NODES_M = np.array([0.0, 350.0, 700.0, 1100.0, 1500.0, 2000.0, 3000.0, 4000.0,
                             5000.0, 6000.0, 8000.0, 10000.0, 12000.0, 15000.0])
#: The altitude nodes added to the second file's (``tools/fitted_dataset.py --altitudes``).
SUPPLEMENT_ALTITUDES_M = np.array([4000.0, 5000.0, 8000.0, 12000.0])
#: The altitude nodes of the second file (the data set of the refit on the corrected
#: reference): the present ones without the supplement's.
V2_ALTITUDE_NODES_M = np.setdiff1d(ALTITUDE_NODES_M, SUPPLEMENT_ALTITUDES_M)
#: AOD nodes: the nodes at 0.0125, 0.075 and 0.15 were added to the third file's, where
#: the reference's own values interpolated between its nodes (``tools/fitted_node_spacing.py
#: aod``, ``aod --hazy``) were 6-25 % off near the horizon at AOD 0.003-0.0125, 9.4 % at 0.07
#: and 15.0 % at 0.165 with a low sun (docs/models.md, "fitted", "The AOD nodes at 0.0125
#: and 0.075" and "The AOD node at 0.15"); the nodes at 0.35 and 0.75 to the fourth file's,
#: where the reference's own values were 8.5 % off at 0.35 and 10.6 % at 0.7 with a low
#: sun (docs/models.md, "fitted", "The AOD nodes at 0.35 and 0.75"; added to the fourth
#: file's fit by ``tools/fit_fitted.py --extend``).
AOD_NODES = np.array([0.0, 0.00625, 0.0125, 0.025, 0.05, 0.075, 0.1, 0.15, 0.25, 0.35, 0.5,
                      0.75, 1.0])
#: The AOD nodes of the fifth file (``--grid fit-v5``): the present ones without 0.00625.
V5_AOD_NODES = np.setdiff1d(AOD_NODES, [0.00625])
#: The AOD nodes of the fourth file (``--grid fit-v4``): the present ones without 0.35 and
#: 0.75.
V4_AOD_NODES = np.setdiff1d(V5_AOD_NODES, [0.35, 0.75])
#: The AOD nodes of the third file (``--grid fit-v3``): the present ones without 0.0125,
#: 0.075 and 0.15.
V3_AOD_NODES = np.array([0.0, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0])
#: Three albedo nodes: between them the radiance follows the form of a Lambertian ground
#: under a scattering atmosphere, L(a) = L_0 + a G / (1 - a S) (see _coefficients.py).
ALBEDO_NODES = np.array([0.0, 0.5, 1.0])

#: The held-out grid: none of its values is a fitting node but the altitudes 0 and 15 km
#: (the ends of the range); every value between two nodes, the twilight elevations midway.
#: Its atmospheres: the third file's five with AOD 0.006 for its 0.0125 (now a node), and
#: AOD 0.018, 0.06 and 0.12 in three intervals between the AOD nodes that had none; AOD
#: 0.3, 0.42, 0.6 and 0.87 for the fourth file's 0.7, one in each interval beside the nodes
#: at 0.35 and 0.75 (near their middles in sqrt(AOD), the model's coordinate); AOD 0.003 and
#: 0.009 for the fifth file's 0.006, one in each interval beside the node at 0.00625 (0.006
#: lies within 4 % of it).
HELDOUT_SUN_ELEVATION_DEG = np.array([-11.5, -9.5, -6.5, -4.5, -2.5, -1.5, 0.25, 0.75, 4.0,
                                      8.5, 16.0, 28.0, 45.0, 70.0])
#: The held-out sun elevations of the sixth file (``--grid heldout-v6``): 0.5 deg (now a
#: node) for the present 0.25 and 0.75, the middles of the intervals beside it.
V6_HELDOUT_SUN_ELEVATION_DEG = np.array([-11.5, -9.5, -6.5, -4.5, -2.5, -1.5, 0.5, 4.0, 8.5,
                                         16.0, 28.0, 45.0, 70.0])
HELDOUT_ALTITUDE_M = np.array([0.0, 400.0, 2200.0, 4500.0, 15000.0])
HELDOUT_ATMOSPHERES = ((0.04, 0.3), (0.08, 0.75), (0.003, 0.6), (0.009, 0.35),
                       (0.018, 0.9), (0.06, 0.15), (0.12, 0.55), (0.18, 0.4),
                       (0.3, 0.35), (0.42, 0.8), (0.6, 0.2),
                       (0.87, 0.65))               # (AOD at 550 nm, albedo)
#: The held-out atmospheres of the fifth file (``--grid heldout-v5``).
V5_HELDOUT_ATMOSPHERES = ((0.04, 0.3), (0.08, 0.75), (0.006, 0.6)) + HELDOUT_ATMOSPHERES[4:]
#: The held-out atmospheres of the fourth file (``--grid heldout-v4``).
V4_HELDOUT_ATMOSPHERES = V5_HELDOUT_ATMOSPHERES[:7] + ((0.7, 0.2),)


#: The held-out atmospheres of the third file (``--grid heldout-v3``).
V3_HELDOUT_ATMOSPHERES = ((0.04, 0.3), (0.08, 0.75), (0.0125, 0.6), (0.18, 0.4), (0.7, 0.2))


#: The grid of the first coefficient file (``tools/fitted_dataset.py --grid fit-v1`` /
#: ``heldout-v1``), to reproduce it and its published figures.
V1_SUN_ELEVATION_NODES_DEG = np.array([-12.0, -10.0, -8.0, -7.0, -6.0, -5.0, -4.0, -3.0,
                                            -2.0, -1.0, 0.0, 1.0, 2.0, 3.5, 5.0, 7.0, 10.0,
                                            14.0, 19.0, 25.0, 32.0, 40.0, 50.0, 62.0, 75.0,
                                            90.0])
V1_ALTITUDE_NODES_M = np.array([0.0, 700.0, 1500.0, 3000.0, 6000.0, 10000.0, 15000.0])
V1_AOD_NODES = np.array([0.0, 0.05, 0.1, 0.25, 0.5, 1.0])
V1_HELDOUT_SUN_ELEVATION_DEG = np.array([-11.0, -9.0, -6.5, -4.5, -2.5, -1.5, 0.5, 4.0,
                                              8.5, 16.0, 28.0, 45.0, 70.0])
V1_HELDOUT_ATMOSPHERES = ((0.05, 0.3), (0.08, 0.75), (0.025, 0.6), (0.18, 0.4),
                               (0.7, 0.2))


def grid(name: str):
    """(sun elevations [deg], altitudes [m], atmospheres [(AOD, albedo)], cell centres)
    of a named data-set grid: "fit" and "heldout" (the shipped file's), "fit-v6" and
    "heldout-v6" (the sixth file's: "fit" without the sun node 0.5 deg, its held-out sun
    0.5 deg for 0.25 and 0.75), "fit-v5" and "heldout-v5" (the fifth file's: "fit-v6"
    without the AOD node 0.00625, its held-out AOD 0.006 for 0.003 and 0.009), "fit-v4" and
    "heldout-v4" (the fourth file's: "fit-v5" without the AOD nodes 0.35 and 0.75, its
    held-out AOD 0.7 for 0.3, 0.42, 0.6 and 0.87), "fit-v3" and
    "heldout-v3" (the third file's: "fit-v4" without the AODs 0.0125, 0.075 and 0.15, its
    five held-out atmospheres), "fit-v2" (the second file's: "fit-v3" without the altitudes
    4, 5, 8 and 12 km), "fit-v1" and
    "heldout-v1" (the first file's), "small" (two atmospheres of "fit")."""
    if name in ("fit", "small", "fit-v6"):
        atm = [(float(a), float(b)) for a in AOD_NODES for b in ALBEDO_NODES]
        if name == "small":
            atm = [(0.1, 0.0), (0.1, 0.5)]
        el = V6_SUN_ELEVATION_NODES_DEG if name == "fit-v6" else SUN_ELEVATION_NODES_DEG
        return el, ALTITUDE_NODES_M, atm, False
    if name in ("fit-v5", "fit-v4"):
        nodes = V5_AOD_NODES if name == "fit-v5" else V4_AOD_NODES
        atm = [(float(a), float(b)) for a in nodes for b in ALBEDO_NODES]
        return V6_SUN_ELEVATION_NODES_DEG, ALTITUDE_NODES_M, atm, False
    held = {"heldout": HELDOUT_ATMOSPHERES, "heldout-v6": HELDOUT_ATMOSPHERES,
            "heldout-v5": V5_HELDOUT_ATMOSPHERES, "heldout-v4": V4_HELDOUT_ATMOSPHERES,
            "heldout-v3": V3_HELDOUT_ATMOSPHERES}
    if name in held:
        el = HELDOUT_SUN_ELEVATION_DEG if name == "heldout" else V6_HELDOUT_SUN_ELEVATION_DEG
        return el, HELDOUT_ALTITUDE_M, list(held[name]), True
    if name in ("fit-v3", "fit-v2"):
        atm = [(float(a), float(b)) for a in V3_AOD_NODES for b in ALBEDO_NODES]
        alt = ALTITUDE_NODES_M if name == "fit-v3" else V2_ALTITUDE_NODES_M
        return V6_SUN_ELEVATION_NODES_DEG, alt, atm, False
    if name == "fit-v1":
        atm = [(float(a), float(b)) for a in V1_AOD_NODES for b in ALBEDO_NODES]
        return V1_SUN_ELEVATION_NODES_DEG, V1_ALTITUDE_NODES_M, atm, False
    if name == "heldout-v1":
        return (V1_HELDOUT_SUN_ELEVATION_DEG, HELDOUT_ALTITUDE_M,
                list(V1_HELDOUT_ATMOSPHERES), True)
    raise ValueError(f"grid = {name!r} is not one of {', '.join(GRID_NAMES)}")


GRID_NAMES = ("fit", "heldout", "fit-v6", "heldout-v6", "fit-v5", "heldout-v5", "fit-v4",
              "heldout-v4", "fit-v3", "heldout-v3", "fit-v2", "fit-v1", "heldout-v1", "small")


def horizon_zenith_rad(altitude_m: float) -> float:
    """Zenith angle of the horizon [rad] seen from ``altitude_m`` above a sphere of radius
    :data:`EARTH_RADIUS`: pi/2 + acos(R / (R + h))."""
    return 0.5 * math.pi + math.acos(EARTH_RADIUS / (EARTH_RADIUS + max(altitude_m, 0.0)))


def sky_x():
    return np.linspace(0.0, 1.0, N_SKY)


def ground_x():
    return np.linspace(0.0, 1.0, N_GROUND)


def phi_nodes_rad() -> np.ndarray:
    """Azimuths from the sun's vertical plane [rad], (N_PHI,)."""
    t = np.linspace(0.0, 1.0, N_PHI)
    return math.pi * (A_PHI * t + (1.0 - A_PHI) * t * t)


def theta_nodes_rad(altitude_m: float, midpoints: bool = False
                    ) -> tuple[np.ndarray, np.ndarray]:
    """(sky, ground) zenith angles [rad] of the view grid for an observer at
    ``altitude_m``: (N_SKY,) from the horizon up, (N_GROUND,) from the horizon down (with
    ``midpoints`` the centres of the cells between them, in the mapped coordinate x)."""
    th_h = horizon_zenith_rad(altitude_m)
    xs, xg = sky_x(), ground_x()
    if midpoints:
        xs, xg = 0.5 * (xs[1:] + xs[:-1]), 0.5 * (xg[1:] + xg[:-1])
    sky = (th_h - EPS) * (1.0 - xs * xs)
    ground = th_h + EPS + (math.pi - th_h - EPS) * xg * xg
    return sky, ground


def sky_cell(theta, phi, theta_h: float):
    """The sky grid's cell of directions at zenith angles ``theta`` (< ``theta_h``, the
    horizon's) and azimuths from the sun's vertical plane ``phi`` in [0, pi] [rad]: (iu, it,
    fu, ft), the cell's lower node indices along the rows (from the horizon up) and the
    azimuths, and the fractions of the way to the next nodes, in the mapped coordinates.
    The inverses of :func:`theta_nodes_rad` (theta = (theta_h - EPS)(1 - x^2), x = u /
    (N_SKY - 1)) and :func:`phi_nodes_rad` (phi = pi (A_PHI t + (1 - A_PHI) t^2), t = v /
    (N_PHI - 1)), clamped to the last cell as the lookup kernel clamps
    (:func:`._kernels.lookup`)."""
    theta = np.asarray(theta, dtype=np.float64)
    phi = np.asarray(phi, dtype=np.float64)
    q = 1.0 - np.minimum(theta, theta_h - EPS) / (theta_h - EPS)
    u = np.sqrt(np.maximum(q, 0.0)) * (N_SKY - 1)
    iu = np.minimum(u.astype(np.int64), N_SKY - 2)
    a, b = A_PHI, 1.0 - A_PHI
    t = (-a + np.sqrt(a * a + 4.0 * b * phi / math.pi)) / (2.0 * b) * (N_PHI - 1)
    it = np.minimum(t.astype(np.int64), N_PHI - 2)
    return iu, it, np.minimum(u - iu, 1.0), np.clip(t - it, 0.0, 1.0)


def directions(altitude_m: float, sun_azimuth_deg: float = 180.0,
               midpoints: bool = False) -> np.ndarray:
    """The view grid's unit directions (East-North-Up) for an observer at ``altitude_m``
    with the sun at ``sun_azimuth_deg``: shape (N_SKY + N_GROUND, N_PHI, 3), the sky rows
    first. ``midpoints``: the centres of the grid's cells instead (in the mapped
    coordinates), (N_SKY + N_GROUND - 2, N_PHI - 1, 3): the directions farthest from every
    node, where the held-out grid measures the model."""
    sky, ground = theta_nodes_rad(altitude_m, midpoints)
    if midpoints:
        t = np.linspace(0.0, 1.0, N_PHI)
        t = 0.5 * (t[1:] + t[:-1])
        phi = math.pi * (A_PHI * t + (1.0 - A_PHI) * t * t)
    else:
        phi = phi_nodes_rad()
    th = np.concatenate([sky, ground])[:, None]
    az = math.radians(sun_azimuth_deg) + phi[None, :]
    st = np.sin(th)
    return np.stack(np.broadcast_arrays(st * np.sin(az), st * np.cos(az), np.cos(th)),
                    axis=-1)
