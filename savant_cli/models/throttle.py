"""The throttles: the engine controller's setting and its law, for the first stage and
for the upper stage.

A liquid first stage with a ``throttle`` section (``vehicle/tree.py::Throttle``) burns
at ``k`` × its rated vacuum thrust (``models/propulsion.py``), ``k`` a fraction held in
the plant's input ``u[U_THROTTLE]`` between flight-control cycles. Every cycle the flight
software commands (:func:`throttle_step`)::

    k_c = k_sched(t)                          (the schedule; its maximum without one)
    k_c = min(k_c, k a_lim / a)               (with an axial-acceleration limit, a > 0)
    k⁺  = clamp(clamp(k_c, k_min, k_max), k − ṙ Δt, k + ṙ Δt)

with ``a`` the sensed axial specific force (body x, m/s²) at the cycle, ``a_lim`` the
limit, ``ṙ`` the throttle rate limit (1/s) and ``Δt`` the cycle (s). The limit's ratio
law needs nothing but the accelerometer: with ``a = (k F − L)/m`` (``F`` the vacuum thrust
at full setting along body x, ``L`` drag plus back-pressure loss) its fixed point is the
setting that holds ``a = a_lim`` exactly, and the error shrinks by ``−L/(m a_lim)`` a cycle
(it converges while drag and back-pressure loss are below the limited thrust). The
acceleration grows between cycles as propellant burns: by ``a ṁ Δt / m`` at most. The
mass flow follows the thrust at the rated Isp (a constant Isp over the throttle range).
An unthrottled vehicle reads 1 whatever ``u`` holds (:func:`held`).

A throttled upper stage (``u[U_US_THROTTLE]``, :func:`held_upper`) runs the same law with
its own bounds, rate and acceleration limit and no schedule (its command is its
maximum), from its ignition to its cutoff command: its guidance, PEG, models the burn as
constant thrust until the limit and constant acceleration after it (``models/peg.py``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from savant_cli.models import blocks
from savant_cli.models.interp import interp1_at, tab, tab_offset

_PARAMS = blocks.PARAMETERS.block("throttle")
P_ON = _PARAMS.scalar("on", "1", "1: the first stage is throttled (u holds its setting), 0: it burns at rated thrust")
P_MIN = _PARAMS.scalar("minimum", "1", "lowest throttle setting, fraction of rated thrust")
P_MAX = _PARAMS.scalar("maximum", "1", "highest throttle setting, fraction of rated thrust")
P_RATE = _PARAMS.scalar("rate", "1/s", "largest change of the setting per second")
P_ACCEL_LIMIT = _PARAMS.scalar("axial_acceleration_limit", "m/s^2",
                               "sensed axial acceleration the throttle holds (0: no limit)")
P_SCHEDULED = _PARAMS.scalar("scheduled", "1", "1: the command follows the schedule table, 0: the maximum")
P_US_ON = _PARAMS.scalar("upper_stage.on", "1", "1: the upper stage is throttled (u holds its setting)")
P_US_MIN = _PARAMS.scalar("upper_stage.minimum", "1", "the upper stage's lowest setting, fraction of rated thrust")
P_US_MAX = _PARAMS.scalar("upper_stage.maximum", "1", "the upper stage's highest setting (its command)")
P_US_RATE = _PARAMS.scalar("upper_stage.rate", "1/s", "largest change of the upper stage's setting per second")
P_US_ACCEL_LIMIT = _PARAMS.scalar("upper_stage.axial_acceleration_limit", "m/s^2",
                                  "sensed axial acceleration the upper stage's throttle holds (0: unthrottled)")
_TABLES = blocks.TABLES.block("throttle")
T_TIME = _TABLES.table("fs_throttle_time", "s", "first-stage throttle schedule, mission time")
T_SETTING = _TABLES.table("fs_throttle", "1", "throttle setting at T_TIME, fraction of rated thrust")

_AUX = blocks.DIAGNOSTICS.block("throttle")
A_SETTING = _AUX.scalar("setting", "1", "the first stage's throttle setting (1: rated or unthrottled)")
A_US_SETTING = _AUX.scalar("upper_stage_setting", "1", "the upper stage's throttle setting (1: rated or unthrottled)",
                           blocks.Logged("upper_stage_throttle", (), "", lambda model: model.p[P_US_ON] != 0.0))

#: The tables of a stage without a schedule (never read: ``P_SCHEDULED`` is 0).
UNSCHEDULED = {"fs_throttle_time": np.array([0.0, 1.0]), "fs_throttle": np.array([1.0, 1.0])}


def build(inputs: blocks.ModelInputs, p: np.ndarray, tables: dict[str, np.ndarray]) -> None:
    """The first stage's throttle (none: ``P_ON`` 0, a setting of 1) and the upper
    stage's (none: ``P_US_ON`` 0)."""
    liquid = inputs.vehicle.first_stage.liquid
    th = liquid.throttle if liquid is not None else None
    tables.update(UNSCHEDULED)
    p[P_MIN] = p[P_MAX] = p[P_US_MIN] = p[P_US_MAX] = 1.0
    upper = inputs.vehicle.upper_stage.throttle
    if upper is not None:
        p[P_US_ON] = 1.0
        p[P_US_MIN], p[P_US_MAX], p[P_US_RATE] = upper.minimum, upper.maximum, upper.rate_per_s
        p[P_US_ACCEL_LIMIT] = upper.axial_acceleration_limit_mps2
    if th is None:
        return
    p[P_ON] = 1.0
    p[P_MIN] = th.minimum
    p[P_MAX] = th.maximum
    p[P_RATE] = th.rate_per_s
    p[P_ACCEL_LIMIT] = th.axial_acceleration_limit_mps2 or 0.0
    if th.time_s is not None:
        p[P_SCHEDULED] = 1.0
        tables.update(fs_throttle_time=th.time_s, fs_throttle=th.setting)


