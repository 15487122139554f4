"""Propulsion: first-stage motor and upper-stage engine thrust, mass flow, propellant
states, and the thrust force and moment of a gimbaled nozzle.

First stage (solid motor): the mass flow is the load ``M`` spread over the burn in the
shape of the vacuum-thrust table ``F_tab(t)`` (mission time), and the vacuum thrust is
that flow at the motor's Isp::

    ṁ(t) = M F_tab(t) / I_tab,     F_vac(t) = g0 Isp_vac ṁ(t),     I_tab = ∫ F_tab dt

(zero outside the table's time span; trapezoidal ``I_tab`` is exact for the linear
interpolation). So ``∫ ṁ dt = M`` and the delivered vacuum impulse is ``g0 Isp_vac M``
by construction: the motor stops thrusting exactly when its propellant is gone, whatever
the load, Isp or burn rate (a burn-rate factor k compresses the table: ``k F_tab(k t)``).
For a consistent table (``I_tab = g0 Isp M``; the shipped Ares-I table within 0.007 %) the
nominal thrust is the table's. A liquid first stage instead burns like the upper stage:
``F_vac = k F_rated f(t − t_ign)`` with its start-up fraction ``f`` (ignition
``t_ign`` = minus the transient's length: full thrust at liftoff) and its throttle
setting ``k`` (``models/throttle.py``; 1 unthrottled), ``ṁ = F_vac / (g0 Isp)`` split
oxidizer : fuel by its mixture ratio, until either tank is empty or, after a cutoff
command at ``t_cut`` (a vehicle event shutting its engines down, ``sim/engine.py``), its
shutdown transient ends: the thrust decays linearly from the command over
``T_sd = 2 I_sd / F_rated`` (``I_sd`` its engines' summed shutdown impulse), the setting
held from the command on, so the impulse after it is ``k I_sd``. Upper stage (J-2X
class): ``F_vac = F_rated f(t − t_ign)`` with the start-up thrust fraction ``f`` from a
table; ``ṁ = F_vac / (g0 Isp)``, split LOX : LH2 by
the mixture ratio. After the cutoff command at ``t_cut`` the thrust decays linearly to
zero over ``T_sd = 2 I_sd / F_rated`` (the shutdown transient; ``I_sd`` the engine's
shutdown impulse, ``upper_stage.shutdown_impulse_Ns``), so the impulse delivered after
the command is ``I_sd`` (the transient starts at rated thrust, the start-up long over),
burning propellant at the same Isp and mixture ratio. Delivered thrust
``F = max(F_vac − p_amb A_exit, 0)``.

The thrust acts at the active stage's gimbal along the nozzle axis, turned by the
actuator angles plus the nozzle's null bias, minus the structure's flex rotation at the
gimbal (follower thrust)::

    F_b = F (cos δp cos δy, −sin δy, sin δp cos δy),     M_cg = r_cg→gimbal × F_b

with ``r_cg→gimbal = diag(−1, 1, −1)(gimbal − cg)`` (structure → body axes). Source:
SAVANT §III, "Propulsion" and "Thrust vector control".
"""

from __future__ import annotations

import numpy as np
from numba import njit

from savant_cli import constants
from savant_cli.models import blocks
from savant_cli.models.configurations import ENGINE_FIRST, ENGINE_UPPER
from savant_cli.models.interp import interp1_at, tab, tab_offset

G0 = constants.G0

GIMBAL = blocks.Record("gimbal point", ("x", "m", "structure x"), ("y", "m", "structure y"),
                       ("z", "m", "structure z"))
GIMBAL_X, GIMBAL_Y, GIMBAL_Z = GIMBAL.offsets

_PARAMS = blocks.PARAMETERS.block("propulsion")
P_ON = _PARAMS.scalar("on", "1", "1: thrust applied (environment.thrust)")
P_FS_ISP = _PARAMS.scalar("first_stage.isp_vac", "s", "first-stage vacuum specific impulse")
P_FS_EXIT_AREA = _PARAMS.scalar("first_stage.exit_area", "m^2", "first-stage nozzle exit area")
P_FS_FLOW_PER_THRUST = _PARAMS.scalar("first_stage.flow_per_table_thrust", "kg/(N*s)",
                                      "load / table impulse: mass flow per N of the thrust table")
