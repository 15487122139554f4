"""Choices are ``StrEnum`` types (issue 28 item 3; docs/architecture.md, "Where a new config
option goes"): every choice field of every schema refuses a value outside its members,
naming the key, the value and the members, as ``one_of`` words it; and no schema holds a
choice as a free string documented by a comment."""

from __future__ import annotations

import dataclasses
import enum
import re
import typing
from pathlib import Path

import pytest

from savant_cli.config import GROUP_VARIANTS, STUDY_SCHEMAS, SavantConfig, validate
from savant_cli.errors import ConfigError
from savant_cli.hydra_compose import compose_config, task_config


def _choice_fields(schema: type, prefix: str):
    """(dotted key, Enum type, is a list) of every Enum-typed field below ``schema``,
    through nested dataclasses (not through maps keyed by the user)."""
    hints = typing.get_type_hints(schema)
    for f in dataclasses.fields(schema):
        t = hints[f.name]
        args = typing.get_args(t)
        if typing.get_origin(t) is typing.Union:  # Optional[X]
            t = next(a for a in args if a is not type(None))
            args = typing.get_args(t)
        key = f"{prefix}.{f.name}"
        if isinstance(t, type) and issubclass(t, enum.Enum):
            yield key, t, False
        elif typing.get_origin(t) is list and isinstance(args[0], type) and issubclass(args[0], enum.Enum):
            yield key, args[0], True
        elif dataclasses.is_dataclass(t):
            yield from _choice_fields(t, key)


def _cases():
    """Every choice with the overrides that select the option holding it."""
    out = []
    for f in dataclasses.fields(SavantConfig):
        t = typing.get_type_hints(SavantConfig)[f.name]
        if dataclasses.is_dataclass(t):
            out += [([], *c) for c in _choice_fields(t, f.name)]
    for group, variants in GROUP_VARIANTS.items():
        for option, schema in variants.items():
            out += [([f"{group}={option}"], *c) for c in _choice_fields(schema, group)]
    for name, schema in STUDY_SCHEMAS.items():
        out += [([f"study={name}"], *c) for c in _choice_fields(schema, "study")]
    return out


CASES = _cases()


def test_the_choices_are_found():
    """The walk sees the choices it must (a walk that found none would pass anything)."""
    keys = {key for _, key, _, _ in CASES}
    assert {"output.console", "winds.gust.onset", "winds.gust.frame", "winds.shear.shape", "phase.start",
            "phase.stop_at", "guidance.first_stage_schedule", "flex.switching", "actuator.first_stage.feedback",
            "requirements.flex.upper_stage.default.stabilization", "requirements.mission.failure_classes",
            "study.jacobian", "study.charts", "study.frozen_time.criteria", "study.kinds", "study.axes",
            "study.parameters", "study.chart_axes", "study.optimizer.method", "study.schedules"} <= keys


@pytest.mark.parametrize("overrides, key, choice, is_list", CASES,
                         ids=[f"{o[0] if o else ''}:{k}" for o, k, _, _ in CASES])
def test_a_value_outside_a_choice_is_refused_naming_its_members(overrides, key, choice, is_list):
    bad = "not_a_member"
    value = f"[{next(iter(choice)).value},{bad}]" if is_list else bad
    with pytest.raises(ConfigError) as exc:
        validate(task_config(compose_config(overrides + [f"{key}={value}"], None)))
    assert exc.value.key == (f"{key}[1]" if is_list else key)
    assert exc.value.value == bad
    assert exc.value.allowed == f"must be one of {', '.join(m.name for m in choice)}"


def test_a_choice_is_a_member_and_a_string():
    cfg = validate(task_config(compose_config(["winds=design_gust", "study=time_margins"], None)))
    assert type(cfg.winds.gust.onset).__name__ == "GustOnset" and cfg.winds.gust.onset == "altitude"
    assert all(isinstance(k, str) for k in cfg.study.kinds)
    assert list(cfg.study.kinds) == ["gain_high", "gain_low", "delay"]


def test_a_map_keyed_by_a_choice_refuses_another_key():
    with pytest.raises(ConfigError) as exc:
        validate(task_config(compose_config(["study=fcs_design", "+study.every_s.middle=2"], None)))
    assert exc.value.key == "study.every_s.middle" and exc.value.allowed == "its keys must be one of stack, upper"


def test_no_schema_holds_a_choice_as_a_free_string():
    """A ``str`` field commented with its alternatives (``# a | b``) is a choice left
    untyped."""
    root = Path(__import__("savant_cli.config", fromlist=["x"]).__file__).parent
    pattern = re.compile(r"^\s+\w+: (Optional\[)?str\]? = .*#.*\b\w+ \| \w+")
    found = [f"{p.relative_to(root)}:{i}: {line.strip()}" for p in sorted(root.rglob("*.py"))
             for i, line in enumerate(p.read_text().splitlines(), 1) if pattern.match(line)]
    assert not found, "\n".join(found)
