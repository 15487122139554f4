"""``study=flyoff``: controllers compared on the same dispersed runs."""

from __future__ import annotations

from dataclasses import dataclass

from omegaconf import MISSING

from savant_cli.config.study.montecarlo import MonteCarloStudyConfig, check_montecarlo
from savant_cli.errors import ConfigError


@dataclass
class FlyoffStudyConfig(MonteCarloStudyConfig):
    """``study=flyoff``: two or more controllers fly the same nominal and the same
    dispersed runs (the Monte Carlo keys apply to each), compared metric by metric."""

    name: str = "flyoff"
    controllers: list[str] = MISSING


def check_flyoff(s: FlyoffStudyConfig) -> None:
    """The Monte Carlo keys (:func:`check_montecarlo`) and at least two different controllers."""
    check_montecarlo(s)
    if len(set(s.controllers)) < 2:
        raise ConfigError("study.controllers", list(s.controllers), "must name at least two different controllers")
