"""Earth rotation, shape and frames (ECI, ECEF, geodetic, NED).

Conventions (docs/architecture.md): ECI has Z on the spin axis and X through the
Greenwich meridian at t = 0; ECEF rotates about Z at ``omega`` (rad/s), so
``C_ecef←eci(t) = R3(omega t)``. NED is north-east-down at the WGS84 geodetic
latitude/longitude. Geodetic latitude/longitude are in rad, heights in m above the
ellipsoid. All functions are compiled with numba and allocate only their small results.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from savant_cli import constants
from savant_cli.models import blocks
from savant_cli.models.fused import fma

_PARAMS = blocks.PARAMETERS.block("earth")
P_RE = _PARAMS.scalar("equatorial_radius", "m", "WGS84 semi-major axis")
P_E2 = _PARAMS.scalar("eccentricity_squared", "1", "WGS84 first eccentricity squared")
P_OMEGA_E = _PARAMS.scalar("rotation_rate", "rad/s", "Earth rotation rate about ECI Z")
_AUX = blocks.DIAGNOSTICS.block("earth")
A_ALT = _AUX.scalar("altitude", "m", "WGS84 geodetic altitude of the CG", blocks.Logged("altitude"))
A_LAT = _AUX.scalar("latitude", "rad", "WGS84 geodetic latitude", blocks.Logged("latitude"))
A_LON = _AUX.scalar("longitude", "rad", "longitude (east positive)", blocks.Logged("longitude"))
A_VEARTH = _AUX.scalar("earth_relative_speed", "m/s", "Earth-relative speed, no wind",
                       blocks.Logged("velocity_earth_relative"))


@njit(cache=True, error_model="numpy", inline="always")
def write_altitude(aux: np.ndarray, alt: float) -> None:
    """Write the altitude (m) into ``aux``: every evaluation, the engine's ground check reads it."""
    aux[A_ALT] = alt


@njit(cache=True, error_model="numpy", inline="always")
def write_diagnostics(aux: np.ndarray, x_ecef: float, y_ecef: float, lat_num: float, lat_den: float,
                      ex: float, ey: float, ez: float) -> None:
    """Write the geodetic latitude and longitude (rad; from :func:`geodetic_of_eci`'s
    by-products, ECEF m) and the Earth-relative speed (m/s; of the velocity ``ex, ey, ez``,
    ECI axes) into ``aux``."""
    lat, lon = latitude_longitude(x_ecef, y_ecef, lat_num, lat_den)
    aux[A_LAT] = lat
    aux[A_LON] = lon
    aux[A_VEARTH] = np.sqrt(ex * ex + ey * ey + ez * ez)


def build(inputs: blocks.ModelInputs, p: np.ndarray, tables: dict[str, np.ndarray]) -> None:
    """WGS84 shape and the Earth rate (``savant_cli.constants``)."""
    p[P_RE] = constants.WGS84_A
    p[P_E2] = constants.WGS84_E2
    p[P_OMEGA_E] = constants.OMEGA_EARTH


@njit(cache=True, error_model="numpy")
def dcm_eci_to_ecef(t_s: float, omega: float) -> np.ndarray:
    """Direction-cosine matrix ECI→ECEF, ``R3(omega t)``.

    Parameters
    ----------
    t_s : float
        Time since the ECI epoch (launch instant), s.
    omega : float
        Earth rotation rate, rad/s.

    Returns
    -------
    ndarray, shape (3, 3)
        ``r_ecef = C @ r_eci``.
    """
    th = omega * t_s
    c = np.cos(th)
    s = np.sin(th)
    m = np.zeros((3, 3))
    m[0, 0] = c
    m[0, 1] = s
    m[1, 0] = -s
    m[1, 1] = c
    m[2, 2] = 1.0
    return m


@njit(cache=True, error_model="numpy", inline="always")
def height_of_eci(t_s: float, rx: float, ry: float, rz: float, omega: float, a: float, e2: float) -> float:
    """Height above the ellipsoid (m) of an ECI point (m) at time ``t_s`` (s): the flight
    software's gain-schedule altitude (``omega`` rad/s, ``a`` m, ``e2`` as
    :func:`geodetic_height_sc`).

    The point is turned into ECEF axes by ``R3(omega t) r`` summed with fused
    multiply-adds, last column first: the arithmetic of the ``dcm_eci_to_ecef(t) @ r``
    BLAS product it replaces, bit for bit (``savant_cli/models/fused.py``), without the
    two arrays.
    """
    th = omega * t_s
    c = np.cos(th)
    s = np.sin(th)
    xe = fma(c, rx, fma(s, ry, 0.0 * rz))
    ye = fma(-s, rx, fma(c, ry, 0.0 * rz))
    ze = fma(0.0, rx, fma(0.0, ry, 1.0 * rz))
    return geodetic_height_sc(xe, ye, ze, a, e2)[0]


