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


# The plot modules must never use matplotlib.pyplot (global state, GUI backends): the
# tests check their source and run them in an interpreter where pyplot is this stub.
PYPLOT_STUB = """
import sys, types
class Stub(types.ModuleType):
    def __getattr__(self, name):
        raise AssertionError(f"pyplot.{name} used")
sys.modules["matplotlib.pyplot"] = Stub("matplotlib.pyplot")
"""


def imported_names(path) -> list[str]:
    """Every module and name a Python source file imports (``a.b`` and ``a.b.name``)."""
    import ast
    from pathlib import Path

    tree = ast.parse(Path(path).read_text(encoding="utf-8"))
    names = [a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names]
    return names + [f"{n.module}.{a.name}" for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) for a in n.names]
