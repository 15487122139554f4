"""Horizontal wind from an altitude profile, with an optional discrete gust and wind
shear (the ``winds`` config group).

**Profile.** The velocity of the air relative to the Earth, toward north and east (m/s),
against geodetic altitude (m); interpolated linearly, held at its end values beyond the
table and multiplied by ``winds.scale``. No vertical component.

**Shear** (``winds.shear``). A build-up of the horizontal wind by ``Δv`` (m/s) toward the
azimuth ψ_s (deg from north, the air moving toward it) over the altitude band
``[h_b, h_b + Δh]``, added to the profile (not scaled by ``winds.scale``)::

    w_s(h) = Δv · r((h − h_b)/Δh) − Δv · r((h − h_b − Δh)/Δh_r)       (Δh_r > 0)
    w_s(h) = Δv · r((h − h_b)/Δh)                                      (Δh_r = 0)

with the ramp ``r(x) = 0`` for ``x ≤ 0``, ``1`` for ``x ≥ 1`` and, between,
``r(x) = x`` (``shape: linear``) or ``r(x) = ½(1 − cos πx)`` (``shape: cosine``). With
``return_thickness_m`` Δh_r = 0 the added wind stays at Δv above the band; with Δh_r > 0
it falls back to zero over ``[h_b + Δh, h_b + Δh + Δh_r]`` with the same ramp, so the
profile above is untouched. Either way the wind changes by exactly Δv across the band.

**Discrete gust** (``winds.gust``). A 1 − cos pulse of amplitude A (m/s) over a full
length d, in the gust coordinate s measured from the onset::

    g(s) = ½ (1 − cos(2π s / d))   for 0 ≤ s ≤ d,   0 otherwise
    v_gust(s) = A g(s)

so the gust peaks at A at mid-length s = d/2, its build-up length (onset to peak) is
d/2, and ∫ v_gust ds = A d / 2. ``d`` is the *whole* thickness of the gust: the
MIL-F-8785C form ``(V_m/2)(1 − cos(π x/d_m))`` with build-up length d_m is the first
half of this pulse with d = 2 d_m. ``onset: altitude``: s = h − h₀ (geodetic altitude, m;
d = ``length_m``, the gust's thickness in altitude); ``onset: time``: s = t − t₀ (mission
time, s; d = ``duration_s``).

Direction, ``frame: ned``: horizontal, the air moving toward the azimuth ψ
(``direction_deg`` from north, clockwise), ``w = v_gust (cos ψ, sin ψ, 0)`` NED.
``frame: flight_path``: across the Earth-relative velocity. With the flight-path frame
x_f = v̂ (Earth-relative velocity), z_f the unit component of the local down
perpendicular to v̂ (below the path, in the vertical plane through it) and
y_f = z_f × x_f (horizontal, right of the path), the air moves along

    w = −v_gust (cos φ z_f + sin φ y_f)

with the clock angle φ (``direction_deg``) about the path: φ = 0 moves the air up across
the path, which for a vehicle flying wings-level (body z toward the local down, as the
stored profile and PEG command it) raises the angle of attack by about A/V; φ = 90° moves
it to the left, raising the sideslip; 180° and 270° the opposites. Where the path is
within 1e-6 rad of vertical (or the Earth-relative speed below 1 m/s) the frame is
undefined and the flight-path gust is zero.

In the plant the total wind (profile + shear + gust, NED) is rotated NED → ECEF → ECI and
subtracted from the Earth-relative velocity to give the air-relative velocity the
aerodynamics see::

    v_air = (v − ω_E ẑ × r) − C_ecef→eci C_ned→ecef w_ned

Cost: the gust and shear are skipped by one parameter test (``winds.discrete_on``); with
both off the arithmetic is the profile's alone, bit for bit.

Sources: the paper's wind input (SAVANT §III, KSC mean annual and strong-jet profiles);
the gust and shear construction in docs/models.md ("Winds").
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from savant_cli.models import blocks
from savant_cli.models.interp import locate_at, tab, tab_offset

_PARAMS = blocks.PARAMETERS.block("winds")
P_SCALE = _PARAMS.scalar("scale", "1", "multiplier of the profile; 0 disables the wind")
P_DISCRETE = _PARAMS.scalar("discrete_on", "1", "1: a gust or a shear is on (0: the profile alone)")
P_GUST_AMP = _PARAMS.scalar("gust_amplitude", "m/s", "discrete gust: peak speed A (0: no gust)")
P_GUST_BY_TIME = _PARAMS.scalar("gust_onset_by_time", "1", "discrete gust: 0 onset and length in altitude, 1 in time")
P_GUST_START = _PARAMS.scalar("gust_onset", "m, s", "discrete gust: onset altitude h₀ (m) or time t₀ (s)")
P_GUST_LENGTH = _PARAMS.scalar("gust_length", "m, s", "discrete gust: full 1 − cos length d, altitude (m) or time (s)")
P_GUST_FRAME = _PARAMS.scalar("gust_frame", "1", "discrete gust: 0 NED azimuth, 1 across the flight path")
P_GUST_COS = _PARAMS.scalar("gust_direction_cos", "1", "discrete gust: cosine of the azimuth or clock angle")
P_GUST_SIN = _PARAMS.scalar("gust_direction_sin", "1", "discrete gust: sine of the azimuth or clock angle")
P_SHEAR_DV = _PARAMS.scalar("shear_delta", "m/s", "wind shear: build-up Δv (0: no shear)")
P_SHEAR_BASE = _PARAMS.scalar("shear_base", "m", "wind shear: bottom of the band h_b, geodetic")
P_SHEAR_THICK = _PARAMS.scalar("shear_thickness", "m", "wind shear: band thickness Δh")
P_SHEAR_RETURN = _PARAMS.scalar("shear_return", "m", "wind shear: thickness Δh_r of the fall back to 0 (0: held)")
P_SHEAR_COSINE = _PARAMS.scalar("shear_cosine", "1", "wind shear: 0 linear ramp, 1 ½(1 − cos) ramp")
P_SHEAR_NORTH = _PARAMS.scalar("shear_north", "1", "wind shear: cosine of its azimuth (north component of a unit Δv)")
P_SHEAR_EAST = _PARAMS.scalar("shear_east", "1", "wind shear: sine of its azimuth (east component of a unit Δv)")
_TABLES = blocks.TABLES.block("winds")
T_ALT = _TABLES.table("wind_alt", "m", "geodetic altitudes of the wind profile, increasing")
T_NORTH = _TABLES.table("wind_north", "m/s", "wind toward north at T_ALT")
T_EAST = _TABLES.table("wind_east", "m/s", "wind toward east at T_ALT")
_AUX = blocks.DIAGNOSTICS.block("winds")
A_WIND = _AUX.array("wind_ned", 3, "m/s", "wind velocity",  # profile, shear and gust
                    blocks.Logged("wind_ned", ("north", "east", "down"), "NED"))


@njit(cache=True, error_model="numpy", inline="always")
def write_diagnostics(aux: np.ndarray, wind_n: float, wind_e: float, wind_d: float) -> None:
    """Write the wind (m/s, north, east, down) into ``aux``."""
    aux[A_WIND] = wind_n
    aux[A_WIND + 1] = wind_e
    aux[A_WIND + 2] = wind_d


def build(inputs: blocks.ModelInputs, p: np.ndarray, tables: dict[str, np.ndarray]) -> None:
    """The ``winds`` group's profile and scale (a still placeholder profile when off), and
    its gust and shear."""
    w = inputs.cfg.winds
    p[P_SCALE] = w.scale if w.enabled else 0.0
    if w.enabled:
        tables.update(wind_alt=np.asarray(w.profile.altitude_m, float), wind_north=np.asarray(w.profile.north_mps, float),
                      wind_east=np.asarray(w.profile.east_mps, float))
    else:
        tables.update(wind_alt=np.array([0.0, 1.0]), wind_north=np.zeros(2), wind_east=np.zeros(2))
    g, s = w.gust, w.shear
    gust_on = g.enabled and g.amplitude_mps != 0.0
    shear_on = s.enabled and s.delta_mps != 0.0
    p[P_DISCRETE] = 1.0 if (gust_on or shear_on) else 0.0
    if gust_on:
        by_time = g.onset == "time"
        p[P_GUST_AMP] = g.amplitude_mps
        p[P_GUST_BY_TIME] = 1.0 if by_time else 0.0
        p[P_GUST_START] = g.onset_time_s if by_time else g.onset_altitude_m
        p[P_GUST_LENGTH] = g.duration_s if by_time else g.length_m
        p[P_GUST_FRAME] = 1.0 if g.frame == "flight_path" else 0.0
        p[P_GUST_COS] = math.cos(math.radians(g.direction_deg))
        p[P_GUST_SIN] = math.sin(math.radians(g.direction_deg))
    if shear_on:
        p[P_SHEAR_DV] = s.delta_mps
        p[P_SHEAR_BASE] = s.base_altitude_m
        p[P_SHEAR_THICK] = s.thickness_m
        p[P_SHEAR_RETURN] = s.return_thickness_m
        p[P_SHEAR_COSINE] = 1.0 if s.shape == "cosine" else 0.0
        p[P_SHEAR_NORTH] = math.cos(math.radians(s.direction_deg))
        p[P_SHEAR_EAST] = math.sin(math.radians(s.direction_deg))


@njit(cache=True, error_model="numpy", inline="always")
def wind_ned(alt_m: float, tb: np.ndarray, p: np.ndarray) -> tuple[float, float]:
    """Scaled wind toward north and east (m/s) at a geodetic altitude (m)."""
    sc = p[P_SCALE]
    o_w, n_w = tab(tb, T_ALT)
    iw, ww = locate_at(tb, o_w, n_w, alt_m)
    o_n = tab_offset(tb, T_NORTH) + iw
    o_e = tab_offset(tb, T_EAST) + iw
    return sc * ((1.0 - ww) * tb[o_n] + ww * tb[o_n + 1]), sc * ((1.0 - ww) * tb[o_e] + ww * tb[o_e + 1])


@njit(cache=True, error_model="numpy")
def one_minus_cosine(s: float, d: float) -> float:
    """The unit 1 − cos pulse ``½(1 − cos(2π s/d))`` on ``0 ≤ s ≤ d``, 0 outside (peak 1
    at ``s = d/2``, area ``d/2``)."""
    if s <= 0.0 or s >= d:
        return 0.0
    return 0.5 * (1.0 - math.cos(2.0 * math.pi * s / d))


@njit(cache=True, error_model="numpy")
def ramp(x: float, cosine: bool) -> float:
    """The shear ramp: 0 for ``x ≤ 0``, 1 for ``x ≥ 1``, between ``x`` (linear) or
    ``½(1 − cos πx)``."""
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    return 0.5 * (1.0 - math.cos(math.pi * x)) if cosine else x


@njit(cache=True, error_model="numpy")
def shear_speed(alt_m: float, p: np.ndarray) -> float:
    """The shear's added wind speed (m/s, along its azimuth) at a geodetic altitude."""
    dv = p[P_SHEAR_DV]
    if dv == 0.0:
        return 0.0
    cosine = p[P_SHEAR_COSINE] != 0.0
    x = (alt_m - p[P_SHEAR_BASE]) / p[P_SHEAR_THICK]
    v = dv * ramp(x, cosine)
    if p[P_SHEAR_RETURN] > 0.0:
        v -= dv * ramp((alt_m - p[P_SHEAR_BASE] - p[P_SHEAR_THICK]) / p[P_SHEAR_RETURN], cosine)
    return v


