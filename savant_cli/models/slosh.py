"""Propellant slosh: one spring-mass analogue per sloshing tank, on any stage.

The vehicle file gives a tank a ``slosh`` section (``savant_cli.flex_slosh``); every such
tank, in the order of the vehicle's propellant states, carries one slosh mass here (at
most :data:`MAX_TANKS`). A tank rides with its stage: in the configurations after its
stage is jettisoned its mass is gone and its states are held.

Each tank's first lateral slosh mode is a point mass ``m_s`` on the tank centerline at
the height ``h_s`` above the tank bottom, on a lateral spring and damper, with the
frequency ``ω_s``, damping ``ζ_s``, mass and height read from a table against the liquid
level (SP-106 data; ``datagen/ares_i_slosh.py``). The level of a flat-bottomed
cylindrical tank is ``m_liquid / (ρ π R²)``. The frequency scales with the square root
of the axial specific force: ``ω = ω_ref √(a / a_ref)``.

The rigid part of the vehicle leaves the slosh masses out: its mass, CG and inertia are
the configuration's minus the point masses on the centerlines. The force of a slosh mass
on the tank (body axes, lateral displacement ``(y, z)`` from the centerline)::

    F_y = m_s (ω² y + 2 ζ ω ẏ),   F_z = m_s (ω² z + 2 ζ ω ż),   F_x = −m_s f_x

(``f_x``: the axial specific force; the masses ride axially with the tank), and the mass
moves relative to the tank under the specific force of its attachment point::

    ÿ = −2ζω ẏ − ω² y − a_y,  a = f/m + α × r + ω × (ω × r) + 2 ω × v_rel  (lateral parts)

At the tank wall (``|(y, z)| = R``) the mass stops: the engine clamps it there and
removes its outward velocity (the paper's only wall interaction). Source: SAVANT §III,
"Slosh"; NASA SP-106 (Abramson, 1966).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from savant_cli.models import blocks
from savant_cli.models.interp import locate_at, tab_offset
from savant_cli.models.mass import minus_point_mass
from savant_cli.vehicle.tree import MAX_SLOSH_TANKS

#: Sloshing tanks a vehicle may have (the size of the per-tank diagnostics).
MAX_TANKS = MAX_SLOSH_TANKS
STATE = blocks.Record(
    "slosh mass",
    ("y", "m", "lateral displacement from the tank centerline, body Y"),
    ("z", "m", "lateral displacement, body Z"),
    ("y_dot", "m/s", "displacement rate, body Y"),
    ("z_dot", "m/s", "displacement rate, body Z"),
)
S_Y, S_Z, S_YDOT, S_ZDOT = STATE.offsets
N_PER_TANK = STATE.size
COLUMNS = blocks.Record(
    "slosh table row",
    ("frequency", "rad/s", "slosh frequency at the reference acceleration"),
    ("damping", "1", "damping ratio"),
    ("mass", "kg", "slosh mass"),
    ("height", "m", "slosh-mass height above the tank bottom"),
)
C_FREQ, C_ZETA, C_MASS, C_HEIGHT = COLUMNS.offsets
N_COLUMNS = COLUMNS.size
TANK = blocks.Record(
    "tank",
    ("radius", "m", "tank radius"),
    ("bottom_station", "m", "tank bottom, structure x"),
    ("density", "kg/m^3", "liquid density"),
    ("reference_accel", "m/s^2", "axial acceleration at which the tank's tabulated frequency holds"),
    ("liquid_state", "1", "index in x of the propellant state the liquid level follows"),
    ("configurations", "1", "the tank is aboard in the configurations below this number"),
)
K_RADIUS, K_BOTTOM, K_DENSITY, K_AREF, K_LIQUID, K_CONFIGS = TANK.offsets
N_TANK_FIELDS = TANK.size

MODE = blocks.Record(
    "a tank's slosh mode at its level",
    ("frequency", "rad/s", "slosh frequency at the tank's reference acceleration"),
    ("damping", "1", "damping ratio"),
    ("mass", "kg", "slosh mass (0 when the tank is not aboard)"),
    ("station", "m", "slosh-mass station, structure x"),
)
M_FREQ, M_ZETA, M_MASS, M_STATION = MODE.offsets
N_MODE = MODE.size

_PARAMS = blocks.PARAMETERS.block("slosh")
P_OFFSET = _PARAMS.scalar("state_offset", "1", "offset of the slosh states in x (−1: slosh off)")
P_N_TANKS = _PARAMS.scalar("n_tanks", "1", "sloshing tanks (0 with slosh off)")
P_ROWS = _PARAMS.scalar("rows", "1", "rows of each tank's padded table (T_LEVEL's second dimension)")
P_FREQ_SCALE = _PARAMS.scalar("frequency_scale", "1", "multiplier of the tabulated frequencies")
P_ZETA_SCALE = _PARAMS.scalar("damping_scale", "1", "multiplier of the tabulated damping")
P_TANKS = _PARAMS.record("tank0", TANK, "first sloshing tank")
for _j in range(1, MAX_TANKS):
    _PARAMS.record(f"tank{_j}", TANK, f"sloshing tank {_j} (records follow one another)")
_TABLES = blocks.TABLES.block("slosh")
T_LEVEL = _TABLES.table("slosh_level", "m", "(n_tanks, n) liquid level, increasing (padded)")
T_DATA = _TABLES.table("slosh_data", "rad/s, 1, kg, m", "(n_tanks, n, COLUMNS) slosh parameters at T_LEVEL")
T_LEN = _TABLES.table("slosh_len", "1", "(n_tanks,) valid rows per tank")


def _tank_columns(suffixes: tuple[str, ...]):
    """The logged columns of a per-tank diagnostic: ``<tank><suffix>`` for each of the
    run's sloshing tanks (their names in the vehicle file)."""
    return lambda model: tuple(f"{tank}{s}" for tank in model.layout.slosh_tanks for s in suffixes)


