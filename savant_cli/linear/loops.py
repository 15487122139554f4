"""The flight control as a discrete LTI at the control rate, the discretized plant with
its sensor transfer functions, and the loops broken at the actuator commands.

Pitch and yaw (``models/fcs.py``), frozen at the snapshot's scheduled gains:

    δc = −[Kp e + Ki I(e) + Kd F(Σ wᵢ ωᵢ) + Kir F_ir(I(ω_own))],     I(z) = T z / (z − 1)

(the integrators are updated before use, as in the flight code), F the two fourth-order
flex-filter sections, the gyro blend and the stage's own gyro as in flight. Roll by the
engines' gimbals (``models/roll_gimbal.py``), where the phase's roll gains are on, is a
third loop, ``δr = −φ [Kp e + Ki I(e) + Kd F_r(Σ wᵢ pᵢ)]`` with the roll filter F_r and
the engagement φ; the roll jets (on/off) are outside linear analysis. The plant is
sampled exactly as the time run samples it (:func:`sensor_plant`): held commands over
each plant step, the rate gyros' own discrete filters at the sensor rate, and the loop's
transport delay (``controller.delay_s``), lifted to the control period.

Loop conventions: ``L`` is the open loop broken at an actuator command with the
negative-feedback convention (closed loop ``L/(1+L)``), so
:func:`control.stability_margins` applies directly.
"""

from __future__ import annotations

from dataclasses import dataclass

import control as ct
import numpy as np
from scipy.linalg import block_diag, expm
from scipy.signal import tf2ss

from savant_cli.linear.plant import ROLL_INPUT, SENSOR_NAMES, PlantLinearization, rolls_by_gimbal
from savant_cli.models import layout
from savant_cli.models.fcs import FCS_STACK, GYRO_FIRST, GYRO_UPPER, FcsTables, engagement
from savant_cli.sim import engine
from savant_cli.sim.build import SimModel
from savant_cli.sim.run import Snapshot

AXES = ("pitch", "yaw")
COMMANDS = ("cmd_pitch", "cmd_yaw")
#: A loop of the roll command to the engines' gimbals, after the pitch and yaw loops.
ROLL = "roll"


@dataclass
class LinearPoint:
    """All linear systems of one operating point (discrete, dt = control period)."""

    time_s: float
    phase: str  # stack | coast | upper
    plant_continuous: ct.StateSpace
    plant: ct.StateSpace  # discretized with the gyro dynamics
    controller: ct.StateSpace
    loops: dict[str, ct.StateSpace]  # loop-at-a-time, the other axes closed (pitch, yaw[, roll])
    loops_open: dict[str, ct.StateSpace]  # SISO with the other axes open
    mimo: ct.StateSpace  # all broken: 2x2 L (3x3 with roll)
    closed: ct.StateSpace  # inputs the commands (pitch, yaw[, roll]), gust_y, gust_z


def fcs_phase(events: np.ndarray) -> int:
    return int(engine.fcs_phase(events))


def _filter(coef: np.ndarray, dt: float) -> ct.StateSpace:
    """Two fourth-order sections in series (coefficients in powers of z⁻¹, a₀ = 1),
    multiplied in state space (no polynomial products or cancellations)."""
    return ct.ss(*tf2ss(coef[0, 0], coef[0, 1]), dt) * ct.ss(*tf2ss(coef[1, 0], coef[1, 1]), dt)


def _pid_block(m: np.ndarray, parts: list) -> tuple:
    """One axis's controller, ``−Σ parts[i](m[i] · inputs)`` as (A, B, C, D)."""
    a = block_diag(*[p.A for p in parts])
    b = np.vstack([p.B @ m[i:i + 1] for i, p in enumerate(parts)])
    cc = -np.hstack([p.C for p in parts])
    dd = -sum(p.D @ m[i:i + 1] for i, p in enumerate(parts))
    return a, b, cc, dd


