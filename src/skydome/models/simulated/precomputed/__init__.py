"""``precomputed``: a spectral sky from precomputed scattering tables (Bruneton 2017).

E. Bruneton's "Precomputed Atmospheric Scattering: a New Implementation" (2017; the
reworking of Bruneton & Neyret 2008) tabulates, for a spherical-shell atmosphere, the
transmittance T(r, mu), the in-scattered radiance S(r, mu, mu_s, nu) summed over N
scattering orders and the ground irradiance E(r, mu_s). Rendering any view is then a few
table lookups. This package computes the tables with numba on the CPU, per wavelength (20
by default over 380-780 nm), for any :class:`skydome.atmosphere.Atmosphere`; it keeps
each constituent's single scattering apart (the phase function is applied at render
time, so the aerosol forward peak stays sharp) and stores multiple scattering as full
radiance.

References
----------
[Bru17] E. Bruneton, Precomputed Atmospheric Scattering: a New Implementation, 2017,
    https://ebruneton.github.io/precomputed_atmospheric_scattering/ (atmosphere/functions.glsl).
[BN08] E. Bruneton, F. Neyret, Precomputed Atmospheric Scattering, EGSR 2008, eqs. 1-9.
"""

from __future__ import annotations

import math

import numpy as np

from skydome._validate import as_directions, as_wavelengths, check_number
from skydome.models import ATMOSPHERE_PARAMETERS, Parameter, SkyModel, register
from skydome.models.simulated.precomputed._precompute import QUADRATURE_SCALE_M, tables_medium
from skydome.models.simulated.precomputed._tables import Tables

__all__ = ["PrecomputedSky", "Precomputed", "Tables", "clear_cache"]

# the observer's sky map of orders 2..N: view zenith nodes below / above the horizon (dense
# at the horizon: _multiple.map_nodes) and azimuth nodes from the sun's over [0, 180] deg
_SLICE_GROUND, _SLICE_SKY, _SLICE_PHI = 64, 192, 96
#: The linear share a of the map's row mapping u(x) = a x + (1 - a) x^2 from the horizon
#: (_multiple.map_nodes): rows a times the uniform spacing at the horizon, 2 - a times it
#: at the zenith (nadir). Uniform rows (a = 1, 48 to the ground) were up to 12 % off a map
#: of 3072 rows at the limb seen from 15 km by day, 83 % in twilight (docs/models.md, "The
#: observer's sky map dense at the horizon")
_SLICE_GROUND_LINEAR, _SLICE_SKY_LINEAR = 0.15, 0.15
#: Gauss-Legendre nodes between two quadrature nodes of a view ray for its columns from
#: the observer with ``observer_columns`` (docs/models.md, "The observer's own columns");
#: the exported shader (export/glsl/precomputed.glsl, SKYDOME_PC_GL6_X) has the same rule
#: written out, so this is 6 or the shader and the model part
OBSERVER_COLUMN_NODES = 6