_AUX = blocks.DIAGNOSTICS.block("slosh")
A_FREQUENCY = _AUX.array("frequency", MAX_TANKS, "rad/s", "slosh frequency per tank (0 once its stage is gone)")
A_LEVEL = _AUX.array("level", MAX_TANKS, "m", "liquid level above the tank bottom",
                     blocks.Logged("liquid_level", (), "", lambda model: model.layout.slosh, _tank_columns(("",))))
A_FORCE = _AUX.array("force", 3 * MAX_TANKS, "N", "force of the slosh masses on the vehicle",
                     blocks.Logged("slosh_force", (), "body", lambda model: model.layout.slosh,
                                   _tank_columns(("_x", "_y", "_z"))))
A_MODE = _AUX.array("mode", N_MODE * MAX_TANKS, "rad/s, 1, kg, m",
                    "each tank's mode at its level (MODE): the mass-properties step hands it to the loads")
assert (A_LEVEL, A_FORCE, A_MODE) == (A_FREQUENCY + MAX_TANKS, A_LEVEL + MAX_TANKS, A_FORCE + 3 * MAX_TANKS)


@njit(cache=True, error_model="numpy", inline="always")
def write_diagnostics(aux: np.ndarray, p: np.ndarray) -> None:
    """Zero the per-tank diagnostics of the tank slots the run does not fill (every slot
    with slosh off): each sloshing tank's own are written where the plant computes them
    (:func:`tank_modes`, :func:`add_loads`), as the loads read them."""
    n = tank_count(p)
    if n == 0:  # the four fields are declared one after another: one block
        aux[A_FREQUENCY:A_MODE + N_MODE * MAX_TANKS] = 0.0
        return
    aux[A_FREQUENCY + n:A_FREQUENCY + MAX_TANKS] = 0.0
    aux[A_LEVEL + n:A_LEVEL + MAX_TANKS] = 0.0
    aux[A_FORCE + 3 * n:A_FORCE + 3 * MAX_TANKS] = 0.0
    aux[A_MODE + N_MODE * n:A_MODE + N_MODE * MAX_TANKS] = 0.0


def build(inputs: blocks.ModelInputs, p: np.ndarray, tables: dict[str, np.ndarray]) -> None:
    """The ``slosh`` group and the vehicle's slosh tables (placeholders when off): each
    sloshing tank's geometry, reference acceleration, liquid state and the configurations
    its stage is aboard in."""
    s = inputs.cfg.slosh
    p[P_OFFSET] = inputs.layout.slosh_offset
    p[P_FREQ_SCALE] = s.frequency_scale if s.enabled else 1.0
    p[P_ZETA_SCALE] = s.damping_scale if s.enabled else 1.0
    sl = inputs.slosh
    p[P_N_TANKS] = 0.0 if sl is None else len(sl.tanks)
    if sl is None:
        tables.update(slosh_level=np.tile([0.0, 1.0], (1, 1)), slosh_data=np.zeros((1, 2, N_COLUMNS)),
                      slosh_len=np.array([2]))
        return
    for j, tank in enumerate(sl.tanks):
        base = P_TANKS + j * N_TANK_FIELDS
        p[base + K_RADIUS], p[base + K_BOTTOM], p[base + K_DENSITY] = (tank.radius_m, tank.bottom_station_m,
                                                                        tank.density_kgm3)
        p[base + K_AREF] = tank.reference_accel_mps2
        p[base + K_LIQUID] = inputs.layout.tank(tank.name)
        p[base + K_CONFIGS] = tank.configurations
    level, n = blocks.stack_padded([t.level_m for t in sl.tanks])
    data, _ = blocks.stack_padded([np.column_stack([t.frequency_rad_s, t.damping, t.mass_kg, t.height_m])
                                   for t in sl.tanks])
    tables.update(slosh_level=level, slosh_data=data, slosh_len=n)
    p[P_ROWS] = level.shape[1]


