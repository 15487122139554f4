"""Frozen-time linearization of the compiled plant about a trajectory state.

The same compiled :func:`savant_cli.sim.plant.derivative` the time simulation integrates
is differentiated numerically. Attitude is perturbed by a small body-axis rotation δθ
(``q = q₀ ⊗ [1, δθ/2]``), so the linear state has three attitude coordinates and no
redundant quaternion component. Position (its effect through gravity and altitude is a
trajectory drift of hours, not a control-loop dynamic), propellant masses (slow, frozen)
and the roll jets' thrust fractions (on/off control, outside linear analysis) are left
out. Velocity stays: it carries the angle-of-attack drift of the pitch plane.

Step sizes are chosen per state from its physical scale (:data:`STEP`), central
differences, error O(h²). Checked (tests/test_linear.py) against a closed-form rigid
pitch-plane model: rigid gain margin within 2e-4 dB, phase margin within 0.1°, the
aerodynamic gain margin within 2.3 %; and against the nonlinear plant's small-step
response within 5 % of peak. ``mode="fixed"`` uses one user step for every
perturbation instead (``rel_step`` × the state's scale).

Inputs: the equivalent engine's pitch and yaw commands and the lateral gusts
(:data:`INPUT_NAMES`), then, for a vehicle that rolls by its engines' gimbals, the roll
command (:data:`ROLL_INPUT`): the mixer's inputs, so the loops break there.
"""

from __future__ import annotations

from dataclasses import dataclass

import control as ct
import numpy as np

from savant_cli.models import actuator, aero, layout, quaternion as qt, sensors, slosh
from savant_cli.models.flex import flex_point
from savant_cli.models.sensors import misalignment
from savant_cli.sim.build import SimModel
from savant_cli.sim.plant import derivative
from savant_cli.sim.run import Snapshot

#: Perturbation scale per kind of state (SI): position m, velocity m/s, angle rad, rate
#: rad/s, actuator angle/rate/acceleration, valve flow, slosh position/velocity. Flex
#: coordinates are scaled so the largest rotation they cause at a point is ~1e-6 rad.
STEP = {"r": 1.0, "v": 1e-3, "att": 1e-6, "w": 1e-6, "act": (1e-6, 1e-5, 1e-4), "valve": 1e-5,
        "slosh": (1e-4, 1e-4), "flex_rot": 1e-6, "input": 1e-6, "gust": 1e-3}
GYRO_NAMES = ("upper", "imu", "first")
SENSOR_NAMES = (["nav_roll", "nav_pitch", "nav_yaw"]
                + [f"gyro_{g}_{a}" for g in GYRO_NAMES for a in ("p", "q", "r")])
INPUT_NAMES = ("dc_pitch", "dc_yaw", "gust_y", "gust_z")
#: The roll command to the engines' gimbals, an input after :data:`INPUT_NAMES` of a
#: vehicle that rolls by its gimbals (:func:`rolls_by_gimbal`).
ROLL_INPUT = "dc_roll"
EXTRA_OUTPUTS = ("gimbal_pitch", "gimbal_yaw", "alpha", "beta")


@dataclass
class PlantLinearization:
    """A continuous linear plant ``ż = A z + B u, y = C z + D u`` with names and scales."""

    sys: ct.StateSpace
    steps: np.ndarray  # perturbation used per state, SI
    z_index: np.ndarray  # index of each linear state's source in x (attitude: Q + axis)


def rolls_by_gimbal(model: SimModel) -> bool:
    """Whether the flight control rolls the vehicle by the engines' gimbals in any phase
    (``controller.roll.gimbal``, ``models/roll_gimbal.py``): its linear plant then has the
    roll command as an input, and its loops a roll loop where the gains are on."""
    return bool(np.any(model.fcs.roll_gimbal != 0.0))