@register
class PrecomputedSky(SkyModel):
    """Bruneton's (2017) precomputed multiple-scattering sky, spectral, built on the CPU.

    Parameters
    ----------
    sun : skydome.Sun
        Sun position. Sun elevations down to ``90 - max_sun_zenith_deg`` (-18 deg by
        default) are in the tables; below that the sky is night: radiance 0.
    {atmosphere_parameters}
    n_wavelengths : int
        Number of table wavelengths, evenly spaced over 380-780 nm (default 20).
    table_wavelengths_nm : array_like, optional
        Explicit table wavelength grid [nm] (instead of ``n_wavelengths``).
    orders : int
        Number of computed scattering orders, [1, 20] (default 6). Ground reflections
        count as orders.
    remaining_orders : {"none", "geometric"}
        "geometric" adds the orders beyond ``orders`` as a geometric series whose ratio is
        that of the last two computed orders' total radiance, per wavelength (clamped to 0.9;
        after Hillaire 2020, eq. 10). Default "geometric".
    transmittance_mu_size, transmittance_r_size : int
        Transmittance (column) table size, default 256 x 64.
    scattering_r_size, scattering_mu_size, scattering_mu_s_size, scattering_nu_size : int
        4-D scattering table size, default 32 x 128 x 48 x 16 (``scattering_mu_size`` even;
        mu on a horizon-centred mapping of the view ray's angle from the local horizon, half
        the nodes for rays that hit the ground; mu_s on a sunset-centred mapping of the sun's
        zenith angle; both the same for every planet radius).
    irradiance_mu_s_size, irradiance_r_size : int
        Ground-irradiance table size, default 64 x 16.
    integration_samples : int
        Quadrature nodes per ray piece for single scattering and the observer's slice of
        orders 2..N (default 20; midpoint nodes in ln(1 + u / 500 m)); half as many for the
        stored table of orders 2..N, and a third as many Gauss-Legendre nodes (7) for the
        precomputation's ray integrals of the scattering density.
    sphere_samples : int
        Zenith-angle samples of the incident directions in the scattering density
        (default 32, Bruneton's 16; azimuth gets twice as many over the full circle).
    high_order_sphere_samples : int, optional
        Zenith-angle samples of the incident directions in the scattering density of
        orders >= 3, at most ``sphere_samples`` (default 16: their sources, scattered at
        least twice, are smooth; None: ``sphere_samples``).
    density_mu_s_size : int, optional
        mu_s nodes of the scattering density J (default: ``scattering_mu_s_size``).
    high_order_r_size, high_order_mu_s_size : int, optional
        A faster approximation, opt-in: the (r, mu_s) nodes of the scattering density of
        orders >= 3 on a coarser grid of the same mappings, interpolated into the summed
        density (None, the default: the full grid, ``scattering_r_size`` x
        ``density_mu_s_size``). 16 x 24 is up to 10 % RMS (19 % max) off the full grid in
        twilight, r 16 alone 0.6-0.9 % RMS (docs/models.md, "Orders >= 3, cheaper").
    high_order_wavelengths : int, optional
        None (the default): the orders >= 3 are computed at every table wavelength, all in
        one batch (the cost of their ray integrals is nearly all geometry, shared by the
        batch's wavelengths). An integer k (opt-in): interpolation nodes of the orders >= 3
        in wavelength: they are computed at k table wavelengths (spread evenly in log
        wavelength, both ends included) and at every table wavelength in a water-vapour or
        oxygen band; at the others they are order 2's scattering density (and order 1's
        ground irradiance) times the ratio of the orders >= 3 to it, interpolated (monotone
        cubic in log-log, ozone's Chappuis band taken out); at the nodes the ratio is kept
        in float16 (the orders >= 3 there within 0.24 % of their value). What it gives up:
        the orders >= 3 at the other wavelengths are interpolated, not computed (with k = 7
        at 20 table wavelengths: the sky within 0.02 % RMS, max 0.06 %, of every wavelength
        computed, sun 60 to -6 deg, AOD 0.2; 0.03 % / 0.08 % at AOD 0.5); it saves time
        only where every wavelength would not fit one batch (many table wavelengths):
        at the default 20 it costs more CPU than computing them all (docs/models.md,
        "Orders >= 3 at a subset of the table wavelengths").
    stored_table : {"full", "subset"}
        "full" (default): the stored 4-D table of orders 2..N (read by aerial perspective,
        the texture/LUT export and the viewer; not by ``radiance()``, which integrates
        orders 2..N at the observer) integrated at every node. The table is not built in
        the precomputation but on its first read (about 13 s CPU at the defaults), from
        the summed scattering density the precomputation keeps; with the cache on it is
        written into the cache entry as it is built, and a later cache hit reads it. "subset": a faster
        approximation, opt-in: integrated at 66 x 25 x 8 of its 128 x 48 x 16 (mu, mu_s,
        nu) nodes and interpolated in the logarithm (the table's integral 6-8x cheaper,
        about 12 s less CPU at the defaults), up to 3 % RMS (16 % max) off the full table
        in aerial-perspective luminance at 1-100 km (docs/models.md, "The stored table on
        a subset of its nodes").
    order_table_divisor : int
        1 (default): the scattering density of every order on the full outgoing grid.
        2, ...: a faster approximation: the density of orders >= 3 on an outgoing grid this
        many times coarser in the angle from the sun and the azimuth about it (never below
        33 x 17), interpolated into the summed density (docs/models.md, "Cost of the
        precomputation").
    max_sun_zenith_deg : float
        Largest sun zenith angle in the tables [deg], [90, 120] (default 108: astronomical
        twilight).
    twilight_reference : bool
        The twilight reference configuration (default False), one switch for the settings
        of :data:`TWILIGHT_REFERENCE_SETTINGS` (those given explicitly win):
        ``twilight_single_scattering=True`` and the finer tables that bring the twilight sky
        within 3 % RMS of ``montecarlo`` to sun -6 deg and within 10 % to -12 deg
        (tests/test_precomputed_twilight.py; docs/models.md, "Twilight: the reference
        configuration"; its cost in docs/performance.md), and by day
        ``observer_single_scattering=True`` and ``observer_columns=True``.
    twilight_single_scattering, observer_single_scattering : bool
        Single scattering integrated at the observer's own altitude and sun on the
        observer's sky map (192 view zenith angles above the horizon, 64 below, both dense
        at the horizon, 96 azimuths), not read from the 4-D table: with the sun below the horizon
        (``twilight_single_scattering``: each ray split at the earth's shadow), or for every
        sun (``observer_single_scattering``: the table's linear interpolation between its
        r nodes is up to 50 % off for an observer inside thick haze, AOD 1 at 0.1-1 km;
        docs/models.md, "Descending rays and observers inside haze").
        ``twilight_single_scattering`` is on by default (the table's single scattering in
        twilight is 7.6 against 4.9 % RMS off ``montecarlo`` at sun -4 deg, and between
        its mu_s nodes it draws the earth's shadow twice); ``observer_single_scattering``
        is opt-in. The viewer's shader and the LUT bakes read the table.
    observer_columns : bool
        The columns (hence the transmittance) from the observer to each quadrature node of
        the observer's sky maps (orders 2..N; single scattering where it is integrated at
        the observer) integrated along the view ray itself (6-point Gauss-Legendre from
        node to node), not the difference of two columns to the top read from the column
        table. Along a grazing ray from an observer inside haze those two columns exceed
        100 optical depths, and their linear interpolation in r made the horizon step by
        about 10 % where the observer crossed a table r node (docs/models.md, "The
        observer's own columns"). On by default; the exported shader's sky map
        (export/glsl/precomputed.glsl, ``skydomeMultipleScatteringAlong``) integrates the
        columns the same way where the bake's luts.json says ``column_nodes: 6``, and takes
        the table's differences, as the model then does, for a sky made with ``False``.
    cache : bool
        Read and write the on-disk table cache (default True): a second model with the same
        atmosphere, wavelengths and settings reads its tables instead of computing them
        (``from_cache`` says which). Folder ``$SKYDOME_CACHE_DIR`` or the user cache folder;
        size limit ``$SKYDOME_CACHE_LIMIT_BYTES`` (default 1.5 GB); :func:`clear_cache`. The
        cache stores the large tables in half precision (the sky within 2.7e-4 of float32
        tables, docs/performance.md) and computes single scattering again when used.
    """

    name = "precomputed"
    reference = ("Bruneton, Precomputed Atmospheric Scattering: a New Implementation (2017); "
                 "Bruneton & Neyret, Precomputed Atmospheric Scattering, EGSR 2008, eqs. 1-9")
    native = "spectral"
    viewer_shader = "precomputed"
    viewer_parameters = ("turbidity", "observer_altitude_m")
    lut_layout = "bruneton"
    airlight = True
    own_ground = "sun_and_sky"            # [Bru17] GetSunAndSkyIrradiance
    twilight_reference = False            # (files saved before the switch existed)
    summary = "Bruneton-style precomputed multiple scattering tables (spectral, any atmosphere)."
    parameters = (
        *ATMOSPHERE_PARAMETERS,
        Parameter("n_wavelengths", "", 20, 1, 400, "table wavelengths over 380-780 nm", kind="int"),
        Parameter("table_wavelengths_nm", "nm", None, doc="explicit table wavelength grid",
                  kind="object"),
        Parameter("orders", "", 6, 1, 20, "scattering orders", kind="int"),
        Parameter("remaining_orders", "", "geometric", doc="orders beyond N: none, or geometric "
                  "(series with the ratio of the last two orders per table cell)",
                  kind="choice", choices=("none", "geometric")),
        Parameter("transmittance_mu_size", "", 256, 4, 4096, "transmittance table, mu axis", kind="int"),
        Parameter("transmittance_r_size", "", 64, 4, 4096, "transmittance table, r axis", kind="int"),
        Parameter("scattering_r_size", "", 32, 2, 512, "scattering table, r axis", kind="int"),
        Parameter("scattering_mu_size", "", 128, 4, 2048, "scattering table, mu axis (even)", kind="int"),
        Parameter("scattering_mu_s_size", "", 48, 2, 512, "scattering table, mu_s axis", kind="int"),
        Parameter("scattering_nu_size", "", 16, 2, 256, "scattering table, nu axis", kind="int"),
        Parameter("irradiance_mu_s_size", "", 64, 2, 4096, "irradiance table, mu_s axis", kind="int"),
        Parameter("irradiance_r_size", "", 16, 2, 4096, "irradiance table, r axis", kind="int"),
        Parameter("integration_samples", "", 20, 2, 1000, "quadrature nodes per ray piece", kind="int"),
        Parameter("sphere_samples", "", 32, 4, 256, "zenith samples of the scattering density",
                  kind="int"),
        Parameter("high_order_sphere_samples", "", 16, 4, 256,
                  "zenith samples of the scattering density of orders >= 3 (None: sphere_samples)",
                  kind="int"),
        Parameter("density_mu_s_size", "", None, 2, 512,
                  "mu_s nodes of the scattering density (default: scattering_mu_s_size)", kind="int"),
        Parameter("high_order_r_size", "", None, 2, 512,
                  "r nodes of the scattering density of orders >= 3 (None: the full grid)",
                  kind="int"),
        Parameter("high_order_mu_s_size", "", None, 2, 512,
                  "mu_s nodes of the scattering density of orders >= 3 (None: the full grid)",
                  kind="int"),
        Parameter("high_order_wavelengths", "", None, 2, 400,
                  "table wavelengths at which orders >= 3 are computed (None: all)", kind="int"),
        Parameter("stored_table", "", "full", doc="stored table of orders 2..N: full, or "
                  "subset (faster approximation: integrated on a subset of its nodes)",
                  kind="choice", choices=("full", "subset")),
        Parameter("order_table_divisor", "", 1, 1, 8,
                  "each order's source table this many times coarser in mu, mu_s, nu", kind="int"),
        Parameter("max_sun_zenith_deg", "deg", 108.0, 90.0, 120.0, "largest sun zenith in the tables"),
        Parameter("cache", "", True, doc="read and write the on-disk table cache", kind="bool"),
        Parameter("twilight_single_scattering", "", True,
                  doc="sun below the horizon: single scattering integrated at the observer, "
                      "each ray split at the earth's shadow (closer to Monte Carlo), not read "
                      "from the 4-D table (False: the table, as the viewer's shader and the "
                      "LUT bakes read it; about 0.1-0.2 s faster a sun, 7.6 against 4.9 % RMS "
                      "off Monte Carlo at sun -4 deg, and the earth's shadow drawn twice "
                      "between the table's mu_s nodes)",
                  kind="bool"),
        Parameter("observer_single_scattering", "", False,
                  doc="single scattering integrated at the observer's own altitude for "
                      "every sun (on the observer's sky map, as twilight_single_scattering "
                      "does below the horizon), not read from the 4-D table, whose linear "
                      "interpolation between its r nodes is up to 50 % off for observers "
                      "inside thick haze; opt-in (the viewer's shader reads the table)",
                  kind="bool"),
        Parameter("observer_columns", "", True,
                  doc="the observer's sky maps (orders 2..N, and single scattering where it "
                      "is integrated at the observer) with each view ray's columns from the "
                      "observer integrated along the ray itself, not read as the difference "
                      "of two columns to the top from the column table, which made the "
                      "horizon of an observer inside haze step by about 10 % at the table's "
                      "r nodes; on by default (the exported shader's sky map does the same, "
                      "luts.json column_nodes); False: the table's differences",
                  kind="bool"),
        Parameter("twilight_reference", "", False,
                  doc="the twilight reference configuration: twilight_single_scattering on "
                      "and finer tables (see TWILIGHT_REFERENCE_SETTINGS; a setting given "
                      "explicitly wins); within 3 % RMS of montecarlo to sun -6 deg and 10 % "
                      "to -12 deg (docs/models.md)",
                  kind="bool"),
    )

    def __init__(self, sun, **params):

        p = self._begin(sun, params)   # sun, strict parameters, atmosphere (the protocol)
        atm = p["atmosphere"]
        if p["twilight_reference"]:
            if params.get("twilight_single_scattering") is False:
                raise ValueError("twilight_single_scattering = False is out of range with "
                                 "twilight_reference = True: the reference configuration "
                                 "integrates single scattering at the observer")
            for k, v in TWILIGHT_REFERENCE_SETTINGS.items():
                if k not in params:
                    p[k] = v
        if p["scattering_mu_size"] % 2:
            raise ValueError(f"scattering_mu_size = {p['scattering_mu_size']} is out of range: "
                             "it must be even, in [4, 2048]")
        if p["table_wavelengths_nm"] is not None:
            if "n_wavelengths" in params:
                raise ValueError("give either n_wavelengths or table_wavelengths_nm, not both")
            wl = as_wavelengths(p["table_wavelengths_nm"], 280.0, 4000.0, "table_wavelengths_nm")
            if wl.size > 1 and np.any(np.diff(wl) <= 0):
                raise ValueError("table_wavelengths_nm must be strictly increasing")
        else:
            n = p["n_wavelengths"]
            wl = np.array([550.0]) if n == 1 else np.linspace(380.0, 780.0, n)
        for k, v in p.items():
            setattr(self, k, v)
        self.sun = sun
        self.atmosphere = atm
        self.cache = bool(p["cache"])
        self.table_wavelengths_nm = wl
        self.n_wavelengths = wl.size
        self._t, self.from_cache = self._tables(atm, wl, p, self.cache, self._density_rows)
        self.precompute_seconds = self._t.precompute_seconds

    def _density_rows(self, scalars, shape):
        """(first, end): the mu_s rows of the scattering density (of ``shape``) that this
        observer's sky reads (:func:`._reach.density_mu_s_rows`; none where the sun is
        below ``mu_s_min``: the sky is then night or the tables', which read no density),
        for the cache's load (:func:`._cache.load`'s ``density_rows``; ``scalars``: the
        entry's)."""
        from skydome.models.simulated.precomputed import _reach

        R, Rt = float(scalars["planet_radius_m"]), float(scalars["top_radius_m"])
        mu_s_min = float(scalars["mu_s_min"])
        mu_s = float(self.sun.direction[2])
        if mu_s < mu_s_min:
            return 0, 0
        return _reach.density_mu_s_rows(R + self.observer_altitude_m, mu_s, R, Rt, mu_s_min,
                                        shape[4])

    @staticmethod
    def _tables(atm, wl, p, use_cache, density_rows=None):
        """(tables, from_cache): from the on-disk cache when it holds this atmosphere and
        these settings, else precomputed (and stored there). ``density_rows``: the
        scattering density's rows to decode at a load from the cache (:func:`._cache.load`:
        the rest is decoded on its first read)."""
        from skydome.models.simulated.precomputed import _cache
        from skydome.models.simulated.precomputed._precompute import (
            attach_stored_table_builder, precompute)

        # tabulated phase functions are evaluated on the table wavelengths here, once
        props = atm.optical_properties(wl, fold=True)   # absorbers folded (exact)
        if not use_cache:
            return precompute(props, wl, p), False
        settings = {k: v for k, v in p.items() if k in _TABLE_SETTINGS}
        k = _cache.key(props, settings)

        def rebuild_density():
            # a damaged band of the entry's density found on its first whole read (see
            # _cache.load): the precomputation again, stored as a new entry; its table
            # holds the decoded values, what a fresh model serves
            fresh = precompute(props, wl, p)
            _cache.store(k, fresh)
            return fresh.scattering_density

        tables = _cache.load(k, density_rows, rebuild_density)
        hit = tables is not None
        if not hit:
            tables = precompute(props, wl, p)
            _cache.store(k, tables)
        # single scattering where the entry does not hold it, computed on first use
        attach_stored_table_builder(tables)
        if not tables.has_multiple_scattering:
            # the stored table, built on first use, is written into the entry then
            tables.set_multiple_scattering_sink(
                lambda shape, slabs: _cache.add_stored_table(k, shape, slabs))
        return tables, hit

    # -- tables helpers -----------------------------------------------------------------------------
    @property
    def _R(self):
        return self._t.planet_radius_m

    @property
    def _Rt(self):
        return self._t.top_radius_m

    @property
    def _mu_s_min(self):
        return self._t.mu_s_min

    @property
    def _alpha(self):
        return self._t.sun_angular_radius_rad

    @property
    def _r0(self):
        return self._R + self.observer_altitude_m

    def _night(self) -> bool:
        return self.sun.direction[2] < self._mu_s_min - 1e-12

    def _solar(self, wl):
        from skydome.spectra import solar_irradiance

        return solar_irradiance(wl) * self.sun.irradiance_scale

    def _to_wavelengths(self, values, wl):
        """Per-unit-solar-irradiance values on the table grid (..., n_table) -> radiometric
        values on ``wl``: linear interpolation in wavelength (end values held beyond the
        table), times the solar spectrum at ``wl``."""
        from skydome.spectra import interpolation_matrix

        tw = self._t.table_wavelengths_nm
        if wl.shape == tw.shape and np.allclose(wl, tw, rtol=0, atol=1e-9):
            return values * self._solar(wl)
        return (values @ interpolation_matrix(tw, wl)) * self._solar(wl)

    def _observer_slices(self, table_only=False):
        """The 4-D tables interpolated at the observer's r and the sun's mu_s."""
        from skydome.models.simulated.precomputed import _mapping, _multiple, _reach

        R, Rt = self._R, self._Rt
        n_r, _, n_ms, _, nl = self._t.table_shape   # single scattering's and the stored table's
        ir, a = _mapping.r_index(self._r0, n_r, R, Rt)
        x = _mapping.mu_s_unit(float(self.sun.direction[2]), self._mu_s_min)
        ims, c = _mapping._split(x * (n_ms - 1), n_ms)
        # single scattering at the observer's two r nodes only (computed where the tables
        # do not hold the whole table: 2 / n_r of it)
        ss = self._t.single_scattering_rows(ir, ir + 2)

        def sl(t, i):
            lo, hi = t[..., i, :, :, :, :], t[..., i + 1, :, :, :, :]
            out = ((1 - a) * ((1 - c) * lo[..., ims, :, :] + c * lo[..., ims + 1, :, :])
                   + a * ((1 - c) * hi[..., ims, :, :] + c * hi[..., ims + 1, :, :]))
            return np.ascontiguousarray(out, dtype=np.float64)

        mu_s = float(self.sun.direction[2])
        if table_only or not self._t.has_density or mu_s < self._mu_s_min:
            # the stored table (built here on its first read)
            return sl(ss, 0), sl(self._t.multiple_scattering, ir)
        # orders 2..N integrated at the observer's own r and mu_s (the aureole of the
        # multiply scattered light is too sharp for the table's mu_s and nu nodes), cached
        cache = self.__dict__.setdefault("_slice_cache", {})
        key = (self._r0, mu_s)
        if key not in cache:
            t = self._t
            cos_th, ground, cphi = self._slice_grid()
            n_g_s = ground.size
            out = np.empty((n_g_s, _SLICE_PHI, nl))
            # the density's mu_s rows that these rays reach (what the cache decoded at the
            # load, where it holds them; else the whole table), and the rows they read
            n_msj = t.density_shape[4]
            first, end = _reach.density_mu_s_rows(self._r0, mu_s, R, Rt, self._mu_s_min,
                                                  n_msj)
            reach = np.empty((n_g_s, 2), dtype=np.int64)
            for _ in range(2):
                J, j0 = t.scattering_density_rows(first, end)
                _multiple.multiple_scattering_slice(J, j0, n_msj, tables_medium(t),
                                                    t.scattering_index, t.columns,
                                                    self._mu_s_min, self._r0, mu_s,
                                                    int(self.integration_samples),
                                                    QUADRATURE_SCALE_M, cos_th, ground,
                                                    cphi, reach, out, *self._column_rule())
                if reach[:, 0].min() >= j0 and reach[:, 1].max() <= j0 + J.shape[4]:
                    break
                # a row outside the bound (which _reach proves cannot be): said, and the
                # slice integrated again from the whole table
                _reach_note(first, end, reach)
                first, end = 0, n_msj
            if len(cache) > 8:
                cache.clear()
            cache[key] = out
        return sl(ss, 0), cache[key]

    def _column_rule(self):
        """(gx, gw) of the observer's sky-map kernels: the Gauss-Legendre rule on [0, 1]
        that integrates the view rays' columns between their nodes with
        ``observer_columns``, else two empty arrays (the column table's differences)."""
        from skydome.transport._quadrature import gauss_legendre_unit

        if getattr(self, "observer_columns", False):
            return gauss_legendre_unit(OBSERVER_COLUMN_NODES)
        return np.empty(0), np.empty(0)

    def _slice_grid(self):
        """(cos of the view zenith angles, which of them look at the ground, cos of the
        azimuths) of the observer's sky map that :meth:`_observer_slices` integrates
        (:meth:`_slice_geometry`: the ground's nodes from the nadir to the horizon, then the
        sky's from the horizon to the zenith)."""
        from skydome.models.simulated.precomputed._multiple import map_nodes

        geom = self._slice_geometry()
        n_g, n_s = int(geom[0]), int(geom[1])
        th = map_nodes(n_g, n_s, float(geom[2]), float(geom[4]), float(geom[5]))
        ground = np.arange(n_g + n_s) < n_g
        cphi = np.cos(np.pi * np.arange(_SLICE_PHI) / (_SLICE_PHI - 1.0))
        return np.cos(th), ground, cphi

    def _slice_geometry_with_single_scattering(self):
        """:meth:`_slice_geometry` with single scattering on the sky map too."""
        geom = self._slice_geometry()
        geom[3] = 1.0
        return geom

    def _slice_geometry(self, table=False):
        """``geom`` of :func:`._render.render_observer`: (n_ground, n_sky, horizon zenith
        angle [rad], 0, the ground's and the sky's linear share of their row mapping,
        :func:`._multiple.map_nodes`) of the observer's sky map (its fourth entry set to 1
        where single scattering is on the map too), or zeros for the table's own mu
        mapping."""
        if table or not self._t.has_density or float(self.sun.direction[2]) < self._mu_s_min:
            return np.zeros(6)
        mu_h = -math.sqrt(max(1.0 - (self._R / self._r0) ** 2, 0.0))
        return np.array([_SLICE_GROUND, _SLICE_SKY, math.acos(mu_h), 0.0, _SLICE_GROUND_LINEAR,
                         _SLICE_SKY_LINEAR])

    # -- public API ---------------------------------------------------------------------------------
    def radiance(self, directions, wavelengths_nm) -> np.ndarray:
        """Spectral radiance [W m^-2 sr^-1 nm^-1] arriving from ``directions`` (..., 3), shape
        (..., n_wavelengths).

        Directions below the horizon see the Lambertian ground (the atmosphere's albedo) lit
        by the transmitted sun and the sky irradiance table, through the air in front of it.
        Wavelengths between table wavelengths are interpolated linearly (relative to the
        solar spectrum); beyond the table's ends its end values are held. Sun below
        ``90 - max_sun_zenith_deg``: 0 (night)."""
        d = as_directions(directions)
        wl = as_wavelengths(wavelengths_nm)
        flat = np.ascontiguousarray(d.reshape(-1, 3))
        tw = self._t.table_wavelengths_nm
        if wl.shape == tw.shape and np.allclose(wl, tw, rtol=0, atol=1e-9):
            # fast path: the kernel applies the solar spectrum itself
            out = self._radiance_table(flat, self._solar(wl))
        else:
            out = self._to_wavelengths(self._radiance_table(flat), wl)
            np.maximum(out, 0.0, out=out)
        return out.reshape(d.shape[:-1] + (wl.size,))

    def xyz(self, directions) -> np.ndarray:
        """CIE 1931 XYZ, Y = luminance [cd m^-2], shape (..., 3): the base class's value
        (:meth:`radiance` on the default wavelengths integrated with the CIE 1931 functions,
        ``spectrum_to_xyz``), computed as one product of the table values with (the
        wavelength interpolation x the solar spectrum x the integration weights), without
        the (n, 41) spectrum between them: the same within rounding (the spectrum's clamp
        at 0 changes nothing there: it interpolates non-negative table values with
        non-negative weights): 0.16-0.21 s against 0.26-0.71 s for 262 144 directions on a
        2-core AMD EPYC, of which the table lookup itself 0.16-0.22 s (docs/performance.md,
        "The precomputed sky's XYZ in one product")."""
        from skydome.spectra import solar_xyz_matrix

        d = as_directions(directions)
        M = self.__dict__.get("_xyz_from_table")
        if M is None:
            M = self._xyz_from_table = solar_xyz_matrix(
                self._t.table_wavelengths_nm, irradiance_scale=self.sun.irradiance_scale)
        out = self._radiance_table(np.ascontiguousarray(d.reshape(-1, 3))) @ M
        return out.reshape(d.shape[:-1] + (3,))

    def radiance_table(self, directions) -> np.ndarray:
        """Radiance per unit extraterrestrial irradiance [sr^-1] on the table wavelengths,
        shape (..., n_table_wavelengths) (the fast path: no spectral interpolation)."""
        d = as_directions(directions)
        return self._radiance_table(np.ascontiguousarray(d.reshape(-1, 3))).reshape(
            d.shape[:-1] + (self.n_wavelengths,))

    def _radiance_table(self, flat, scale=None):
        from skydome.models.simulated.precomputed import _render

        nl = self.n_wavelengths
        scale = np.ones(nl) if scale is None else np.ascontiguousarray(scale, dtype=np.float64)
        out = np.empty((flat.shape[0], nl))
        if self._night():
            out[:] = 0.0
            return out
        ss_s, ms_s = self._observer_slices()
        geom = self._slice_geometry()
        ss_map = self._single_scattering_map()
        if ss_map is not None:
            ss_s, geom = ss_map, self._slice_geometry_with_single_scattering()
        t = self._t
        _render.render_observer(flat, self._r0, np.ascontiguousarray(self.sun.direction), ss_s,
                           t.phase_code, t.phase_param, t.kernel_phase_table, ms_s, t.columns,
                           t.beta_e, t.ground_albedo, t.irradiance, scale, self._R, self._Rt,
                           self._mu_s_min, self._alpha, geom, out)
        return out

    def _single_scattering_map(self):
        """With ``observer_single_scattering``, or ``twilight_single_scattering`` and the
        sun below the horizon (and the observer's sky map of orders 2..N in use): single
        scattering on that sky map, integrated for the observer's own r and mu_s with every
        ray split at the earth's shadow (:func:`._twilight.single_scattering_slice`),
        instead of the 4-D table interpolated at them; None otherwise (the table)."""
        from skydome.models.simulated.precomputed import _twilight
        from skydome.transport._quadrature import gauss_legendre_unit

        mu_s = float(self.sun.direction[2])
        below = getattr(self, "twilight_single_scattering", False) and mu_s < 0.0
        if not (below or getattr(self, "observer_single_scattering", False)):
            return None
        geom = self._slice_geometry()
        if geom[0] <= 0.0:
            return None
        cache = self.__dict__.setdefault("_twilight_cache", {})
        key = (self._r0, mu_s)
        if key not in cache:
            t = self._t
            cos_th, ground, cphi = self._slice_grid()
            rx, rw = gauss_legendre_unit(_twilight.TWILIGHT_SS_NODES)
            out = np.empty((t.scattering_index.size, ground.size, _SLICE_PHI,
                            self.n_wavelengths))
            _twilight.single_scattering_slice(
                t.columns, tables_medium(t), t.scattering_index,
                np.ascontiguousarray(t.scattering_coefficient, dtype=np.float64), self._alpha,
                self._r0, mu_s, QUADRATURE_SCALE_M, rx, rw, cos_th, ground, cphi, out,
                *self._column_rule())
            if len(cache) > 8:
                cache.clear()
            cache[key] = out
        return cache[key]

    def _transmittance_table(self, r, mu):
        from skydome.models.simulated.precomputed import _lookup

        cs = np.empty(self._t.columns.shape[0])
        _lookup.columns_at(self._t.columns, r, mu, self._R, self._Rt, cs)
        return np.exp(-(cs @ self._t.beta_e))

    def sun_visible_fraction(self) -> float:
        """Fraction of the sun's disc above the observer's horizon (0 when the planet
        hides it), which :meth:`sun_radiance` includes."""
        from skydome.models.simulated.precomputed import _lookup

        mu_s = float(self.sun.direction[2])
        return float(_lookup.sun_visible_fraction(self._r0, mu_s, self._R, self._alpha))

    def sun_radiance(self, wavelengths_nm) -> np.ndarray:
        """Radiance of the sun's disc [W m^-2 sr^-1 nm^-1]: E_sun / Omega_sun x T(observer ->
        top) x the fraction of the disc above the horizon (:meth:`sun_visible_fraction`)."""
        wl = as_wavelengths(wavelengths_nm)
        mu_s = float(self.sun.direction[2])
        t = self._transmittance_table(self._r0, mu_s) * self.sun_visible_fraction()
        return self._to_wavelengths(t[None, :], wl)[0] / self.sun.solid_angle_sr

    def irradiance_components(self, wavelengths_nm):
        """(direct, diffuse) spectral irradiance on a horizontal surface at the observer
        [W m^-2 nm^-1]: the transmitted sun (averaged over the disc, [Bru17]
        ComputeDirectIrradiance) and the sky (the irradiance table, orders 1..N and the
        remainder)."""
        from skydome.models.simulated.precomputed import _irradiance, _lookup

        wl = as_wavelengths(wavelengths_nm)
        nl = self.n_wavelengths
        mu_s = float(self.sun.direction[2])
        direct = np.zeros(nl)
        diffuse = np.zeros(nl)
        if not self._night():
            cs = np.empty(self._t.columns.shape[0])
            _irradiance.direct_irradiance_acc(self._t.columns, self._t.beta_e, self._r0, mu_s, self._R,
                                     self._Rt, self._alpha, 1.0, cs, direct)
            _lookup.irradiance_lookup_acc(self._t.irradiance, self._r0, mu_s, self._R, self._Rt,
                                          self._mu_s_min, 1.0, diffuse)
        return (np.maximum(self._to_wavelengths(direct[None], wl)[0], 0.0),
                np.maximum(self._to_wavelengths(diffuse[None], wl)[0], 0.0))

    def ground_irradiance(self, wavelengths_nm) -> np.ndarray:
        """Global spectral irradiance on a horizontal surface at the observer
        [W m^-2 nm^-1] (direct + diffuse, see :meth:`irradiance_components`)."""
        direct, diffuse = self.irradiance_components(wavelengths_nm)
        return direct + diffuse

    def aerial_perspective(self, directions, distance_m, wavelengths_nm):
        """Transmittance and in-scattered radiance between the observer and the point at
        ``distance_m`` along each direction ([Bru17] GetSkyRadianceToPoint).

        Parameters
        ----------
        directions : array_like (..., 3)
        distance_m : float or array_like broadcastable to (...)
            Distance to the object [m], >= 0; clamped to the end of the ray (ground or top
            of the atmosphere).
        wavelengths_nm : array_like

        Returns
        -------
        transmittance : ndarray (..., n_wavelengths)
            Dimensionless.
        inscattered : ndarray (..., n_wavelengths)
            [W m^-2 sr^-1 nm^-1]. An object of radiance L0 appears as T L0 + inscattered.
        """
        from skydome.models.simulated.precomputed import _render

        d = as_directions(directions)
        wl = as_wavelengths(wavelengths_nm)
        dist = np.asarray(distance_m, dtype=np.float64)
        if not np.all(np.isfinite(dist)) or np.any(dist < 0):
            raise ValueError("distance_m must be finite and >= 0 m")
        dist = np.ascontiguousarray(np.broadcast_to(dist, d.shape[:-1]).reshape(-1))
        flat = np.ascontiguousarray(d.reshape(-1, 3))
        nl = self.n_wavelengths
        tr = np.empty((flat.shape[0], nl))
        ins = np.zeros((flat.shape[0], nl))
        t = self._t
        _render.aerial_perspective(flat, dist, self._r0, np.ascontiguousarray(self.sun.direction),
                              t.single_scattering, t.phase_code, t.phase_param,
                              t.kernel_phase_table, t.multiple_scattering, t.columns, t.beta_e, self._R,
                              self._Rt, self._mu_s_min, tr, ins)
        if self._night():
            ins[:] = 0.0
        elif t.has_density:
            # the observer's end of the path: orders 2..N from the observer's slice (as in
            # radiance()) instead of the 4-D table, so that an infinite distance gives the sky
            ss_s, ms_s = self._observer_slices()
            ms_tab = self._observer_slices(table_only=True)[1]
            zero = np.zeros_like(ss_s)
            no_ground = np.zeros_like(t.ground_albedo)
            one = np.ones(nl)
            a_sl, a_tab = np.empty_like(ins), np.empty_like(ins)
            cases = ((zero, ms_s, a_sl, self._slice_geometry()),
                     (zero, ms_tab, a_tab, self._slice_geometry(table=True)))
            ss_map = self._single_scattering_map()
            if ss_map is not None:
                # the sun below the horizon: single scattering at the observer too (as in
                # radiance()), in place of the table's
                cases = ((ss_map, ms_s, a_sl, self._slice_geometry_with_single_scattering()),
                         (ss_s, ms_tab, a_tab, self._slice_geometry(table=True)))
            for ss_x, ms_x, o, geom in cases:
                _render.render_observer(flat, self._r0, np.ascontiguousarray(self.sun.direction), ss_x,
                                   t.phase_code, t.phase_param, t.kernel_phase_table, ms_x,
                                   t.columns, t.beta_e, no_ground, t.irradiance, one, self._R, self._Rt,
                                   self._mu_s_min, self._alpha, geom, o)
            # applied in proportion to the path's share of the whole ray's extinction,
            # 1 - T(d) over 1 - T(end): 0 at distance 0, all of it at the end of the ray
            tr_end, ins_end = np.empty_like(tr), np.zeros_like(ins)
            _render.aerial_perspective(flat, np.full(flat.shape[0], 1e12), self._r0,
                                  np.ascontiguousarray(self.sun.direction), t.single_scattering,
                                  t.phase_code, t.phase_param, t.kernel_phase_table,
                                  t.multiple_scattering, t.columns, t.beta_e, self._R, self._Rt, self._mu_s_min,
                                  tr_end, ins_end)
            share = np.clip((1.0 - tr) / np.maximum(1.0 - tr_end, 1e-300), 0.0, 1.0)
            np.maximum(ins + share * (a_sl - a_tab), 0.0, out=ins)
        tw = t.table_wavelengths_nm
        shape = d.shape[:-1] + (wl.size,)
        trans = np.stack([np.interp(wl, tw, row) for row in tr]) if tw.size > 1 else \
            np.repeat(tr, wl.size, axis=1)
        return (np.clip(trans, 0.0, 1.0).reshape(shape),
                np.maximum(self._to_wavelengths(ins, wl), 0.0).reshape(shape))

    def with_sun(self, sun=None, observer_altitude_m=None) -> "PrecomputedSky":
        """The same tables for another sun position and/or observer altitude [m] (no
        precomputation: the tables hold every altitude and sun zenith angle)."""
        import copy

        from skydome.sun import Sun

        new = copy.copy(self)
        if sun is not None:
            if not isinstance(sun, Sun):
                raise TypeError(f"sun must be a skydome.Sun, not {type(sun).__name__}")
            new.sun = sun
        if observer_altitude_m is not None:
            top = self._Rt - self._R
            new.observer_altitude_m = check_number("observer_altitude_m", observer_altitude_m,
                                                   0.0, top, "m", high_open=True)
        return new

    # -- persistence --------------------------------------------------------------------------------
    _atmosphere_description = None

    def save(self, path) -> None:
        """Write the tables and parameters to an ``.npz`` file (atomically)."""
        from skydome.models.simulated.precomputed import _io

        _io.save(self, path)

    @classmethod
    def load(cls, path, sun=None) -> "PrecomputedSky":
        """Read tables written by :meth:`save`. ``sun`` replaces the saved sun position.

        The loaded model has ``atmosphere = None`` (its description is kept in
        ``describe()``): it renders from the tables alone."""
        from skydome.models.simulated.precomputed import _io

        return _io.load(cls, path, sun)

    @property
    def precompute_time_s(self) -> float:
        """Wall time of the precomputation [s] (of the run that filled the cache, for tables
        read from it)."""
        return float(self._t.precompute_seconds)

    def describe(self):
        out = super().describe()
        out["parameters"]["atmosphere"] = (self.atmosphere.describe() if self.atmosphere is not None
                                           else self._atmosphere_description)
        out["parameters"]["table_wavelengths_nm"] = [float(x) for x in self.table_wavelengths_nm]
        return out

    def export_textures(self, folder) -> list:
        """Write the tables as float32 textures (``.npy``, and ``.exr`` where OpenEXR is
        available) plus ``textures.json`` and ``textures.md`` describing axes, mappings and
        units. Returns the written paths."""
        from skydome.models.simulated.precomputed import _io

        return _io.export_textures(self, folder)