def controller_lti(ft: FcsTables, gains: np.ndarray, phase: int, dt: float,
                   roll_gains: np.ndarray | None = None) -> ct.StateSpace:
    """The flight control as a discrete LTI: pitch and yaw, and roll by the engines'
    gimbals when ``roll_gains`` has a non-zero gain.

    Parameters
    ----------
    ft : FcsTables
        The flight control's filters and blend (``models/fcs.py::fcs_tables``).
    gains : numpy.ndarray
        The 8 scheduled gains Kp, Ki, Kd, Kir of pitch then yaw (``fcs.D_GAINS``).
    phase : int
        Flight-control phase (``FCS_STACK``: the stack filter set and first-stage gyro).
    dt : float
        Control period (s).
    roll_gains : numpy.ndarray, optional
        The roll law's Kp (rad/rad), Ki (1/s), Kd (s), the engagement applied
        (:func:`roll_gains_at`); None or zeros: no roll loop.

    Inputs: the 12 sensor signals (:data:`SENSOR_NAMES`) and the attitude commands
    ``cmd_pitch``, ``cmd_yaw`` (and ``cmd_roll``; rad); outputs the gimbal commands
    ``dc_pitch``, ``dc_yaw`` (and ``dc_roll``).
    """
    fset = 0 if phase == FCS_STACK else 1
    own = GYRO_FIRST if phase == FCS_STACK else GYRO_UPPER
    integ = ct.ss(1.0, 1.0, dt, dt, dt)  # T z / (z − 1) = T + T / (z − 1)
    rolls = roll_gains is not None and bool(np.any(roll_gains != 0.0))
    commands = list(COMMANDS) + (["cmd_roll"] if rolls else [])
    n_in = len(SENSOR_NAMES) + len(commands)
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
        blocks.append(_pid_block(m, parts))
    if rolls:
        kp, ki, kd = roll_gains
        m = np.zeros((2, n_in))  # [e, blended roll rate]
        m[0, 0] = 1.0
        m[0, len(SENSOR_NAMES) + 2] = -1.0
        for g in range(3):
            m[1, 3 + 3 * g] = ft.blend[fset, g]
        blocks.append(_pid_block(m, [kp + ki * integ, kd * _filter(ft.roll_filters[fset], dt)]))
    a = block_diag(*[blk[0] for blk in blocks])
    b = np.vstack([blk[1] for blk in blocks])
    c = block_diag(*[blk[2] for blk in blocks])
    d = np.vstack([blk[3] for blk in blocks])
    return ct.ss(a, b, c, d, dt, inputs=list(SENSOR_NAMES) + commands,
                 outputs=["dc_pitch", "dc_yaw"] + (["dc_roll"] if rolls else []), name="fcs")


def roll_gains_at(ft: FcsTables, phase: int, since_ignition: float) -> np.ndarray:
    """The roll law's gains Kp, Ki, Kd as flown at a point: the phase's, times the loop's
    engagement (``models/fcs.py::engagement``: 0 in the coast, fading in after ignition)."""
    return ft.roll_gimbal[phase] * engagement(phase, since_ignition, ft.fade)


