"""Physical constants and unit conversions, SI throughout.

Sources
-------
- WGS84: NIMA TR8350.2 (defining parameters ``a`` and ``1/f``; ``b`` and ``e²`` derived).
- Gravity: EGM2008 unnormalised zonal coefficients J2, J3, J4 and GM; WGS84 Earth rate.
- US Standard Atmosphere 1976 (NOAA/NASA/USAF, NOAA-S/T 76-1562), Table 2 constants;
  note the standard's gas constant is per mole here (``R_STAR`` in J/(mol·K) with
  ``M0`` in kg/mol), i.e. 8314.32 J/(kmol·K) and 28.9644 kg/kmol in the standard's units.
- Unit conversions: exact international definitions (foot, inch, pound), standard
  gravity for pound-force and slug.
"""

from __future__ import annotations

import math

# --------------------------------------------------------------------- WGS84 ellipsoid
WGS84_A: float = 6378137.0                      # semi-major axis, m
WGS84_INV_F: float = 298.257223563              # inverse flattening, -
WGS84_F: float = 1.0 / WGS84_INV_F              # flattening, -
WGS84_B: float = WGS84_A * (1.0 - WGS84_F)      # semi-minor axis, m (6356752.314245…)
WGS84_E2: float = WGS84_F * (2.0 - WGS84_F)     # first eccentricity squared, -

# --------------------------------------------------------------------- Earth gravity/rotation
MU_EARTH: float = 3.986004418e14                # gravitational parameter GM, m^3/s^2
OMEGA_EARTH: float = 7.292115e-5                # rotation rate about ECEF Z, rad/s
EGM2008_J2: float = 1.0826356666e-3             # zonal harmonic J2, -
EGM2008_J3: float = -2.5324736913e-6            # zonal harmonic J3, -
EGM2008_J4: float = -1.6199743058e-6            # zonal harmonic J4, -
G0: float = 9.80665                             # standard gravity, m/s^2

# --------------------------------------------------------------------- US Standard Atmosphere 1976
R0_US76: float = 6356766.0                      # effective Earth radius for geopotential, m
M0: float = 0.0289644                           # sea-level mean molecular weight, kg/mol
R_STAR: float = 8.31432                         # universal gas constant (US76 value), J/(mol K)
GAMMA_AIR: float = 1.4                          # ratio of specific heats, -
P0: float = 101325.0                            # sea-level pressure, Pa
T0: float = 288.15                              # sea-level temperature, K

# --------------------------------------------------------------------- unit conversions (to SI)
FT: float = 0.3048                              # m per foot
IN: float = 0.0254                              # m per inch
LBF: float = 4.4482216152605                    # N per pound-force
LBM: float = 0.45359237                         # kg per pound-mass
SLUG: float = LBF / FT                          # kg per slug (1 lbf·s²/ft, exactly; 14.5939029372 kg)
DEG: float = math.pi / 180.0                    # rad per degree