P_FS_PROP_FULL = _PARAMS.scalar("first_stage.propellant_full", "kg", "first-stage propellant at liftoff")
P_FS_LIQUID = _PARAMS.scalar("first_stage.liquid", "1", "1: liquid engines (rated thrust, two tanks), 0: a motor")
P_FS_THRUST = _PARAMS.scalar("first_stage.thrust_vac", "N", "liquid first stage's rated vacuum thrust")
P_FS_MR = _PARAMS.scalar("first_stage.mixture_ratio", "1", "liquid first stage's oxidizer : fuel mass ratio")
P_FS_IGNITION = _PARAMS.scalar("first_stage.ignition_time", "s",
                               "liquid first stage's ignition, mission time (minus its start transient's length)")
P_FS_SHUTDOWN_TIME = _PARAMS.scalar("first_stage.shutdown_time", "s",
                                    "a liquid first stage's thrust decay after its cutoff command, 2 I_sd / F_rated")
P_FS_FUEL_TANK = _PARAMS.scalar("first_stage.fuel_state", "1",
                                "index in x of a liquid first stage's fuel (kg; its oxidizer at first_stage.tank_state;"
                                " read only when first_stage.liquid is 1)")
P_US_THRUST = _PARAMS.scalar("upper_stage.thrust_vac", "N", "upper-stage rated vacuum thrust")
P_US_ISP = _PARAMS.scalar("upper_stage.isp_vac", "s", "upper-stage vacuum specific impulse")
P_US_MR = _PARAMS.scalar("upper_stage.mixture_ratio", "1", "LOX : LH2 mass ratio")
P_US_EXIT_AREA = _PARAMS.scalar("upper_stage.exit_area", "m^2", "upper-stage nozzle exit area")
P_US_PROP_FULL = _PARAMS.scalar("upper_stage.propellant_full", "kg", "upper-stage LOX + LH2 at ignition")
P_US_SHUTDOWN_TIME = _PARAMS.scalar("upper_stage.shutdown_time", "s",
                                    "duration of the linear thrust decay after the cutoff command, 2 I_sd / F_rated")
P_FS_TANK = _PARAMS.scalar("first_stage.tank_state", "1",
                           "index in x of the first-stage motor's propellant, or a liquid stage's oxidizer (kg)")
P_US_OX_TANK = _PARAMS.scalar("upper_stage.oxidizer_state", "1", "index in x of the upper stage's LOX (kg)")
P_US_FUEL_TANK = _PARAMS.scalar("upper_stage.fuel_state", "1", "index in x of the upper stage's LH2 (kg)")
P_FS_CONFIGS = _PARAMS.scalar("first_stage.configurations", "1",
                              "configurations flown with the first stage attached: the sequence's first n")
P_US_RESTARTS = _PARAMS.scalar("upper_stage.restarts", "1", "1: the upper stage burns twice (its cutoff, a coast and "
                                                            "its restart: the vehicle's events), 0: once")
P_FS_GIMBAL = _PARAMS.record("first_stage.gimbal", GIMBAL, "first-stage gimbal point")
P_US_GIMBAL = _PARAMS.record("upper_stage.gimbal", GIMBAL, "upper-stage gimbal point")

_TABLES = blocks.TABLES.block("propulsion")
T_FS_TIME = _TABLES.table("fs_time", "s", "first-stage thrust table, mission time")
T_FS_THRUST = _TABLES.table("fs_thrust", "N", "first-stage vacuum thrust at T_FS_TIME")
T_FS_START_TIME = _TABLES.table("fs_start_time", "s", "liquid first stage's start transient, time since ignition")
T_FS_START_FRAC = _TABLES.table("fs_start_frac", "1", "fraction of rated thrust at T_FS_START_TIME")
T_US_START_TIME = _TABLES.table("us_start_time", "s", "upper-stage start transient, time since ignition")
T_US_START_FRAC = _TABLES.table("us_start_frac", "1", "fraction of rated thrust at T_US_START_TIME")
_AUX = blocks.DIAGNOSTICS.block("propulsion")
A_THRUST = _AUX.scalar("thrust", "N", "engine thrust (vacuum minus back-pressure loss)", blocks.Logged("thrust"))
A_THRUST_VAC = _AUX.scalar("thrust_vac", "N", "vacuum thrust of the burning engine (the sensed thrust)")
_DISCRETE = blocks.DISCRETE.block("propulsion")
D_FS_PEAK = _DISCRETE.scalar("first_stage_peak_thrust", "N",
                             "largest sensed first-stage vacuum thrust so far (the separation cue's reference)")
