"""``flex``: the rigid vehicle or retained bending modes."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

from omegaconf import MISSING

from savant_cli.config.checks import non_negative, positive
from savant_cli.config.model_group import ModelGroup
from savant_cli.errors import ConfigError


class FlexSwitching(StrEnum):
    """``flex.switching``: the modal set switched at separation, or blended by the
    propellant burned."""

    separation = "separation"
    propellant = "propellant"


@dataclass
class FlexOffConfig:
    """``flex=off``: the rigid vehicle."""

    name: str = "off"
    enabled: bool = MISSING


@dataclass
class FlexOnConfig:
    """``flex=on``: retained bending modes from the vehicle's modal data."""

    name: str = "on"
    enabled: bool = MISSING
    n_modes: int = MISSING  # retained modes, lowest first
    damping: float = MISSING  # structural damping ratio of every retained mode
    damping_per_mode: list[float] = MISSING  # overrides `damping` when given
    switching: FlexSwitching = MISSING
    frequency_scale: float = MISSING
    shape_scale: float = MISSING


def check_flex(f: FlexOffConfig | FlexOnConfig) -> None:
    """Physical checks of the ``flex`` group."""
    if not f.enabled:
        return
    if f.n_modes < 1:
        raise ConfigError("flex.n_modes", f.n_modes, "must be at least 1 when flex is on (flex=off turns it off)")
    non_negative("flex.damping", f.damping)
    for i, z in enumerate(f.damping_per_mode):
        non_negative(f"flex.damping_per_mode[{i}]", z)
    if f.damping_per_mode and len(f.damping_per_mode) < f.n_modes:
        raise ConfigError("flex.damping_per_mode", list(f.damping_per_mode),
                          f"must give at least flex.n_modes = {f.n_modes} values, or be empty")
    positive("flex.frequency_scale", f.frequency_scale)
    non_negative("flex.shape_scale", f.shape_scale)


GROUP = ModelGroup("flex", {"off": FlexOffConfig, "on": FlexOnConfig}, lambda f, cfg: check_flex(f))
