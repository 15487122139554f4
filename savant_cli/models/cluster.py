"""Engine clusters: the burning stage's thrust shared over its engines, each at its own
gimbal point and cant, with its own tail-wags-dog reaction.

A stage's engines are identical (``vehicle/two_stage.py``): the propulsion model
computes the stage's thrust (the engines' sum), and each of the ``n`` engines carries
``F/n`` along its own thrust line, at its own arm from the CG::

    F_i = (F/n) (cos θp cos θy, −sin θy, sin θp cos θy),   θ = δ + bias + cant_i − flex rotation
    r_i = r_cg→gimbal + diag(−1, 1, −1) Δ_i,               M = Σ r_i × F_i

with ``Δ_i`` the engine's gimbal offset from the stage's mean gimbal point (structure
frame). The gimbals are ganged: every engine of the stage follows the stage's pitch and
yaw channel (the control mixer, ``models/mixer.py``, is not in the flight loop yet), and
each engine's moving mass reacts on the vehicle at its own gimbal (``models/twd.py``). The
flexible body sees the stage's engines at the stage's one gimbal node. One engine at the
stage's gimbal, not canted, is the stage's single engine, bit for bit.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from savant_cli.models import blocks, propulsion, twd
from savant_cli.models.configurations import ENGINE_FIRST
from savant_cli.models.interp import tab

MOUNT = blocks.Record(
    "engine mount",
    ("stage", "1", "0 first stage, 1 upper stage"),
    ("share", "1", "the engine's share of its stage's thrust (1/n of n identical engines)"),
    ("dx", "m", "gimbal offset from the stage's gimbal point, structure x"),
    ("dy", "m", "gimbal offset, structure y"),
    ("dz", "m", "gimbal offset, structure z"),
    ("cant_pitch", "rad", "nozzle cant at null, pitch (added to the thrust-line angle)"),
    ("cant_yaw", "rad", "nozzle cant at null, yaw"),
)
M_STAGE, M_SHARE, M_DX, M_DY, M_DZ, M_CANT_PITCH, M_CANT_YAW = MOUNT.offsets
MOUNT_SIZE = MOUNT.size

_PARAMS = blocks.PARAMETERS.block("cluster")
P_UPPER_FIRST = _PARAMS.scalar("upper_stage_first_mount", "1",
                               "the upper stage's first mount record (the first stage's engines come before)")
_TABLES = blocks.TABLES.block("cluster")
T_MOUNTS = _TABLES.table("mounts", "1", f"one {MOUNT_SIZE}-element engine-mount record per engine, stage by stage")


def build(inputs: blocks.ModelInputs, p: np.ndarray, tables: dict[str, np.ndarray]) -> None:
    """Each stage's engine mounts (a stage without ``mounts``: one engine at its gimbal)."""
    mounts = mount_table(inputs.vehicle)
    p[P_UPPER_FIRST] = np.count_nonzero(mounts[:, M_STAGE] == 0.0)
    tables.update(mounts=mounts)


def mount_table(vehicle) -> np.ndarray:
    """The :data:`MOUNT` records of the vehicle's engines, ``(n_engines, MOUNT.size)``."""
    rows = []
    for stage, record in enumerate((vehicle.first_stage, vehicle.upper_stage)):
        mounts = record.mounts or (None,)
        for mount in mounts:
            offset, cant = (np.zeros(3), np.zeros(2)) if mount is None else (mount.offset_m, mount.cant_rad)
            rows.append([float(stage), 1.0 / len(mounts), *offset, *cant])
    return np.array(rows, dtype=float)


@njit(cache=True, error_model="numpy", inline="always")
def cluster_loads(tb: np.ndarray, p: np.ndarray, engine: int, thrust: float, pitch: float, yaw: float, ddp: float,
                  ddy: float, rgx: float, rgy: float, rgz: float):
    """Thrust and tail-wags-dog loads of the active stage's engines.

    Parameters
    ----------
    engine : int
        The engine phase (the upper stage's engines from separation on).
    thrust : float
        The stage's delivered thrust, N.
    pitch, yaw : float
        The thrust-line angles of the stage's channels (actuator angle + null bias −
        flex rotation at the gimbal), rad.
    ddp, ddy : float
        The nozzles' angular accelerations, rad/s².
    rgx, rgy, rgz : float
        ``r_cg→gimbal`` of the stage's gimbal point, body axes, m.

    Returns
    -------
    tuple of float
        ``(Fx, Fy, Fz, Mx, My, Mz)`` the thrust force (N) and its moment about the CG
        (N·m), then ``(Fx, Fy, Fz, Ty, Tz, Mx, My, Mz)`` the engines' tail-wags-dog force
        and torque at the gimbal and moment about the CG (as ``twd.twd_loads``), body axes.
    """
    o, n = tab(tb, T_MOUNTS)
    split = o + int(p[P_UPPER_FIRST]) * MOUNT_SIZE
    first, stop = (o, split) if engine == ENGINE_FIRST else (split, o + n)
    ftx = fty = ftz = mtx = mty = mtz = 0.0
    fwx = fwy = fwz = twy = twz = mwx = mwy = mwz = 0.0
    for b in range(first, stop, MOUNT_SIZE):
        ex, ey, ez = rgx - tb[b + M_DX], rgy + tb[b + M_DY], rgz - tb[b + M_DZ]  # structure → body offset
        fx, fy, fz, mx, my, mz = propulsion.thrust_loads(tb[b + M_SHARE] * thrust, pitch + tb[b + M_CANT_PITCH],
                                                         yaw + tb[b + M_CANT_YAW], ex, ey, ez)
        wx, wy, wz, ty, tz, nx, ny, nz = twd.twd_loads(p, engine, ddp, ddy, ex, ey, ez)
        ftx += fx
        fty += fy
        ftz += fz
        mtx += mx
        mty += my
        mtz += mz
        fwx += wx
        fwy += wy
        fwz += wz
        twy += ty
        twz += tz
        mwx += nx
        mwy += ny
        mwz += nz
    return (ftx, fty, ftz, mtx, mty, mtz), (fwx, fwy, fwz, twy, twz, mwx, mwy, mwz)
