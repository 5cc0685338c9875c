"""Physical constants, each with its source.

SI units throughout (m, s, K, Pa, W, sr), wavelengths in nm at public boundaries.
"""

# Maximum luminous efficacy of radiation for photopic vision [lm/W]
# (CIE 015:2018; the SI definition of the candela fixes 683 lm/W at 540 THz).
K_M = 683.0

# Molecular number density of the standard atmosphere at sea level [m^-3]
# (survey eq. 5, after Preetham, Shirley & Smits 1999: 2.545e25 m^-3 at 288.15 K, 1013 mbar).
N_S_SURVEY = 2.545e25

# Refractive index of air in the visible (survey eq. 6, [Jac02]).
N_AIR_SURVEY = 1.000278

# Rayleigh scale height [m] (survey eq. 7, [NSTN93]: H0 = 7994 m).
H_RAYLEIGH = 7994.0

# Aerosol (Mie) scale height [m] (survey section 4, [NDKY96]: 1200 m).
H_MIE = 1200.0

# Mean Earth radius used by Bruneton 2017 and Nishita 1993 [m].
EARTH_RADIUS = 6360.0e3

# Top of the atmosphere above the ground [m] (Bruneton 2017 demo uses 60 km, Hillaire 100 km).
ATMOSPHERE_THICKNESS = 60.0e3

# Boltzmann constant [J/K] (CODATA 2018, exact).
K_BOLTZMANN = 1.380649e-23

# Loschmidt constant at 273.15 K, 101325 Pa [m^-3] (CODATA 2018).
LOSCHMIDT = 2.686780111e25

# Standard temperature and pressure of the US Standard Atmosphere 1976 at sea level.
T_STANDARD = 288.15  # [K]
P_STANDARD = 101325.0  # [Pa]

# Rayleigh depolarisation factor of air (Penndorf 1957; Bates 1984 gives 0.0279 at 550 nm).
RAYLEIGH_DEPOLARISATION = 0.0279

# Mean apparent angular radius of the Sun [deg] (IAU nominal solar radius 695 700 km
# at 1 au = 149 597 870.7 km gives 0.2665 deg; Radiance uses 0.2665 for its 0.533 deg disc).
SUN_ANGULAR_RADIUS_DEG = 0.2665

# Total solar irradiance at 1 au [W/m^2] (Kopp & Lean 2011).
SOLAR_CONSTANT = 1361.0

# Dobson unit [molecules m^-2].
DOBSON_UNIT = 2.6867e20