Precomputed = PrecomputedSky

#: The settings of ``twilight_reference=True`` (docs/models.md, "Twilight: the reference
#: configuration"): single scattering integrated at the observer for every sun, the view
#: rays' columns integrated along the rays themselves (docs/models.md, "The observer's own
#: columns"), and the finer tables measured to bring the twilight sky within 3 % RMS of
#: ``montecarlo`` to sun -6 deg and 10 % to -12 deg.
TWILIGHT_REFERENCE_SETTINGS = {
    "twilight_single_scattering": True,
    "observer_single_scattering": True,
    "observer_columns": True,
    "scattering_mu_s_size": 96,
    "high_order_sphere_samples": 32,
}

# the parameters that change the tables (the cache key); observer altitude, turbidity (it
# enters through the atmosphere) and the wavelength count (through the grid) do not
_TABLE_SETTINGS = ("orders", "remaining_orders", "transmittance_mu_size", "transmittance_r_size",
                   "scattering_r_size", "scattering_mu_size", "scattering_mu_s_size",
                   "scattering_nu_size", "irradiance_mu_s_size", "irradiance_r_size",
                   "integration_samples", "sphere_samples", "high_order_sphere_samples",
                   "density_mu_s_size", "high_order_r_size", "high_order_mu_s_size",
                   "high_order_wavelengths", "stored_table", "order_table_divisor",
                   "max_sun_zenith_deg")


def _reach_note(first, end, reach) -> None:
    """One line on stderr: the observer's rays read density rows outside ``first..end-1``."""
    import sys

    print(f"skydome: the observer's rays read the scattering density's mu_s rows "
          f"{int(reach[:, 0].min())}..{int(reach[:, 1].max()) - 1}, outside the bound "
          f"{first}..{end - 1}; integrated again from the whole table", file=sys.stderr)


def clear_cache() -> int:
    """Remove every cached table set from the cache folder; returns the bytes freed."""
    from skydome.models.simulated.precomputed import _cache

    return _cache.clear_cache()