class SloshTank(NamedTuple):
    """One tank's slosh mode at its current liquid level (zeros with slosh off).

    Attributes
    ----------
    level_m : float
        Liquid level above the tank bottom, m.
    frequency_rad_s : float
        Slosh frequency at the reference axial acceleration, rad/s.
    damping : float
        Damping ratio ζ (1).
    mass_kg : float
        Slosh mass, kg.
    station_m : float
        Slosh-mass station, structure x, m.
    """

    level_m: float
    frequency_rad_s: float
    damping: float
    mass_kg: float
    station_m: float


class RigidMotion(NamedTuple):
    """The motion of the rigid part a slosh mass rides on (body axes).

    Attributes
    ----------
    cg_m : tuple of 3 float
        The rigid part's CG, structure frame, m.
    lateral_specific_force_m_s2 : tuple of 2 float
        Its non-gravitational acceleration along body Y and Z, m/s².
    rate_rad_s : tuple of 3 float
        Body rate ω, rad/s.
    angular_acceleration_rad_s2 : tuple of 3 float
        Angular acceleration α, rad/s².
    """

    cg_m: tuple[float, float, float]
    lateral_specific_force_m_s2: tuple[float, float]
    rate_rad_s: tuple[float, float, float]
    angular_acceleration_rad_s2: tuple[float, float, float]


@njit(cache=True, error_model="numpy", inline="always")
def slosh_tank(tb: np.ndarray, p: np.ndarray, j: int, liquid_kg: float) -> SloshTank:
    """The slosh mode of tank ``j`` holding ``liquid_kg`` (kg)."""
    base = P_TANKS + j * N_TANK_FIELDS
    radius, density = p[base + K_RADIUS], p[base + K_DENSITY]
    level = max(liquid_kg, 0.0) / (density * np.pi * radius * radius)
    o_l = tab_offset(tb, T_LEVEL)
    ns = int(p[P_ROWS])
    i, w = locate_at(tb, o_l + j * ns, int(tb[tab_offset(tb, T_LEN) + j]), level)
    r0 = tab_offset(tb, T_DATA) + (j * ns + i) * N_COLUMNS
    r1 = r0 + N_COLUMNS
    a = 1.0 - w
    w_ref = (a * tb[r0 + C_FREQ] + w * tb[r1 + C_FREQ]) * p[P_FREQ_SCALE]
    zeta = (a * tb[r0 + C_ZETA] + w * tb[r1 + C_ZETA]) * p[P_ZETA_SCALE]
    mass = a * tb[r0 + C_MASS] + w * tb[r1 + C_MASS]
    height = a * tb[r0 + C_HEIGHT] + w * tb[r1 + C_HEIGHT]
    return SloshTank(level, w_ref, zeta, mass, p[base + K_BOTTOM] - height)


@njit(cache=True, error_model="numpy", inline="always")
def tank_count(p: np.ndarray) -> int:
    """The sloshing tanks of the run (0 with slosh off)."""
    return int(p[P_N_TANKS]) if p[P_OFFSET] >= 0.0 else 0


@njit(cache=True, error_model="numpy", inline="always")
def stored_tank(aux: np.ndarray, j: int) -> SloshTank:
    """Tank ``j``'s mode as :func:`tank_modes` stored it in ``aux``."""
    k = A_MODE + j * N_MODE
    return SloshTank(aux[A_LEVEL + j], aux[k + M_FREQ], aux[k + M_ZETA], aux[k + M_MASS], aux[k + M_STATION])


