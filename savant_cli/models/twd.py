"""Tail-wags-dog: the reaction of the nozzle's angular acceleration on the vehicle.

The moving engine (mass m_R, CG a distance l_R aft of the gimbal, inertia I_R about the
gimbal) accelerated at δ̈ pushes on the vehicle at the gimbal with the force
``m_R l_R δ̈`` and the torque ``I_R δ̈`` (body axes; pitch δ̈ acts about Y with the force
along Z, yaw δ̈ about Z with the force along −Y). About the CG, for an on-axis gimbal,
the moment is ``(I_R + m_R l_R l_c) δ̈``. Only the angular-acceleration terms are kept
(small angles), as in the source paper; the translational effect of the force on the
CG is neglected there too. Source: SAVANT §III, "Tail-wags-dog"; ``docs/models.md``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from savant_cli.models import blocks
from savant_cli.models.configurations import ENGINE_FIRST

ENGINE = blocks.Record(
    "moving engine",
    ("mass", "kg", "mass of the gimbaled engine/nozzle"),
    ("cg_from_gimbal", "m", "distance from the gimbal to the moving mass's CG (aft)"),
    ("inertia", "kg*m^2", "inertia of the moving mass about the gimbal"),
)
E_MASS, E_ARM, E_INERTIA = ENGINE.offsets

_PARAMS = blocks.PARAMETERS.block("twd")
P_ON = _PARAMS.scalar("on", "1", "1: the engine-inertia reaction is applied (twd=on)")
P_FS_ENGINE = _PARAMS.record("first_stage", ENGINE, "first-stage moving engine")
P_US_ENGINE = _PARAMS.record("upper_stage", ENGINE, "upper-stage moving engine")
P_BOOSTER_ENGINE = _PARAMS.record("boosters", ENGINE, "each gimbaled booster's moving nozzle (zero: fixed nozzles)")
_AUX = blocks.DIAGNOSTICS.block("twd")
A_MOMENT = _AUX.array("moment", 3, "N*m", "engine-inertia (tail-wags-dog) moment about the CG (zero with twd=off)",
                      blocks.Logged("twd_moment", ("x", "y", "z"), "body"))


@njit(cache=True, error_model="numpy", inline="always")
def write_diagnostics(aux: np.ndarray, mx: float, my: float, mz: float) -> None:
    """Write the tail-wags-dog moment about the CG (N·m, body axes) into ``aux``."""
    aux[A_MOMENT] = mx
    aux[A_MOMENT + 1] = my
    aux[A_MOMENT + 2] = mz


def build(inputs: blocks.ModelInputs, p: np.ndarray, tables: dict[str, np.ndarray]) -> None:
    """The ``twd`` switch and the vehicle's moving-engine data."""
    p[P_ON] = 1.0 if inputs.cfg.twd.enabled else 0.0
    v = inputs.vehicle
    engines = [(P_FS_ENGINE, v.first_stage.engine), (P_US_ENGINE, v.upper_stage.engine)]
    if v.gimbaled_boosters:
        engines.append((P_BOOSTER_ENGINE, v.boosters.engine))
    for base, eng in engines:
        p[base + E_MASS] = eng.mass_kg
        p[base + E_ARM] = eng.cg_from_gimbal_m
        p[base + E_INERTIA] = eng.inertia_about_gimbal_kgm2


@njit(cache=True, error_model="numpy", inline="always")
def twd_loads(p: np.ndarray, engine: int, ddp: float, ddy: float, rgx: float, rgy: float, rgz: float):
    """Engine-inertia reaction of the active stage's engine (:func:`moving_mass_loads`
    of its record)."""
    return moving_mass_loads(p, P_FS_ENGINE if engine == ENGINE_FIRST else P_US_ENGINE, ddp, ddy, rgx, rgy, rgz)


@njit(cache=True, error_model="numpy", inline="always")
def moving_mass_loads(p: np.ndarray, e: int, ddp: float, ddy: float, rgx: float, rgy: float, rgz: float):
    """Engine-inertia reaction of the moving mass whose :data:`ENGINE` record is at
    ``p[e]``, for nozzle accelerations ``ddp``, ``ddy`` (rad/s²) at the arm
    ``r_cg→gimbal`` (m, body axes).

    Returns
    -------
    tuple of float
        ``(Fx, Fy, Fz, Ty, Tz, Mx, My, Mz)``: the force at the gimbal (N), the torque
        at the gimbal (N·m) and the moment about the CG (N·m), body axes. All zero with
        tail-wags-dog off.
    """
    if p[P_ON] == 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    m_l = p[e + E_MASS] * p[e + E_ARM]
    fwx = 0.0
    fwy = -m_l * ddy
    fwz = m_l * ddp
    twy = p[e + E_INERTIA] * ddp
    twz = p[e + E_INERTIA] * ddy
    return (fwx, fwy, fwz, twy, twz, rgy * fwz - rgz * fwy, rgz * fwx - rgx * fwz + twy,
            rgx * fwy - rgy * fwx + twz)
