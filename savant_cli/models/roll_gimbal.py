"""Roll by the engines' gimbals: the flight control's roll law for a stage whose engines
can roll the vehicle (a cluster with a non-zero roll column, ``models/cluster.py``).

Run at the flight-control rate after :func:`~savant_cli.models.fcs.fcs_step`::

    δr = −φ [ Kp e + Ki ∫e dt + Kd F(ω_err) ]

* ``e`` is the roll attitude error and ``F(ω_err)`` the roll-filtered blended roll-rate
  error, the same two signals the roll jets' phase plane reads;
* ``δr`` (rad) is the equivalent roll angle, the most-deflected nozzle's angle
  (the mixer, ``models/cluster.py``); the gains (``controller.roll.gimbal.stack`` and
  ``.upper``: Kp rad/rad, Ki 1/s, Kd s) are those of that angle;
* ``φ`` is the pitch/yaw loop's engagement (``fcs.engagement``): 1 on the stack, 0 in
  the coast (no thrust: no command, the integrator held), fading in from 0 to 1 over
  the upper-stage start.

With gains of 0 (the default) the command is 0 and the engines do not roll the vehicle.
The roll jets' phase plane runs beside the law: with both, the gimbals hold the roll
attitude inside the jets' deadband and the jets fire only on errors beyond it, as a
backup. A design rule for the gains: with ``b_r`` the roll moment of one radian of
``δr`` (the stage's thrust times :func:`savant_cli.models.cluster.roll_effectiveness`)
and ``I_xx`` the roll inertia, ``Kp = I_xx ω²/b_r`` and ``Kd = 2 ζ ω I_xx/b_r`` put the
rigid roll loop at the natural frequency ω (rad/s) and damping ζ.

Its discrete state is appended after the other models' (``models/__init__.py``), so
older staging-state files stay valid.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from savant_cli.models import blocks
from savant_cli.models.fcs import D_ERR

_DISCRETE = blocks.DISCRETE.block("roll_gimbal")
D_CMD_ROLL = _DISCRETE.scalar("command", "rad", "roll command to the engines' gimbals δr (equivalent roll angle)")
D_INT_ROLL = _DISCRETE.scalar("attitude_integral", "rad*s", "integral of the roll attitude error")


@njit(cache=True, error_model="numpy")
def roll_gimbal_step(d: np.ndarray, gains: np.ndarray, engagement: float, rate_error: float, dt: float) -> None:
    """One flight-control cycle of the roll law: ``δr`` into ``d[D_CMD_ROLL]``.

    Parameters
    ----------
    d : ndarray
        Discrete state; reads the roll attitude error ``d[fcs.D_ERR]`` (rad).
    gains : ndarray (3,)
        The phase's Kp (rad/rad), Ki (1/s), Kd (s).
    engagement : float
        The loop's engagement φ (1): the integrator runs while it is above 0.
    rate_error : float
        Flex-filtered roll-rate error, rad/s.
    dt : float
        Control period, s.
    """
    if engagement > 0.0:
        d[D_INT_ROLL] += d[D_ERR] * dt
    d[D_CMD_ROLL] = -engagement * (gains[0] * d[D_ERR] + gains[1] * d[D_INT_ROLL] + gains[2] * rate_error)


@njit(cache=True, error_model="numpy")
def reset(d: np.ndarray) -> None:
    """At separation: the command at null and the integrator cleared (the stage changes)."""
    d[D_CMD_ROLL] = 0.0
    d[D_INT_ROLL] = 0.0
