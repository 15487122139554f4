"""The whole summary of a flown run, one way for every study: the flight scalars
(:mod:`savant_cli.sim.summary`), the flight health (:mod:`savant_cli.sim.health`, which
may turn a ``complete`` status into an unhealthy one), the separation state against
``requirements.separation`` and the mission outcome (:mod:`savant_cli.sim.mission`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from savant_cli.config import SavantConfig, SeparationRequirement
from savant_cli.models.peg import insertion_target
from savant_cli.sim import mission
from savant_cli.sim.build import SimModel
from savant_cli.sim.health import assess
from savant_cli.sim.run import SimResult
from savant_cli.sim.summary import summarize


def tolerance_of(cfg: SavantConfig) -> mission.Tolerance:
    """The insertion tolerances of a (validated) config (``guidance.target.tolerance``)."""
    t = cfg.guidance.target.tolerance
    return mission.Tolerance(float(t.perigee_km), float(t.apogee_km), float(t.inclination_deg))


def judge_separation(summary: dict[str, Any], req: SeparationRequirement) -> dict[str, Any]:
    """``separation_requirements_met`` (1, 0, or None: no separation or nothing required)
    and ``separation_violations`` (each quantity above its bound, with both numbers) of a
    summary with :data:`~savant_cli.sim.summary.SEPARATION_KEYS`, against
    ``requirements.separation`` (:class:`~savant_cli.config.SeparationRequirement`)."""
    bounds = (("separation_body_rate_deg_s", req.max_body_rate_deg_s, "body rate", "deg/s"),
              ("separation_attitude_error_deg", req.max_attitude_error_deg, "attitude error", "deg"),
              ("separation_qalpha_Pa_deg", req.max_qalpha_Pa_deg, "q·α", "Pa·deg"))
    judged = [(key, bound, name, unit) for key, bound, name, unit in bounds
              if bound is not None and summary.get(key) is not None]
    if not judged:
        return {"separation_requirements_met": None, "separation_violations": ""}
    bad = [f"{name} {summary[key]:.4g} {unit} > {bound:g}" for key, bound, name, unit in judged
           if not summary[key] <= bound]
    return {"separation_requirements_met": int(not bad), "separation_violations": "; ".join(bad)}


def run_summary(result: SimResult, sig: dict, model: SimModel, cfg: SavantConfig,
                qalpha_limit: float | None) -> dict[str, Any]:
    """Summary, health and mission keys of a flown run (``cfg``: the run's own, dispersed,
    config; ``qalpha_limit``: its vehicle's q·α allowable, Pa·deg, or None). Sets
    ``result.status``/``message`` for an unhealthy flight, as :func:`~savant_cli.sim.health.assess`."""
    health = assess(result, sig, model, cfg.sim.health)
    summary = {**summarize(result, sig, target=insertion_target(cfg.guidance), qalpha_limit=qalpha_limit,
                           p=model.p), **health}
    summary.update(judge_separation(summary, cfg.requirements.separation))
    summary["stop_reason"] = result.stop_reason
    outcome = mission.classify(summary, result.status, result.stop_reason, cfg.phase.stop_at == "cutoff",
                               tolerance_of(cfg))
    summary.update(mission.mission_keys(outcome, cfg.requirements.mission.failure_classes))
    note = nonfinite_note(summary, result.status)
    if note:
        result.message = f"{result.message}; {note}"
    return summary


#: Why a summary key can be infinite in a run that flew: said in the run's message.
NONFINITE_REASONS = {"apogee_altitude_km": "the orbit at the last sample is open (escape energy): it has no apogee",
                     "semi_major_axis_m": "the orbit at the last sample is open (escape energy)"}


def nonfinite_note(summary: dict[str, Any], status: str) -> str:
    """The sentence a run's message gets when its summary holds an infinite or NaN
    number (``summary.json`` writes them as ``null``): which keys, and why; empty when
    every number is finite."""
    bad = [k for k, v in summary.items()
           if isinstance(v, (float, np.floating)) and not np.isfinite(v)]
    if not bad:
        return ""
    why = "the run diverged, so its last state is not physical" if status == "diverged" else ""
    parts = []
    for key in bad[:4]:
        reason = why or NONFINITE_REASONS.get(key, "not defined for this flight")
        parts.append(f"{key} = {summary[key]} ({reason})")
    more = f" and {len(bad) - 4} more" if len(bad) > 4 else ""
    return "not finite in the summary (null in summary.json): " + "; ".join(parts) + more
