"""Table mappings and look-ups of the numerical core (numba, scalar).

Bruneton's (2017) transmittance and irradiance parametrisations
(precomputed_atmospheric_scattering, atmosphere/functions.glsl, [Bru17]) as inverse pairs
(the precomputed model's scattering mappings are its own, models/simulated/precomputed/
_mapping.py), without the texel-centre offset: a
table axis of n nodes holds node i at the unit coordinate x = i / (n - 1). H =
sqrt(Rt^2 - R^2) is the distance to the top along the horizon from the ground and rho =
sqrt(r^2 - R^2) the distance to the horizon from radius r.

* transmittance (r, mu) <-> (x_r, x_mu): x_r = rho / H, x_mu = (d - d_min) / (d_max - d_min)
  with d the distance to the top, d_min = Rt - r, d_max = rho + H
  (GetTransmittanceTextureUvFromRMu / GetRMuFromTransmittanceTextureUv);
* irradiance (r, mu_s): x_r = (r - R) / (Rt - R), x_mu_s = (mu_s + 1) / 2.

Interpolation cells: :func:`cell` turns a unit coordinate into a node and a fraction;
:func:`transmittance_cell` does so for (r, mu) on an n_r x n_mu table, and the bilinear
look-ups (:func:`bilerp`, :func:`lookup_columns`, :func:`lookup_rmu`) are the one
(r, mu) interpolation of every table indexed that way.
"""

from __future__ import annotations

import math

from skydome._kernel_cache import njit

from skydome.transport._geometry import clamp_cosine, distance_to_sphere_far, safe_sqrt


# -- transmittance (r, mu) -------------------------------------------------------------------------
@njit(cache=True)
def transmittance_unit_from_r_mu(r, mu, R, Rt):
    """(x_r, x_mu) in [0, 1]^2 of the transmittance mapping ([Bru17]
    GetTransmittanceTextureUvFromRMu without the texel-centre offset)."""
    H = math.sqrt(Rt * Rt - R * R)
    rho = safe_sqrt(r * r - R * R)
    d = distance_to_sphere_far(r, mu, Rt)
    d_min = Rt - r
    d_max = rho + H
    x_mu = 0.0 if d_max <= d_min else (d - d_min) / (d_max - d_min)
    return rho / H, min(max(x_mu, 0.0), 1.0)


@njit(cache=True)
def r_mu_from_transmittance_unit(x_r, x_mu, R, Rt):
    """(r, mu) of a transmittance unit coordinate ([Bru17] GetRMuFromTransmittanceTextureUv),
    the inverse of :func:`transmittance_unit_from_r_mu`."""
    H = math.sqrt(Rt * Rt - R * R)
    rho = H * x_r
    r = math.sqrt(rho * rho + R * R)
    d_min = Rt - r
    d_max = rho + H
    d = d_min + x_mu * (d_max - d_min)
    if d == 0.0:
        return r, 1.0
    return r, clamp_cosine((H * H - rho * rho - d * d) / (2.0 * r * d))


# -- irradiance (r, mu_s) ---------------------------------------------------------------------------
@njit(cache=True)
def irradiance_unit_from_r_mu_s(r, mu_s, R, Rt):
    """(x_r, x_mu_s) = ((r - R) / (Rt - R), (mu_s + 1) / 2) ([Bru17]
    GetIrradianceTextureUvFromRMuS without the texel-centre offset)."""
    return (r - R) / (Rt - R), 0.5 * (mu_s + 1.0)


@njit(cache=True)
def r_mu_s_from_irradiance_unit(x_r, x_mu_s, R, Rt):
    """Inverse of :func:`irradiance_unit_from_r_mu_s` ([Bru17] GetRMuSFromIrradianceTextureUv)."""
    return R + x_r * (Rt - R), 2.0 * x_mu_s - 1.0


# -- interpolation cells and look-ups --------------------------------------------------------------
@njit(cache=True)
def cell(x, n):
    """(i, f): lower node and fraction of the unit coordinate x (clamped to [0, 1]) on an
    axis of n >= 2 nodes at i / (n - 1)."""
    fx = min(max(x, 0.0), 1.0) * (n - 1)
    i = min(int(fx), n - 2)
    return i, fx - i


