"""The whole config (:class:`SavantConfig`), the model groups it holds
(:data:`MODEL_GROUPS`) and the check across its groups."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from savant_cli.config import actuator, flex, navigation, slosh, twd
from savant_cli.config.controller import ControllerConfig
from savant_cli.config.dispersions import DispersionSetConfig
from savant_cli.config.guidance import GuidanceConfig
from savant_cli.config.model_group import ModelGroup
from savant_cli.config.output import OutputConfig
from savant_cli.config.requirements import RequirementSet
from savant_cli.config.run import EnvironmentConfig, PhaseConfig, SimConfig
from savant_cli.config.sensors import SensorsConfig
from savant_cli.config.winds import WindsConfig
from savant_cli.errors import ConfigError

#: The model groups, whose options carry different keys (each declared as ``GROUP`` in its
#: schema module): ``validate`` types each by its option's schema and runs its check. A new
#: model group adds its ``GROUP`` here and its field (the shipped default option) below.
MODEL_GROUPS: tuple[ModelGroup, ...] = (actuator.GROUP, flex.GROUP, slosh.GROUP, twd.GROUP, navigation.GROUP)

#: Group → option → schema, of :data:`MODEL_GROUPS`.
GROUP_VARIANTS: dict[str, dict[str, type]] = {g.name: dict(g.variants) for g in MODEL_GROUPS}


@dataclass
class SavantConfig:
    """The whole configuration: every group, as validated by
    :func:`savant_cli.config.validate`. ``vehicle`` is checked by
    :func:`savant_cli.vehicle.load_vehicle`; the model groups (:data:`MODEL_GROUPS`) are
    typed by their option's schema, ``study`` by its study's (``STUDY_SCHEMAS``). Units: in
    each group's schema."""

    vehicle: Any = None  # validated by savant_cli.vehicle.load_vehicle (tables and keys)
    phase: PhaseConfig = field(default_factory=PhaseConfig)
    # the model groups (MODEL_GROUPS), typed per option in validate()
    actuator: Any = field(default_factory=lambda: {"name": "third_order"})
    flex: Any = field(default_factory=lambda: {"name": "off"})
    slosh: Any = field(default_factory=lambda: {"name": "off"})
    twd: Any = field(default_factory=lambda: {"name": "off"})
    navigation: Any = field(default_factory=lambda: {"name": "perfect"})
    winds: WindsConfig = field(default_factory=WindsConfig)
    controller: ControllerConfig = field(default_factory=ControllerConfig)
    guidance: GuidanceConfig = field(default_factory=GuidanceConfig)
    sensors: SensorsConfig = field(default_factory=SensorsConfig)
    dispersions: DispersionSetConfig = field(default_factory=DispersionSetConfig)
    requirements: RequirementSet = field(default_factory=RequirementSet)
    study: Any = field(default_factory=lambda: {"name": "nominal"})  # typed per study in validate()
    sim: SimConfig = field(default_factory=SimConfig)
    environment: EnvironmentConfig = field(default_factory=EnvironmentConfig)
    output: OutputConfig = field(default_factory=OutputConfig)


def check_vehicle_match(cfg: SavantConfig) -> None:
    """Guidance and flight control generated for another vehicle are refused unless the
    user says so (``guidance.allow_other_vehicle``, ``controller.allow_other_vehicle``)."""
    flown = (cfg.vehicle or {}).get("name", "") if isinstance(cfg.vehicle, dict) else ""
    for group, node, fix in (("guidance", cfg.guidance, "its command file"), ("controller", cfg.controller, "its gains")):
        if node.vehicle and flown and node.vehicle != flown and not node.allow_other_vehicle:
            raise ConfigError(f"{group}.vehicle", node.vehicle,
                              f"{group}={node.name} was generated for vehicle {node.vehicle} ({fix} fit that vehicle "
                              f"only) but this run flies vehicle={flown}: choose the {group} of {flown} (its vehicle "
                              f"config selects it by default), or set {group}.allow_other_vehicle=true to fly it anyway")
