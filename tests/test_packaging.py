"""The package list in pyproject.toml ships every subpackage of the source tree.

CI installs the project non-editable (``pip install ".[test]"``), so a subpackage missing
from ``[tool.setuptools] packages`` is absent from the installed package and every import
of it fails; this test names the missing one instead.
"""

from __future__ import annotations

import importlib
import tomllib
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def _source_subpackages() -> set[str]:
    root = REPO / "savant_cli"
    return {
        ".".join(("savant_cli",) + init.parent.relative_to(root).parts).rstrip(".")
        for init in root.rglob("__init__.py")
    }


def test_every_source_subpackage_is_listed_in_pyproject():
    listed = set(tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    missing = sorted(_source_subpackages() - listed)
    assert not missing, f"add to [tool.setuptools] packages in pyproject.toml: {missing}"


def test_every_source_subpackage_imports_from_the_installed_package():
    for name in sorted(_source_subpackages()):
        importlib.import_module(name)