D_FS_LAST = _DISCRETE.scalar("first_stage_last_thrust", "N", "sensed first-stage vacuum thrust at the last step")
D_FS_IMPULSE = _DISCRETE.scalar("first_stage_impulse", "N*s",
                                "first-stage vacuum impulse delivered so far (trapezoid of the sensed thrust)")
D_US_SD_LAST = _DISCRETE.scalar("upper_stage_last_thrust", "N", "sensed upper-stage vacuum thrust at the last "
                                "step of the shutdown transient")
D_US_SD_IMPULSE = _DISCRETE.scalar("shutdown_impulse", "N*s", "upper-stage vacuum impulse delivered after the cutoff "
                                   "command (trapezoid of the sensed thrust)")
D_FS_PROP_SEP = _DISCRETE.scalar("first_stage_propellant_at_separation", "kg",
                                 "first-stage propellant left in the motor at separation (0 before)")
A_MOMENT = _AUX.array("moment", 3, "N*m", "thrust moment about the CG",
                      blocks.Logged("thrust_moment", ("x", "y", "z"), "body"))


@njit(cache=True, error_model="numpy", inline="always")
def write_diagnostics(aux: np.ndarray, thrust: float, thrust_vac: float, mx: float, my: float, mz: float) -> None:
    """Write the delivered and vacuum thrust (N) and the thrust moment about the CG (N·m,
    body axes) into ``aux``."""
    aux[A_THRUST] = thrust
    aux[A_THRUST_VAC] = thrust_vac
    aux[A_MOMENT] = mx
    aux[A_MOMENT + 1] = my
    aux[A_MOMENT + 2] = mz


def build(inputs: blocks.ModelInputs, p: np.ndarray, tables: dict[str, np.ndarray]) -> None:
    """Engine data of the vehicle; ``environment.thrust``."""
    fs, us = inputs.vehicle.first_stage, inputs.vehicle.upper_stage
    p[P_ON] = 1.0 if inputs.cfg.environment.thrust else 0.0
    p[P_FS_ISP] = fs.isp_vac_s
    p[P_FS_EXIT_AREA] = fs.nozzle_exit_area_m2
    p[P_FS_FLOW_PER_THRUST] = fs.propellant_kg / table_impulse(fs.thrust_time_s, fs.thrust_vac_N)
    p[P_FS_PROP_FULL] = fs.propellant_kg
    p[P_FS_CONFIGS] = inputs.vehicle.first_stage_configurations
    p[P_US_THRUST] = us.thrust_vac_N
    p[P_US_ISP] = us.isp_vac_s
    p[P_US_MR] = us.mixture_ratio
    p[P_US_EXIT_AREA] = us.nozzle_exit_area_m2
    p[P_US_PROP_FULL] = us.lox_kg + us.lh2_kg
    p[P_US_SHUTDOWN_TIME] = 2.0 * us.shutdown_impulse_Ns / us.thrust_vac_N
    p[P_US_RESTARTS] = 1.0 if inputs.vehicle.events.has("upper_stage_restart") else 0.0
    fs_tanks, (ox, fuel) = inputs.vehicle.first_stage_tanks, inputs.vehicle.upper_stage_tanks
    p[P_FS_TANK] = inputs.layout.tank(fs_tanks[0])
    p[P_US_OX_TANK] = inputs.layout.tank(ox)
    p[P_US_FUEL_TANK] = inputs.layout.tank(fuel)
    p[P_FS_GIMBAL:P_FS_GIMBAL + GIMBAL.size] = fs.gimbal_m
    p[P_US_GIMBAL:P_US_GIMBAL + GIMBAL.size] = us.gimbal_m
    tables.update(fs_time=fs.thrust_time_s, fs_thrust=fs.thrust_vac_N, us_start_time=us.startup_time_s,
                  us_start_frac=us.startup_fraction, fs_start_time=np.array([0.0, 1.0]),
                  fs_start_frac=np.array([1.0, 1.0]))  # the start tables: a motor never reads them
    if fs.liquid is not None:
        p[P_FS_LIQUID] = 1.0
        p[P_FS_FUEL_TANK] = inputs.layout.tank(fs_tanks[1])
        p[P_FS_THRUST] = fs.liquid.thrust_vac_N
        p[P_FS_MR] = fs.liquid.mixture_ratio
        p[P_FS_IGNITION] = -float(fs.liquid.startup_time_s[-1])
        p[P_FS_SHUTDOWN_TIME] = 2.0 * fs.liquid.shutdown_impulse_Ns / fs.liquid.thrust_vac_N
        tables.update(fs_start_time=fs.liquid.startup_time_s, fs_start_frac=fs.liquid.startup_fraction)


