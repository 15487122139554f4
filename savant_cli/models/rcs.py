"""Roll reaction-control jets: thrust-fraction ramps and the roll torque.

Each direction (positive, negative roll) has ``n`` jets on a moment arm ``l``; the
commanded direction's thrust fraction ramps linearly to 1 in ``ramp_up`` s, the other to
0 in ``ramp_down`` s; a ramp time of 0 is an instantaneous step, applied by
:func:`step_jets` when the flight software's command changes. Jet thrust ``F_jet = max(F_vac(h) − p_amb A_exit, 0)`` from a vacuum
thrust table against altitude. Roll torque about body X::

    L = (f₊ − f₋) n F_jet l

The same pods may hold pitch and yaw jets, fired in the coasts (the flight control's
coast phase: no thrust, no gimbal authority): ``n`` jets of vacuum thrust ``F`` per
direction, their lateral force acting on the centerline at the pods' station ``x_j``
(structure x; the pods' jets fire in pairs about it), the jets on the side that turns
the vehicle the commanded way. With ``l = x_j − x_cg`` (structure axes: aft of the CG
positive) and the commands ``c_p``, ``c_y`` (+1, 0, −1)::

    F_z = c_p n F sgn(l),   F_y = −c_y n F sgn(l),   M_y = c_p n F |l|,   M_z = c_y n F |l|

(``r × F`` with ``r = (−l, 0, 0)`` in body axes). Their propellant, as the roll jets', is
not modelled.

Source: SAVANT §III, "Roll control system".
"""

from __future__ import annotations

import numpy as np
from numba import njit

from savant_cli.models import blocks
from savant_cli.models.interp import interp1_at, tab, tab_offset

#: The jets' states: the thrust fractions of the positive- and the negative-roll jets (1,
#: 0..1), from the offset ``P_STATE_OFFSET`` in ``x`` (``models/layout.py``).
STATE_NAMES = ("rcs_pos", "rcs_neg")
N_JET_STATES = len(STATE_NAMES)

_PARAMS = blocks.PARAMETERS.block("rcs")
P_STATE_OFFSET = _PARAMS.scalar("state_offset", "1",
                                "offset in x of the jets' thrust fractions, positive then negative")
P_EXIT_AREA = _PARAMS.scalar("exit_area", "m^2", "nozzle exit area of one jet")
P_N = _PARAMS.scalar("jets_per_direction", "1", "jets firing together for one roll direction")
P_ARM = _PARAMS.scalar("moment_arm", "m", "roll moment arm of each jet")
P_RAMP_UP = _PARAMS.scalar("ramp_up", "s", "time from closed to full thrust")
P_RAMP_DOWN = _PARAMS.scalar("ramp_down", "s", "time from full thrust to closed")
P_PY_FORCE = _PARAMS.scalar("pitch_yaw_force", "N", "the pitch and yaw jets' force per direction, n F (0: none)")
P_PY_STATION = _PARAMS.scalar("pitch_yaw_station", "m", "structure x at which the pitch and yaw jets push")
_TABLES = blocks.TABLES.block("rcs")
T_ALT = _TABLES.table("rcs_alt", "m", "altitudes of the jet thrust table")
T_THRUST = _TABLES.table("rcs_thrust", "N", "vacuum thrust of one jet at T_ALT")
_AUX = blocks.DIAGNOSTICS.block("rcs")
A_TORQUE = _AUX.scalar("torque", "N*m", "roll-jet torque about body X", blocks.Logged("rcs_torque"))


@njit(cache=True, error_model="numpy", inline="always")
def write_diagnostics(aux: np.ndarray, torque: float) -> None:
    """Write the roll-jet torque (N·m, about body X) into ``aux``."""
    aux[A_TORQUE] = torque


