"""The sun: its position (given, or from place and time) and its disc.

``Sun(elevation_deg, azimuth_deg)`` places the sun directly; ``Sun.from_location(lat, lon,
time)`` computes its position with NREL's SPA (Reda & Andreas 2004, through pvlib) or with
the Preetham et al. 1999 appendix formula. Azimuth is measured from north towards east.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from skydome._validate import check_number
from skydome.constants import SUN_ANGULAR_RADIUS_DEG

__all__ = ["Sun"]


@dataclass(frozen=True)
class Sun:
    """The sun as seen by the observer.

    Parameters
    ----------
    elevation_deg : float
        Elevation above the horizon [deg], in [-90, 90]. Negative values put the sun
        below the horizon (twilight, night); models state what they do there.
    azimuth_deg : float
        Azimuth from north towards east [deg], any finite value (wrapped to [0, 360)).
    angular_radius_deg : float
        Apparent angular radius of the disc [deg], in (0, 5]; default 0.2665.
    distance_au : float
        Earth-sun distance [au], in [0.95, 1.05]; the extraterrestrial irradiance is
        scaled by 1/distance_au^2.
    """

    elevation_deg: float
    azimuth_deg: float
    angular_radius_deg: float = SUN_ANGULAR_RADIUS_DEG
    distance_au: float = 1.0

    def __post_init__(self):
        object.__setattr__(self, "elevation_deg",
                           check_number("elevation_deg", self.elevation_deg, -90.0, 90.0, "deg"))
        az = check_number("azimuth_deg", self.azimuth_deg, unit="deg")
        object.__setattr__(self, "azimuth_deg", az % 360.0)
        object.__setattr__(self, "angular_radius_deg",
                           check_number("angular_radius_deg", self.angular_radius_deg, 0.0, 5.0,
                                        "deg", low_open=True))
        object.__setattr__(self, "distance_au",
                           check_number("distance_au", self.distance_au, 0.95, 1.05, "au"))

    @property
    def zenith_deg(self) -> float:
        """Zenith angle [deg]."""
        return 90.0 - self.elevation_deg

    @property
    def direction(self) -> np.ndarray:
        """Unit vector towards the sun, shape (3,), East-North-Up."""
        from skydome.transport.geometry import direction_from_angles

        return direction_from_angles(self.elevation_deg, self.azimuth_deg)

    @property
    def solid_angle_sr(self) -> float:
        """Solid angle of the disc [sr]: 2 pi (1 - cos r)."""
        return 2.0 * np.pi * (1.0 - np.cos(np.radians(self.angular_radius_deg)))

    @property
    def irradiance_scale(self) -> float:
        """Factor 1/d^2 applied to the 1 au extraterrestrial irradiance."""
        return 1.0 / (self.distance_au * self.distance_au)
