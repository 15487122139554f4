"""Every margin and every operating point judged against the requirement set (issue 12
item 7; the set is the ``requirements`` config group, ``config.RequirementSet``).

A point's checks, from its margin rows (labelled by mode, :mod:`savant_cli.linear.modes`),
its bending-mode peaks and its closed-loop poles:

- ``rigid``: a gain margin ≥ 0 dB (the phase crossover above the bandwidth) against
  ``rigid.gain_dB``; the phase margin against ``rigid.phase_deg``;
- ``aero``: the gain-reduction margin of the aerodynamically unstable vehicle against
  ``aero.gain_dB``; ``integrator`` (the rigid body's low side without an aerodynamic
  instability) against ``rigid.gain_reduction_dB``;
- ``slosh_<tank>`` (ares_i: ``slosh_lox``, ``slosh_lh2``): every crossing against
  ``slosh.gain_dB``/``phase_deg``;
- ``flex_<n>``, with the stage's requirement of that mode
  (``requirements.flex.<stage>``):

  - ``gain``-stabilized: the mode's attenuation (−peak |L| near its resonance, dB) at
    least ``gain_dB``;
  - ``phase``-stabilized: every crossing the mode makes at least ``phase_deg`` of phase
    margin and ``gain_dB`` of gain margin (|value|; a mode that makes no crossing is
    below 0 dB, which is checked);
  - ``either``: gain-stabilized if its attenuation meets ``gain_dB``, else judged
    phase-stabilized; when both fail, the checks shown are the crossings' if the mode
    reaches 0 dB and its attenuation otherwise;

- the closed loop: stable (every pole faster than the frozen-time drift in the left
  half-plane).

A margin of either sign is judged by its magnitude (a negative gain margin is a
gain-reduction margin, a negative phase margin the distance to the critical point on the
other side). A point passes when every check passes; its worst offender is the failing
check with the smallest ratio of value to requirement (a lost closed loop first, the
fastest-diverging one first among them).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields, is_dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from savant_cli.config import RequirementSet

if TYPE_CHECKING:  # the Monte Carlo workers' journal needs the encoding, not the linear analysis
    from savant_cli.linear.margins import MarginRow
    from savant_cli.linear.modes import ModePeak

#: Stage of a flight-control phase (``LinearPoint.phase``).
STAGE_OF_PHASE = {"stack": "first_stage", "coast": "upper_stage", "upper": "upper_stage"}


@dataclass(frozen=True)
class Check:
    """One requirement check of one point.

    Attributes
    ----------
    time_s : float
        Flight time of the point (s).
    axis : str
        Loop (``pitch``, ``yaw``), or ``""`` for the closed loop.
    mode : str
        The mode checked (``rigid``, ``aero``, ``integrator``, ``slosh_<tank>``,
        ``flex_<n>`` …) or ``closed_loop``.
    criterion : str
        ``gain margin``, ``gain-reduction margin``, ``phase margin``, ``attenuation``
        (a gain-stabilized bending mode) or ``stability`` (the closed loop).
    value : float
        The margin (dB or deg), the attenuation (dB) or, for ``stability``, the largest
        real part of the closed-loop poles (1/s).
    required : float
        What the requirement set asks (same unit; 0 for ``stability``: the real part
        must be below it).
    unit : str
        ``dB``, ``deg`` or ``1/s``.
    frequency_hz : float
        Where the value is read (Hz; NaN for ``stability``).
    passed : bool
        Whether the check passes.
    """

    time_s: float
    axis: str
    mode: str
    criterion: str
    value: float
    required: float
    unit: str
    frequency_hz: float
    passed: bool

    @property
    def ratio(self) -> float:
        """How far the value is from its requirement: |margin| / required (value /
        required for an attenuation); −∞ for a lost closed loop, +∞ for a kept one or a
        requirement of 0."""
        if self.criterion == "stability":
            return float("inf") if self.passed else float("-inf")
        magnitude = self.value if self.criterion == "attenuation" else abs(self.value)
        if self.required <= 0.0:
            return float("inf") if self.passed else float("-inf")
        return magnitude / self.required

    @property
    def severity(self) -> tuple[float, float]:
        """Sort key, worst first: the :attr:`ratio`, then (for lost closed loops, all at
        −∞) the larger real part."""
        return (self.ratio, -self.value if self.criterion == "stability" else 0.0)

    def text(self) -> str:
        """E.g. ``"55.0 s pitch flex_1 phase margin 15.9 deg < 30 deg at 1.02 Hz"``."""
        if self.criterion == "stability":
            return (f"{self.time_s:.1f} s closed loop {'stable' if self.passed else 'UNSTABLE'} "
                    f"(largest real part {self.value:.4g} 1/s)")
        op = ">=" if self.passed else "<"
        shown = self.value if self.criterion == "attenuation" else abs(self.value)
        return (f"{self.time_s:.1f} s {self.axis} {self.mode} {self.criterion} {shown:.1f} {self.unit} {op} "
                f"{self.required:g} {self.unit} at {self.frequency_hz:.3g} Hz")


@dataclass(frozen=True)
class PointVerdict:
    """The requirement verdict of one operating point: its checks, and each margin row's
    verdict (in the order of the rows given to :func:`evaluate_point`)."""

    time_s: float
    stage: str
    checks: tuple[Check, ...]
    row_verdicts: tuple[bool, ...]

    @property
    def passed(self) -> bool:
        return all(c.passed for c in self.checks)

    @property
    def failed(self) -> list[Check]:
        return [c for c in self.checks if not c.passed]

    @property
    def worst(self) -> Check | None:
        """The failing check furthest below its requirement; if all pass, the tightest."""
        pool = self.failed or [c for c in self.checks if c.criterion != "stability"]
        return min(pool, key=lambda c: c.severity) if pool else None


#: Sections of a requirement set that are not stability margins: bounds of the flown
#: state and the mission's counted classes, which the design corners leave as they are.
NOT_MARGINS = ("separation", "mission")


def scaled_requirements(req: RequirementSet, fraction: float) -> RequirementSet:
    """``req`` with every margin and attenuation (dB, deg; not :data:`NOT_MARGINS`) times ``fraction`` and its name
    marked (e.g. ``"ares_i × 0.5"``); 0 leaves closed-loop stability the only check that
    can fail. Used for the uncertainty corners of the flight-control design."""

    def scale(node):
        if isinstance(node, dict):
            return {k: scale(v) for k, v in node.items()}
        if not is_dataclass(node):
            return node
        return replace(node, **{f.name: (getattr(node, f.name) * fraction if f.name.endswith(("_dB", "_deg"))
                                         else scale(getattr(node, f.name))) for f in fields(node)
                                if f.name not in ("name", "source") + NOT_MARGINS})

    return replace(scale(req), name=f"{req.name} × {fraction:g}")


def _requirement(row: MarginRow, req: RequirementSet, stage: str) -> tuple[str, float, str]:
    """(mode, required value, criterion) of a margin row; a row labelled by band alone
    (no mode) is judged as its band's."""
    mode = row.mode or {"slosh": "slosh", "flex": "flex"}.get(row.band, "rigid" if row.value >= 0 else "aero")
    gain = row.kind == "gain"
    if mode == "aero":
        return mode, req.aero.gain_dB, "gain-reduction margin"
    if mode == "integrator":
        return mode, req.rigid.gain_reduction_dB, "gain-reduction margin"
    if mode.startswith("slosh"):
        return mode, req.slosh.gain_dB if gain else req.slosh.phase_deg, "gain margin" if gain else "phase margin"
    if mode.startswith("flex"):
        m = req.flex_mode(stage, mode)
        return mode, m.gain_dB if gain else m.phase_deg, "gain margin" if gain else "phase margin"
    if gain and row.value < 0.0:
        return mode, req.rigid.gain_reduction_dB, "gain-reduction margin"
    return mode, req.rigid.gain_dB if gain else req.rigid.phase_deg, "gain margin" if gain else "phase margin"