def table_impulse(time_s: np.ndarray, thrust_N: np.ndarray) -> float:
    """Impulse of a linearly interpolated thrust table (N·s): the trapezoidal integral,
    exact for the interpolation the plant uses."""
    return float(np.trapezoid(thrust_N, time_s))


@njit(cache=True, error_model="numpy", inline="always")
def first_stage_propellant(x: np.ndarray, p: np.ndarray) -> float:
    """The first stage's propellant remaining (kg): its motor's, or its oxidizer plus fuel."""
    if p[P_FS_LIQUID] == 0.0:
        return x[int(p[P_FS_TANK])]
    return x[int(p[P_FS_TANK])] + x[int(p[P_FS_FUEL_TANK])]


@njit(cache=True, error_model="numpy", inline="always")
def upper_stage_propellant(x: np.ndarray, p: np.ndarray) -> tuple[float, float]:
    """The upper stage's LOX and LH2 remaining (kg)."""
    return x[int(p[P_US_OX_TANK])], x[int(p[P_US_FUEL_TANK])]


@njit(cache=True, error_model="numpy", inline="always")
def first_stage_flow(x: np.ndarray, tb: np.ndarray, p: np.ndarray, t: float, throttle: float,
                     t_cut: float) -> tuple[float, float]:
    """Vacuum thrust (N) and mass flow (kg/s) of the first stage at mission time ``t``
    (s). A motor: ``ṁ = M F_tab(t) / I_tab``, ``F_vac = g0 Isp ṁ``, zero outside the
    table's time span and once its propellant state is empty. Liquid engines: ``F_vac =
    throttle F_rated f(t − t_ign)``, × the shutdown decay ``max(0, 1 − (t − t_cut)/T_sd)``
    once the cutoff command at ``t_cut`` (s; 0 or less: none yet) is given, ``ṁ = F_vac /
    (g0 Isp)``, zero once either tank is empty (``throttle``: the setting it burns at, 1
    unthrottled). The sequencer's sensed thrust (chamber pressure) is this ``F_vac``."""
    if p[P_FS_LIQUID] != 0.0:
        return liquid_first_stage_flow(x, tb, p, t, throttle, t_cut)
    return trace_flow(tb, T_FS_TIME, T_FS_THRUST, first_stage_propellant(x, p), p[P_FS_FLOW_PER_THRUST], p[P_FS_ISP],
                      t)


