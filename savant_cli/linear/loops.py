"""The flight control as a discrete LTI at the control rate, the discretized plant with
its sensor transfer functions, and the loops broken at the actuator commands.

Pitch and yaw (``models/fcs.py``), frozen at the snapshot's scheduled gains:

    δc = −[Kp e + Ki I(e) + Kd F(Σ wᵢ ωᵢ) + Kir F_ir(I(ω_own))],     I(z) = T z / (z − 1)

(the integrators are updated before use, as in the flight code), F the two fourth-order
flex-filter sections, the gyro blend and the stage's own gyro as in flight. The roll jets
(on/off) are outside linear analysis. The continuous plant plus the gyros' second-order
transfer functions is discretized with a zero-order hold at the control period, so the
sample-and-hold of the commands is in the model.

Loop conventions: ``L`` is the open loop broken at an actuator command with the
negative-feedback convention (closed loop ``L/(1+L)``), so
:func:`control.stability_margins` applies directly.
"""

from __future__ import annotations

from dataclasses import dataclass

import control as ct
import numpy as np
from scipy.linalg import block_diag
from scipy.signal import tf2ss

from savant_cli.models.fcs import FCS_STACK, GYRO_FIRST, GYRO_UPPER
from savant_cli.sim import engine as E
from savant_cli.sim import layout as L
from savant_cli.sim.build import SimModel
from savant_cli.sim.run import Snapshot
from savant_cli.linear.plant import SENSOR_NAMES, PlantLinearization

AXES = ("pitch", "yaw")
COMMANDS = ("cmd_pitch", "cmd_yaw")


@dataclass
class LinearPoint:
    """All linear systems of one operating point (discrete, dt = control period)."""

    time_s: float
    phase: str  # stack | coast | upper
    plant_continuous: ct.StateSpace
    plant: ct.StateSpace  # discretized with the gyro dynamics
    controller: ct.StateSpace
    loops: dict[str, ct.StateSpace]  # loop-at-a-time, other axis closed
    loops_open: dict[str, ct.StateSpace]  # SISO with the other axis open
    mimo: ct.StateSpace  # both broken: 2x2 L
    closed: ct.StateSpace  # inputs cmd_pitch, cmd_yaw, gust_y, gust_z


def fcs_phase(events: np.ndarray) -> int:
    return int(E.fcs_phase(events))


def _filter(coef: np.ndarray, dt: float) -> ct.StateSpace:
    """Two fourth-order sections in series (coefficients in powers of z⁻¹, a₀ = 1),
    multiplied in state space (no polynomial products or cancellations)."""
    return ct.ss(*tf2ss(coef[0, 0], coef[0, 1]), dt) * ct.ss(*tf2ss(coef[1, 0], coef[1, 1]), dt)


def controller_lti(model: SimModel, snap: Snapshot, dt: float) -> ct.StateSpace:
    """The pitch/yaw flight control at a snapshot as a discrete LTI.

    Inputs: the 12 sensor signals (:data:`SENSOR_NAMES`) and the attitude commands
    ``cmd_pitch``, ``cmd_yaw`` (rad); outputs the gimbal commands ``dc_pitch``, ``dc_yaw``.
    """
    ft = model.fcs
    phase = fcs_phase(snap.events)
    fset = 0 if phase == FCS_STACK else 1
    own = GYRO_FIRST if phase == FCS_STACK else GYRO_UPPER
    gains = snap.d[L.D_GAINS:L.D_GAINS + 8]
    integ = ct.ss(1.0, 1.0, dt, dt, dt)  # T z / (z − 1) = T + T / (z − 1)
    n_in = len(SENSOR_NAMES) + len(COMMANDS)
    blocks = []
    for c, axis in enumerate(AXES):
        ax = c + 1  # body y (pitch), z (yaw)
        kp, ki, kd, kir = gains[4 * c:4 * c + 4]
        parts = [kp + ki * integ, kd * _filter(ft.filters[fset, 0], dt),
                 kir * _filter(ft.filters[fset, 1], dt) * integ]
        m = np.zeros((3, n_in))  # [e, blended rate, own-gyro rate] from the inputs
        m[0, ax] = 1.0
        m[0, len(SENSOR_NAMES) + c] = -1.0  # e = attitude − command
        for g in range(3):
            m[1, 3 + 3 * g + ax] = ft.blend[fset, g]
        m[2, 3 + 3 * own + ax] = 1.0
        a = block_diag(*[p.A for p in parts])
        b = np.vstack([p.B @ m[i:i + 1] for i, p in enumerate(parts)])
        cc = -np.hstack([p.C for p in parts])
        dd = -sum(p.D @ m[i:i + 1] for i, p in enumerate(parts))
        blocks.append((a, b, cc, dd))
    a = block_diag(blocks[0][0], blocks[1][0])
    b = np.vstack([blocks[0][1], blocks[1][1]])
    c = block_diag(blocks[0][2], blocks[1][2])
    d = np.vstack([blocks[0][3], blocks[1][3]])
    return ct.ss(a, b, c, d, dt, inputs=list(SENSOR_NAMES) + list(COMMANDS), outputs=["dc_pitch", "dc_yaw"],
                 name="fcs")


