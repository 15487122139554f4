"""``twd``: the engine-inertia reaction (tail-wags-dog) off or on."""

from __future__ import annotations

from dataclasses import dataclass

from omegaconf import MISSING

from savant_cli.config.model_group import ModelGroup


@dataclass
class TwdOffConfig:
    """``twd=off``: no engine-inertia reaction."""

    name: str = "off"
    enabled: bool = MISSING


@dataclass
class TwdOnConfig:
    """``twd=on``: the engine-inertia reaction (data: the vehicle's engines)."""

    name: str = "on"
    enabled: bool = MISSING


GROUP = ModelGroup("twd", {"off": TwdOffConfig, "on": TwdOnConfig}, lambda t, cfg: None)  # no keys to check
