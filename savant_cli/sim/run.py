"""Drive the compiled engine for one run: chunked calls with a progress bar, stop
reasons, and conversion of the raw log into named signals with units."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from savant_cli import constants, lifecycle
from savant_cli.io.record import Signal
from savant_cli.models import (
    blocks, earth, layout, navigation, peg, quaternion as qt, rcs, roll_gimbal, slosh, throttle
)
from savant_cli.sim import compile_notice, engine, loop_perturbation
from savant_cli.sim.build import SimModel
from savant_cli.sim.plant import compose, derivative

STOP_MESSAGES = {
    engine.STOP_CUTOFF: "cutoff: target orbital energy reached",
    engine.STOP_GUIDANCE_CUTOFF: "cutoff: PEG time to go elapsed",
    engine.STOP_DEPLETION: "cutoff: upper-stage propellant depleted before the target",
    engine.STOP_SEPARATION: "end of phase at first-stage separation",
    engine.STOP_TIME: "maximum simulation time reached",
}
DIVERGED = (engine.DIVERGED_NONFINITE, engine.DIVERGED_GROUND, engine.DIVERGED_RATE)
#: Why a run stopped, as a word (:attr:`SimResult.stop_reason`; the mission outcome reads it).
STOP_REASONS = {
    engine.STOP_CUTOFF: "cutoff_energy",
    engine.STOP_GUIDANCE_CUTOFF: "cutoff_guidance",
    engine.STOP_DEPLETION: "depletion",
    engine.STOP_SEPARATION: "separation",
    engine.STOP_TIME: "time_limit",
    engine.GUIDANCE_FAILED: "guidance_failed",
    **{code: "diverged" for code in DIVERGED},
}


@dataclass
class SimResult:
    """Raw outcome of one run."""

    log: np.ndarray  # (n_rows, n_cols) logged rows: t, x, aux, d
    x: np.ndarray  # final state
    d: np.ndarray  # final discrete state
    u: np.ndarray  # final held inputs
    k_final: int  # plant step index at the stop
    events: np.ndarray  # event times (NaN if not reached), see engine.EVENT_NAMES
    status: str  # complete | diverged | interrupted
    stop_code: int
    message: str
    t_final: float
    sim_wall_time_s: float  # wall time inside the compiled flight loop (compile excluded)
    snapshots: dict = field(default_factory=dict)  # step → Snapshot, for linearization
    compile_time_s: float = 0.0  # wall time compiling or loading the kernels before the first step

    @property
    def stop_reason(self) -> str:
        """Why the run stopped (:data:`STOP_REASONS`; ``"interrupted"`` by the user)."""
        if self.status == "interrupted":
            return "interrupted"
        return STOP_REASONS.get(self.stop_code, f"code_{self.stop_code}")


@dataclass(frozen=True)
class Snapshot:
    """The complete simulation state at the start of a plant step (before its events)."""

    step: int
    t: float
    x: np.ndarray
    d: np.ndarray
    u: np.ndarray
    events: np.ndarray


def log_columns(n_state: int) -> int:
    """Columns of a log row: time, the state, the diagnostics, the discrete state."""
    return 1 + n_state + layout.N_AUX + layout.N_DISC


def simulate(model: SimModel, progress: bool = True, chunk_s: float = 10.0,
             snapshot_steps: tuple[int, ...] = (), start: Snapshot | None = None, t_stop: float | None = None,
             perturbation: np.ndarray | None = None, keep_partial: bool = False) -> SimResult:
    """Fly one run from the model's initial state until a stop condition.

    A diverging run returns normally with ``status = "diverged"`` (``"guidance_failed"``
    when closed-loop guidance stopped it) and the history up to the failure. A
    ``KeyboardInterrupt`` propagates (the caller's work stops there), unless
    ``keep_partial``: then it returns ``status = "interrupted"`` with the history flown
    so far (the nominal flight writes it). The complete state at each
    of ``snapshot_steps`` (plant step indices) reached is kept in ``result.snapshots``.

    ``start``: fly on from this snapshot instead of liftoff; ``t_stop``: stop at this
    mission time (s) as at ``sim.max_time_s`` (``STOP_TIME``), if earlier;
    ``perturbation``: a gain and delay inserted at a gimbal command
    (:mod:`savant_cli.sim.loop_perturbation`; the run works on a copy).
    """
    rt = model.rates
    src = start if start is not None else Snapshot(model.k0, model.k0 * rt.dt, model.x0, model.d0, model.u0,
                                                   model.events0)
    x = src.x.copy()
    d = src.d.copy()
    u = src.u.copy()
    events = src.events.copy()
    pert = loop_perturbation.NONE if perturbation is None else perturbation.copy()
    t_max = model.sched.max_time_s if t_stop is None else min(t_stop, model.sched.max_time_s)
    n_total = int(np.ceil(t_max / rt.dt)) + 1
    n_rows = (n_total - src.step) // rt.n_log + 2
    nx = x.size
    log = np.empty((n_rows, log_columns(nx)))  # every kept row is fully written
    tb = model.packed_tables
    chunk = max(1, int(round(chunk_s / rt.dt)))
    k = src.step
    pending = sorted(s for s in set(snapshot_steps) if s >= k)
    snaps: dict[int, Snapshot] = {}
    row = 0
    code = engine.RUNNING
    detail = ""
    wall = 0.0
    status = "complete"
    # the kernels compile (cold cache, said on stderr) or load here, not in the timed loop
    compile_s = compile_notice.load_kernels([
        (engine.advance, (x, d, u, events, k, 0, rt, model.p, tb, model.fcs, model.gyro, model.smoother,
                          model.guidance, model.sched, log, row, pert)),
        (derivative, (k * rt.dt, x, u, model.p, tb, np.zeros(layout.N_AUX), np.zeros(nx))),
    ], apart=(compose, (k * rt.dt, x, u, model.p, tb, np.zeros(layout.N_AUX), np.zeros(nx), True)))  # the plant, in parallel
    bar = Progress(TextColumn("[bold]flight"), BarColumn(), TextColumn("t = {task.fields[t]:6.1f} s"),
                   TimeElapsedColumn(), transient=True, disable=not progress)
    with bar:
        task = bar.add_task("flight", total=t_max, t=k * rt.dt, completed=k * rt.dt)
        try:
            while code == engine.RUNNING and k < n_total:
                while pending and pending[0] == k:
                    snaps[k] = Snapshot(k, k * rt.dt, x.copy(), d.copy(), u.copy(), events.copy())
                    pending.pop(0)
                n_next = min(chunk, n_total - k)
                if pending:
                    n_next = min(n_next, pending[0] - k)
                t0 = time.perf_counter()
                code, done, row, detail = engine.advance(
                    x, d, u, events, k, n_next, rt, model.p, tb,
                    model.fcs, model.gyro, model.smoother, model.guidance, model.sched, log, row, pert)
                wall += time.perf_counter() - t0
                k += done
                bar.update(task, completed=k * rt.dt, t=k * rt.dt)
                lifecycle.stage("flight")
        except KeyboardInterrupt:
            if not keep_partial:
                raise
            status = "interrupted"
            detail = "interrupted by the user"
    t_final = k * rt.dt
    if code == engine.RUNNING and status == "complete":
        code = engine.STOP_TIME
    if status == "interrupted":
        message = f"interrupted at t = {t_final:.2f} s"
    elif code in DIVERGED:
        status = "diverged"
        message = f"diverged at t = {t_final:.3f} s: {detail}"
    elif code == engine.GUIDANCE_FAILED:
        status = "guidance_failed"
        message = f"guidance failed at t = {t_final:.3f} s: {detail}"
    else:
        message = STOP_MESSAGES.get(code, f"stopped with code {code}")
    # close the history with the final state (for summaries at cutoff)
    if row < log.shape[0] and (row == 0 or log[row - 1, 0] < t_final):
        aux = np.zeros(layout.N_AUX)
        derivative(t_final, x, u, model.p, tb, aux, np.zeros(nx))
        log[row, 0] = t_final
        log[row, 1:1 + nx] = x
        log[row, 1 + nx:1 + nx + layout.N_AUX] = aux
        log[row, 1 + nx + layout.N_AUX:] = d
        row += 1
    return SimResult(log=log[:row].copy(), x=x, d=d, u=u, k_final=k, events=events, status=status, stop_code=code,
                     message=message, t_final=t_final, sim_wall_time_s=wall, snapshots=snaps,
                     compile_time_s=compile_s)


# ----------------------------------------------------------------- signals from log
def channel_columns(n_channels: int) -> tuple[str, ...]:
    """The gimbal channels' column names in the histories: ``pitch``, ``yaw`` (the first
    engine's), then ``pitch2``, ``yaw2`` … (each further engine's, then each gimbaled
    booster's)."""
    pq = ("pitch", "yaw")
    return pq + tuple(f"{axis}{i}" for i in range(2, n_channels // 2 + 1) for axis in pq)


def _split(log: np.ndarray, nx: int):
    t = log[:, 0]
    x = log[:, 1:1 + nx]
    aux = log[:, 1 + nx:1 + nx + layout.N_AUX]
    d = log[:, 1 + nx + layout.N_AUX:]
    return t, x, aux, d


def launch_frame(model: SimModel) -> np.ndarray:
    """ECI→launch-frame DCM: the pad's north-east-down axes frozen in inertial space at
    liftoff (the reference of the Euler-angle attitude plots)."""
    r0 = model.x0[layout.R:layout.R + 3]
    lat, lon, _ = earth.ecef_to_geodetic(r0, constants.WGS84_A, constants.WGS84_E2)
    return earth.dcm_ecef_to_ned(lat, lon)  # ECI = ECEF at t = 0


def navigation_signals(d: np.ndarray) -> dict[str, Signal]:
    """The inertial navigation's errors (``navigation=inertial``, ``models/navigation.py``),
    navigated minus true, from the logged discrete state (updated every IMU sample)."""
    xyz = ("x", "y", "z")
    return {
        "navigation_position_error": Signal(d[:, navigation.D_POSITION:navigation.D_POSITION + 3], "m",
                                            "navigated minus true position", xyz, "ECI"),
        "navigation_velocity_error": Signal(d[:, navigation.D_VELOCITY:navigation.D_VELOCITY + 3], "m/s",
                                            "navigated minus true velocity", xyz, "ECI"),
        "navigation_attitude_error": Signal(d[:, navigation.D_ATTITUDE:navigation.D_ATTITUDE + 3], "rad",
                                            "navigated attitude error: rotation vector from the true to the "
                                            "navigated body attitude", xyz, "ECI"),
    }


def guidance_signals(t: np.ndarray, r: np.ndarray, d: np.ndarray, p: np.ndarray) -> dict[str, Signal]:
    """Powered Explicit Guidance's histories (``models/peg.py``), from the logged
    discrete state (each holds its latest cycle's value between cycles) and the position
    ``r`` (ECI, m) at the logged times ``t`` (s); ``p``: the plant parameters (the target
    plane)."""
    xyz = ("x", "y", "z")
    active = d[:, peg.D_ACTIVE] > 0.0
    lam, lam_dot = d[:, peg.D_LAMBDA:peg.D_LAMBDA + 3], d[:, peg.D_LAMBDA_DOT:peg.D_LAMBDA_DOT + 3]
    i_f = lam + lam_dot * (t - d[:, peg.D_T_LAMBDA])[:, None]
    i_f /= np.maximum(np.linalg.norm(i_f, axis=1), 1e-300)[:, None]
    up = r / np.linalg.norm(r, axis=1)[:, None]
    normal = -p[peg.P_IY:peg.P_IY + 3]
    steering = np.column_stack([np.arcsin(np.clip(np.sum(i_f * up, axis=1), -1, 1)),
                                np.arcsin(np.clip(i_f @ normal, -1, 1))])
    steering[~active] = 0.0
    return {
        "peg_active": Signal(d[:, peg.D_ACTIVE], "1", "1 once PEG steers the vehicle"),
        "peg_converged": Signal(d[:, peg.D_CONVERGED], "1", "1: the latest PEG cycle converged"),
        "peg_time_to_go": Signal(d[:, peg.D_TGO], "s", "PEG burn time to go (0 before PEG engages)"),
        "peg_cutoff_time": Signal(d[:, peg.D_T_CUTOFF], "s", "predicted cutoff time (0 before PEG engages)"),
        "peg_velocity_to_go": Signal(d[:, peg.D_VGO:peg.D_VGO + 3], "m/s", "velocity to be gained", xyz, "ECI"),
        "peg_velocity_to_go_magnitude": Signal(np.linalg.norm(d[:, peg.D_VGO:peg.D_VGO + 3], axis=1), "m/s",
                                               "magnitude of the velocity to be gained"),
        "peg_steering_angles": Signal(steering, "rad", "PEG's thrust direction: elevation above the local horizontal, "
                                      "and out of the target plane toward its angular momentum (0 before PEG engages)",
                                      ("elevation", "out_of_plane")),
        "peg_lambda": Signal(d[:, peg.D_LAMBDA:peg.D_LAMBDA + 3], "1", "steering unit vector (thrust direction "
                             "at t_lambda)", xyz, "ECI"),
        "peg_lambda_dot": Signal(d[:, peg.D_LAMBDA_DOT:peg.D_LAMBDA_DOT + 3], "1/s", "steering turning rate", xyz,
                                 "ECI"),
        "peg_t_lambda": Signal(d[:, peg.D_T_LAMBDA], "s", "time at which the thrust points along lambda"),
        "peg_cutoff_position": Signal(d[:, peg.D_RD:peg.D_RD + 3], "m", "predicted (target) cutoff position", xyz,
                                      "ECI"),
        "peg_cutoff_velocity": Signal(d[:, peg.D_VD:peg.D_VD + 3], "m/s", "target cutoff velocity at the predicted "
                                      "cutoff position", xyz, "ECI"),
        "peg_thrust_acceleration": Signal(d[:, peg.D_ACCEL], "m/s^2", "sensed thrust acceleration over the last "
                                          "guidance cycle"),
        "peg_terminal": Signal(d[:, peg.D_TERMINAL], "1", "1: steering frozen near cutoff"),
    }


def logged_diagnostics(aux: np.ndarray, model: SimModel) -> dict[str, Signal]:
    """The time histories of the diagnostics the models declare logged
    (:class:`savant_cli.models.blocks.Logged`), in declaration order: the field's units
    and description, the declaration's name, columns and frame; a field whose ``when``
    is false for ``model`` (its model off) is left out.

    Parameters
    ----------
    aux : numpy.ndarray
        The logged diagnostics, one row per sample.
    model : SimModel
        The built model that flew."""
    out = {}
    for f in blocks.DIAGNOSTICS.fields:
        lg = f.logged
        if lg is not None and (lg.when is None or lg.when(model)):
            columns = lg.columns if lg.columns_of is None else lg.columns_of(model)
            size = f.size if lg.columns_of is None else len(columns)  # a per-tank field: the run's tanks
            data = aux[:, f.index] if f.size == 1 else aux[:, f.index:f.index + size]
            out[lg.name] = Signal(data, f.units, f.description, columns, lg.frame)
    return out


def signals(result: SimResult, model: SimModel) -> dict[str, Signal]:
    """Named time histories with units, frames and column names."""
    lay = model.layout
    t, x, aux, d = _split(result.log, lay.n)
    xyz = ("x", "y", "z")
    rpy = ("roll", "pitch", "yaw")
    n_ch = len(lay.channels)  # every engine's pitch and yaw channels
    channels = channel_columns(n_ch)
    c_launch = launch_frame(model)
    q = x[:, layout.Q:layout.Q + 4]
    qc = d[:, layout.D_QS:layout.D_QS + 4]
    euler = qt.euler_321(np.einsum("ij,njk->nik", c_launch, qt.dcm_array(q))) if len(t) else np.zeros((0, 3))
    euler_c = qt.euler_321(np.einsum("ij,njk->nik", c_launch, qt.dcm_array(qc))) if len(t) else np.zeros((0, 3))
    config = np.full(len(t), 0.0)  # each jettison moves to the next configuration
    for k in (engine.EV_BOOSTER_JETTISON, engine.EV_SEPARATION, *engine.EV_ITEMS):
        if not np.isnan(result.events[k]):
            config[t >= result.events[k]] += 1.0
    s = {
        "time": Signal(t, "s", "mission time from liftoff"),
        "position_eci": Signal(x[:, layout.R:layout.R + 3], "m", "CG position", xyz, "ECI"),
        "velocity_eci": Signal(x[:, layout.V:layout.V + 3], "m/s", "CG inertial velocity", xyz, "ECI"),
        "body_rate": Signal(x[:, layout.W:layout.W + 3], "rad/s", "body angular rate relative to ECI", ("p", "q", "r"), "body"),
        "quaternion": Signal(q, "1", "attitude q_b2i (body to ECI, scalar first)", ("w", "x", "y", "z"), "ECI"),
        "quaternion_command": Signal(qc, "1", "smoothed guidance command q_c2i (commanded body to ECI)", ("w", "x", "y", "z"), "ECI"),
        "quaternion_guidance": Signal(d[:, layout.D_QG:layout.D_QG + 4], "1", "latest raw guidance command q_c2i", ("w", "x", "y", "z"), "ECI"),
        "rate_command": Signal(d[:, layout.D_RATE_CMD_B:layout.D_RATE_CMD_B + 3], "rad/s", "smoothed rate command", ("p", "q", "r"), "body"),
        "attitude_error": Signal(d[:, layout.D_ERR:layout.D_ERR + 3], "rad", "attitude error from the error quaternion (body rotated past command > 0)", rpy, "body"),
        "rate_error": Signal(d[:, layout.D_RATE_ERR:layout.D_RATE_ERR + 3], "rad/s", "blended rate error", ("p", "q", "r"), "body"),
        "attitude_euler": Signal(euler, "rad", "body attitude, 3-2-1 Euler angles relative to the launch frame (pad NED frozen at liftoff)", rpy, "launch"),
        "attitude_euler_command": Signal(euler_c, "rad", "smoothed command attitude, 3-2-1 Euler angles relative to the launch frame", rpy, "launch"),
        "gimbal_command": Signal(d[:, [layout.D_CMD_P, layout.D_CMD_Y]], "rad", "flight-control gimbal commands",
                                 channels[:2], "body"),
        "gimbal_rate": Signal(x[:, [lay.channel(k) + 1 for k in range(n_ch)]], "rad/s", "nozzle angular rates", channels,
                              "body"),
        "rcs_command": Signal(d[:, layout.D_CMD_RCS], "1", "roll jet command (+1 positive roll torque, 0, -1)"),
        "propellant_remaining": Signal(x[:, [lay.tank(n) for n in lay.tanks]], "kg", "propellant remaining", lay.tanks),
        "sensed_rate": Signal(d[:, layout.D_GYRO_Y:layout.D_GYRO_Y + 9], "rad/s", "rate-gyro outputs (rigid plus flex rate "
                              "at each gyro's node, through the gyro dynamics)",
                              tuple(f"{g}_{a}" for g in ("upper", "imu", "first") for a in ("p", "q", "r")), "body"),
        "flex_navigation_rotation": Signal(d[:, layout.D_FLEX_NAV:layout.D_FLEX_NAV + 3], "rad",
                                           "flex rotation at the navigation unit, added to the attitude errors", rpy, "body"),
        "fcs_gains": Signal(d[:, layout.D_GAINS:layout.D_GAINS + 8], "1", "applied gains: scheduled, faded in over the J-2X start (Kp rad/rad, Ki 1/s, Kd s, Kir rad/rad)",
                            ("pitch_kp", "pitch_ki", "pitch_kd", "pitch_kir", "yaw_kp", "yaw_ki", "yaw_kd", "yaw_kir")),
        "configuration": Signal(config, "1", "the configuration flown: its number in the vehicle's sequence (0 at "
                                                 "liftoff, one more at each jettison)"),
    }
    s.update(logged_diagnostics(aux, model))
    if model.p[peg.P_ON] != 0.0:
        s.update(guidance_signals(t, x[:, layout.R:layout.R + 3], d, model.p))
    if model.p[navigation.P_ON] != 0.0:
        s.update(navigation_signals(d))
    if model.p[throttle.P_ON] != 0.0:
        s["throttle"] = Signal(aux[:, throttle.A_SETTING], "1", "the first stage's throttle setting, fraction of rated "
                               "vacuum thrust")
    if model.p[rcs.P_PY_FORCE] > 0.0:  # pitch and yaw jets (the coasts)
        s["pitch_yaw_jet_command"] = Signal(d[:, layout.D_CMD_PY:layout.D_CMD_PY + 2], "1", "pitch and yaw jet "
                                            "commands (+1 a positive moment about the axis, 0, -1)", ("pitch", "yaw"))
    if n_ch > 2:  # a cluster: every engine's channels, and the roll command the mixer spreads over them
        s["gimbal_angle"] = Signal(x[:, [lay.channel(k) for k in range(n_ch)]], "rad",
                                   "each engine's gimbal angles (pitch, yaw: the first engine's; pitch2, yaw2: the "
                                   "second's …)", channels, "body")
        s["roll_gimbal_command"] = Signal(d[:, roll_gimbal.D_CMD_ROLL], "rad",
                                          "roll command to the engines' gimbals (the most-deflected nozzle's angle)")
    if lay.simplex:
        s["actuator_ram_position"] = Signal(x[:, [lay.channel(k) + 2 for k in range(n_ch)]], "rad",
                                            "simplex ram position as an equivalent gimbal angle", channels, "body")
        s["actuator_valve_flow"] = Signal(x[:, [lay.valve + layout.N_VALVE_PER_CHANNEL * k for k in range(n_ch)]],
                                          "rad/s", "simplex power-valve flow as no-load ram rate", channels, "body")
    if lay.slosh:
        tanks = lay.slosh_tanks
        yz = tuple(f"{tank}_{axis}" for tank in tanks for axis in ("y", "z"))
        starts = [lay.slosh_offset + slosh.N_PER_TANK * j for j in range(len(tanks))]
        s["slosh_position"] = Signal(x[:, [k + o for k in starts for o in (slosh.S_Y, slosh.S_Z)]], "m",
                                     "slosh-mass displacement from the tank centerline", yz, "body")
        s["slosh_velocity"] = Signal(x[:, [k + o for k in starts for o in (slosh.S_YDOT, slosh.S_ZDOT)]],
                                     "m/s", "slosh-mass lateral velocity", yz, "body")
        s["slosh_frequency"] = Signal(aux[:, slosh.A_FREQUENCY:slosh.A_FREQUENCY + len(tanks)] / (2.0 * np.pi), "Hz",
                                      "slosh natural frequency at the current acceleration", tanks)
    if lay.n_modes:
        fo, n = lay.flex, lay.n_modes
        modes = tuple(f"mode_{i + 1}" for i in range(n))
        s["flex_q"] = Signal(x[:, fo:fo + n], "kg^0.5*m", "modal coordinates (unit generalized mass)", modes)
        s["flex_qdot"] = Signal(x[:, fo + n:fo + 2 * n], "kg^0.5*m/s", "modal velocities", modes)
    return s
