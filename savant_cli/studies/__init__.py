"""The study registry: ``study.name`` → its module.

Each study module exposes ``run(cfg, raw_cfg, out_dir) -> int`` (process exit code) and
optionally ``check_folder(cfg, out_dir)``. Studies compose single runs; they never copy
the engine. Running a study and writing its report is :func:`savant_cli.runner.run_study`,
above this package: nothing here imports the entry points or the report.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from savant_cli.config import STUDY_SCHEMAS
from savant_cli.errors import ConfigError

STUDIES = tuple(STUDY_SCHEMAS)


def get_study(name: str) -> ModuleType:
    """The study module called ``name``.

    Parameters
    ----------
    name : str
        ``study.name``, one of :data:`STUDIES`.

    Returns
    -------
    types.ModuleType
        ``savant_cli.studies.<name>``, imported.

    Raises
    ------
    ConfigError
        ``name`` is not a study.
    """
    if name not in STUDIES:
        raise ConfigError("study.name", name, f"must be one of {', '.join(STUDIES)}")
    return importlib.import_module(f"savant_cli.studies.{name}")


def check_folder(cfg, out_dir) -> None:
    """A study's own refusals of an existing run folder (its module's optional
    ``check_folder(cfg, out_dir)``: a Monte Carlo folder holding runs of another
    configuration), run before anything is written into the folder.

    Raises
    ------
    ConfigError
        The folder cannot take this run.
    """
    check = getattr(get_study(cfg.study.name), "check_folder", None)
    if check is not None:
        check(cfg, out_dir)