def _row_check(row: MarginRow, req: RequirementSet, stage: str) -> Check:
    mode, required, criterion = _requirement(row, req, stage)
    return Check(row.time_s, row.axis, mode, criterion, row.value, required, row.unit, row.frequency_hz,
                 abs(row.value) >= required)


def _flex_checks(crossings: list[tuple[int, Check]], peak: ModePeak | None, stabilization: str,
                 gain_dB: float) -> tuple[list[Check], dict[int, bool]]:
    """The checks of one bending mode in one loop, and the verdict of each of its rows."""
    attenuation = None
    if peak is not None:
        att = -peak.peak_dB
        attenuation = Check(peak.time_s, peak.axis, peak.mode, "attenuation", att, gain_dB, "dB",
                            peak.frequency_hz, att >= gain_dB)
    crossing = [c for _, c in crossings]
    if not crossing and peak is not None:  # no crossing: the mode stays below 0 dB
        crossing = [Check(peak.time_s, peak.axis, peak.mode, "attenuation", -peak.peak_dB, 0.0, "dB",
                          peak.frequency_hz, peak.peak_dB < 0.0)]
    phase_ok = all(c.passed for c in crossing)
    if stabilization == "gain" and attenuation is not None:
        chosen = [attenuation]
    elif stabilization == "phase" or attenuation is None:
        chosen = crossing
    elif attenuation.passed:
        chosen = [attenuation]
    elif phase_ok or peak.peak_dB >= 0.0:
        chosen = crossing
    else:
        chosen = [attenuation]
    mode_ok = all(c.passed for c in chosen)
    verdicts = {i: (c.passed if c in chosen else mode_ok) for i, c in crossings}
    return chosen, verdicts