@njit(cache=True, error_model="numpy")
def eci_to_ecef(r_eci: np.ndarray, t_s: float, omega: float) -> np.ndarray:
    """Rotate a vector from ECI to ECEF axes at time ``t_s`` (s); ``omega`` in rad/s."""
    th = omega * t_s
    c = np.cos(th)
    s = np.sin(th)
    out = np.empty(3)
    out[0] = c * r_eci[0] + s * r_eci[1]
    out[1] = -s * r_eci[0] + c * r_eci[1]
    out[2] = r_eci[2]
    return out


@njit(cache=True, error_model="numpy")
def ecef_to_eci(r_ecef: np.ndarray, t_s: float, omega: float) -> np.ndarray:
    """Rotate a vector from ECEF to ECI axes at time ``t_s`` (s); ``omega`` in rad/s."""
    th = omega * t_s
    c = np.cos(th)
    s = np.sin(th)
    out = np.empty(3)
    out[0] = c * r_ecef[0] - s * r_ecef[1]
    out[1] = s * r_ecef[0] + c * r_ecef[1]
    out[2] = r_ecef[2]
    return out


@njit(cache=True, error_model="numpy")
def geodetic_to_ecef(lat_rad: float, lon_rad: float, h_m: float, a: float,
                     e2: float) -> np.ndarray:
    """ECEF position of a geodetic point.

    Parameters
    ----------
    lat_rad, lon_rad : float
        Geodetic latitude and longitude, rad.
    h_m : float
        Height above the ellipsoid, m.
    a : float
        Ellipsoid semi-major axis, m.
    e2 : float
        First eccentricity squared.

    Returns
    -------
    ndarray, shape (3,)
        Position in ECEF, m.
    """
    sl = np.sin(lat_rad)
    cl = np.cos(lat_rad)
    n = a / np.sqrt(1.0 - e2 * sl * sl)      # prime-vertical radius of curvature
    out = np.empty(3)
    out[0] = (n + h_m) * cl * np.cos(lon_rad)
    out[1] = (n + h_m) * cl * np.sin(lon_rad)
    out[2] = (n * (1.0 - e2) + h_m) * sl
    return out


@njit(cache=True, error_model="numpy")
def ecef_to_geodetic(r_ecef: np.ndarray, a: float, e2: float) -> tuple[float, float, float]:
    """Geodetic latitude, longitude and height of an ECEF position.

    Bowring's parametric-latitude iteration, written with ``atan2`` so that it is
    regular at the poles and on the equator. One iteration already gives < 1e-8 rad;
    the two used here reach round-off (< 1e-15 rad, < 1e-7 m) for heights from −5 km
    to 40 000 km at every latitude. The height uses
    ``h = p cos(lat) + z sin(lat) − a sqrt(1 − e2 sin²(lat))``, which is well
    conditioned at every latitude.

    Parameters
    ----------
    r_ecef : ndarray, shape (3,)
        Position in ECEF, m (not at the Earth's centre).
    a : float
        Ellipsoid semi-major axis, m.
    e2 : float
        First eccentricity squared.

    Returns
    -------
    lat_rad : float
        Geodetic latitude, rad, in [−π/2, π/2].
    lon_rad : float
        Longitude, rad, in (−π, π].
    h_m : float
        Height above the ellipsoid, m.
    """
    return geodetic_xyz(r_ecef[0], r_ecef[1], r_ecef[2], a, e2)


@njit(cache=True, error_model="numpy")
def geodetic_xyz(x: float, y: float, z: float, a: float, e2: float) -> tuple[float, float, float]:
    """:func:`ecef_to_geodetic` on scalar ECEF coordinates (m); no array is created."""
    lat, lon, h, _, _, _, _ = geodetic_xyz_sc(x, y, z, a, e2)
    return lat, lon, h


@njit(cache=True, error_model="numpy")
def geodetic_xyz_sc(x: float, y: float, z: float, a: float, e2: float):
    """Geodetic latitude, longitude (rad), height (m) and their sines and cosines.

    Returns
    -------
    tuple of float
        ``(lat, lon, h, sin lat, cos lat, sin lon, cos lon)``.
    """
    h, sl, cl, slon, clon, num, den = geodetic_height_sc(x, y, z, a, e2)
    return np.arctan2(num, den), np.arctan2(y, x), h, sl, cl, slon, clon