def linear_states(model: SimModel, config: int = 0) -> tuple[list[str], np.ndarray]:
    """Names of the linear states in configuration ``config`` and the index in ``x`` each
    comes from; attitude coordinates carry the index ``Q + 1 + axis`` (their quaternion
    vector component). The slosh states of a tank whose stage is gone are left out (held,
    they would be poles at the origin that nothing moves)."""
    lay = model.layout
    gone = set()
    for j in range(len(lay.slosh_tanks)):
        if config >= model.p[slosh.P_TANKS + j * slosh.N_TANK_FIELDS + slosh.K_CONFIGS]:
            start = lay.slosh_offset + slosh.N_PER_TANK * j
            gone.update(range(start, start + slosh.N_PER_TANK))
    full = lay.names()
    idx = list(range(layout.V, layout.V + 3))
    names = ["dv_x", "dv_y", "dv_z", "dtheta_x", "dtheta_y", "dtheta_z"]
    idx += [layout.Q + 1, layout.Q + 2, layout.Q + 3]
    idx += list(range(layout.W, layout.W + 3))
    names += ["p", "q", "r"]
    channels = range(lay.channel_offset, lay.channel_offset + layout.N_PER_CHANNEL * len(lay.channels))
    idx += list(channels)
    names += [full[i] for i in channels]
    extra = [i for i in range(lay.n_core, lay.n) if i not in gone]
    idx += extra
    names += [full[i] for i in extra]
    return names, np.asarray(idx)


