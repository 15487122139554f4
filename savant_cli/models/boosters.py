"""Strap-on boosters: identical solid motors on the first stage, lit at liftoff, with
fixed or gimbaled nozzles, jettisoned together (docs/vehicles.md, "Strap-on boosters").

Each booster burns its own propellant state in the shape of the boosters' vacuum-thrust
table exactly as the first-stage motor does (``propulsion.trace_flow``, the one kernel
of both: ``ṁᵢ = kᵢ M F_tab(kᵢ t) / I_tab``, ``F_vac,i = g0 Isp ṁᵢ``, with its own
burn-rate factor ``kᵢ``, 1 unless dispersed: load and impulse conserved) and pushes
``max(F_vac,i − p A_exit, 0)`` along its nozzle's fixed cant at its nozzle point (the
thrust line of ``propulsion.thrust_loads``, its direction computed once). While the
boosters are attached (the liftoff configuration, number 0) the vehicle's mass
properties are that configuration's table, which holds them at their full load, with
each booster's full-load row exchanged for its own table's row at its own propellant
(:func:`exchange`).

With booster TVC each nozzle gimbals in pitch and yaw on its own channel pair (after the
first stage's engines', ``actuator.P_BOOSTER_CHANNEL``), commanded by the control mixer
together with the first stage's engines while the boosters are attached
(``models/cluster.py``): its thrust line is its limited actuator angles plus the
boosters' null bias plus its cant, ``propulsion.thrust_loads`` at its nozzle, and its
moving nozzle reacts on the vehicle at its nozzle point (``twd.moving_mass_loads`` of
the boosters' record).

Its discrete fields are declared after every other model's (``models/__init__.py``):
older staging-state files stay valid.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from savant_cli.models import actuator, blocks, flex, twd
from savant_cli.models.interp import tab_offset
from savant_cli.models.mass import N_COLUMNS, stacked_row, stacked_tables
from savant_cli.models.propulsion import P_ON, table_impulse, thrust_loads, trace_flow

_PARAMS = blocks.PARAMETERS.block("boosters")
P_N_BOOSTERS = _PARAMS.scalar("count", "1", "strap-on boosters (0: none)")
P_TANK = _PARAMS.scalar("tank_state", "1", "index in x of the first booster's propellant (kg; the others follow it)")
P_ISP = _PARAMS.scalar("isp_vac", "s", "each booster's vacuum specific impulse")
P_EXIT_AREA = _PARAMS.scalar("exit_area", "m^2", "each booster's nozzle exit area")
P_FLOW_PER_THRUST = _PARAMS.scalar("flow_per_table_thrust", "kg/(N*s)", "each booster's load / table impulse")

_TABLES = blocks.TABLES.block("boosters")
T_TIME = _TABLES.table("booster_time", "s", "each booster's thrust table, mission time")
T_THRUST = _TABLES.table("booster_thrust", "N", "each booster's vacuum thrust at T_TIME")
MOUNT = blocks.Record("booster nozzle", ("x", "m", "structure x"), ("y", "m", "structure y"),
                      ("z", "m", "structure z"), ("thrust_x", "1", "unit thrust direction at its fixed cant, body x"),
                      ("thrust_y", "1", "body y"), ("thrust_z", "1", "body z"))
N_MOUNT = MOUNT.size
T_MOUNT = _TABLES.table("booster_mount", "m, 1", "(boosters, MOUNT) each booster's nozzle and thrust direction")
T_MASS_PROP = _TABLES.table("booster_mass_prop", "kg", "(boosters, n) each booster's own propellant, ascending "
                            "(padded)")
T_MASS_DATA = _TABLES.table("booster_mass_data", "kg, m, kg*m^2", "(boosters, n, mass COLUMNS) each booster's own "
                            "mass-properties rows")
T_MASS_LEN = _TABLES.table("booster_mass_len", "1", "(boosters,) valid rows per booster")
T_RATE = _TABLES.table("booster_burn_rate", "1", "(boosters,) each booster's burn-rate factor k: k F_tab(k t)")
T_CANT = _TABLES.table("booster_cant", "rad", "(boosters, 2) each booster's nozzle cant at null, pitch and yaw")
T_FULL = _TABLES.table("booster_full", "kg, m, kg*m^2", "(boosters, mass COLUMNS) each booster's own row at its full "
                       "load (inertia as tensor elements)")

_AUX = blocks.DIAGNOSTICS.block("boosters")
A_THRUST = _AUX.scalar("thrust", "N", "the strap-on boosters' delivered thrust, summed",
                       blocks.Logged("booster_thrust"))
#: Gimbaled boosters whose angles are logged (the first ones of a vehicle with more).
MAX_LOGGED_GIMBALS = 8


def _gimbal_columns(model) -> tuple[str, ...]:
    """``booster_<n>_pitch``, ``booster_<n>_yaw`` of each logged booster (1-based, the
    vehicle file's order)."""
    n = min(int(model.p[P_N_BOOSTERS]), MAX_LOGGED_GIMBALS)
    return tuple(f"booster_{i + 1}_{axis}" for i in range(n) for axis in ("pitch", "yaw"))


A_GIMBAL = _AUX.array("gimbal_angles", 2 * MAX_LOGGED_GIMBALS, "rad",
                      f"each booster's limited gimbal angles, pitch then yaw, the first {MAX_LOGGED_GIMBALS} boosters "
                      f"(0: fixed nozzles, or jettisoned)",
                      blocks.Logged("booster_gimbal_angle", (), "body",
                                    lambda model: model.p[actuator.P_BOOSTER_CHANNEL] >= 0.0, _gimbal_columns))
A_NOZZLE_LOADS = _AUX.array("nozzle_loads", 5 * flex.MAX_BOOSTERS, "N, N*m",
                            "each booster's loads on the structure at its nozzle for the flexible body's boosted "
                            "modal sets (0 otherwise): the thrust and the moving nozzle's reaction force (body x, y, "
                            "z), its reaction torque (body y, z)")
_DISCRETE = blocks.DISCRETE.block("boosters")
D_PROP_JET = _DISCRETE.scalar("propellant_at_jettison", "kg",
                              "the boosters' propellant left at their jettison, summed (0 before)")
D_PEAK = _DISCRETE.scalar("peak_thrust", "N", "largest sensed vacuum thrust so far of the booster whose thrust "
                          "fraction the boosters' jettison watches")


@njit(cache=True, error_model="numpy", inline="always")
def write_diagnostics(aux: np.ndarray, thrust: float, x: np.ndarray, p: np.ndarray, attached: bool) -> None:
    """Write the boosters' delivered thrust (N, summed) and each gimbaled booster's limited
    gimbal angles (rad, pitch then yaw; the first :data:`MAX_LOGGED_GIMBALS`; 0 once
    jettisoned) into ``aux``; their nozzle loads are :func:`loads`' (zero without the
    boosted modal sets, or once jettisoned)."""
    aux[A_THRUST] = thrust
    if not (attached and p[flex.P_N_BOOSTERS] > 0.0):
        aux[A_NOZZLE_LOADS:A_NOZZLE_LOADS + 5 * flex.MAX_BOOSTERS] = 0.0
    aux[A_GIMBAL:A_GIMBAL + 2 * MAX_LOGGED_GIMBALS] = 0.0
    if not attached or p[actuator.P_BOOSTER_CHANNEL] < 0.0:
        return
    lim = p[actuator.P_BOOSTER_GIMBAL + actuator.G_LIMIT]
    for i in range(min(int(p[P_N_BOOSTERS]), MAX_LOGGED_GIMBALS)):
        kp = booster_channel(p, i)
        aux[A_GIMBAL + 2 * i] = actuator.clip(x[kp], lim)
        aux[A_GIMBAL + 2 * i + 1] = actuator.clip(x[kp + actuator.N_PER_CHANNEL], lim)


@njit(cache=True, error_model="numpy", inline="always")
def booster_channel(p: np.ndarray, i: int) -> int:
    """Index in ``x`` of gimbaled booster ``i``'s pitch channel's angle δ (its yaw
    channel's follows, ``actuator.N_PER_CHANNEL`` later)."""
    return int(p[actuator.P_CHANNEL_OFFSET]) + actuator.N_PER_CHANNEL * (int(p[actuator.P_BOOSTER_CHANNEL]) + 2 * i)


def build(inputs: blocks.ModelInputs, p: np.ndarray, tables: dict[str, np.ndarray]) -> None:
    """The boosters' parameters and tables (placeholders, never read, without boosters)."""
    b = inputs.vehicle.boosters
    if b is None:
        tables.update(booster_time=np.array([0.0, 1.0]), booster_thrust=np.zeros(2),
                      booster_mount=np.zeros((1, N_MOUNT)),
                      booster_mass_prop=np.zeros((1, 1)), booster_mass_data=np.zeros((1, 1, N_COLUMNS)),
                      booster_mass_len=np.ones(1, dtype=np.int64), booster_burn_rate=np.ones(1),
                      booster_cant=np.zeros((1, 2)), booster_full=np.zeros((1, N_COLUMNS)))
        return
    p[P_N_BOOSTERS] = b.count
    p[P_TANK] = inputs.layout.tank(b.tanks[0])
    if [inputs.layout.tank(t) for t in b.tanks] != list(range(int(p[P_TANK]), int(p[P_TANK]) + b.count)):
        raise RuntimeError("the boosters' propellant states must be consecutive")
    p[P_ISP] = b.isp_vac_s
    p[P_EXIT_AREA] = b.nozzle_exit_area_m2
    p[P_FLOW_PER_THRUST] = b.propellant_kg / table_impulse(b.thrust_time_s, b.thrust_vac_N)
    prop, data, n = stacked_tables(list(b.mass))
    tables.update(booster_time=b.thrust_time_s, booster_thrust=b.thrust_vac_N,
                  booster_mount=np.column_stack([b.nozzle_m, thrust_direction(b.cant_rad)]),
                  booster_mass_prop=prop, booster_mass_data=data, booster_mass_len=n,
                  booster_burn_rate=np.ones(b.count) if b.burn_rate is None else np.asarray(b.burn_rate, float),
                  booster_cant=np.asarray(b.cant_rad, float),
                  booster_full=np.array([[m.mass_kg[-1], *m.cg_m[-1], *m.inertia_kgm2[-1, :3], *-m.inertia_kgm2[-1, 3:]]
                                         for m in b.mass]))


def thrust_direction(cant_rad: np.ndarray) -> np.ndarray:
    """Unit thrust directions (body axes, ``(n, 3)``) of nozzles at fixed cants ``(n, 2)``
    (pitch, yaw, rad): the force of ``propulsion.thrust_loads`` for a unit thrust
    (computed once: the cants never move)."""
    return np.array([thrust_loads(1.0, float(pitch), float(yaw), 0.0, 0.0, 0.0)[:3] for pitch, yaw in cant_rad])


@njit(cache=True, error_model="numpy", inline="always")
def flow(x: np.ndarray, tb: np.ndarray, p: np.ndarray, t: float, i: int) -> tuple[float, float]:
    """Vacuum thrust (N) and mass flow (kg/s) of booster ``i`` at mission time ``t`` (s):
    ``propulsion.trace_flow`` of its table and its own propellant state at its burn rate
    ``k``, ``ṁ = k (M / I_tab) F_tab(k t)`` (the sequencer's sensed thrust)."""
    k = tb[tab_offset(tb, T_RATE) + i]
    return trace_flow(tb, T_TIME, T_THRUST, x[int(p[P_TANK]) + i], k * p[P_FLOW_PER_THRUST], p[P_ISP], k * t)


@njit(cache=True, error_model="numpy")  # a call: the vehicles without boosters never enter it
def loads(x: np.ndarray, tb: np.ndarray, p: np.ndarray, t: float, pres: float, attached: bool,
          cgx: float, cgy: float, cgz: float, xd: np.ndarray, aux: np.ndarray):
    """The boosters' delivered thrust (N, summed), force (N) and moment about the CG
    (N·m), then their nozzles' tail-wags-dog moment about the CG (N·m), body axes, with
    each booster's propellant rate written into ``xd`` (kg/s; 0 once ``attached`` is
    False: jettisoned, its state emptied).

    Each booster's delivered thrust ``max(F_vac − p A_exit, 0)`` (``pres``: ambient
    pressure, Pa) acts at its nozzle along its fixed cant's direction
    (:func:`thrust_direction`), or with TVC along its limited gimbal angles plus the
    null bias plus its cant (the nozzle accelerations written into ``xd`` by
    ``cluster.gimbal_rates`` load its moving mass), its moment ``r × F`` with the arm
    ``r`` from the CG ``cgx, cgy, cgz`` (structure frame, m) in body axes. With the
    flexible body's boosted sets (flex on) the structure at the nozzle's point turns the
    thrust line (its rotation subtracted from the pitch and yaw angles, as at the stage's
    gimbal) and moves the point (the arm plus its displacement), and the loads there go
    into ``aux[A_NOZZLE_LOADS]`` for the modes."""
    tank = int(p[P_TANK])
    thrust = fx = fy = fz = mx = my = mz = wx = wy = wz = 0.0
    gimbaled = p[actuator.P_BOOSTER_CHANNEL] >= 0.0
    flexible = attached and p[flex.P_N_BOOSTERS] > 0.0
    for i in range(int(p[P_N_BOOSTERS])):
        if not attached:
            xd[tank + i] = 0.0
            continue
        f_vac, mdot = flow(x, tb, p, t, i)
        xd[tank + i] = -mdot
        f = max(f_vac - pres * p[P_EXIT_AREA], 0.0) if mdot > 0.0 and p[P_ON] != 0.0 else 0.0
        m = tab_offset(tb, T_MOUNT) + i * N_MOUNT
        rx, ry, rz = -(tb[m] - cgx), tb[m + 1] - cgy, -(tb[m + 2] - cgz)
        ty = tz = 0.0
        if flexible:
            pt = flex.booster_point(p, tb, i)
            _, ty, tz = flex.rotation_at(x, 0, p, tb, pt, False)
            dx, dy, dz = flex.displacement_at(x, 0, p, tb, pt)
            rx, ry, rz = rx + dx, ry + dy, rz + dz
        nfx = nfy = nfz = nty = ntz = 0.0
        if gimbaled:
            ax, ay, az, bx, by, bz, nfx, nfy, nfz, nty, ntz, nx, ny, nz = gimbaled_loads(x, xd, tb, p, i, f, rx, ry,
                                                                                           rz, ty, tz)
            wx += nx
            wy += ny
            wz += nz
        elif flexible:
            cant = tab_offset(tb, T_CANT) + 2 * i
            ax, ay, az, bx, by, bz = thrust_loads(f, tb[cant] - ty, tb[cant + 1] - tz, rx, ry, rz)
        else:
            ax, ay, az = f * tb[m + 3], f * tb[m + 4], f * tb[m + 5]
            bx, by, bz = ry * az - rz * ay, rz * ax - rx * az, rx * ay - ry * ax
        if flexible:
            k = A_NOZZLE_LOADS + 5 * i
            aux[k], aux[k + 1], aux[k + 2] = ax + nfx, ay + nfy, az + nfz
            aux[k + 3], aux[k + 4] = nty, ntz
        thrust += f
        fx += ax
        fy += ay
        fz += az
        mx += bx
        my += by
        mz += bz
    return thrust, fx, fy, fz, mx, my, mz, wx, wy, wz


@njit(cache=True, error_model="numpy", inline="always")
def gimbaled_loads(x: np.ndarray, xd: np.ndarray, tb: np.ndarray, p: np.ndarray, i: int, f: float,
                   rx: float, ry: float, rz: float, ty: float, tz: float):
    """Gimbaled booster ``i``'s thrust force (N) and moment about the CG (N·m) for its
    delivered thrust ``f`` (N) at the arm ``r`` (CG → nozzle, body axes, m), its thrust
    line turned back by the structure's rotation ``ty``, ``tz`` at the nozzle (rad; 0
    rigid), then its moving nozzle's tail-wags-dog force and torque at the nozzle (N,
    N·m) and moment about the CG (N·m), body axes."""
    kp = booster_channel(p, i)
    ky = kp + actuator.N_PER_CHANNEL
    g = actuator.P_BOOSTER_GIMBAL
    lim = p[g + actuator.G_LIMIT]
    cant = tab_offset(tb, T_CANT) + 2 * i
    ax, ay, az, bx, by, bz = thrust_loads(f, actuator.clip(x[kp], lim) + p[g + actuator.G_BIAS_PITCH] + tb[cant] - ty,
                                          actuator.clip(x[ky], lim) + p[g + actuator.G_BIAS_YAW] + tb[cant + 1] - tz,
                                          rx, ry, rz)
    w = twd.moving_mass_loads(p, twd.P_BOOSTER_ENGINE, xd[kp + 1], xd[ky + 1], rx, ry, rz)
    return ax, ay, az, bx, by, bz, w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7]