@njit(cache=True, error_model="numpy")
def gust_speed(t: float, alt_m: float, p: np.ndarray) -> float:
    """The discrete gust's speed A·g(s) (m/s) at mission time ``t`` and altitude ``alt_m``."""
    amp = p[P_GUST_AMP]
    if amp == 0.0:
        return 0.0
    s = (t if p[P_GUST_BY_TIME] != 0.0 else alt_m) - p[P_GUST_START]
    return amp * one_minus_cosine(s, p[P_GUST_LENGTH])


@njit(cache=True, error_model="numpy")
def discrete_ned(t: float, alt_m: float, vn: float, ve: float, vd: float, p: np.ndarray) -> tuple[float, float, float]:
    """Shear plus gust, NED (m/s), given the Earth-relative velocity in NED (m/s; the
    flight-path frame of a ``frame: flight_path`` gust)."""
    sv = shear_speed(alt_m, p)
    wn = sv * p[P_SHEAR_NORTH]
    we = sv * p[P_SHEAR_EAST]
    wd = 0.0
    g = gust_speed(t, alt_m, p)
    if g != 0.0:
        c, s = p[P_GUST_COS], p[P_GUST_SIN]
        if p[P_GUST_FRAME] == 0.0:
            wn += g * c
            we += g * s
        else:
            speed = math.sqrt(vn * vn + ve * ve + vd * vd)
            if speed > 1.0:
                xn, xe, xd = vn / speed, ve / speed, vd / speed
                # z_f: the local down (0, 0, 1) less its component along the path
                zn, ze, zd = -xd * xn, -xd * xe, 1.0 - xd * xd
                zl = math.sqrt(zn * zn + ze * ze + zd * zd)
                if zl > 1e-6:
                    zn, ze, zd = zn / zl, ze / zl, zd / zl
                    yn = ze * xd - zd * xe  # y_f = z_f × x_f
                    ye = zd * xn - zn * xd
                    yd = zn * xe - ze * xn
                    wn -= g * (c * zn + s * yn)
                    we -= g * (c * ze + s * ye)
                    wd -= g * (c * zd + s * yd)
    return wn, we, wd