def sensor_plant(lin: PlantLinearization, model: SimModel, dt: float) -> ct.StateSpace:
    """The linear plant as the flight software samples it, at the control period ``dt``.

    Exactly the time run's schedule (``engine.advance``), lifted from the plant step h to
    ``dt = N h``: the continuous plant with each plant step's input held (zero-order hold
    over h, :func:`scipy.linalg.expm`); at every sensor sample each rate gyro's discrete
    filter (the time run's own ``model.gyro`` matrices) reads the rate at the gyro and
    outputs its previous state's value; the flight control reads the navigation attitude
    and the gyro outputs at the start of its cycle, and its commands reach the actuators
    ``m = controller.delay_s / h`` plant steps later (the first ``m`` steps of a cycle
    still hold the previous commands, one extra state per command). Gust inputs are held
    over the cycle, undelayed.

    Returns a discrete system (dt) with the plant's inputs and outputs (``gyro_*`` now the
    gyro filter outputs).
    """
    sys = lin.sys
    a, b, c, d = (np.asarray(m, dtype=float) for m in (sys.A, sys.B, sys.C, sys.D))
    n, nu = b.shape
    rt = model.rates
    h, n_sub = rt.dt, rt.n_fcs
    m_delay = model.sched.command_delay_steps
    if abs(n_sub * h - dt) > 1e-12 or not 0 <= m_delay < n_sub:
        raise ValueError(f"control period {dt} s must be {n_sub} plant steps of {h} s and exceed the delay")
    zoh = expm(np.block([[a * h, b * h], [np.zeros((nu, n + nu))]]))
    phi, gam = zoh[:n, :n], zoh[:n, n:]
    gyro = [i for i, name in enumerate(sys.output_labels) if name.startswith("gyro_")]
    ng = len(gyro)
    ag = block_diag(*[model.gyro.ad] * ng)
    bg = block_diag(*[model.gyro.bd.reshape(2, 1)] * ng)
    cg = block_diag(*[model.gyro.cd.reshape(1, 2)] * ng)
    nx = n + 2 * ng
    # one plant step of [x, gyro filter states]; a sensor step also samples the gyros
    step_m = {False: block_diag(phi, np.eye(2 * ng)),
              True: np.block([[phi, np.zeros((n, 2 * ng))], [bg @ c[gyro], ag]])}
    step_b = {False: np.vstack([gam, np.zeros((2 * ng, nu))]), True: np.vstack([gam, bg @ d[gyro]])}
    commands = [sys.input_labels.index(name) for name in ("dc_pitch", "dc_yaw", ROLL_INPUT)
                if name in sys.input_labels]
    total = np.eye(nx)
    b_now = np.zeros((nx, nu))
    b_prev = np.zeros((nx, len(commands)))
    for j in range(n_sub):
        sensing = j % rt.n_sensor == 0
        mj, bj = step_m[sensing], step_b[sensing]
        total, b_now, b_prev = mj @ total, mj @ b_now, mj @ b_prev
        if j < m_delay:  # the previous cycle's commands still act
            b_prev += bj[:, commands]
            bj = bj.copy()
            bj[:, commands] = 0.0
        b_now += bj
    # outputs at the cycle's start: sensors of x, gyro filters' outputs
    c_out = np.hstack([c, np.zeros((c.shape[0], 2 * ng))])
    d_now = d.copy()
    d_prev = np.zeros((c.shape[0], len(commands)))
    c_out[gyro] = np.hstack([np.zeros((ng, n)), cg])
    d_now[gyro] = 0.0
    if m_delay:  # what the commands feed through to at the cycle's start is the held ones
        d_prev[:, :] = d_now[:, commands]
        d_now[:, commands] = 0.0
        k = len(commands)
        a_l = np.block([[total, b_prev], [np.zeros((k, nx + k))]])
        b_l = np.vstack([b_now, np.eye(nu)[commands]])
        c_l = np.hstack([c_out, d_prev])
    else:
        a_l, b_l, c_l = total, b_now, c_out
    return ct.ss(a_l, b_l, c_l, d_now, dt, inputs=sys.input_labels, outputs=sys.output_labels, name="plant")


def snapshot_controller(model: SimModel, snap: Snapshot, dt: float) -> ct.StateSpace:
    """:func:`controller_lti` of the model's flight control at a snapshot's gains (the
    roll loop's where the vehicle rolls by its gimbals)."""
    phase = fcs_phase(snap.events)
    roll = roll_gains_at(model.fcs, phase, snap.t - snap.u[layout.U_T_IGN]) if rolls_by_gimbal(model) else None
    return controller_lti(model.fcs, snap.d[layout.D_GAINS:layout.D_GAINS + 8], phase, dt, roll)


