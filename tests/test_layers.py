"""The package's floors (docs/architecture.md, "Layers"): the import-linter contract of
``pyproject.toml`` holds on the installed package, and fails on an upward import put into
a copy of it."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import savant_cli

PYPROJECT = Path(__file__).resolve().parents[1] / "pyproject.toml"
LINT_IMPORTS = Path(sys.executable).with_name("lint-imports")


def _lint(cwd: Path, pythonpath: Path | None = None) -> subprocess.CompletedProcess:
    """``lint-imports`` on the contract of ``cwd/pyproject.toml``, no cache written."""
    env = dict(os.environ)
    if pythonpath is not None:
        env["PYTHONPATH"] = str(pythonpath)
    return subprocess.run([str(LINT_IMPORTS), "--no-cache"], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=300)


@pytest.fixture(scope="module")
def linter() -> Path:
    if not LINT_IMPORTS.is_file():
        pytest.fail(f"{LINT_IMPORTS} missing: the test extra installs import-linter")
    return LINT_IMPORTS


def test_the_installed_package_keeps_its_floors(linter, tmp_path):
    shutil.copy(PYPROJECT, tmp_path / "pyproject.toml")
    proc = _lint(tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "Contracts: 1 kept, 0 broken." in proc.stdout


def test_an_upward_import_breaks_the_contract(linter, tmp_path):
    """The same contract on a copy of the package: kept as copied, broken once the aero
    model (the models floor) imports the command line (the top floor), and the report
    names that import."""
    shutil.copytree(Path(savant_cli.__file__).parent, tmp_path / "savant_cli",
                    ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(PYPROJECT, tmp_path / "pyproject.toml")
    kept = _lint(tmp_path, pythonpath=tmp_path)
    assert kept.returncode == 0, kept.stdout + kept.stderr
    aero = tmp_path / "savant_cli" / "models" / "aero.py"
    aero.write_text(aero.read_text(encoding="utf-8") + "\nimport savant_cli.cli  # an upward import\n",
                    encoding="utf-8")
    broken = _lint(tmp_path, pythonpath=tmp_path)
    assert broken.returncode == 1, broken.stdout + broken.stderr
    assert "savant_cli.models is not allowed to import savant_cli.cli" in broken.stdout
    assert "savant_cli.models.aero -> savant_cli.cli" in broken.stdout


ISORT = Path(sys.executable).with_name("isort")
ROOT = PYPROJECT.parent


def _isort(cwd: Path, *paths: str) -> subprocess.CompletedProcess:
    """``isort --check-only`` with the settings of ``cwd/pyproject.toml``."""
    if not ISORT.is_file():
        pytest.fail(f"{ISORT} missing: the test extra installs isort")
    return subprocess.run([str(ISORT), "--check-only", "--diff", *paths], cwd=cwd, capture_output=True, text=True,
                          timeout=300)


def test_imports_are_ordered():
    proc = _isort(ROOT, "savant_cli", "tests", "benchmarks")
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_the_import_order_check_fails_on_imports_out_of_order(tmp_path):
    shutil.copy(PYPROJECT, tmp_path / "pyproject.toml")
    (tmp_path / "ordered.py").write_text("import os\nimport sys\n\nprint(os, sys)\n")
    (tmp_path / "unordered.py").write_text("import sys\nimport os\n\nprint(os, sys)\n")
    assert _isort(tmp_path, "ordered.py").returncode == 0
    proc = _isort(tmp_path, "unordered.py")
    assert proc.returncode == 1 and "unordered.py" in proc.stdout + proc.stderr, proc.stdout + proc.stderr