def _steps(model: SimModel, idx: np.ndarray, mode: str, rel_step: float) -> np.ndarray:
    lay = model.layout
    h = np.empty(idx.size)
    for j, i in enumerate(idx):
        if i < layout.R + 3:
            h[j] = STEP["r"]
        elif i < layout.V + 3:
            h[j] = STEP["v"]
        elif layout.Q <= i < layout.Q + 4:
            h[j] = STEP["att"]
        elif layout.W <= i < layout.W + 3:
            h[j] = STEP["w"]
        elif lay.channel_offset <= i < lay.rcs:
            h[j] = STEP["act"][(i - lay.channel_offset) % layout.N_PER_CHANNEL]
        elif lay.simplex and lay.valve <= i < lay.valve + layout.N_VALVE_PER_CHANNEL * len(lay.channels):
            h[j] = STEP["valve"]
        elif lay.slosh and lay.slosh_offset <= i < lay.slosh_offset + slosh.N_PER_TANK * len(lay.slosh_tanks):
            h[j] = STEP["slosh"][((i - lay.slosh_offset) % 4) // 2]
        else:  # flex: q then q̇, scaled by the largest rotation per unit coordinate
            mode_i = (i - lay.flex) % lay.n_modes
            shapes = model.tables.flex_shape[:, mode_i, :, 3:]
            sigma = max(float(np.abs(shapes).max()), 1e-12)
            w = max(float(model.tables.flex_freq[:, mode_i].max()), 1.0)
            h[j] = STEP["flex_rot"] / sigma * (1.0 if i < lay.flex + lay.n_modes else w)
    if mode == "fixed":  # one user step: the attitude perturbation becomes rel_step rad
        h = h * (rel_step / STEP["att"])
    return h


def _apply(x0: np.ndarray, idx: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Full state for a linear perturbation ``z`` (attitude as a body rotation)."""
    x = x0.copy()
    dtheta = np.zeros(3)
    for j, i in enumerate(idx):
        if layout.Q < i < layout.Q + 4:
            dtheta[i - layout.Q - 1] = z[j]
        else:
            x[i] += z[j]
    if np.any(dtheta):
        dq = np.array([1.0, *(0.5 * dtheta)])
        x[layout.Q:layout.Q + 4] = qt.qnormalize(qt.qmul(x0[layout.Q:layout.Q + 4], dq / np.linalg.norm(dq)))
    return x


def _rates(x0: np.ndarray, idx: np.ndarray, x: np.ndarray, xd: np.ndarray) -> np.ndarray:
    """ż from ẋ: the attitude rows are 2·vec(q₀* ⊗ q̇) (q₀ frozen)."""
    out = xd[idx].copy()
    att = [j for j, i in enumerate(idx) if layout.Q < i < layout.Q + 4]
    if att:
        dq = qt.qmul(qt.qconj(x0[layout.Q:layout.Q + 4]), xd[layout.Q:layout.Q + 4])
        out[att] = 2.0 * dq[1:4]
    return out


def _outputs(model: SimModel, t: float, x: np.ndarray, x0: np.ndarray, u: np.ndarray, tb: np.ndarray) -> np.ndarray:
    """Sensor signals the flight control reads, as the time run forms them (engine.advance):
    the navigation attitude q_b2i ⊗ q_s2b relative to its value at ``x0``, plus the flex
    rotation at the nav unit; each gyro's rigid + flex rate in its own (misaligned) axes;
    then gimbal angles and α, β."""
    p = model.p
    config = int(u[layout.U_CONFIG])
    rot = np.zeros(3)
    flex_point(x, config, p, tb, layout.PT_IMU, False, rot)
    q_imu = misalignment(p[sensors.P_IMU_MISALIGN:sensors.P_IMU_MISALIGN + 3])[0]
    dq = qt.qmul(qt.qconj(qt.qmul(x0[layout.Q:layout.Q + 4], q_imu)), qt.qmul(x[layout.Q:layout.Q + 4], q_imu))
    y = [2.0 * dq[1:4] + rot]
    for pt, pm in zip(layout.GYRO_POINTS, layout.GYRO_MISALIGN, strict=True):
        fr = np.zeros(3)
        flex_point(x, config, p, tb, pt, True, fr)
        y.append(misalignment(p[pm:pm + 3])[1] @ (x[layout.W:layout.W + 3] + fr))
    aux = np.zeros(layout.N_AUX)
    derivative(t, x, u, model.p, tb, aux, np.zeros(x.size))
    y.append(np.array([aux[actuator.A_ANGLES], aux[actuator.A_ANGLES + 1], aux[aero.A_ALPHA], aux[aero.A_BETA]]))
    return np.concatenate(y)


def linearize_plant(model: SimModel, snap: Snapshot, mode: str = "auto", rel_step: float = 1e-6) -> PlantLinearization:
    """Continuous frozen-time linear plant at a snapshot.

    Parameters
    ----------
    model : SimModel
        The model the time run flew.
    snap : Snapshot
        Operating point (state, flight-software state, held inputs at one plant step).
    mode : {"auto", "fixed"}
        "auto": per-state steps from :data:`STEP`; "fixed": those steps scaled so the
        attitude step equals ``rel_step`` rad (one user step for every perturbation).
    rel_step : float
        The user step of ``mode="fixed"``.

    Returns
    -------
    PlantLinearization
        Inputs ``dc_pitch, dc_yaw`` (actuator commands, rad) and ``gust_y, gust_z``
        (body-axis gust velocity, m/s); outputs the FCS sensors (``nav_*`` rad,
        ``gyro_*`` rad/s) and ``gimbal_pitch, gimbal_yaw, alpha, beta`` (rad).
    """
    tb = model.packed_tables
    names, idx = linear_states(model, int(snap.u[layout.U_CONFIG]))
    h = _steps(model, idx, mode, rel_step)
    n = idx.size
    x0, u0, t = snap.x, snap.u.copy(), snap.t
    aux = np.zeros(layout.N_AUX)
    xd = np.zeros(x0.size)
    a = np.zeros((n, n))
    c_rows = len(SENSOR_NAMES) + len(EXTRA_OUTPUTS)
    c = np.zeros((c_rows, n))

    def f(x, u):
        derivative(t, x, u, model.p, tb, aux, xd)
        return _rates(x0, idx, x, xd)

    for j in range(n):
        e = np.zeros(n)
        e[j] = h[j]
        xp, xm = _apply(x0, idx, e), _apply(x0, idx, -e)
        a[:, j] = (f(xp, u0) - f(xm, u0)) / (2.0 * h[j])
        c[:, j] = (_outputs(model, t, xp, x0, u0, tb) - _outputs(model, t, xm, x0, u0, tb)) / (2.0 * h[j])
    inputs = ((layout.U_DPC, STEP["input"]), (layout.U_DYC, STEP["input"]), (layout.U_GUST + 1, STEP["gust"]),
              (layout.U_GUST + 2, STEP["gust"]))
    names_in = list(INPUT_NAMES)
    if rolls_by_gimbal(model):
        inputs += ((layout.U_ROLL, STEP["input"]),)
        names_in.append(ROLL_INPUT)
    b = np.zeros((n, len(inputs)))
    d = np.zeros((c_rows, len(inputs)))
    for k, (ui, hu) in enumerate(inputs):
        up, um = u0.copy(), u0.copy()
        up[ui] += hu
        um[ui] -= hu
        b[:, k] = (f(x0.copy(), up) - f(x0.copy(), um)) / (2.0 * hu)
        d[:, k] = (_outputs(model, t, x0, x0, up, tb) - _outputs(model, t, x0, x0, um, tb)) / (2.0 * hu)
    sys = ct.ss(a, b, c, d, states=names, inputs=names_in, outputs=list(SENSOR_NAMES) + list(EXTRA_OUTPUTS),
                name=f"plant_t{int(round(t * 1000))}ms")
    return PlantLinearization(sys=sys, steps=h, z_index=idx)
