"""A gain multiplier and a pure time delay inserted at one gimbal command, for the
time-domain stability margins (``study=time_margins``, docs/design_studies.md).

The engine applies the flight control's commands to the actuators after its own loop
delay (``controller.delay_s``) and holds them between cycles. With a perturbation
armed, the command of one axis (pitch or yaw, the loop that ``study=linear`` breaks at
the same place) reaches its actuator as::

    δ_c,applied(t) = K · δ_c,held(t − τ) + e(t)      for t_start ≤ t < t_end
    δ_c,applied(t) = δ_c,held(t)                      otherwise

with ``K`` the gain multiplier, ``τ`` the inserted delay (s; linear between plant
steps, so the margin is a continuous function of it) and ``e`` an excitation doublet
(+a for its first half, −a for its second, rad) that starts at ``t_start``. The delay
line starts full of the command held when the perturbation is armed (a delay element
switched in at ``t_start``), so the run must start at or before ``t_start``.

The perturbation is one float array: a header (:data:`AXIS` … :data:`HELD`) and the
delay line behind it. :data:`NONE`, with axis −1, is the engine's default: the check
costs one comparison per plant step and leaves every flown number unchanged.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from savant_cli.models.layout import U_DPC, U_DYC

AXIS = 0  # 0 pitch, 1 yaw, −1: nothing inserted
T_START = 1  # s, mission time
T_END = 2  # s
GAIN = 3  # multiplier of the held command (1: none)
DELAY = 4  # s, inserted delay
PULSE_AMPLITUDE = 5  # rad, excitation doublet amplitude (0: none)
PULSE_DURATION = 6  # s, the whole doublet
ARMED = 7  # 1 once the delay line holds the command
HELD = 8  # the held command (rad) of the axis, as the flight control set it
HEADER = 9

AXES = ("pitch", "yaw")

#: No perturbation: the engine's default.
NONE = np.array([-1.0] + [0.0] * (HEADER - 1))


def perturbation(axis: str, t_start: float, t_end: float, gain: float = 1.0, delay_s: float = 0.0,
                 pulse_rad: float = 0.0, pulse_s: float = 0.0, dt: float = 0.005) -> np.ndarray:
    """The array that arms a perturbation of the ``axis`` command.

    Parameters
    ----------
    axis : {"pitch", "yaw"}
        The gimbal command perturbed.
    t_start, t_end : float
        Mission time (s) the perturbation is applied from and until.
    gain : float
        Loop-gain multiplier (1 = none).
    delay_s : float
        Inserted pure delay, s (≥ 0).
    pulse_rad, pulse_s : float
        Excitation doublet amplitude (rad) and total duration (s) from ``t_start``.
    dt : float
        Plant step (s): sizes the delay line.
    """
    if axis not in AXES:
        raise ValueError(f"axis must be one of {AXES}, not {axis!r}")
    if delay_s < 0.0:
        raise ValueError(f"delay_s must be >= 0, not {delay_s}")
    n_line = int(math.ceil(delay_s / dt)) + 2
    a = np.zeros(HEADER + n_line)
    a[AXIS] = AXES.index(axis)
    a[T_START], a[T_END], a[GAIN], a[DELAY] = t_start, t_end, gain, delay_s
    a[PULSE_AMPLITUDE], a[PULSE_DURATION] = pulse_rad, pulse_s
    return a


@njit(cache=True, error_model="numpy")
def apply(pert: np.ndarray, k: int, t: float, dt: float, command_update: bool, u: np.ndarray) -> None:
    """Replace the held command of the perturbed axis in ``u`` by its perturbed value at
    plant step ``k`` (time ``t`` s, step ``dt`` s). ``command_update``: the engine has
    just written the flight control's new commands into ``u``."""
    slot = U_DPC if int(pert[AXIS]) == 0 else U_DYC
    line = pert[HEADER:]
    n = line.size
    if pert[ARMED] == 0.0:  # armed now: the line starts full of the current command
        pert[HELD] = u[slot]
        line[:] = u[slot]
        pert[ARMED] = 1.0
    elif command_update:
        pert[HELD] = u[slot]
    line[k % n] = pert[HELD]
    if t < pert[T_START] or t >= pert[T_END]:
        u[slot] = pert[HELD]
        return
    steps = pert[DELAY] / dt
    i0 = int(math.floor(steps))
    w = steps - i0
    delayed = (1.0 - w) * line[(k - i0) % n] + w * line[(k - i0 - 1) % n]
    value = pert[GAIN] * delayed
    tp = t - pert[T_START]
    if tp < pert[PULSE_DURATION]:
        value += pert[PULSE_AMPLITUDE] if tp < 0.5 * pert[PULSE_DURATION] else -pert[PULSE_AMPLITUDE]
    u[slot] = value
