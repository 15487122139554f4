"""``slosh``: propellant slosh off or on."""

from __future__ import annotations

from dataclasses import dataclass

from omegaconf import MISSING

from savant_cli.config.checks import non_negative, positive
from savant_cli.config.model_group import ModelGroup


@dataclass
class SloshOffConfig:
    """``slosh=off``: no propellant slosh."""

    name: str = "off"
    enabled: bool = MISSING


@dataclass
class SloshOnConfig:
    """``slosh=on``: a spring-mass slosh mode in every tank with a ``slosh`` section."""

    name: str = "on"
    enabled: bool = MISSING
    frequency_scale: float = MISSING
    damping_scale: float = MISSING


def check_slosh(s: SloshOffConfig | SloshOnConfig) -> None:
    """Physical checks of the ``slosh`` group."""
    if s.enabled:
        positive("slosh.frequency_scale", s.frequency_scale)
        non_negative("slosh.damping_scale", s.damping_scale)


GROUP = ModelGroup("slosh", {"off": SloshOffConfig, "on": SloshOnConfig}, lambda s, cfg: check_slosh(s))
