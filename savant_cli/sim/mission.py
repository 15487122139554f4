"""A run's mission outcome, beside its flight status (issue 26 item 1).

The flight *status* (``complete``, ``limit_cycle``, ``saturated``, ``diverged`` …) says
how the flight went; the *mission outcome* says whether the run did what the vehicle is
for, and if not, why: each run falls in zero or more named **failure classes**, each
decided from stored numbers by a written rule (docs/outputs.md, "Mission outcome"):

``loss_of_control``
    The engine stopped the run on a divergence (a non-finite state, ground impact, a body
    rate above ``sim.max_body_rate_deg_s``), or flight health found the attitude error
    (or α) beyond its loss-of-control bound (summary ``loss_of_control``).
``guidance_failure``
    Closed-loop guidance stopped the run (``guidance_failed``: no converged solution).
``propellant_depletion``
    An upper-stage propellant ran out before guidance commanded the cutoff.
``time_limit``
    The run reached ``sim.max_time_s`` before its phase's end.
``insertion_tolerance``
    The run cut off, but its osculating perigee, apogee or inclination differs from the
    target by more than ``guidance.target.tolerance`` (strictly more: an error equal to
    the tolerance is inside it). Judged only for a phase that ends at cutoff.
``structural_allowable``
    The total q·α exceeded the vehicle's allowable (``qalpha_limit_exceeded``).
``separation_state``
    At first-stage separation the body rate, attitude error or q·α was above its bound in
    ``requirements.separation`` (``separation_requirements_met`` = 0).
``unhealthy_flight``
    Flight health flagged a limit cycle, a slow divergence, or time on an actuator limit
    beyond ``sim.health.max_saturation_s`` (``health_flags``).
``run_error``
    The run could not be flown to a verdict: a dispersed sample the config refuses, or a
    software error (status ``invalid`` or ``failed``). Counted as a failure: a run that was
    not flown demonstrates nothing.

A run **succeeds** when none of its classes is among the counted ones
(``requirements.mission.failure_classes``, by default all). An ``interrupted`` run has
no outcome and is not counted anywhere.

The classes of a run are stored as one integer, ``mission_class_mask`` (bit ``i`` for
``FAILURE_CLASSES[i]``), so that a batch's journal and ``savant.h5`` keep them as a
number and a batch can be recounted under another counted set.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from savant_cli.io.record import FAILURE_CLASSES

#: Words for each class on a console line.
CLASS_LABELS = {"loss_of_control": "loss of control", "guidance_failure": "guidance failure",
                "propellant_depletion": "propellant depletion", "time_limit": "time limit",
                "insertion_tolerance": "insertion outside tolerance",
                "structural_allowable": "structural allowable exceeded",
                "separation_state": "separation state outside its requirements", "unhealthy_flight": "unhealthy flight",
                "run_error": "run error"}
#: Health flags (``sim/health.py``) that make a flight unhealthy.
UNHEALTHY_FLAGS = ("limit_cycle", "slow_divergence", "saturated")
#: Statuses of a run that was not flown to a verdict.
ERROR_STATUSES = ("failed", "invalid")
#: The summary keys :func:`mission_keys` adds to a run's summary.
MISSION_KEYS = ("mission_class_mask", "mission_classes", "mission_success", "mission_verdict")


@dataclass(frozen=True)
class Tolerance:
    """Insertion tolerances: the largest |error| of the osculating perigee and apogee
    altitudes (km) and of the inclination (deg) that is still on target."""

    perigee_km: float
    apogee_km: float
    inclination_deg: float


@dataclass(frozen=True)
class MissionOutcome:
    """The failure classes of one run and, per class, the numbers behind it."""

    reasons: dict[str, str]  # class → what decided it, in words and numbers

    @property
    def classes(self) -> tuple[str, ...]:
        """The run's classes in :data:`FAILURE_CLASSES` order."""
        return tuple(c for c in FAILURE_CLASSES if c in self.reasons)

    @property
    def mask(self) -> int:
        return class_mask(self.classes)

    def success(self, counted: Iterable[str] = FAILURE_CLASSES) -> bool:
        """No class of the run is among ``counted``."""
        return not set(self.classes) & set(counted)

    def line(self, counted: Iterable[str] = FAILURE_CLASSES) -> str:
        """``"mission: SUCCESS"``, or ``"mission: FAILURE — <class>: <reason>; …"``; classes
        not counted are named as such."""
        counted = set(counted)
        failing = [c for c in self.classes if c in counted]
        ignored = [c for c in self.classes if c not in counted]
        text = "mission: " + ("FAILURE — " + "; ".join(f"{CLASS_LABELS[c]}: {self.reasons[c]}" for c in failing)
                              if failing else "SUCCESS")
        if ignored:
            text += " (not counted as failures: " + "; ".join(f"{CLASS_LABELS[c]}: {self.reasons[c]}"
                                                               for c in ignored) + ")"
        return text


def class_mask(classes: Iterable[str]) -> int:
    """The bit mask of ``classes`` (bit ``i`` for ``FAILURE_CLASSES[i]``)."""
    return sum(1 << FAILURE_CLASSES.index(c) for c in set(classes))