def _series(p: tuple, k: tuple) -> tuple:
    """``p`` then ``k`` ((A, B, C, D) each): python-control's ``k * p``, the same
    operations in the same order (so the same bits), without its signal bookkeeping."""
    pa, pb, pc, pd = p
    ka, kb, kc, kd = k
    a = np.concatenate((np.concatenate((pa, np.zeros((pa.shape[0], ka.shape[1]))), axis=1),
                        np.concatenate((kb @ pc, ka), axis=1)), axis=0)
    return a, np.concatenate((pb, kb @ pd), axis=0), np.concatenate((kd @ pc, kc), axis=1), kd @ pd


def _feedback_static(g: tuple, h: np.ndarray, sign: float) -> tuple:
    """``g`` with the static gain ``h`` in its feedback path: python-control's
    ``StateSpace.feedback`` for a system without states, the same operations."""
    a1, b1, c1, d1 = g
    f = np.eye(d1.shape[1]) - sign * h @ d1
    e_d2 = np.linalg.solve(f, h)
    t1 = np.eye(d1.shape[0]) + sign * d1 @ e_d2
    t2 = np.eye(d1.shape[1]) + sign * e_d2 @ d1
    return a1 + sign * b1 @ e_d2 @ c1, b1 @ t2, t1 @ c1, d1 @ t2


def broken_loops(plant: ct.StateSpace, fcs: ct.StateSpace, dt: float
                 ) -> tuple[ct.StateSpace, dict[str, ct.StateSpace], dict[str, ct.StateSpace]]:
    """``G`` (the gimbal commands → the controller's commands, negative-feedback sign
    inside: pitch, yaw, and roll when the controller has a roll loop), the loops broken at
    one command with the others closed, and with the others open. The algebra is
    python-control's series and feedback, done on the matrices (:func:`_series`,
    :func:`_feedback_static`): a design search builds these loops for every candidate."""
    n_s = len(SENSOR_NAMES)
    pm = tuple(np.asarray(m, dtype=float) for m in (plant.A, plant.B, plant.C, plant.D))
    km = tuple(np.asarray(m, dtype=float) for m in (fcs.A, fcs.B, fcs.C, fcs.D))
    axes = AXES + ((ROLL,) if fcs.noutputs > len(AXES) else ())
    n = len(axes)
    # G: plant inputs → controller outputs (commands zero); G2: from the gimbal commands
    a, b, c, d = _series((pm[0], pm[1], pm[2][:n_s, :], pm[3][:n_s, :]), (km[0], km[1][:, :n_s], km[2],
                                                                         km[3][:, :n_s]))
    columns = [plant.input_labels.index(f"dc_{axis}") for axis in axes]
    g2m = (a, b[:, columns], c, d[:, columns]) if n > len(AXES) else (a, b[:, :2], c, d[:, :2])
    g2 = ct.ss(*g2m, dt)
    loops, loops_open = {}, {}
    for k, axis in enumerate(axes):
        close_other = np.eye(n)
        close_other[k, k] = 0.0  # the other axes' commands fed back (dc = r + k)
        oa, ob, oc, od = _feedback_static(g2m, close_other, 1.0)
        loops[axis] = ct.ss(oa, ob[:, [k]], -oc[[k], :], -od[[k], :][:, [k]], dt, name=f"L_{axis}",
                            inputs=[f"dc_{axis}"], outputs=[f"k_{axis}"])
        loops_open[axis] = ct.ss(a, g2m[1][:, [k]], -c[[k], :], -g2m[3][[k], :][:, [k]], dt, name=f"Lo_{axis}",
                                 inputs=[f"dc_{axis}"], outputs=[f"k_{axis}"])
    return g2, loops, loops_open