def build(inputs: blocks.ModelInputs, p: np.ndarray, tables: dict[str, np.ndarray]) -> None:
    """The vehicle's roll jets."""
    rcs = inputs.vehicle.rcs
    p[P_STATE_OFFSET] = inputs.layout.rcs
    p[P_EXIT_AREA] = rcs.exit_area_m2
    p[P_N] = rcs.jets_per_direction
    p[P_ARM] = rcs.moment_arm_m
    p[P_RAMP_UP] = rcs.ramp_up_s
    p[P_RAMP_DOWN] = rcs.ramp_down_s
    p[P_PY_FORCE] = rcs.pitch_yaw_jets_per_direction * rcs.pitch_yaw_thrust_N
    p[P_PY_STATION] = rcs.location_m[0]
    tables.update(rcs_alt=rcs.altitude_m, rcs_thrust=rcs.thrust_vac_N)


@njit(cache=True, error_model="numpy", inline="always")
def jet_ramp(frac: float, on: bool, ramp_up_s: float, ramp_down_s: float) -> float:
    """Rate of the jet thrust fraction (1/s): linear ramp up to 1 when open, down to 0
    when shut; 0 for a ramp time of 0 (:func:`step_jets` steps the fraction instead)."""
    if on:
        return 1.0 / ramp_up_s if frac < 1.0 and ramp_up_s > 0.0 else 0.0
    return -1.0 / ramp_down_s if frac > 0.0 and ramp_down_s > 0.0 else 0.0


@njit(cache=True, error_model="numpy", inline="always")
def jet_rates(x: np.ndarray, p: np.ndarray, command: float) -> tuple[float, float]:
    """Derivatives of the positive and negative thrust fractions for a jet command
    (+1 positive roll, −1 negative, 0 off)."""
    k = int(p[P_STATE_OFFSET])
    return (jet_ramp(x[k], command > 0.5, p[P_RAMP_UP], p[P_RAMP_DOWN]),
            jet_ramp(x[k + 1], command < -0.5, p[P_RAMP_UP], p[P_RAMP_DOWN]))


@njit(cache=True, error_model="numpy", inline="always")
def step_jets(x: np.ndarray, p: np.ndarray, command: float) -> None:
    """At a new jet command (+1, 0, −1): the thrust fractions whose ramp time is 0 jump
    to their end value (1 for the commanded direction, 0 for the other)."""
    k = int(p[P_STATE_OFFSET])
    for i, on in ((k, command > 0.5), (k + 1, command < -0.5)):
        if on and p[P_RAMP_UP] <= 0.0:
            x[i] = 1.0
        elif not on and p[P_RAMP_DOWN] <= 0.0:
            x[i] = 0.0


@njit(cache=True, error_model="numpy", inline="always")
def roll_torque(x: np.ndarray, tb: np.ndarray, p: np.ndarray, alt_m: float, pres: float) -> float:
    """Roll torque of the jets about body X (N·m) at altitude ``alt_m`` (m) and ambient
    pressure ``pres`` (Pa)."""
    o_ra, n_ra = tab(tb, T_ALT)
    f_jet = interp1_at(tb, o_ra, tab_offset(tb, T_THRUST), n_ra, alt_m) - pres * p[P_EXIT_AREA]
    if f_jet < 0.0:
        f_jet = 0.0
    k = int(p[P_STATE_OFFSET])
    return (x[k] - x[k + 1]) * p[P_N] * f_jet * p[P_ARM]


@njit(cache=True, error_model="numpy", inline="always")
def pitch_yaw_loads(p: np.ndarray, command_pitch: float, command_yaw: float,
                    cgx: float) -> tuple[float, float, float, float]:
    """The pitch and yaw jets' lateral force (N, body y and z) and moment about the CG
    (N·m, body y and z) for the commands ``command_pitch``, ``command_yaw`` (+1, 0, −1:
    a positive moment about the axis, or none) with the CG at structure x ``cgx`` (m)
    (module notes)."""
    force = p[P_PY_FORCE]
    arm = p[P_PY_STATION] - cgx
    side = 1.0 if arm >= 0.0 else -1.0
    fz = command_pitch * force * side
    fy = -command_yaw * force * side
    return fy, fz, arm * fz, -arm * fy