@njit(cache=True, error_model="numpy", inline="always")
def tank_modes(x: np.ndarray, p: np.ndarray, tb: np.ndarray, config: int, aux: np.ndarray) -> None:
    """Every sloshing tank's mode at its liquid level in configuration ``config`` into
    ``aux`` (its level and :data:`MODE`): zeros for a tank whose stage is gone."""
    for j in range(tank_count(p)):
        base = P_TANKS + j * N_TANK_FIELDS
        k = A_MODE + j * N_MODE
        if config < p[base + K_CONFIGS]:
            tank = slosh_tank(tb, p, j, x[int(p[base + K_LIQUID])])
            aux[A_LEVEL + j] = tank.level_m
            aux[k + M_FREQ] = tank.frequency_rad_s
            aux[k + M_ZETA] = tank.damping
            aux[k + M_MASS] = tank.mass_kg
            aux[k + M_STATION] = tank.station_m
        else:
            aux[A_LEVEL + j] = aux[k + M_FREQ] = aux[k + M_ZETA] = aux[k + M_MASS] = aux[k + M_STATION] = 0.0


@njit(cache=True, error_model="numpy", inline="always")
def rigid_part(p: np.ndarray, aux: np.ndarray, mass, cgx, cgy, cgz, ixx, iyy, izz, ixy, ixz, iyz):
    """Mass (kg), CG (structure, m) and inertia about its own CG (body, kg·m², tensor
    elements) of the vehicle without the slosh masses of :func:`tank_modes` (``aux``), at
    their stations on the tank centerlines."""
    n = tank_count(p)
    m_r = mass
    moment_x = mass * cgx
    for j in range(n):
        k = A_MODE + j * N_MODE
        m_r -= aux[k + M_MASS]
        moment_x -= aux[k + M_MASS] * aux[k + M_STATION]
    cgx_r = moment_x / m_r
    cgy_r = mass * cgy / m_r
    cgz_r = mass * cgz / m_r
    # remove each slosh mass (offset from the total CG), then move to the rigid CG
    for j in range(n):
        k = A_MODE + j * N_MODE
        ixx, iyy, izz, ixy, ixz, iyz = minus_point_mass(ixx, iyy, izz, ixy, ixz, iyz, aux[k + M_MASS],
                                                        -(aux[k + M_STATION] - cgx), -cgy, cgz)
    ixx, iyy, izz, ixy, ixz, iyz = minus_point_mass(ixx, iyy, izz, ixy, ixz, iyz, m_r, -(cgx_r - cgx),
                                                    cgy_r - cgy, -(cgz_r - cgz))
    return m_r, cgx_r, cgy_r, cgz_r, ixx, iyy, izz, ixy, ixz, iyz


@njit(cache=True, error_model="numpy", inline="always")
def add_loads(x: np.ndarray, p: np.ndarray, aux: np.ndarray, fex: float, fey: float, fez: float, mass_total: float,
              cg: tuple[float, float, float]) -> tuple[float, float, float, float, float, float]:
    """The external non-gravitational force ``fe`` (N, body) plus every slosh mass's
    force on the vehicle, and the slosh masses' moment about the rigid CG ``cg``
    (structure, m; N·m, body). Each tank's frequency at the current acceleration and its
    force go into ``aux`` (the modal equations and the rates read them)."""
    fx, fy, fz = fex, fey, fez
    msx = msy = msz = 0.0
    n = tank_count(p)
    if n == 0:
        return fx, fy, fz, msx, msy, msz
    f_mag = np.sqrt(fex * fex + fey * fey + fez * fez) / mass_total
    fx_spec = fex / mass_total  # axial specific force; the masses ride axially with the tank
    so = int(p[P_OFFSET])
    a_ref = ratio = 0.0
    for j in range(n):
        tank = stored_tank(aux, j)
        if p[P_TANKS + j * N_TANK_FIELDS + K_AREF] != a_ref:  # tanks of one reference share the ratio
            a_ref = p[P_TANKS + j * N_TANK_FIELDS + K_AREF]
            ratio = np.sqrt(f_mag / a_ref)
        w = tank.frequency_rad_s * ratio
        fsx, fsy, fsz, mx, my, mz = tank_force(x, so + N_PER_TANK * j, tank, w, fx_spec, cg)
        aux[A_FREQUENCY + j] = w
        aux[A_FORCE + 3 * j] = fsx
        aux[A_FORCE + 3 * j + 1] = fsy
        aux[A_FORCE + 3 * j + 2] = fsz
        fx, fy, fz = fx + fsx, fy + fsy, fz + fsz
        msx, msy, msz = msx + mx, msy + my, msz + mz
    return fx, fy, fz, msx, msy, msz