@njit(cache=True, error_model="numpy")  # a call: the vehicles without boosters never enter it
def exchange(x: np.ndarray, p: np.ndarray, tb: np.ndarray, m: float, cgx: float, cgy: float, cgz: float,
             ixx: float, iyy: float, izz: float, ixy: float, ixz: float, iyz: float):
    """The liftoff configuration's mass properties ``m, cg…, i…`` (as
    ``mass.mass_properties`` returns them: its table holds the boosters at their full
    load) with each booster's full-load row exchanged for its row at its own propellant
    (its state in ``x``), by the parallel-axis theorem about the table's CG ``C₀``::

        M = m + Σ (mₙ − m_f),    e = Σ (mₙ dₙ − m_f d_f) / M,    d = S (c − C₀)
        J = J₀ + Σ [Jₙ + mₙ (|dₙ|² E − dₙ dₙᵀ) − J_f − m_f (|d_f|² E − d_f d_fᵀ)]
              − M (|e|² E − e eᵀ)

    (``S = diag(−1, 1, −1)``: structure to body axes; ``J`` tensors about the CGs, body
    axes). The new CG is ``C₀ + S e``. Returns the same tuple for the new whole."""
    tank = int(p[P_TANK])
    full = tab_offset(tb, T_FULL)
    sx = sy = sz = 0.0  # first moment about C₀, body axes
    mass = m
    for i in range(int(p[P_N_BOOSTERS])):
        for sign in (-1.0, 1.0):
            if sign < 0.0:  # the full-load row, read once at the build
                r = full + i * N_COLUMNS
                mb, bx, by, bz, jxx, jyy, jzz, jxy, jxz, jyz = (tb[r], tb[r + 1], tb[r + 2], tb[r + 3], tb[r + 4],
                                                                tb[r + 5], tb[r + 6], tb[r + 7], tb[r + 8], tb[r + 9])
            else:
                mb, bx, by, bz, jxx, jyy, jzz, jxy, jxz, jyz = stacked_row(tb, T_MASS_PROP, T_MASS_DATA, T_MASS_LEN,
                                                                           i, x[tank + i])
            dx, dy, dz = -(bx - cgx), by - cgy, -(bz - cgz)
            w = sign * mb
            mass += w
            sx += w * dx
            sy += w * dy
            sz += w * dz
            ixx += sign * jxx + w * (dy * dy + dz * dz)
            iyy += sign * jyy + w * (dx * dx + dz * dz)
            izz += sign * jzz + w * (dx * dx + dy * dy)
            ixy += sign * jxy - w * dx * dy
            ixz += sign * jxz - w * dx * dz
            iyz += sign * jyz - w * dy * dz
    ex, ey, ez = sx / mass, sy / mass, sz / mass
    return (mass, cgx - ex, cgy + ey, cgz - ez,
            ixx - mass * (ey * ey + ez * ez), iyy - mass * (ex * ex + ez * ez), izz - mass * (ex * ex + ey * ey),
            ixy + mass * ex * ey, ixz + mass * ex * ez, iyz + mass * ey * ez)
