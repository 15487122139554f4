"""The validation entry: a composed config merged onto the schema (:func:`validate`) and
the physical checks of every group (:func:`check_physics`)."""

from __future__ import annotations

import dataclasses
from typing import Any

from omegaconf import DictConfig, OmegaConf
from omegaconf.errors import MissingMandatoryValue, OmegaConfBaseException

from savant_cli.config.checks import allowed_of
from savant_cli.config.controller import check_controller, check_delay
from savant_cli.config.guidance import check_guidance
from savant_cli.config.requirements import check_requirements
from savant_cli.config.run import check_environment, check_phase, check_sim
from savant_cli.config.savant import GROUP_VARIANTS, MODEL_GROUPS, SavantConfig, check_vehicle_match
from savant_cli.config.sensors import check_sensors
from savant_cli.config.study import check_study_times, study_option
from savant_cli.config.winds import check_winds, check_winds_scale
from savant_cli.errors import ConfigError
from savant_cli.paths import shipped_config_dir


def _strict_merge(cfg: DictConfig) -> DictConfig:
    """Merge ``cfg`` onto the schema; unknown keys and wrong types raise ConfigError."""
    schema = OmegaConf.structured(SavantConfig)
    plain = OmegaConf.to_container(cfg, resolve=True)
    plain.pop("hydra", None)
    try:
        merged = OmegaConf.merge(schema, plain)
    except OmegaConfBaseException as exc:
        key = getattr(exc, "full_key", None) or "?"
        value = getattr(exc, "value", None)
        msg = str(exc).splitlines()[0]
        if "not in struct" in msg or "Key '" in msg and "not in" in msg:
            allowed = "unknown key; see `savant run --cfg job` for the known keys"
        else:
            allowed = allowed_of(msg)
        raise ConfigError(key, value, allowed) from None
    return merged


def check_physics(cfg: SavantConfig) -> None:
    """Physical checks of a typed config (every group); raises ConfigError naming the key."""
    check_vehicle_match(cfg)
    check_sim(cfg.sim)
    check_environment(cfg.environment)
    check_phase(cfg.phase)
    for group in MODEL_GROUPS:
        group.check(getattr(cfg, group.name), cfg)
    check_delay(cfg.controller.delay_s, cfg.sim)
    check_requirements(cfg.requirements)
    check_sensors(cfg.sensors, cfg.sim)
    check_winds_scale(cfg.winds)
    check_study_times(cfg)
    check_winds(cfg.winds)
    check_controller(cfg.controller)
    check_guidance(cfg.guidance, cfg.sim)


def validate(cfg: DictConfig) -> SavantConfig:
    """Merge a composed config onto the schema and check it.

    Returns
    -------
    SavantConfig
        A typed (OmegaConf structured) view of the validated config.

    Raises
    ------
    ConfigError
        Naming the key, the value and what is allowed.
    """
    merged = _strict_merge(cfg)
    try:
        typed = OmegaConf.to_object(merged)
    except MissingMandatoryValue as exc:  # a key the schema leaves to the YAML, which is silent
        key = str(getattr(exc, "full_key", None) or "?")
        group = key.split(".")[0]
        where = (f"the selected {group} option file must give it (as the shipped ones in conf/{group}/ do; "
                 f"a file of your own takes the keys it leaves out from a shipped option it names first: "
                 f"defaults: [<option>, _self_])"
                 if (shipped_config_dir() / group).is_dir() else
                 "the top-level config.yaml must give it (as the shipped conf/config.yaml does)")
        raise ConfigError(key, "???", f"is required: the schema has no default for it; {where}, "
                                      f"or set it on the command line") from None
    typed.study = study_option(typed.study)
    for group in GROUP_VARIANTS:
        setattr(typed, group, group_option(group, getattr(typed, group)))
    check_physics(typed)
    return typed


def has_key(schema: type, path: list[str]) -> bool:
    """Whether the dotted ``path`` names a field of the dataclass ``schema``."""
    node: Any = schema
    for part in path:
        fields = {f.name: f for f in dataclasses.fields(node)} if dataclasses.is_dataclass(node) else {}
        if part not in fields:
            return False
        default = fields[part].default_factory() if fields[part].default_factory is not dataclasses.MISSING \
            else fields[part].default
        node = type(default) if dataclasses.is_dataclass(default) else None
    return True


def group_option(group: str, node: Any) -> Any:
    """The section of a group with per-option schemas
    (:data:`~savant_cli.config.savant.GROUP_VARIANTS`), merged onto its option's schema: a
    key of another option, or of a model that is switched off, is refused naming the
    options where it exists."""
    variants = GROUP_VARIANTS[group]
    if dataclasses.is_dataclass(node):
        node = OmegaConf.to_container(OmegaConf.structured(node))
    name = node.get("name") if isinstance(node, dict) else None
    if name not in variants:
        raise ConfigError(f"{group}.name", name, f"must be one of {', '.join(variants)}")
    try:
        return OmegaConf.to_object(OmegaConf.merge(OmegaConf.structured(variants[name]), node))
    except OmegaConfBaseException as exc:
        sub = str(getattr(exc, "full_key", None) or "?")
        key = f"{group}.{sub}"
        msg = str(exc).splitlines()[0]
        if "not in struct" in msg or ("Key '" in msg and "not in" in msg):
            where = [opt for opt, schema in variants.items() if opt != name and has_key(schema, sub.split("."))]
            allowed = (f"not a key of {group}={name}; it belongs to {' and '.join(f'{group}={w}' for w in where)}"
                       if where else f"not a key of {group}={name} (nor of any other {group} option)")
        elif "missing mandatory value" in msg.lower():
            allowed = f"is required: {group}={name} has no default for it (conf/{group}/{name}.yaml gives one)"
        else:
            allowed = allowed_of(msg)
        value = node
        for part in sub.split("."):
            value = value.get(part) if isinstance(value, dict) else None
        raise ConfigError(key, value, allowed) from None