def classes_of(mask: int) -> tuple[str, ...]:
    """The classes of a bit mask, in :data:`FAILURE_CLASSES` order."""
    return tuple(c for i, c in enumerate(FAILURE_CLASSES) if int(mask) >> i & 1)


def classify(summary: Mapping[str, Any], status: str, stop_reason: str, judge_insertion: bool,
             tolerance: Tolerance | None) -> MissionOutcome:
    """The mission outcome of one run (rules in the module notes).

    Parameters
    ----------
    summary : mapping
        The run's summary with its health keys (``sim/summary.py``, ``sim/health.py``):
        ``insertion_*_error_*``, ``qalpha_limit_exceeded``, ``loss_of_control``,
        ``health_flags`` … (a missing key decides nothing).
    status : str
        The run's flight status.
    stop_reason : str
        Why the engine stopped (:attr:`savant_cli.sim.run.SimResult.stop_reason`).
    judge_insertion : bool
        The phase ends at cutoff, so the orbit is judged against ``tolerance``.
    tolerance : Tolerance or None
        The insertion tolerances; None: the insertion is not judged.
    """
    reasons: dict[str, str] = {}
    if status in ERROR_STATUSES:
        return MissionOutcome({"run_error": summary.get("message") or status})
    if status == "diverged":
        reasons["loss_of_control"] = str(summary.get("message") or "the run diverged")
    elif summary.get("loss_of_control"):
        reasons["loss_of_control"] = str(summary.get("loss_of_control_reason") or "beyond the loss-of-control bound")
    if status == "guidance_failed":
        reasons["guidance_failure"] = str(summary.get("message") or "guidance failed")
    if stop_reason == "depletion":
        reasons["propellant_depletion"] = f"upper-stage propellant depleted at {_num(summary, 'final_time_s', '.1f')} s"
    if stop_reason == "time_limit":
        reasons["time_limit"] = f"sim.max_time_s reached at {_num(summary, 'final_time_s', '.1f')} s"
    if judge_insertion and tolerance is not None and stop_reason in ("cutoff_guidance", "cutoff_energy"):
        misses = []
        for key, tol, unit in (("insertion_perigee_error_km", tolerance.perigee_km, "km"),
                               ("insertion_apogee_error_km", tolerance.apogee_km, "km"),
                               ("insertion_inclination_error_deg", tolerance.inclination_deg, "deg")):
            err = summary.get(key)
            if err is None or not abs(err) <= tol:  # a missing or non-finite error is not on target
                misses.append(f"{key.removeprefix('insertion_').removesuffix('_error_' + unit)} error "
                              f"{_fmt(err)} {unit} (tolerance ±{tol:g})")
        if misses:
            reasons["insertion_tolerance"] = ", ".join(misses)
    if summary.get("qalpha_limit_exceeded") == 1:
        reasons["structural_allowable"] = (f"q·α {_num(summary, 'max_qalpha_Pa_deg', ',.0f')} Pa·deg = "
                                           f"{_num(summary, 'qalpha_limit_ratio', '.3f')} × the allowable, "
                                           f"{_num(summary, 'time_above_qalpha_limit_s', '.2f')} s above it")
    if summary.get("separation_requirements_met") == 0:
        reasons["separation_state"] = str(summary.get("separation_violations") or "outside requirements.separation")
    flags = [f for f in str(summary.get("health_flags") or "").split(",") if f in UNHEALTHY_FLAGS]
    if flags:
        reasons["unhealthy_flight"] = "; ".join(_health_reason(summary, f) for f in flags)
    return MissionOutcome(reasons)


def _health_reason(summary: Mapping[str, Any], flag: str) -> str:
    """The numbers behind one health flag, from the run's health keys."""
    if flag == "limit_cycle":
        return (f"limit cycle of {summary.get('limit_cycle_signal') or '?'}, "
                f"{_num(summary, 'limit_cycle_amplitude_deg', '.3g')} deg at "
                f"{_num(summary, 'limit_cycle_frequency_hz', '.3g')} Hz")
    if flag == "slow_divergence":
        return f"slow divergence of {summary.get('slow_divergence_signal') or '?'}"
    held = {k: v for k, v in summary.items() if k.startswith(("time_at_rate_limit_", "time_at_gimbal_stop_"))
            and isinstance(v, (int, float))}
    if not held:
        return "saturated"
    key = max(held, key=held.get)
    where = key.removeprefix("time_at_").removesuffix("_s").replace("_", " ")
    return f"saturated, {held[key]:.2f} s at the {where}"


def mission_keys(outcome: MissionOutcome, counted: Iterable[str]) -> dict[str, Any]:
    """The run-summary keys of an outcome: ``mission_class_mask`` (int),
    ``mission_classes`` (comma-separated, every class of the run), ``mission_success``
    (1 or 0, with the ``counted`` classes) and ``mission_verdict`` (the line)."""
    counted = tuple(counted)
    return {"mission_class_mask": outcome.mask, "mission_classes": ",".join(outcome.classes),
            "mission_success": int(outcome.success(counted)), "mission_verdict": outcome.line(counted)}


def _fmt(value: Any, spec: str = ".4g") -> str:
    return "n/a" if value is None else format(value, spec)


def _num(summary: Mapping[str, Any], key: str, spec: str) -> str:
    return _fmt(summary.get(key), spec)