def assemble(model: SimModel, snap: Snapshot, lin: PlantLinearization, dt: float) -> LinearPoint:
    """Discrete plant, controller, broken loops and closed loop of one point (state-space
    algebra: series and feedback, no signal-name interconnection, for speed)."""
    plant = sensor_plant(lin, model, dt)
    fcs = snapshot_controller(model, snap, dt)
    g2, loops, loops_open = broken_loops(plant, fcs, dt)
    axes = tuple(loops)
    n, n_s = len(axes), len(SENSOR_NAMES)
    mimo = -g2
    mimo = ct.ss(mimo.A, mimo.B, mimo.C, mimo.D, dt, inputs=[f"dc_{a}" for a in axes],
                 outputs=[f"k_{a}" for a in axes], name="L_mimo")
    # closed loop: inputs [plant inputs, cmd (n)], outputs [k (n), selected plant outputs]
    n_in = plant.ninputs
    p_aug = ct.append(plant, ct.ss([], [], [], np.eye(n), dt))  # commands pass through
    sel_k = np.zeros((n_s + n, plant.noutputs + n))
    sel_k[:n_s, :n_s] = np.eye(n_s)
    sel_k[n_s:, plant.noutputs:] = np.eye(n)
    picks = ["nav_pitch", "nav_yaw", "gimbal_pitch", "gimbal_yaw", "alpha", "beta"] + (["nav_roll"] if n > 2 else [])
    sel_y = np.zeros((len(picks), plant.noutputs + n))
    for i, name in enumerate(picks):
        sel_y[i, plant.output_labels.index(name)] = 1.0
    # one copy of the plant states: [sensors, cmds] → controller, the picks pass through
    h = ct.series(p_aug, ct.ss([], [], [], np.vstack([sel_k, sel_y]), dt),
                  ct.append(fcs, ct.ss([], [], [], np.eye(len(picks)), dt)))
    fb = np.zeros((n_in + n, n + len(picks)))
    for k, axis in enumerate(axes):
        fb[plant.input_labels.index(f"dc_{axis}"), k] = 1.0  # dc = k
    cl = ct.feedback(h, ct.ss([], [], [], fb, dt), sign=1)
    gusts = [plant.input_labels.index("gust_y"), plant.input_labels.index("gust_z")]
    if n == 2:
        inputs, outputs = [n_in, n_in + 1] + gusts, [2, 3, 4, 5, 6, 7, 0, 1]
        in_names = ["pitch_command", "yaw_command", "gust_y", "gust_z"]
        out_names = ["pitch_attitude", "yaw_attitude", "pitch_gimbal", "yaw_gimbal", "alpha", "beta",
                     "pitch_gimbal_command", "yaw_gimbal_command"]
    else:  # the roll command and attitude after pitch and yaw's, the roll gimbal command last
        inputs, outputs = [n_in, n_in + 1, n_in + 2] + gusts, [3, 4, 9, 5, 6, 7, 8, 0, 1, 2]
        in_names = ["pitch_command", "yaw_command", "roll_command", "gust_y", "gust_z"]
        out_names = ["pitch_attitude", "yaw_attitude", "roll_attitude", "pitch_gimbal", "yaw_gimbal", "alpha",
                     "beta", "pitch_gimbal_command", "yaw_gimbal_command", "roll_gimbal_command"]
    cl = cl[outputs, inputs]
    closed = ct.ss(cl.A, cl.B, cl.C, cl.D, dt, inputs=in_names, outputs=out_names, name="closed_loop")
    phase = {0: "stack", 1: "coast", 2: "upper"}[fcs_phase(snap.events)]
    return LinearPoint(time_s=snap.t, phase=phase, plant_continuous=lin.sys, plant=plant, controller=fcs,
                       loops=loops, loops_open=loops_open, mimo=mimo, closed=closed)


__all__ = ["AXES", "COMMANDS", "ROLL", "LinearPoint", "assemble", "broken_loops", "controller_lti", "roll_gains_at",
           "sensor_plant", "snapshot_controller"]