@njit(cache=True)
def transmittance_cell(r, mu, R, Rt, n_r, n_mu):
    """(i, j, a, b): bilinear cell and fractions of (r, mu) on an n_r x n_mu table in the
    transmittance mapping."""
    x_r, x_mu = transmittance_unit_from_r_mu(r, mu, R, Rt)
    i, a = cell(x_r, n_r)
    j, b = cell(x_mu, n_mu)
    return i, j, a, b


@njit(cache=True)
def bilerp(tab, i, j, a, b):
    """Bilinear interpolation of the 2-D array tab at cell (i, j), fractions (a, b)."""
    return ((1.0 - a) * ((1.0 - b) * tab[i, j] + b * tab[i, j + 1])
            + a * ((1.0 - b) * tab[i + 1, j] + b * tab[i + 1, j + 1]))


@njit(cache=True)
def lookup_columns(table, r, mu, R, Rt, out):
    """out[c] = bilinear look-up of table[c, r, mu] (per-constituent columns to the top in
    the transmittance mapping, :func:`skydome.transport._kernels.build_column_table`)."""
    i, j, a, b = transmittance_cell(r, mu, R, Rt, table.shape[1], table.shape[2])
    lookup_columns_cell(table, i, j, a, b, out)


@njit(cache=True, inline="always")
def lookup_columns_cell(table, i, j, a, b, out):
    """out[c] = bilinear interpolation of table[c] at cell (i, j), fractions (a, b) (the
    look-up of :func:`lookup_columns` once the cell is known)."""
    w00 = (1.0 - a) * (1.0 - b)
    w01 = (1.0 - a) * b
    w10 = a * (1.0 - b)
    w11 = a * b
    for c in range(table.shape[0]):
        out[c] = (w00 * table[c, i, j] + w01 * table[c, i, j + 1]
                  + w10 * table[c, i + 1, j] + w11 * table[c, i + 1, j + 1])


@njit(cache=True)
def lookup_column(table, c, r, mu, R, Rt):
    """Bilinear look-up of constituent c's column to the top from (r, mu) in table[c, r, mu]."""
    i, j, a, b = transmittance_cell(r, mu, R, Rt, table.shape[1], table.shape[2])
    return bilerp(table[c], i, j, a, b)


@njit(cache=True)
def lookup_rmu(table, r, mu, R, Rt, w, out):
    """out[l] = w x bilinear look-up of table[r, mu, l] (a per-wavelength table in the
    transmittance mapping, e.g. Bruneton's or Hillaire's transmittance texture)."""
    i, j, a, b = transmittance_cell(r, mu, R, Rt, table.shape[0], table.shape[1])
    w00 = w * (1.0 - a) * (1.0 - b)
    w01 = w * (1.0 - a) * b
    w10 = w * a * (1.0 - b)
    w11 = w * a * b
    for l in range(out.shape[0]):
        out[l] = (w00 * table[i, j, l] + w01 * table[i, j + 1, l]
                  + w10 * table[i + 1, j, l] + w11 * table[i + 1, j + 1, l])


@njit(cache=True)
def bilerp_last(tab, i, j, a, b, l):
    """Bilinear interpolation of tab[:, :, l] at cell (i, j), fractions (a, b) (a table with
    the wavelength axis last)."""
    return ((1.0 - a) * ((1.0 - b) * tab[i, j, l] + b * tab[i, j + 1, l])
            + a * ((1.0 - b) * tab[i + 1, j, l] + b * tab[i + 1, j + 1, l]))


@njit(cache=True)
def irradiance_cell(r, mu_s, R, Rt, n_r, n_mu_s):
    """(i, j, a, b): bilinear cell and fractions of (r, mu_s) on an n_r x n_mu_s table in
    the irradiance mapping (linear in altitude and in mu_s)."""
    x_r, x_m = irradiance_unit_from_r_mu_s(r, mu_s, R, Rt)
    i, a = cell(x_r, n_r)
    j, b = cell(x_m, n_mu_s)
    return i, j, a, b
