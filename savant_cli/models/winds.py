"""Horizontal wind from an altitude profile (the ``winds`` config group).

The profile gives the velocity of the air relative to the Earth, toward north and east
(m/s), against geodetic altitude (m); it is interpolated linearly, held at its end
values beyond the table and multiplied by ``winds.scale``. The wind has no vertical
component. In the plant it is rotated NED → ECEF → ECI and subtracted from the
Earth-relative velocity to give the air-relative velocity the aerodynamics see::

    v_air = (v − ω_E ẑ × r) − C_ecef→eci C_ned→ecef w_ned

Source: the paper's wind input (SAVANT §III, KSC mean annual and strong-jet profiles).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from savant_cli.models import blocks
from savant_cli.models.interp import locate_at, tab, tab_offset

_PARAMS = blocks.PARAMETERS.block("winds")
P_SCALE = _PARAMS.scalar("scale", "1", "multiplier of the profile; 0 disables the wind")
_TABLES = blocks.TABLES.block("winds")
T_ALT = _TABLES.table("wind_alt", "m", "geodetic altitudes of the wind profile, increasing")
T_NORTH = _TABLES.table("wind_north", "m/s", "wind toward north at T_ALT")
T_EAST = _TABLES.table("wind_east", "m/s", "wind toward east at T_ALT")
_AUX = blocks.DIAGNOSTICS.block("winds")
A_WIND = _AUX.array("wind_ned", 3, "m/s", "wind north, east, down")


def build(inputs: blocks.ModelInputs, p: np.ndarray, tables: dict[str, np.ndarray]) -> None:
    """The ``winds`` group's profile and scale (a still placeholder profile when off)."""
    w = inputs.cfg.winds
    p[P_SCALE] = w.scale if w.enabled else 0.0
    if w.enabled:
        tables.update(wind_alt=np.asarray(w.profile.altitude_m, float), wind_north=np.asarray(w.profile.north_mps, float),
                      wind_east=np.asarray(w.profile.east_mps, float))
    else:
        tables.update(wind_alt=np.array([0.0, 1.0]), wind_north=np.zeros(2), wind_east=np.zeros(2))


@njit(cache=True, error_model="numpy", inline="always")
def wind_ned(alt_m: float, tb: np.ndarray, p: np.ndarray) -> tuple[float, float]:
    """Scaled wind toward north and east (m/s) at a geodetic altitude (m)."""
    sc = p[P_SCALE]
    o_w, n_w = tab(tb, T_ALT)
    iw, ww = locate_at(tb, o_w, n_w, alt_m)
    o_n = tab_offset(tb, T_NORTH) + iw
    o_e = tab_offset(tb, T_EAST) + iw
    return sc * ((1.0 - ww) * tb[o_n] + ww * tb[o_n + 1]), sc * ((1.0 - ww) * tb[o_e] + ww * tb[o_e + 1])


@njit(cache=True, error_model="numpy", inline="always")
def air_relative_velocity(alt_m: float, sl: float, cl: float, so: float, co: float, ct: float, st: float,
                          ex: float, ey: float, ez: float, tb: np.ndarray, p: np.ndarray):
    """Air-relative velocity in ECI axes (m/s) and the wind north, east (m/s).

    Parameters
    ----------
    alt_m : float
        Geodetic altitude, m.
    sl, cl, so, co : float
        Sine and cosine of the geodetic latitude and of the longitude.
    ct, st : float
        Cosine and sine of the Earth rotation angle ω_E t.
    ex, ey, ez : float
        Earth-relative velocity, ECI axes, m/s.

    Returns
    -------
    tuple of float
        ``(v_air_x, v_air_y, v_air_z, wind_north, wind_east)``.
    """
    if p[P_SCALE] == 0.0:
        return ex, ey, ez, 0.0, 0.0
    wn_n, wn_e = wind_ned(alt_m, tb, p)
    # NED → ECEF (north = (−sl·co, −sl·so, cl), east = (−so, co, 0)), then ECEF → ECI
    we_x = -sl * co * wn_n - so * wn_e
    we_y = -sl * so * wn_n + co * wn_e
    we_z = cl * wn_n
    return ex - (ct * we_x - st * we_y), ey - (st * we_x + ct * we_y), ez - we_z, wn_n, wn_e
