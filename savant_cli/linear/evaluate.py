"""The judgement of one operating point's loops: every margin labelled by its mode, the
bending-mode peaks, closed-loop stability and the requirement verdict. One copy, called by
``study=linear`` (and through it the flex sweep and the Monte Carlo margins) and by the
flight-control design, which keeps each point's plant (:class:`FrozenPoint`) and judges
candidate controllers against it: the plant does not depend on the controller.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import control as ct
import numpy as np

from savant_cli.config import RequirementSet
from savant_cli.linear.loops import AXES, broken_loops, controller_lti, fcs_phase, roll_gains_at, sensor_plant
from savant_cli.linear.margins import MarginRow, loop_margins
from savant_cli.linear.modes import MarginLabeler, ModePeak, aero_unstable, state_groups
from savant_cli.linear.plant import ROLL_INPUT, PlantLinearization, linearize_plant
from savant_cli.linear.requirements import STAGE_OF_PHASE, PointVerdict, evaluate_point
from savant_cli.linear.response import FastResponse
from savant_cli.models.fcs import FcsTables, flight_gains
from savant_cli.models.layout import U_T_IGN, R, V
from savant_cli.sim.build import SimModel
from savant_cli.sim.engine import schedule_variable
from savant_cli.sim.run import Snapshot

#: Closed-loop poles slower than this (rad/s) are the frozen-time trajectory's drift, not
#: the loop's stability.
DRIFT_RAD_S = 0.05
PHASE_NAMES = {0: "stack", 1: "coast", 2: "upper"}


def closed_loop_stability(poles_z: np.ndarray, dt: float) -> tuple[bool, float]:
    """Whether every closed-loop pole (z-plane, control period ``dt``) faster than the
    drift (:data:`DRIFT_RAD_S`) lies in the left half-plane, and the largest real part
    of those (1/s; NaN if none)."""
    s = np.log(np.asarray(poles_z, dtype=complex)) / dt
    fast = s[np.abs(s) > DRIFT_RAD_S]
    return bool(np.all(fast.real < 0.0)), float(fast.real.max()) if fast.size else float("nan")


def judge_loops(loops: dict[str, ct.StateSpace], groups: np.ndarray, unstable: bool, time_s: float,
                axes: tuple[str, ...] | None = None
                ) -> tuple[list[MarginRow], list[ModePeak], dict[str, FastResponse]]:
    """Every crossing of each loop of ``axes`` (None: every loop, pitch, yaw and roll
    where there is one) labelled by its mode, each loop's bending-mode peaks, and the
    loops' fast responses (for further use, e.g. disk margins)."""
    rows, peaks, responses = [], [], {}
    for axis in (tuple(loops) if axes is None else axes):
        fr = FastResponse(loops[axis])
        labeler = MarginLabeler(loops[axis], groups, unstable)
        rows += loop_margins(loops[axis], time_s, axis, response=fr, labeler=labeler)
        peaks += labeler.flex_peaks(fr, time_s, axis)
        responses[axis] = fr
    return rows, peaks, responses


def verdict(time_s: float, phase: str, rows: list[MarginRow], peaks: list[ModePeak], stable: bool,
            max_real: float, requirements: RequirementSet) -> tuple[list[MarginRow], PointVerdict]:
    """The point's requirement verdict, and its rows carrying their own verdicts."""
    v = evaluate_point(time_s, STAGE_OF_PHASE[phase], rows, peaks, stable, max_real, requirements)
    return [replace(r, meets_requirement=ok) for r, ok in zip(rows, v.row_verdicts)], v


@dataclass
class FrozenPoint:
    """One operating point's plant, kept for judging many controllers.

    Attributes
    ----------
    time_s : float
        Flight time (s).
    phase : int
        Flight-control phase at the point (``models/fcs.py``).
    schedule_var : float
        What the gains are scheduled on there (altitude m, or speed m/s).
    since_ignition : float
        Time since the upper-stage ignition command (s; the gains' fade-in,
        ``models/fcs.py::engagement``; read in upper-stage flight only).
    lin : PlantLinearization
        The continuous linear plant.
    plant : control.StateSpace
        The plant as the flight software samples it (:func:`sensor_plant`).
    aero_unstable : bool
        Whether the plant has an aerodynamically unstable rigid pole.
    """

    time_s: float
    phase: int
    schedule_var: float
    since_ignition: float
    lin: PlantLinearization
    plant: ct.StateSpace
    aero_unstable: bool

    @property
    def phase_name(self) -> str:
        return PHASE_NAMES[self.phase]


def freeze(model: SimModel, snap: Snapshot, dt: float, jacobian: str = "auto", rel_step: float = 1e-6) -> FrozenPoint:
    """Linearize the plant at a snapshot once (``study.jacobian``, ``jacobian_step``)."""
    lin = linearize_plant(model, snap, mode=jacobian, rel_step=rel_step)
    phase = fcs_phase(snap.events)
    sched_var = schedule_variable(snap.t, snap.x[R:R + 3], snap.x[V:V + 3], phase, model.p)
    return FrozenPoint(float(snap.t), phase, float(sched_var),
                       float(snap.t - snap.u[U_T_IGN]), lin, sensor_plant(lin, model, dt), aero_unstable(lin))


def point_controller(point: FrozenPoint, ft: FcsTables, dt: float, gains: np.ndarray | None = None) -> ct.StateSpace:
    """The flight control ``ft`` as an LTI at a frozen point: its gains at the point's
    state as in flight (scheduled, faded in after ignition), or ``gains`` (Kp, Ki, Kd, Kir
    of pitch then yaw); with the roll loop where the point's plant has the roll input."""
    if gains is None:
        gains = np.zeros(8)
        flight_gains(ft, point.phase, point.schedule_var, point.since_ignition, gains, 0)
    roll = roll_gains_at(ft, point.phase, point.since_ignition) if ROLL_INPUT in point.plant.input_labels else None
    return controller_lti(ft, gains, point.phase, dt, roll)


def candidate_loops(point: FrozenPoint, ft: FcsTables, dt: float) -> dict[str, ct.StateSpace]:
    """The loops (broken at one command, the other closed) of ``ft`` at a frozen point."""
    return broken_loops(point.plant, point_controller(point, ft, dt), dt)[1]


def judge_controller(point: FrozenPoint, ft: FcsTables, dt: float, requirements: RequirementSet,
                     gains: np.ndarray | None = None, axes: tuple[str, ...] = AXES
                     ) -> tuple[list[MarginRow], list[ModePeak], PointVerdict]:
    """The margins, bending-mode peaks and verdict of a candidate flight control ``ft`` on
    a frozen point (the loops of ``axes``; the closed loop with every loop); its gains
    scheduled at the point's state as in flight, or ``gains`` (Kp, Ki, Kd, Kir of pitch
    then yaw) when given."""
    fcs = point_controller(point, ft, dt, gains)
    g2, loops, _ = broken_loops(point.plant, fcs, dt)
    groups = state_groups(point.lin, point.plant, fcs)
    rows, peaks, _ = judge_loops(loops, groups, point.aero_unstable, point.time_s, tuple(axes))
    closed = ct.feedback(g2, ct.ss([], [], [], np.eye(g2.ninputs), dt), sign=1)
    stable, max_real = closed_loop_stability(closed.poles(), dt)
    rows, v = verdict(point.time_s, point.phase_name, rows, peaks, stable, max_real, requirements)
    return rows, peaks, v
