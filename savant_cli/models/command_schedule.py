"""What the stored attitude profile is indexed by: mission time, or, in the first
stage, the Earth-relative speed (``guidance.first_stage_schedule``).

With ``time`` the command table is read at the mission time ``t`` (the source paper's
workflow). With ``relative_velocity`` the first stage reads it at the profile time
``τ`` at which the reference ascent (the command file's ``v_rel_m_s`` column) had the
vehicle's current Earth-relative speed, so a hot or cold motor flies the pitch profile
at the speeds it was shaped for (the Space Shuttle's first-stage pitch table was
indexed by relative velocity the same way). That holds up to the reference's fastest
first-stage sample (the motor's tail-off slows the vehicle before separation); from
there the profile runs on in time from where the speed index left it
(``τ = t + (τ_peak − t_peak)``), through separation and the upper stage. The commanded
rates of the table are per second of profile time; they are scaled by ``dτ/dt`` over
the last guidance interval.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from savant_cli.models import blocks

#: guidance.first_stage_schedule values; a value's code in the engine's schedule is its index
SCHEDULES = ("time", "relative_velocity")
BY_TIME = 0

_DISCRETE = blocks.DISCRETE.block("command_schedule")
D_PROFILE_TIME = _DISCRETE.scalar("profile_time", "s", "time in the command table of the latest guidance sample")
D_PROFILE_OFFSET = _DISCRETE.scalar("profile_offset", "s", "profile time minus mission time at the latest sample")
D_PROFILE_RATE = _DISCRETE.scalar("profile_rate", "1", "dτ/dt over the last guidance interval")


@njit(cache=True, error_model="numpy")
def profile_time(d: np.ndarray, t: float, speed: float, first_stage: bool, ref_speed: np.ndarray,
                 ref_time: np.ndarray, initialize: bool) -> float:
    """Profile time ``τ`` (s) for a guidance sample at mission time ``t`` and Earth-relative
    speed ``speed`` (m/s); updates the schedule's discrete state.

    ``ref_speed``, ``ref_time``: the reference ascent's speed at the table's samples from
    liftoff to its first-stage peak (strictly increasing, checked when the model is built)."""
    if first_stage and (initialize or d[D_PROFILE_TIME] < ref_time[ref_time.size - 1]):
        tau = np.interp(speed, ref_speed, ref_time)
        if not initialize:
            tau = max(tau, d[D_PROFILE_TIME])  # the profile never runs backwards
    else:
        tau = t + d[D_PROFILE_OFFSET]
    if initialize:
        d[D_PROFILE_RATE] = 1.0
    else:
        h = t - (d[D_PROFILE_TIME] - d[D_PROFILE_OFFSET])
        d[D_PROFILE_RATE] = (tau - d[D_PROFILE_TIME]) / h if h > 0.0 else 1.0
    d[D_PROFILE_TIME] = tau
    d[D_PROFILE_OFFSET] = tau - t
    return tau