def start(p: np.ndarray, tb: np.ndarray) -> float:
    """The setting at liftoff: the schedule's at 0 s, or the maximum."""
    return scheduled(p, tb, 0.0) if p[P_ON] != 0.0 else 1.0


@njit(cache=True, error_model="numpy", inline="always")
def write_diagnostics(aux: np.ndarray, setting: float, upper_setting: float) -> None:
    """Write the throttle settings the first and the upper stage burn at (1) into ``aux``."""
    aux[A_SETTING] = setting
    aux[A_US_SETTING] = upper_setting


@njit(cache=True, error_model="numpy", inline="always")
def held_upper(setting: float, p: np.ndarray) -> float:
    """The throttle the upper stage burns at: the held ``setting`` if it is throttled, else 1."""
    return setting if p[P_US_ON] != 0.0 else 1.0


@njit(cache=True, error_model="numpy")
def cycle_upper(setting: float, accel: float, dt: float, p: np.ndarray) -> float:
    """The upper stage's setting after a flight-control cycle of ``dt`` (s) with the
    sensed axial acceleration ``accel`` (m/s²): the law with its maximum as the command."""
    return throttle_step(setting, p[P_US_MAX], accel, p[P_US_ACCEL_LIMIT], p[P_US_MIN], p[P_US_MAX],
                         p[P_US_RATE] * dt)


@njit(cache=True, error_model="numpy", inline="always")
def held(setting: float, p: np.ndarray) -> float:
    """The throttle the first stage burns at: the held ``setting`` if it is throttled, else 1."""
    return setting if p[P_ON] != 0.0 else 1.0


@njit(cache=True, error_model="numpy")
def scheduled(p: np.ndarray, tb: np.ndarray, t: float) -> float:
    """The schedule's setting at mission time ``t`` (s; its end values beyond its span),
    or the maximum without a schedule."""
    if p[P_SCHEDULED] == 0.0:
        return p[P_MAX]
    o, n = tab(tb, T_TIME)
    return interp1_at(tb, o, tab_offset(tb, T_SETTING), n, t)


@njit(cache=True, error_model="numpy")
def throttle_step(setting: float, command: float, accel: float, accel_limit: float, minimum: float, maximum: float,
                  max_change: float) -> float:
    """One cycle of the throttle law (module docstring): the new setting from the held
    ``setting``, the scheduled ``command``, the sensed axial acceleration ``accel`` and its
    limit ``accel_limit`` (m/s²; 0: none), the bounds and the largest change this cycle."""
    if accel_limit > 0.0 and accel > 0.0:
        command = min(command, setting * accel_limit / accel)
    command = min(max(command, minimum), maximum)
    return min(max(command, setting - max_change), setting + max_change)


@njit(cache=True, error_model="numpy")
def acceleration_limited(p: np.ndarray) -> bool:
    """Whether the throttle holds an axial-acceleration limit (the law then needs the
    sensed acceleration each cycle)."""
    return p[P_ON] != 0.0 and p[P_ACCEL_LIMIT] > 0.0


@njit(cache=True, error_model="numpy")
def cycle(setting: float, t: float, accel: float, dt: float, p: np.ndarray, tb: np.ndarray) -> float:
    """The setting after the flight-control cycle at mission time ``t`` (s) of length
    ``dt`` (s), with the sensed axial acceleration ``accel`` (m/s²)."""
    return throttle_step(setting, scheduled(p, tb, t), accel, p[P_ACCEL_LIMIT], p[P_MIN], p[P_MAX], p[P_RATE] * dt)