def sensor_plant(lin: PlantLinearization, model: SimModel, dt: float) -> ct.StateSpace:
    """The continuous plant followed by the rate gyros' transfer functions, discretized
    with a zero-order hold at ``dt``."""
    wn = model.info["gyro_wn_rad_s"]
    zeta = model.info["gyro_zeta"]
    p = lin.sys
    n_out = p.noutputs
    blocks = []
    for i, name in enumerate(p.output_labels):
        if name.startswith("gyro_"):
            blocks.append(ct.ss(ct.tf([wn * wn], [1.0, 2.0 * zeta * wn, wn * wn])))
        else:
            blocks.append(ct.ss([], [], [], [[1.0]]))
    s = ct.append(*blocks)
    assert s.ninputs == n_out
    cont = ct.series(p, s)
    cont = ct.ss(cont.A, cont.B, cont.C, cont.D, inputs=p.input_labels, outputs=p.output_labels, name="plant")
    disc = ct.c2d(cont, dt, "zoh")
    return ct.ss(disc.A, disc.B, disc.C, disc.D, dt, inputs=p.input_labels, outputs=p.output_labels, name="plant")


def assemble(model: SimModel, snap: Snapshot, lin: PlantLinearization, dt: float) -> LinearPoint:
    """Discrete plant, controller, broken loops and closed loop of one point (state-space
    algebra: series and feedback, no signal-name interconnection, for speed)."""
    plant = sensor_plant(lin, model, dt)
    fcs = controller_lti(model, snap, dt)
    n_s = len(SENSOR_NAMES)
    # G: plant inputs → controller outputs (commands zero); G2: from the two gimbal commands
    g = ct.series(plant[:n_s, :], fcs[:, :n_s])
    g2 = g[:, :2]
    loops, loops_open = {}, {}
    for c, axis in enumerate(AXES):
        close_other = np.zeros((2, 2))
        close_other[1 - c, 1 - c] = 1.0  # the other axis's command fed back (dc = r + k)
        one_open = ct.feedback(g2, ct.ss([], [], [], close_other, dt), sign=1)
        loops[axis] = _named(-one_open[c, c], f"L_{axis}", f"dc_{axis}", f"k_{axis}")
        loops_open[axis] = _named(-g2[c, c], f"Lo_{axis}", f"dc_{axis}", f"k_{axis}")
    mimo = -g2
    mimo = ct.ss(mimo.A, mimo.B, mimo.C, mimo.D, dt, inputs=["dc_pitch", "dc_yaw"], outputs=["k_pitch", "k_yaw"],
                 name="L_mimo")
    # closed loop: inputs [dc (2), gust (2), cmd (2)], outputs [k (2), selected plant outputs]
    n_in = plant.ninputs
    p_aug = ct.append(plant, ct.ss([], [], [], np.eye(2), dt))  # commands pass through
    sel_k = np.zeros((n_s + 2, plant.noutputs + 2))
    sel_k[:n_s, :n_s] = np.eye(n_s)
    sel_k[n_s:, plant.noutputs:] = np.eye(2)
    picks = ["nav_pitch", "nav_yaw", "gimbal_pitch", "gimbal_yaw", "alpha", "beta"]
    sel_y = np.zeros((len(picks), plant.noutputs + 2))
    for i, name in enumerate(picks):
        sel_y[i, plant.output_labels.index(name)] = 1.0
    # one copy of the plant states: [sensors, cmds] → controller, the picks pass through
    h = ct.series(p_aug, ct.ss([], [], [], np.vstack([sel_k, sel_y]), dt),
                  ct.append(fcs, ct.ss([], [], [], np.eye(len(picks)), dt)))
    fb = np.zeros((n_in + 2, 2 + len(picks)))
    fb[0, 0] = fb[1, 1] = 1.0  # dc = k
    cl = ct.feedback(h, ct.ss([], [], [], fb, dt), sign=1)
    inputs = [n_in, n_in + 1, 2, 3]  # cmd_pitch, cmd_yaw, gust_y, gust_z
    outputs = [2, 3, 4, 5, 6, 7, 0, 1]
    cl = cl[outputs, inputs]
    closed = ct.ss(cl.A, cl.B, cl.C, cl.D, dt, inputs=["pitch_command", "yaw_command", "gust_y", "gust_z"],
                   outputs=["pitch_attitude", "yaw_attitude", "pitch_gimbal", "yaw_gimbal", "alpha", "beta",
                            "pitch_gimbal_command", "yaw_gimbal_command"], name="closed_loop")
    phase = {0: "stack", 1: "coast", 2: "upper"}[fcs_phase(snap.events)]
    return LinearPoint(time_s=snap.t, phase=phase, plant_continuous=lin.sys, plant=plant, controller=fcs,
                       loops=loops, loops_open=loops_open, mimo=mimo, closed=closed)


def _named(sys: ct.StateSpace, name: str, inp: str, out: str) -> ct.StateSpace:
    return ct.ss(sys.A, sys.B, sys.C, sys.D, sys.dt, inputs=[inp], outputs=[out], name=name)


__all__ = ["AXES", "COMMANDS", "LinearPoint", "assemble", "controller_lti",
           "sensor_plant"]
