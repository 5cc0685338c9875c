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

# Boltzmann constant [J/K] (CODATA 2018, exact).
K_BOLTZMANN = 1.380649e-23

# Mean apparent angular radius of the Sun [deg] (IAU nominal solar radius 695 700 km
# at 1 au = 149 597 870.7 km gives 0.2665 deg; Radiance uses 0.2665 for its 0.533 deg disc).
SUN_ANGULAR_RADIUS_DEG = 0.2665

# Solar radius NREL's SPA uses for the sun's upper limb at sunrise and sunset [deg]
# (Reda & Andreas 2004, eq. 42 and A.4: 0.26667 deg). Kept apart from the disc radius above.
SPA_SUN_RADIUS_DEG = 0.26667

#: Full angle of the solar disc in Radiance [deg]: gendaylit, gendaymtx and the
#: ``solar source sun`` line all use 0.533 deg (Ward, Radiance's gensky/gendaylit sources).
RADIANCE_SUN_ANGLE_DEG = 0.533

#: Radiance's luminous efficacy of equal-energy white [lm W^-1] (color.h WHTEFFICACY):
#: luminance = 179 x (0.265 R + 0.670 G + 0.065 B) in Radiance's units.
RADIANCE_WHITE_EFFICACY = 179.0

# Total solar irradiance at 1 au [W/m^2], one name per source:
# Gueymard 2018 (Solar Energy 168, 2-9: 1361.1 +- 0.5), the library's default;
SOLAR_CONSTANT_GUEYMARD2018 = 1361.1
# the World Radiation Centre value that Perez et al. 1990 fitted their clearness and
# brightness bins with (1367; also Radiance's gendaylit).
SOLAR_CONSTANT_WRC = 1367.0

# Dobson unit [molecules m^-2].
DOBSON_UNIT = 2.6867e20
