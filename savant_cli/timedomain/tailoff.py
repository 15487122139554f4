"""The time-domain checks of the first-stage tail-off window (issue 26 item 6;
docs/requirements.md, *The tail-off window*).

Inside the window frozen-time margins are not judged (``linear/frozen_time.py``). The
nonlinear simulation judges instead: from the stored state at the window's start the
flight is flown on through separation with each required margin used up at one gimbal
command (the loop broken where ``study=linear`` breaks it,
:mod:`savant_cli.sim.loop_perturbation`), and a 0.5° doublet to excite it:

* ``gain_high``: the loop gain × 10^(``requirements.rigid.gain_dB``/20);
* ``gain_low``: × 10^(−``requirements.aero.gain_dB``/20) (the gain-reduction
  requirement);
* ``delay``: a pure delay ``τ = requirements.rigid.phase_deg / (360 f_c)``, the required
  phase margin at the axis's rigid crossover ``f_c`` at the window's start (from the
  scan).

A check passes when that flight reaches separation without diverging and its state at
separation meets ``requirements.separation`` (body rate, attitude error, q·α): a loop
with the required margins still hands the upper stage a state it can separate from. The
flight's own separation state is judged in every run (``sim/run_summary.py``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from savant_cli.config import RequirementSet
from savant_cli.sim import engine, loop_perturbation
from savant_cli.sim.build import SimModel
from savant_cli.sim.run import Snapshot, signals, simulate
from savant_cli.sim.run_summary import judge_separation
from savant_cli.sim.summary import separation_state, total_alpha_deg

#: Flown this long past the separation of the unperturbed flight (s): a perturbed run may
#: separate a step later.
_PAST_SEPARATION_S = 1.0


@dataclass(frozen=True)
class TailoffCheck:
    """One time-domain check of the window: an axis, the margin used up, and what the
    flight handed over at separation."""

    axis: str
    kind: str
    value: float  # dB (gain) or ms (delay)
    unit: str
    status: str  # the run's status (complete, diverged …)
    separated: bool
    state: dict[str, float | None]  # separation_* keys (sim/summary.py)
    met: bool
    violations: str

    def text(self) -> str:
        sign = "-" if self.kind == "gain_low" else "+"
        what = f"{self.axis} {'delay ' if self.kind == 'delay' else 'gain '}{sign}{self.value:.3g} {self.unit}"
        if not self.separated:
            return f"{what}: did not reach separation ({self.status})"
        return f"{what}: {'meets' if self.met else 'FAILS'} the separation requirements" + (
            f" ({self.violations})" if self.violations else "")

    def as_dict(self) -> dict[str, Any]:
        return {"axis": self.axis, "kind": self.kind, "value": self.value, "unit": self.unit, "status": self.status,
                "separated": self.separated, **self.state, "met": self.met, "violations": self.violations}


def perturbations(req: RequirementSet, crossover_hz: float) -> list[tuple[str, float, str, float, float]]:
    """``(kind, value, unit, gain multiplier, delay s)`` of the three checks; the delay
    uses up ``rigid.phase_deg`` at ``crossover_hz`` (none without a crossover)."""
    out = [("gain_high", req.rigid.gain_dB, "dB", 10.0 ** (req.rigid.gain_dB / 20.0), 0.0),
           ("gain_low", req.aero.gain_dB, "dB", 10.0 ** (-req.aero.gain_dB / 20.0), 0.0)]
    if crossover_hz > 0.0 and np.isfinite(crossover_hz):
        tau = req.rigid.phase_deg / (360.0 * crossover_hz)
        out.append(("delay", 1000.0 * tau, "ms", 1.0, tau))
    return out


def check(model: SimModel, snap: Snapshot, separation_s: float, axis: str, kind: str, value: float, unit: str,
          gain: float, delay_s: float, req: RequirementSet, pulse_rad: float, pulse_s: float) -> TailoffCheck:
    """Fly one check from ``snap`` (the window's start) through separation."""
    t_stop = separation_s + _PAST_SEPARATION_S
    pert = loop_perturbation.perturbation(axis, snap.t, t_stop, gain, delay_s, pulse_rad, pulse_s, model.rates.dt)
    result = simulate(model, progress=False, start=snap, t_stop=t_stop, perturbation=pert)
    t_sep = result.events[engine.EV_SEPARATION]
    separated = bool(np.isfinite(t_sep)) and result.status not in ("diverged", "guidance_failed")
    state: dict[str, float | None] = dict.fromkeys(("separation_body_rate_deg_s", "separation_attitude_error_deg",
                                                    "separation_qalpha_Pa_deg"))
    met, violations = False, ""
    if separated:
        sig = signals(result, model)
        qalpha = sig["dynamic_pressure"].data * total_alpha_deg(sig["alpha"].data, sig["beta"].data)
        state = separation_state(sig["time"].data, sig["body_rate"].data, sig["attitude_error"].data, qalpha,
                                 float(t_sep))
        verdict = judge_separation(state, req.separation)
        met = verdict["separation_requirements_met"] != 0
        violations = verdict["separation_violations"]
    return TailoffCheck(axis, kind, float(value), unit, result.status, separated, state, met, violations)


def checks(model: SimModel, snap: Snapshot, separation_s: float, crossover_hz: dict[str, float],
           req: RequirementSet, excitation_deg: float, excitation_s: float) -> list[TailoffCheck]:
    """Every check, pitch then yaw (``crossover_hz``: each axis's rigid crossover at the
    window's start, Hz)."""
    out = []
    for axis in loop_perturbation.AXES:
        for kind, value, unit, gain, delay in perturbations(req, crossover_hz.get(axis, float("nan"))):
            out.append(check(model, snap, separation_s, axis, kind, value, unit, gain, delay, req,
                             np.radians(excitation_deg), excitation_s))
    return out


def verdict_text(window_text: str, results: list[TailoffCheck]) -> tuple[str, bool]:
    """The verdict line's tail-off clause and whether every check passed."""
    ok = all(c.met for c in results) and bool(results)
    bad = [c.text() for c in results if not c.met]
    head = f"{window_text} judged in the time domain: "
    if not results:
        return head + "no check could be flown", False
    return head + (f"PASS, {len(results)} of {len(results)} checks with the required margins used up meet the "
                   f"separation requirements" if ok else
                   f"FAIL, {len(results) - len(bad)} of {len(results)} checks pass; " + "; ".join(bad)), ok