@njit(cache=True, error_model="numpy", inline="always")
def tank_force(x: np.ndarray, k: int, tank: SloshTank, w: float, fx_spec: float,
               cg: tuple[float, float, float]) -> tuple[float, float, float, float, float, float]:
    """Force of one slosh mass on the vehicle (N, body) and its moment about the rigid CG
    (N·m): states ``x[k:k+4]``, the tank's mode ``tank`` flown at the frequency ``w``
    (rad/s), axial specific force ``fx_spec`` (m/s²), rigid CG ``cg`` (structure, m)."""
    m, zeta = tank.mass_kg, tank.damping
    cgx, cgy, cgz = cg
    fy = m * (w * w * x[k + S_Y] + 2.0 * zeta * w * x[k + S_YDOT])
    fz = m * (w * w * x[k + S_Z] + 2.0 * zeta * w * x[k + S_ZDOT])
    fx = -m * fx_spec
    rx, ry, rz = -(tank.station_m - cgx), x[k + S_Y] - cgy, x[k + S_Z] + cgz  # rigid CG → slosh mass, body
    return fx, fy, fz, ry * fz - rz * fy, rz * fx - rx * fz, rx * fy - ry * fx


@njit(cache=True, error_model="numpy", inline="always")
def tank_rates(x: np.ndarray, k: int, tank: SloshTank, w: float, motion: RigidMotion, xd: np.ndarray) -> None:
    """Slosh-mass equations of one tank into ``xd[k:k+4]``: the tank's mode ``tank`` flown
    at the frequency ``w`` (rad/s) on the rigid part's ``motion``."""
    zeta, station = tank.damping, tank.station_m
    cgx, cgy, cgz = motion.cg_m
    aby, abz = motion.lateral_specific_force_m_s2
    wx, wy, wz = motion.rate_rad_s
    alx, aly, alz = motion.angular_acceleration_rad_s2
    rx, ry, rz = -(station - cgx), x[k + S_Y] - cgy, x[k + S_Z] + cgz
    vy, vz = x[k + S_YDOT], x[k + S_ZDOT]
    # specific force of the point of the rigid body where the mass sits, plus Coriolis:
    # f + α × r + ω × (ω × r) + 2 ω × v_rel   (lateral components)
    wdr = wx * rx + wy * ry + wz * rz
    w2 = wx * wx + wy * wy + wz * wz
    acc_y = aby + (alz * rx - alx * rz) + (wy * wdr - w2 * ry) + 2.0 * (-wx * vz)
    acc_z = abz + (alx * ry - aly * rx) + (wz * wdr - w2 * rz) + 2.0 * (wx * vy)
    xd[k + S_Y] = vy
    xd[k + S_Z] = vz
    xd[k + S_YDOT] = -2.0 * zeta * w * vy - w * w * x[k + S_Y] - acc_y
    xd[k + S_ZDOT] = -2.0 * zeta * w * vz - w * w * x[k + S_Z] - acc_z


@njit(cache=True, error_model="numpy", inline="always")
def rates(x: np.ndarray, p: np.ndarray, aux: np.ndarray, config: int, motion: RigidMotion, xd: np.ndarray) -> None:
    """Every tank's slosh-mass equations into ``xd`` on the rigid part's ``motion``
    (modes and frequencies from :func:`tank_modes` and :func:`add_loads`); the states of
    a tank whose stage is gone (configuration ``config``) are held."""
    so = int(p[P_OFFSET])
    for j in range(tank_count(p)):
        k = so + N_PER_TANK * j
        if config < p[P_TANKS + j * N_TANK_FIELDS + K_CONFIGS]:
            tank_rates(x, k, stored_tank(aux, j), aux[A_FREQUENCY + j], motion, xd)
        else:
            xd[k + S_Y] = xd[k + S_Z] = xd[k + S_YDOT] = xd[k + S_ZDOT] = 0.0


@njit(cache=True, error_model="numpy")
def contain(x: np.ndarray, p: np.ndarray) -> None:
    """Keep every slosh mass inside its tank: at the wall it stops (its outward velocity
    is removed), the paper's only wall interaction. Nothing when slosh is off."""
    so = int(p[P_OFFSET])
    for tank in range(tank_count(p)):
        k = so + N_PER_TANK * tank
        radius = p[P_TANKS + tank * N_TANK_FIELDS + K_RADIUS]
        r = np.sqrt(x[k + S_Y] ** 2 + x[k + S_Z] ** 2)
        if r > radius:
            ny, nz = x[k + S_Y] / r, x[k + S_Z] / r
            x[k + S_Y] = radius * ny
            x[k + S_Z] = radius * nz
            vr = x[k + S_YDOT] * ny + x[k + S_ZDOT] * nz
            if vr > 0.0:
                x[k + S_YDOT] -= vr * ny
                x[k + S_ZDOT] -= vr * nz