@njit(cache=True, error_model="numpy", inline="always")
def trace_flow(tb: np.ndarray, t_time: int, t_thrust: int, propellant_kg: float, flow_per_thrust: float,
               isp_vac_s: float, t: float) -> tuple[float, float]:
    """Vacuum thrust (N) and mass flow (kg/s) at mission time ``t`` (s) of a motor flown by
    its thrust table (time field ``t_time``, thrust field ``t_thrust``) holding
    ``propellant_kg``: ``ṁ = (M / I_tab) F_tab(t)`` (``flow_per_thrust`` = M / I_tab),
    ``F_vac = g0 Isp ṁ``; zero outside the table's time span and once the propellant is
    gone."""
    o_ft, n_ft = tab(tb, t_time)
    if propellant_kg <= 0.0 or t < tb[o_ft] or t > tb[o_ft + n_ft - 1]:
        return 0.0, 0.0
    mdot = flow_per_thrust * interp1_at(tb, o_ft, tab_offset(tb, t_thrust), n_ft, t)
    if not mdot > 0.0:
        return 0.0, 0.0
    return G0 * isp_vac_s * mdot, mdot


@njit(cache=True, error_model="numpy", inline="always")
def liquid_tank_dry(x: np.ndarray, p: np.ndarray) -> bool:
    """Whether a liquid first stage's oxidizer or fuel is gone (its engines then stop)."""
    return not (x[int(p[P_FS_TANK])] > 0.0 and x[int(p[P_FS_FUEL_TANK])] > 0.0)


@njit(cache=True, error_model="numpy")  # a call, not inlined: a motor's every step stays as short as it was
def liquid_first_stage_flow(x: np.ndarray, tb: np.ndarray, p: np.ndarray, t: float, throttle: float,
                            t_cut: float) -> tuple[float, float]:
    """:func:`first_stage_flow` of liquid engines."""
    if liquid_tank_dry(x, p):
        return 0.0, 0.0
    o_st, n_st = tab(tb, T_FS_START_TIME)
    f_vac = throttle * p[P_FS_THRUST] * interp1_at(tb, o_st, tab_offset(tb, T_FS_START_FRAC), n_st,
                                                  t - p[P_FS_IGNITION])
    if t_cut > 0.0 and t > t_cut:
        f_vac *= shutdown_decay(t - t_cut, p[P_FS_SHUTDOWN_TIME])
        if not f_vac > 0.0:
            return 0.0, 0.0
    return f_vac, f_vac / (G0 * p[P_FS_ISP])


@njit(cache=True, error_model="numpy", inline="always")
def upper_stage_thrust_vac(x: np.ndarray, tb: np.ndarray, p: np.ndarray, t: float, t_ign: float,
                           t_cut: float, setting: float) -> float:
    """Vacuum thrust of the upper-stage engine (N) at mission time ``t`` (s): the start-up
    fraction at ``t − t_ign`` × the rated thrust (× the throttle ``setting`` of a
    throttled stage, ``throttle.held_upper``), × the shutdown decay
    ``max(0, 1 − (t − t_cut)/T_sd)`` once the cutoff command at ``t_cut`` (s; 0 or less:
    none yet) is given (the setting held); zero once either tank is empty."""
    lox, lh2 = upper_stage_propellant(x, p)
    if not (lox > 0.0 and lh2 > 0.0):
        return 0.0
    o_st, n_st = tab(tb, T_US_START_TIME)
    f_vac = interp1_at(tb, o_st, tab_offset(tb, T_US_START_FRAC), n_st, t - t_ign) * p[P_US_THRUST]
    if setting != 1.0:
        f_vac *= setting
    if t_cut > 0.0 and t > t_cut:
        f_vac *= shutdown_decay(t - t_cut, p[P_US_SHUTDOWN_TIME])
    return f_vac


@njit(cache=True, error_model="numpy", inline="always")
def shutdown_decay(since_s: float, t_sd: float) -> float:
    """Fraction of the thrust at the cutoff command left ``since_s`` (s, > 0) after it: a
    linear decay to zero over the shutdown transient ``t_sd`` (s; 0: at once)."""
    return max(1.0 - since_s / t_sd, 0.0) if t_sd > 0.0 else 0.0


@njit(cache=True, error_model="numpy", inline="always")
def propellant_remaining(x: np.ndarray, p: np.ndarray, config: int) -> float:
    """Propellant of the burning configuration (kg): the first stage's while it is
    attached, LOX + LH2 after separation (the mass tables' argument)."""
    if config < p[P_FS_CONFIGS]:
        return first_stage_propellant(x, p)
    lox, lh2 = upper_stage_propellant(x, p)
    return lox + lh2


