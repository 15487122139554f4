"""Shared fixtures: composing configs with hydra.compose, as `savant run` does."""

from __future__ import annotations

import pytest
from hydra import compose, initialize_config_dir

from savant_cli.paths import shipped_config_dir


def compose_config(overrides: list[str] | None = None):
    """The raw composed config (DictConfig) for the given overrides."""
    with initialize_config_dir(config_dir=str(shipped_config_dir()), version_base="1.3"):
        return compose(config_name="config", overrides=list(overrides or []))


@pytest.fixture
def compose_cfg():
    return compose_config
