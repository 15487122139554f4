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


def assert_report_redraws(run_dir) -> list[str]:
    """``savant report`` on a finished study: with the study's own ``plots/`` moved away,
    it draws every figure again from ``savant.h5`` alone, byte for byte the same PNGs
    (same names, same pixels), and nothing else. Returns the relative names."""
    import shutil
    from pathlib import Path

    from rich.console import Console

    from savant_cli.report import report

    run_dir = Path(run_dir)
    first = run_dir.parent / f"{run_dir.name}_plots_as_drawn"
    shutil.move(run_dir / "plots", first)
    try:
        paths = report(run_dir, console=Console(quiet=True))
        drawn = sorted(str(p.relative_to(first)) for p in first.rglob("*.png"))
        again = sorted(str(p.relative_to(run_dir / "plots")) for p in (run_dir / "plots").rglob("*.png"))
        assert again == drawn, (set(drawn) ^ set(again))
        assert sorted(str(p.relative_to(run_dir / "plots")) for p in paths) == drawn
        for name in drawn:
            assert (first / name).read_bytes() == (run_dir / "plots" / name).read_bytes(), name
        return drawn
    finally:
        shutil.rmtree(first, ignore_errors=True)