def evaluate_point(time_s: float, stage: str, rows: list[MarginRow], peaks: list[ModePeak], stable: bool,
                   max_real: float, req: RequirementSet) -> PointVerdict:
    """The verdict of one point (module notes).

    Parameters
    ----------
    time_s : float
        Flight time of the point (s).
    stage : str
        ``first_stage`` or ``upper_stage`` (:data:`STAGE_OF_PHASE`).
    rows : list of MarginRow
        The point's margins, both loops.
    peaks : list of ModePeak
        The point's bending-mode peaks (:meth:`MarginLabeler.flex_peaks`).
    stable : bool
        Whether the closed loop is stable.
    max_real : float
        Largest real part of its poles outside the frozen-time drift (1/s).
    req : RequirementSet
        The requirement set.
    """
    checks: list[Check] = []
    verdicts: dict[int, bool] = {}
    flex: dict[tuple[str, str], list[tuple[int, Check]]] = {}
    for i, row in enumerate(rows):
        c = _row_check(row, req, stage)
        if c.mode.startswith("flex"):
            flex.setdefault((row.axis, c.mode), []).append((i, c))
        else:
            checks.append(c)
            verdicts[i] = c.passed
    peak_of = {(p.axis, p.mode): p for p in peaks}
    for key in sorted(set(flex) | set(peak_of)):
        m = req.flex_mode(stage, key[1])
        chosen, v = _flex_checks(flex.get(key, []), peak_of.get(key), m.stabilization, m.gain_dB)
        checks += chosen
        verdicts.update(v)
    checks.append(Check(time_s, "", "closed_loop", "stability", max_real, 0.0, "1/s", float("nan"), bool(stable)))
    return PointVerdict(time_s, stage, tuple(checks), tuple(verdicts[i] for i in range(len(rows))))


def verdict_line(groups: Sequence[tuple[str, Sequence[PointVerdict]]], set_name: str,
                 noun: str = "points") -> str:
    """One line: the set, how many groups pass (a group of points, e.g. a Monte Carlo
    run's, passes when all its points do) and the worst offender, prefixed with its
    group's label (``""``: none).

    Parameters
    ----------
    groups : sequence of (str, sequence of PointVerdict)
        Label and verdicts of each group (a linear study: one point each).
    set_name : str
        The requirement set's name.
    noun : str
        What a group is called (``points``, ``cases``, ``runs``).
    """
    if not groups:
        return f"requirements {set_name}: no {noun}"
    failing = [(label, v) for label, vs in groups for v in vs if not v.passed]
    n_fail = sum(not all(v.passed for v in vs) for _, vs in groups)
    head = f"requirements {set_name}: {'FAIL' if failing else 'PASS'}, {len(groups) - n_fail} of {len(groups)} {noun} pass"
    if not failing:
        return head
    label, worst = min(((label, v.worst) for label, v in failing), key=lambda lw: lw[1].severity)
    return f"{head}; worst: {label + ': ' if label else ''}{worst.text()}"


def check_dict(c: Check) -> dict:
    """A check as plain JSON-ready values."""
    return {"time_s": c.time_s, "axis": c.axis, "mode": c.mode, "criterion": c.criterion, "value": c.value,
            "required": c.required, "unit": c.unit, "frequency_hz": c.frequency_hz, "passed": c.passed}


def summary(points: list[PointVerdict], req: RequirementSet) -> dict:
    """The ``requirements`` entry of a study's ``summary.json``: the set, the verdict,
    and per point whether it passes, its failures and its worst offender."""
    return {"set": req.name, "passed": all(p.passed for p in points), "line": verdict_line([("", [p]) for p in points], req.name),
            "points_passing": f"{sum(p.passed for p in points)} of {len(points)}",
            "points": [{"time_s": p.time_s, "stage": p.stage, "passed": p.passed,
                        "worst": check_dict(p.worst) if p.worst else None,
                        "failed": [check_dict(c) for c in p.failed]} for p in points]}


# ---------------------------------------------------------------- numeric encoding
# The Monte Carlo journal and tables hold checks as numbers (one row per check).