@njit(cache=True, error_model="numpy", inline="always")
def air_relative_velocity(t: float, alt_m: float, sl: float, cl: float, so: float, co: float, ct: float, st: float,
                          ex: float, ey: float, ez: float, tb: np.ndarray, p: np.ndarray):
    """Air-relative velocity in ECI axes (m/s) and the wind north, east, down (m/s).

    Parameters
    ----------
    t : float
        Mission time, s (a gust with ``onset: time``).
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
        ``(v_air_x, v_air_y, v_air_z, wind_north, wind_east, wind_down)``.
    """
    if p[P_SCALE] == 0.0 and p[P_DISCRETE] == 0.0:
        return ex, ey, ez, 0.0, 0.0, 0.0
    wn_n, wn_e = wind_ned(alt_m, tb, p)
    if p[P_DISCRETE] != 0.0:
        # the Earth-relative velocity: ECI → ECEF axes → NED
        vx = ct * ex + st * ey
        vy = -st * ex + ct * ey
        vn = -sl * co * vx - sl * so * vy + cl * ez
        ve = -so * vx + co * vy
        vd = -cl * co * vx - cl * so * vy - sl * ez
        dn, de, dd = discrete_ned(t, alt_m, vn, ve, vd, p)
        wn_n += dn
        wn_e += de
        we_x = -sl * co * wn_n - so * wn_e - cl * co * dd
        we_y = -sl * so * wn_n + co * wn_e - cl * so * dd
        we_z = cl * wn_n - sl * dd
        return ex - (ct * we_x - st * we_y), ey - (st * we_x + ct * we_y), ez - we_z, wn_n, wn_e, dd
    # NED → ECEF (north = (−sl·co, −sl·so, cl), east = (−so, co, 0)), then ECEF → ECI
    we_x = -sl * co * wn_n - so * wn_e
    we_y = -sl * so * wn_n + co * wn_e
    we_z = cl * wn_n
    return ex - (ct * we_x - st * we_y), ey - (st * we_x + ct * we_y), ez - we_z, wn_n, wn_e, 0.0