@njit(cache=True, error_model="numpy", inline="always")
def thrust_and_flow(x: np.ndarray, tb: np.ndarray, p: np.ndarray, engine: int, t: float, t_ign: float,
                    t_cut: float, throttle: float, fs_t_cut: float, pres: float,
                    us_throttle: float) -> tuple[float, float, float, float]:
    """Delivered thrust (N), the first- and upper-stage mass flows (kg/s) and the vacuum
    thrust of the burning engine (N).

    ``engine`` is the engine phase, ``t`` mission time (s), ``t_ign`` the upper-stage
    ignition time (s), ``t_cut`` its cutoff command time (s; 0 or less: none yet),
    ``throttle`` the first stage's setting (1 unthrottled), ``fs_t_cut`` a liquid first
    stage's cutoff command time (s; 0 or less: none yet), ``pres`` the ambient pressure
    (Pa), ``us_throttle`` the upper stage's setting (1 unthrottled).
    """
    thrust = 0.0
    f_vac = 0.0
    mdot_fs = 0.0
    mdot_us = 0.0
    if engine == ENGINE_FIRST:
        f_vac, mdot_fs = first_stage_flow(x, tb, p, t, throttle, fs_t_cut)
        if mdot_fs > 0.0:
            thrust = max(f_vac - pres * p[P_FS_EXIT_AREA], 0.0)
    elif engine == ENGINE_UPPER:
        f_vac = upper_stage_thrust_vac(x, tb, p, t, t_ign, t_cut, us_throttle)
        mdot_us = f_vac / (G0 * p[P_US_ISP])
        thrust = max(f_vac - pres * p[P_US_EXIT_AREA], 0.0)
    if p[P_ON] == 0.0:
        thrust = 0.0
    return thrust, mdot_fs, mdot_us, f_vac


@njit(cache=True, error_model="numpy", inline="always")
def propellant_rates(p: np.ndarray, mdot_fs: float, mdot_us: float) -> tuple[float, float, float, float]:
    """Derivatives of the first stage's motor (or oxidizer) and fuel (0 for a motor),
    and of the upper stage's LOX and LH2 propellant states (kg/s)."""
    mr = p[P_US_MR]
    dm_fs, dm_fs_fuel = -mdot_fs, 0.0
    if p[P_FS_LIQUID] != 0.0:
        r = p[P_FS_MR]
        dm_fs, dm_fs_fuel = -mdot_fs * r / (1.0 + r), -mdot_fs / (1.0 + r)
    return dm_fs, dm_fs_fuel, -mdot_us * mr / (1.0 + mr), -mdot_us / (1.0 + mr)


@njit(cache=True, error_model="numpy", inline="always")
def gimbal_arm(p: np.ndarray, engine: int, cgx: float, cgy: float, cgz: float) -> tuple[float, float, float]:
    """``r_cg→gimbal`` of the active stage in body axes (m); the CG in structure axes (m).
    The upper-stage gimbal is active from separation on (coast included)."""
    g = P_FS_GIMBAL if engine == ENGINE_FIRST else P_US_GIMBAL
    return -(p[g + GIMBAL_X] - cgx), p[g + GIMBAL_Y] - cgy, -(p[g + GIMBAL_Z] - cgz)


@njit(cache=True, error_model="numpy", inline="always")
def thrust_loads(thrust: float, pitch: float, yaw: float, rgx: float, rgy: float, rgz: float):
    """Thrust force (N) and its moment about the CG (N·m), body axes, for nozzle angles
    ``pitch``, ``yaw`` (rad, the thrust-line angles) at the arm ``r_cg→gimbal`` (m)."""
    if not thrust > 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    cdp, sdp = np.cos(pitch), np.sin(pitch)
    cdy, sdy = np.cos(yaw), np.sin(yaw)
    ftx = thrust * cdp * cdy
    fty = -thrust * sdy
    ftz = thrust * sdp * cdy
    return ftx, fty, ftz, rgy * ftz - rgz * fty, rgz * ftx - rgx * ftz, rgx * fty - rgy * ftx
