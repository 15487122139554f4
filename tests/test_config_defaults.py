"""A default lives in one place (issue 28 item 3; docs/architecture.md, "Where a new config
option goes").

The rule: a key a shipped YAML sets must not also have a schema default of the same
value. For each shipped YAML of a group (``conf/<group>/<option>.yaml``, the ``study``
section of a ``# @package _global_`` study file, the sections of ``conf/config.yaml``),
every leaf key is compared with the default its schema gives it: the option's schema for
a :data:`~savant_cli.config.GROUP_VARIANTS` group, the study's for ``study``, the
:class:`~savant_cli.config.SavantConfig` field's type otherwise. Equal (a float and an
int of the same value count as equal) is a duplicate. ``name`` (the option's identity)
is exempt. The shipped files follow the first of the two ways out: the YAML holds every
value, the schema says ``MISSING``; code outside a composing run reads a shipped option
with :func:`~savant_cli.config.shipped_option`.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest
import yaml
from omegaconf import MISSING, OmegaConf

from savant_cli.config import GROUP_VARIANTS, STUDY_SCHEMAS, SavantConfig, validate
from savant_cli.errors import ConfigError
from savant_cli.hydra_compose import compose_config, task_config
from savant_cli.paths import shipped_config_dir


def _schema_of(group: str, node: dict) -> type | None:
    if group in GROUP_VARIANTS:
        return GROUP_VARIANTS[group].get(node.get("name"))
    if group == "study":
        return STUDY_SCHEMAS.get(node.get("name"))
    f = {f.name: f for f in dataclasses.fields(SavantConfig)}.get(group)
    if f is None:
        return None
    default = f.default_factory() if f.default_factory is not dataclasses.MISSING else f.default
    return type(default) if dataclasses.is_dataclass(default) else None


def _leaves(node, prefix=()):
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _leaves(v, prefix + (k,))
    else:
        yield prefix, node


def _default_at(schema: type, path: tuple) -> object:
    node = OmegaConf.to_container(OmegaConf.structured(schema))
    for part in path:
        if not isinstance(node, dict) or part not in node:
            return MISSING
        node = node[part]
    return node


def _same(default: object, value: object) -> bool:
    if default is MISSING or default == MISSING:
        return False
    if isinstance(default, float) and isinstance(value, (int, float)) and not isinstance(value, bool):
        return default == value
    return type(default) is type(value) and default == value


def _sections(conf: Path):
    for f in sorted(conf.glob("*/*.yaml")):
        text = f.read_text()
        data = yaml.safe_load(text) or {}
        if text.startswith("# @package _global_"):
            yield from ((f, g, s) for g, s in data.items() if g != "defaults" and isinstance(s, dict))
        else:
            yield f, f.parent.name, data
    top = yaml.safe_load((conf / "config.yaml").read_text())
    yield from ((conf / "config.yaml", g, s) for g, s in top.items() if g not in ("defaults", "hydra"))


def duplicates(conf: Path) -> set[str]:
    """``<file>: <key> = <value>`` of every key a shipped YAML and its schema both give."""
    out = set()
    for f, group, section in _sections(conf):
        if group == "study" and "name" not in section:
            section = dict(section, name=f.stem)  # a study file inheriting another's keys
        schema = _schema_of(group, section)
        if schema is None:
            continue
        for path, value in _leaves(section):
            if path != ("name",) and _same(_default_at(schema, path), value):
                out.add(f"{f.relative_to(conf)}: {group}.{'.'.join(map(str, path))} = {value!r}")
    return out


def test_a_default_lives_in_one_place():
    found = sorted(duplicates(shipped_config_dir()))
    assert not found, ("these keys have a default both in the schema and in the YAML; drop the schema's "
                       "(docs/architecture.md, 'Where a new config option goes'):\n" + "\n".join(found))


def test_the_actuator_values_live_in_the_yaml_only():
    assert not any(d.startswith("actuator/") for d in duplicates(shipped_config_dir()))
    from savant_cli.config import SimplexStage, ThirdOrderStage

    for stage in (ThirdOrderStage, SimplexStage):
        assert all(f.default == MISSING for f in dataclasses.fields(stage) if f.default is not dataclasses.MISSING)


def test_the_rule_sees_a_duplicate(tmp_path, monkeypatch):
    """The check itself: a YAML repeating its schema's default is found (a schema with
    defaults in place of the shipped one, whose leaves are all MISSING)."""

    @dataclasses.dataclass
    class FlexOnWithDefaults:
        name: str = "on"
        enabled: bool = True
        frequency_scale: float = 1.0
        shape_scale: float = 1.0

    monkeypatch.setitem(GROUP_VARIANTS["flex"], "on", FlexOnWithDefaults)
    (tmp_path / "flex").mkdir()
    (tmp_path / "flex" / "on.yaml").write_text("name: 'on'\nenabled: true\nfrequency_scale: 2.0\nshape_scale: 1.0\n")
    (tmp_path / "config.yaml").write_text("defaults: []\n")
    assert duplicates(tmp_path) == {"flex/on.yaml: flex.enabled = True", "flex/on.yaml: flex.shape_scale = 1.0"}


def test_a_missing_actuator_value_and_a_bad_choice_are_refused_clearly():
    import pytest

    from conftest import compose_config
    from savant_cli.config import group_option, validate
    from savant_cli.errors import ConfigError

    with pytest.raises(ConfigError) as exc:
        group_option("actuator", {"name": "third_order", "first_stage": {"loop_gain_rad_s": 1.0}})
    assert exc.value.key == "actuator.first_stage.rate_limit_deg_s"
    assert "is required" in exc.value.allowed and "conf/actuator/third_order.yaml" in exc.value.allowed
    for overrides, key, value, allowed in (
            (["actuator=simplex", "actuator.first_stage.feedback=ram"], "actuator.first_stage.feedback", "ram",
             "must be one of piston, nozzle"),
            (["flex=on", "flex.switching=never"], "flex.switching", "never", "must be one of separation, propellant"),
            (["output.console=loud"], "output.console", "loud", "must be one of full, summary, quiet"),
            (["study=linear", "study.charts=some"], "study.charts", "some", "must be one of auto, all, none")):
        with pytest.raises(ConfigError) as exc:
            validate(compose_config(overrides))
        assert (exc.value.key, exc.value.value, exc.value.allowed) == (key, value, allowed)


@pytest.mark.parametrize("group, option, key", [("guidance", "ares_i_peg", "allow_other_vehicle"),
                                                ("actuator", "third_order", "first_stage.natural_frequency_hz")])
def test_a_user_option_file_without_a_required_key_is_refused_naming_it(tmp_path, group, option, key):
    """A key whose one default is the shipped YAML's (the schema says MISSING) is required
    of a user's own option file: leaving it out is refused naming the key (exit 2), not a
    traceback."""
    node = yaml.safe_load((shipped_config_dir() / group / f"{option}.yaml").read_text())
    mine = tmp_path / group / "mine.yaml"
    mine.parent.mkdir()
    mine.write_text(yaml.safe_dump(node))
    validate(task_config(compose_config([f"{group}=mine"], tmp_path)))  # the user's folder is read: the whole copy passes
    parent, leaf = node, key.split(".")
    for part in leaf[:-1]:
        parent = parent[part]
    assert leaf[-1] in parent, f"conf/{group}/{option}.yaml no longer sets {key}"
    del parent[leaf[-1]]
    mine.write_text(yaml.safe_dump(node))
    with pytest.raises(ConfigError) as exc:  # the copy without the key is refused
        validate(task_config(compose_config([f"{group}=mine"], tmp_path)))
    assert exc.value.key == f"{group}.{key}" and "required" in exc.value.allowed


def test_a_run_level_key_left_out_names_the_top_level_config():
    """A ``sim`` key (its one default in ``conf/config.yaml``, no ``conf/sim/`` folder) left
    unset is refused naming the key and the file that holds it."""
    cfg = compose_config(["study=nominal"], None)
    cfg = task_config(cfg)
    OmegaConf.update(cfg, "sim.fcs_rate_hz", "???")
    with pytest.raises(ConfigError) as exc:
        validate(cfg)
    assert exc.value.key == "sim.fcs_rate_hz" and "conf/config.yaml" in exc.value.allowed
    assert "conf/sim/" not in exc.value.allowed


def _option_files():
    conf = shipped_config_dir()
    return [(f.parent.name, f.stem) for f in sorted(conf.glob("*/*.yaml")) if f.parent.name not in ("vehicle", "hydra")]


@pytest.mark.parametrize("group, option", _option_files())
def test_shipped_option_reads_what_a_run_composes(group, option):
    """:func:`~savant_cli.config.shipped_option` (the shipped settings outside a composing
    run) equals the section a run selecting the option validates; an option file it
    cannot read alone (another option's keys, the composed tree's) is refused saying so."""
    from savant_cli.config import shipped_option

    overrides = [f"{group}={option}"] + (["vehicle=small_launcher"] if option.startswith("small") else [])
    try:
        mine = shipped_option(group, option)
    except ValueError as exc:
        assert "compose it with Hydra" in str(exc)
        text = (shipped_config_dir() / group / f"{option}.yaml").read_text()
        assert "defaults:" in text or "${" in text  # the reason it gives is in the file
        return
    composed = getattr(validate(task_config(compose_config(overrides, None))), group)
    assert mine == composed


@pytest.mark.parametrize("section", ["sim", "environment", "output"])
def test_shipped_option_reads_a_top_level_section(section):
    from savant_cli.config import shipped_option

    assert shipped_option(section) == getattr(validate(task_config(compose_config([], None))), section)
