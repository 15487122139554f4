"""The free parameters of the flight-control design, in physical terms, and the controller
they make.

The flight control is the one of ``savant_cli/datagen/fcs_gains.py``: per schedule
(``stack`` vs altitude, ``upper`` vs Earth-relative speed) a PID gain table placed at the
rigid-body natural frequency ``omega`` (rad/s; ``omega_end`` at the last breakpoint, linear
in between) and damping ``zeta``, with the integral gain ``integral_ratio`` × ω × the
attitude stiffness, and the stiffness shared with the filtered integrated-rate path
(``kir_share``); the rate and
integrated-rate paths filtered by a 4th-order Butterworth low-pass (``lowpass_hz``) and two
notches (``notch1_hz``/``notch1_q``, ``notch2_hz``/``notch2_q``, ``scipy.signal.iirnotch``);
on the stack the rate blend's first-stage gyro weight ``blend_first`` (the upper-stage gyro
takes the rest) and the tail-off gain caps ``tailoff_kp_cap``, ``tailoff_kd_cap``. A
candidate is a set of these values; its controller is the design rules' YAML text written
with them (:func:`controller_text`) and read back
(:func:`controller_tables`), so what is judged is exactly what is written, rounding
included.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, fields

from omegaconf import OmegaConf

from savant_cli.config import ControllerConfig, DesignParameters
from savant_cli.datagen import fcs_gains
from savant_cli.models.fcs import FcsTables, fcs_tables

#: Parameters a schedule may set for itself over the spec's common value.
SPEC_VALUES = ("kir_share", "integral_ratio", "tailoff_kp_cap", "tailoff_kd_cap")


@dataclass(frozen=True)
class FreeParameter:
    """One tuned value: where it sits, its start and bounds (physical units)."""

    schedule: str
    name: str
    initial: float
    low: float
    high: float

    def normalized(self, value: float) -> float:
        """``value`` as a fraction of the range (0 at ``low``, 1 at ``high``)."""
        return (value - self.low) / (self.high - self.low)

    def physical(self, u: float) -> float:
        """The value at fraction ``u`` of the range."""
        return self.low + u * (self.high - self.low)


def _filters(spec: dict, schedule: str) -> dict:
    spec.setdefault("filters", None)
    if spec["filters"] is None:
        from savant_cli.datagen import flex_filters

        spec["filters"] = copy.deepcopy(flex_filters.DESIGN)
    return spec["filters"][schedule]


def rule_value(spec: dict, schedule: str, name: str, stack_blend: list[float]) -> float:
    """A parameter's value in the design rules ``spec`` (``stack_blend``: the vehicle's
    mode-nulling blend, used when the spec has none)."""
    d = spec[schedule]
    if name == "omega" or name == "zeta":
        return float(d[name])
    if name == "omega_end":
        return float(d.get("omega_end", d["omega"]))
    if name in SPEC_VALUES:
        return float(d.get(name, spec[name]))
    if name == "blend_first":
        return float((spec.get("stack_blend") or stack_blend)[2])
    f = _filters(copy.deepcopy(spec), schedule)
    if name == "lowpass_hz":
        return float(f["lowpass_hz"])
    q = f["notch_q"]
    q = (q, q) if isinstance(q, (int, float)) else q
    k = int(name[5]) - 1  # notch1_*, notch2_*
    return float(f["notch_hz"][k] if name.endswith("_hz") else q[k])


def free_parameters(config: DesignParameters, schedules: list[str], spec: dict,
                    stack_blend: list[float]) -> list[FreeParameter]:
    """The tuned parameters of ``schedules`` (``study.parameters``), their start the
    configured one or the design rules' value; those the rules hold fixed
    (``spec["fixed_parameters"]``, e.g. a PD law's integral paths) are not tuned."""
    out = []
    fixed = set(spec.get("fixed_parameters", ()))
    for sched in schedules:
        params = getattr(config, sched)
        for f in fields(params):
            p = getattr(params, f.name)
            if p is None or f.name in fixed:
                continue
            start = rule_value(spec, sched, f.name, stack_blend) if p.initial is None else float(p.initial)
            out.append(FreeParameter(sched, f.name, min(max(start, p.low), p.high), float(p.low), float(p.high)))
    return out


def apply(spec: dict, values: dict[tuple[str, str], float]) -> dict:
    """A copy of the design rules ``spec`` with ``values`` ((schedule, name) → value); a
    tuned ``blend_first`` becomes the spec's own ``stack_blend``."""
    out = copy.deepcopy(spec)
    for (sched, name), v in values.items():
        v = float(v)
        if name in ("omega", "omega_end", "zeta") + SPEC_VALUES:
            out[sched] = {**out[sched], name: v}
        elif name == "blend_first":  # 4 decimals, as the YAML writes it: the weights sum to 1
            v = round(v, 4)
            out["stack_blend"] = [round(1.0 - v, 4), 0.0, v]
        else:
            f = _filters(out, sched)
            if name == "lowpass_hz":
                f["lowpass_hz"] = v
            else:
                k = int(name[5]) - 1
                key = "notch_hz" if name.endswith("_hz") else "notch_q"
                cur = f[key]
                cur = [cur, cur] if isinstance(cur, (int, float)) else list(cur)
                cur[k] = v
                f[key] = tuple(cur)
    return out


def controller_text(spec: dict, points: dict, stack_blend: list[float], vehicle: str,
                    design: dict | None = None) -> str:
    """The controller YAML of ``spec`` at the design points of
    :func:`savant_cli.datagen.fcs_gains.design_points`; ``design`` (``{"rules": name,
    "parameters": {(schedule, name): value}}``) is written as the file's ``design`` block."""
    return fcs_gains.controller_yaml(fcs_gains.gain_tables(points, spec), stack_blend, spec, vehicle, design)


def controller_config(text: str) -> ControllerConfig:
    """The controller YAML text read as the schema reads the shipped files."""
    raw = OmegaConf.create(text)
    OmegaConf.resolve(raw)  # yaw: ${.pitch}
    node = OmegaConf.merge(OmegaConf.structured(ControllerConfig), raw)
    return OmegaConf.to_object(node)


def controller_tables(text: str) -> FcsTables:
    """The flight-control tables of a controller YAML text."""
    return fcs_tables(controller_config(text))
