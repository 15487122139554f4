"""One frozen-time operating point analysed (:func:`analyse` → :class:`PointAnalysis`):
the plant linearized (``linear/plant.py``), assembled with the discrete flight control
(``linear/loops.py``), its loops' margins labelled by mode with the bending-mode peaks
(``linear/evaluate.py``), disk margins, bandwidths and closed-loop stability, and the
requirement verdict; and the scan of a flight's first-stage tail-off window
(:func:`scan_tailoff`, the physical criteria of ``linear/frozen_time.py``). Used by every
study that judges frozen points (``study=linear``, ``montecarlo``, ``flex_sweep``,
``time_margins``, ``mode_retention``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from savant_cli.config import LinearStudyConfig, RequirementSet
from savant_cli.linear.evaluate import closed_loop_stability, judge_loops, verdict as judge_verdict
from savant_cli.linear.frozen_time import FrozenTimeWindow, scan_point, window as window_of
from savant_cli.linear.loops import LinearPoint, assemble
from savant_cli.linear.margins import MarginRow, bandwidth_hz, disk_margins
from savant_cli.linear.modes import ModePeak, aero_unstable, state_groups
from savant_cli.linear.plant import linearize_plant
from savant_cli.linear.requirements import PointVerdict
from savant_cli.sim.build import SimModel
from savant_cli.sim.run import Snapshot, simulate


@dataclass
class PointAnalysis:
    """Everything ``study=linear`` computes at one operating point (:func:`analyse`).

    Attributes
    ----------
    point : LinearPoint
        The linear systems: plant, controller, broken loops, closed loop.
    rows : list of MarginRow
        Every crossing of every loop (gain dB, phase deg, frequency Hz), labelled by
        mode; with a requirement set, each with whether it meets it.
    peaks : list of ModePeak
        The loops' peak gain (dB) at each bending mode they carry.
    scalars : dict
        ``time_s`` (s), per axis the disk margins (gain dB, phase deg) and
        ``<axis>_bandwidth_hz`` (Hz), the MIMO disk margins (``mimo_*``),
        ``closed_loop_stable`` and ``closed_loop_max_real_1_per_s`` (1/s).
    verdict : PointVerdict or None
        Against the requirement set, when one is given.
    """

    point: LinearPoint
    rows: list[MarginRow]  # every crossing of every loop, labelled by mode
    peaks: list[ModePeak]  # the loops' peak gain at each bending mode they carry
    scalars: dict  # disk margins, bandwidths, closed-loop stability
    verdict: PointVerdict | None  # against the requirement set, when one is given


def analyse(model: SimModel, snap: Snapshot, study: LinearStudyConfig, dt: float,
            requirements: RequirementSet | None = None) -> PointAnalysis:
    """Linear systems, margins, bending-mode peaks, scalar results and (with
    ``requirements``) the requirement verdict of one point.

    Parameters
    ----------
    model : SimModel
        The built numeric model the flight was flown with.
    snap : Snapshot
        The flight's state at the point (its time ``snap.t`` in s).
    study : LinearStudyConfig
        The Jacobian's method (``jacobian``) and relative step (``jacobian_step``).
    dt : float
        The flight-control period (s) of the discrete loops.
    requirements : RequirementSet, optional
        The set the point is judged against; None: no verdict.

    Returns
    -------
    PointAnalysis
    """
    lin = linearize_plant(model, snap, mode=study.jacobian, rel_step=study.jacobian_step)
    pt = assemble(model, snap, lin, dt)
    groups = state_groups(lin, pt.plant, pt.controller)
    rows, peaks, responses = judge_loops(pt.loops, groups, aero_unstable(lin), snap.t)
    extra: dict[str, float] = {"time_s": snap.t}
    for c, axis in enumerate(pt.loops):  # pitch, yaw, and roll where the vehicle rolls by its gimbals
        for k, v in disk_margins(pt.loops[axis], responses[axis]).items():
            extra[f"{axis}_{k}"] = v
        extra[f"{axis}_bandwidth_hz"] = bandwidth_hz(pt.closed[c, c])
    for k, v in disk_margins(pt.mimo).items():
        extra[f"mimo_{k}"] = v
    stable, max_real = closed_loop_stability(pt.closed.poles(), dt)
    extra["closed_loop_stable"] = stable
    extra["closed_loop_max_real_1_per_s"] = max_real
    verdict = None
    if requirements is not None:
        rows, verdict = judge_verdict(snap.t, pt.phase, rows, peaks, stable, max_real, requirements)
    return PointAnalysis(pt, rows, peaks, extra, verdict)


def scan_tailoff(model: SimModel, separation_s: float | None, study: LinearStudyConfig, dt: float,
                 requirements: RequirementSet) -> tuple[FrozenTimeWindow | None, list[Snapshot]]:
    """The first-stage tail-off window of a flight that separated at ``separation_s``
    (``linear/frozen_time.py``): the flight flown again from its start to separation,
    keeping its state every ``study.frozen_time.step_s`` over the last ``scan_s`` (the same
    compiled model: the same trajectory), each state analysed, the criteria evaluated.

    Parameters
    ----------
    model : SimModel
        The built numeric model of the flight.
    separation_s : float or None
        The flight's separation time (s); None or NaN: no separation, no window.
    study : LinearStudyConfig
        The scan (``frozen_time``: criteria, ``scan_s``, ``step_s`` in s), the clearance
        before separation (``event_clearance_s``, s) and the Jacobian's settings.
    dt : float
        The flight-control period (s).
    requirements : RequirementSet
        Its rigid gain margin (dB) sets the control-power criterion's threshold.

    Returns
    -------
    window : FrozenTimeWindow or None
        None without a separation or with no criterion configured.
    snapshots : list of Snapshot
        The scan's states, in time order.
    """
    spec = study.frozen_time
    if not spec.criteria or separation_s is None or not np.isfinite(separation_s):
        return None, []
    rt = model.rates
    control = rt.dt * rt.n_fcs
    first = max(separation_s - spec.scan_s, control)
    times = np.arange(first, separation_s - study.event_clearance_s, spec.step_s)
    steps = sorted({int(round(t / control)) * rt.n_fcs for t in times})
    flown = simulate(model, progress=False, snapshot_steps=tuple(steps), t_stop=separation_s)
    snaps = [flown.snapshots[k] for k in sorted(flown.snapshots) if flown.snapshots[k].t < separation_s]
    points = []
    for snap in snaps:
        a = analyse(model, snap, study, dt, None)
        points.append(scan_point(a.point, a.rows))
    return window_of(points, separation_s, tuple(spec.criteria), requirements.rigid.gain_dB), snaps