#: Criteria, by code.
CRITERIA = ("gain margin", "gain-reduction margin", "phase margin", "attenuation", "stability")
#: Stages, by code.
STAGES = ("first_stage", "upper_stage")
#: Mode names with a fixed code; ``flex_<n>`` is ``len(FIXED_MODES) - 1 + n``. The two
#: slosh entries are the codes of a vehicle's first two sloshing tanks, named here for
#: the default tank names (:data:`DEFAULT_SLOSH_TANKS`); its further tanks' codes are
#: −1, −2, … (:func:`mode_code`).
FIXED_MODES = ("rigid", "aero", "integrator", "slosh_lox", "slosh_lh2", "closed_loop")
#: The sloshing tanks a batch's codes name when it records none (ares_i's and
#: small_launcher's, and every batch written before tanks were named by the vehicle).
DEFAULT_SLOSH_TANKS = ("lox", "lh2")
_SLOSH_CODES = (FIXED_MODES.index("slosh_lox"), FIXED_MODES.index("slosh_lh2"))
#: Loops, by code (−1: none, the closed loop).
AXIS_NAMES = ("pitch", "yaw", "roll")
#: Columns of :func:`checks_array`.
CHECK_ARRAY_COLUMNS = ("time_s", "axis", "mode", "criterion", "value", "required", "frequency_hz", "passed", "stage")


def mode_code(mode: str, slosh_tanks: Sequence[str] = DEFAULT_SLOSH_TANKS) -> int:
    """Integer code of a mode label (``rigid`` … ``closed_loop``, ``flex_<n>``,
    ``slosh_<tank>`` for a tank of ``slosh_tanks``, the vehicle's sloshing tanks in order:
    the first two take the fixed slosh codes, the others −1, −2, …)."""
    if mode.startswith("flex_"):
        return len(FIXED_MODES) - 1 + int(mode[5:])
    if mode.startswith("slosh_"):
        k = list(slosh_tanks).index(mode[len("slosh_"):])
        return _SLOSH_CODES[k] if k < len(_SLOSH_CODES) else len(_SLOSH_CODES) - 1 - k
    return FIXED_MODES.index(mode)


def mode_name(code: int, slosh_tanks: Sequence[str] = DEFAULT_SLOSH_TANKS) -> str:
    """The mode label of :func:`mode_code` (the same ``slosh_tanks``)."""
    if code < 0:
        return f"slosh_{slosh_tanks[len(_SLOSH_CODES) - 1 - code]}"
    if code in _SLOSH_CODES:
        return f"slosh_{slosh_tanks[_SLOSH_CODES.index(code)]}"
    return FIXED_MODES[code] if code < len(FIXED_MODES) else f"flex_{code - len(FIXED_MODES) + 1}"


def slosh_mode_tanks(tanks: Sequence[str]) -> tuple[str, ...]:
    """The tanks the slosh mode codes of a vehicle with sloshing ``tanks`` name: its own,
    or :data:`DEFAULT_SLOSH_TANKS` when it has none."""
    return tuple(tanks) or DEFAULT_SLOSH_TANKS


def checks_array(verdicts: Sequence[PointVerdict], slosh_tanks: Sequence[str] = DEFAULT_SLOSH_TANKS) -> np.ndarray:
    """Every check of the points as rows of :data:`CHECK_ARRAY_COLUMNS` (codes for the
    strings; slosh modes as :func:`mode_code` of ``slosh_tanks``)."""
    rows = [(c.time_s, AXIS_NAMES.index(c.axis) if c.axis else -1, mode_code(c.mode, slosh_tanks),
             CRITERIA.index(c.criterion),
             c.value, c.required, c.frequency_hz, float(c.passed), STAGES.index(v.stage))
            for v in verdicts for c in v.checks]
    return np.array(rows, dtype=float).reshape(-1, len(CHECK_ARRAY_COLUMNS))


def verdicts_of_array(rows: np.ndarray, slosh_tanks: Sequence[str] = DEFAULT_SLOSH_TANKS) -> list[PointVerdict]:
    """The point verdicts of :func:`checks_array` rows (without row verdicts; the same
    ``slosh_tanks``)."""
    points: dict[float, list[Check]] = {}
    stage: dict[float, str] = {}
    for t, ax, mode, crit, value, required, f, passed, st in rows:
        unit = {"stability": "1/s", "phase margin": "deg"}.get(CRITERIA[int(crit)], "dB")
        points.setdefault(float(t), []).append(
            Check(float(t), AXIS_NAMES[int(ax)] if ax >= 0 else "", mode_name(int(mode), slosh_tanks),
                  CRITERIA[int(crit)],
                  float(value), float(required), unit, float(f), bool(passed)))
        stage[float(t)] = STAGES[int(st)]
    return [PointVerdict(t, stage[t], tuple(cs), ()) for t, cs in points.items()]
