"""Zonal gravity: point mass plus J2, J3 and J4.

The zonal terms depend only on the distance ``r`` and the coordinate ``z`` along the
spin axis, so the same expressions hold in ECI and ECEF (both have Z on the spin
axis); inputs and outputs are in whichever of the two frames the caller uses.

With ``s = z / r`` and the Legendre polynomials ``P2 = (3s² − 1)/2``,
``P3 = (5s³ − 3s)/2``, ``P4 = (35s⁴ − 30s² + 3)/8``, the potential is

    U = μ/r [1 − J2 (R/r)² P2(s) − J3 (R/r)³ P3(s) − J4 (R/r)⁴ P4(s)],

and the acceleration is its gradient ``a = ∇U`` (Vallado, *Fundamentals of
Astrodynamics and Applications*, 4th ed., eq. 8-30 and the J2–J4 accelerations).
Note ``U > 0``: the specific mechanical energy is ``½ v² − U``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from savant_cli import constants
from savant_cli.models import blocks

_PARAMS = blocks.PARAMETERS.block("gravity")
P_MU = _PARAMS.scalar("mu", "m^3/s^2", "Earth gravitational parameter")
P_J2 = _PARAMS.scalar("j2", "1", "unnormalised zonal coefficient J2 (EGM2008)")
P_J3 = _PARAMS.scalar("j3", "1", "unnormalised zonal coefficient J3 (EGM2008)")
P_J4 = _PARAMS.scalar("j4", "1", "unnormalised zonal coefficient J4 (EGM2008)")
P_ORDER = _PARAMS.scalar("order", "1", "highest zonal term used: 0 point mass, 2, 3 or 4")
_AUX = blocks.DIAGNOSTICS.block("gravity")
A_GRAV = _AUX.array("acceleration", 3, "m/s^2", "gravitational acceleration (J2-J4 zonal model)",
                    blocks.Logged("gravity_eci", ("x", "y", "z"), "ECI"))


@njit(cache=True, error_model="numpy", inline="always")
def write_diagnostics(aux: np.ndarray, gx: float, gy: float, gz: float) -> None:
    """Write the gravitational acceleration (m/s², ECI) into ``aux``."""
    aux[A_GRAV] = gx
    aux[A_GRAV + 1] = gy
    aux[A_GRAV + 2] = gz


def build(inputs: blocks.ModelInputs, p: np.ndarray, tables: dict[str, np.ndarray]) -> None:
    """EGM2008 zonal coefficients; ``environment.gravity_order``."""
    p[P_MU] = constants.MU_EARTH
    p[P_J2] = constants.EGM2008_J2
    p[P_J3] = constants.EGM2008_J3
    p[P_J4] = constants.EGM2008_J4
    p[P_ORDER] = inputs.cfg.environment.gravity_order


@njit(cache=True, error_model="numpy")
def gravity_zonal(r_eci: np.ndarray, mu: float, re: float, j2: float, j3: float,
                  j4: float) -> np.ndarray:
    """Gravitational acceleration of point mass + J2 + J3 + J4.

    Parameters
    ----------
    r_eci : ndarray, shape (3,)
        Position from the Earth's centre, m, in ECI (or ECEF) axes.
    mu : float
        Gravitational parameter, m^3/s^2.
    re : float
        Reference radius of the harmonics, m.
    j2, j3, j4 : float
        Unnormalised zonal coefficients (pass 0 to drop a term).

    Returns
    -------
    ndarray, shape (3,)
        Acceleration, m/s^2, in the same axes as ``r_eci``.
    """
    ax, ay, az = gravity_zonal_xyz(r_eci[0], r_eci[1], r_eci[2], mu, re, j2, j3, j4)
    out = np.empty(3)
    out[0] = ax
    out[1] = ay
    out[2] = az
    return out


@njit(cache=True, error_model="numpy")
def gravity_zonal_xyz(x: float, y: float, z: float, mu: float, re: float, j2: float, j3: float,
                      j4: float) -> tuple[float, float, float]:
    """:func:`gravity_zonal` on scalar coordinates (m), returning a tuple (m/s²)."""
    r2 = x * x + y * y + z * z
    r = np.sqrt(r2)
    zr2 = z * z / r2                      # (z/r)^2
    mu_r3 = mu / (r2 * r)

    # point mass
    kxy = -mu_r3
    kz = -mu_r3
    # J2
    if j2 != 0.0:
        c2 = -1.5 * j2 * mu_r3 * re * re / r2
        kxy += c2 * (1.0 - 5.0 * zr2)
        kz += c2 * (3.0 - 5.0 * zr2)
    # J3 (its z-term is not proportional to z, kept separately)
    az_extra = 0.0
    if j3 != 0.0:
        c3 = -2.5 * j3 * mu_r3 * re * re * re / (r2 * r2)
        kxy += c3 * (3.0 * z - 7.0 * z * zr2)
        az_extra = c3 * (6.0 * z * z - 7.0 * z * z * zr2 - 0.6 * r2)
    # J4
    if j4 != 0.0:
        c4 = 1.875 * j4 * mu_r3 * re * re * re * re / (r2 * r2)
        kxy += c4 * (1.0 - 14.0 * zr2 + 21.0 * zr2 * zr2)
        kz += c4 * (5.0 - 70.0 / 3.0 * zr2 + 21.0 * zr2 * zr2)

    return kxy * x, kxy * y, kz * z + az_extra


@njit(cache=True, error_model="numpy")
def gravity_potential(r: np.ndarray, mu: float, re: float, j2: float, j3: float,
                      j4: float) -> float:
    """Zonal gravitational potential ``U`` (with ``a = ∇U``, ``U > 0``).

    Parameters
    ----------
    r : ndarray, shape (3,)
        Position from the Earth's centre, m, in ECI or ECEF axes.
    mu, re, j2, j3, j4 : float
        As for :func:`gravity_zonal` (m^3/s^2, m, -, -, -).

    Returns
    -------
    float
        Potential, m^2/s^2.
    """
    rn = np.sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2])
    s = r[2] / rn
    s2 = s * s
    q = re / rn
    p2 = 0.5 * (3.0 * s2 - 1.0)
    p3 = 0.5 * (5.0 * s2 - 3.0) * s
    p4 = 0.125 * ((35.0 * s2 - 30.0) * s2 + 3.0)
    return mu / rn * (1.0 - q * q * (j2 * p2 + q * (j3 * p3 + q * j4 * p4)))


@njit(cache=True, error_model="numpy", inline="always")
def gravity_at(rx: float, ry: float, rz: float, p: np.ndarray, re: float) -> tuple[float, float, float]:
    """Gravity (m/s², ECI) at an ECI position (m) with the configured zonal order; ``re``
    is the harmonics' reference radius (the WGS84 equatorial radius)."""
    order = p[P_ORDER]
    return gravity_zonal_xyz(rx, ry, rz, p[P_MU], re, p[P_J2] if order >= 2 else 0.0,
                             p[P_J3] if order >= 3 else 0.0, p[P_J4] if order >= 4 else 0.0)