@njit(cache=True, error_model="numpy", inline="always")
def geodetic_height_sc(x: float, y: float, z: float, a: float, e2: float):
    """Height above the ellipsoid (m) and the sines and cosines of the geodetic latitude
    and longitude of an ECEF point (m), without the angles themselves.

    Bowring's iteration on the parametric latitude, written with normalised vectors in
    place of ``arctan2``/``sin``/``cos`` pairs (the same numbers, a third of the cost on
    the plant's hot path, which needs the sines and cosines for the wind rotation but the
    angles only for its diagnostics). The latitude is ``atan2(num, den)``.

    Returns
    -------
    tuple of float
        ``(h, sin lat, cos lat, sin lon, cos lon, num, den)``.
    """
    p = np.sqrt(x * x + y * y)
    if p > 0.0:
        slon, clon = y / p, x / p
    else:
        slon, clon = 0.0, 1.0
    sqrt1me2 = np.sqrt(1.0 - e2)              # b / a
    b = a * sqrt1me2
    ep2b = e2 / (1.0 - e2) * b                # e'^2 b
    e2a = e2 * a
    # parametric latitude β as (sin β, cos β), first guess from the spherical direction
    yb, xb = z, sqrt1me2 * p
    nb = np.sqrt(yb * yb + xb * xb)
    sb, cb = yb / nb, xb / nb
    num, den = z, p
    sl, cl = sb, cb
    for _ in range(2):
        num = z + ep2b * sb * sb * sb
        den = p - e2a * cb * cb * cb
        nl = np.sqrt(num * num + den * den)
        sl, cl = num / nl, den / nl
        yb, xb = sqrt1me2 * sl, cl
        nb = np.sqrt(yb * yb + xb * xb)
        sb, cb = yb / nb, xb / nb
    h = p * cl + z * sl - a * np.sqrt(1.0 - e2 * sl * sl)
    return h, sl, cl, slon, clon, num, den


@njit(cache=True, error_model="numpy")
def dcm_ecef_to_ned(lat_rad: float, lon_rad: float) -> np.ndarray:
    """Direction-cosine matrix ECEF→NED at a geodetic latitude/longitude.

    Parameters
    ----------
    lat_rad, lon_rad : float
        Geodetic latitude and longitude, rad.

    Returns
    -------
    ndarray, shape (3, 3)
        Rows are the north, east and down unit vectors in ECEF axes;
        ``v_ned = C @ v_ecef``.
    """
    sl = np.sin(lat_rad)
    cl = np.cos(lat_rad)
    so = np.sin(lon_rad)
    co = np.cos(lon_rad)
    m = np.empty((3, 3))
    m[0, 0] = -sl * co
    m[0, 1] = -sl * so
    m[0, 2] = cl
    m[1, 0] = -so
    m[1, 1] = co
    m[1, 2] = 0.0
    m[2, 0] = -cl * co
    m[2, 1] = -cl * so
    m[2, 2] = -sl
    return m


@njit(cache=True, error_model="numpy")
def velocity_relative_eci(r_eci: np.ndarray, v_eci: np.ndarray, omega: float) -> np.ndarray:
    """Earth-relative velocity expressed in ECI axes, ``v − ω ẑ × r``.

    Parameters
    ----------
    r_eci : ndarray, shape (3,)
        Position, m, ECI.
    v_eci : ndarray, shape (3,)
        Inertial velocity, m/s, ECI.
    omega : float
        Earth rotation rate, rad/s.

    Returns
    -------
    ndarray, shape (3,)
        Velocity relative to the rotating Earth, m/s, in ECI axes.
    """
    out = np.empty(3)
    out[0], out[1], out[2] = earth_relative_velocity_xyz(r_eci[0], r_eci[1], v_eci[0], v_eci[1], v_eci[2], omega)
    return out


@njit(cache=True, error_model="numpy", inline="always")
def earth_relative_velocity_xyz(rx: float, ry: float, vx: float, vy: float, vz: float,
                                omega: float) -> tuple[float, float, float]:
    """:func:`velocity_relative_eci` on scalars (m, m/s; ``omega`` rad/s)."""
    return vx + omega * ry, vy - omega * rx, vz


@njit(cache=True, error_model="numpy", inline="always")
def geodetic_of_eci(t: float, rx: float, ry: float, rz: float, p: np.ndarray):
    """Geodetic position of an ECI point at mission time ``t`` (s).

    Returns
    -------
    tuple of float
        ``(h, sin lat, cos lat, sin lon, cos lon, cos ωt, sin ωt, x, y, num, den)``: the
        height (m), the sines and cosines the NED↔ECI rotations need, and what
        :func:`latitude_longitude` turns into the angles (only diagnostics need them).
    """
    th = p[P_OMEGA_E] * t
    ct, st = np.cos(th), np.sin(th)
    xe, ye = ct * rx + st * ry, -st * rx + ct * ry
    alt, sl, cl, so, co, num, den = geodetic_height_sc(xe, ye, rz, p[P_RE], p[P_E2])
    return alt, sl, cl, so, co, ct, st, xe, ye, num, den


@njit(cache=True, error_model="numpy", inline="always")
def latitude_longitude(xe: float, ye: float, num: float, den: float) -> tuple[float, float]:
    """Geodetic latitude and longitude (rad) from :func:`geodetic_of_eci`'s by-products."""
    return np.arctan2(num, den), np.arctan2(ye, xe)


@njit(cache=True, error_model="numpy", inline="always")
def earth_relative_velocity(rx: float, ry: float, vx: float, vy: float, vz: float,
                            p: np.ndarray) -> tuple[float, float, float]:
    """``v − ω_E ẑ × r``: velocity relative to the rotating Earth, ECI axes, m/s."""
    return earth_relative_velocity_xyz(rx, ry, vx, vy, vz, p[P_OMEGA_E])
