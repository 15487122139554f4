"""Studies: each module exposes ``run(cfg, raw_cfg, out_dir) -> int`` (process exit code).

Studies compose single runs; they never copy the engine.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from savant_cli.errors import ConfigError

from savant_cli.config import STUDY_SCHEMAS

STUDIES = tuple(STUDY_SCHEMAS)


def get_study(name: str) -> ModuleType:
    """The study module called ``name``."""
    if name not in STUDIES:
        raise ConfigError("study.name", name, f"must be one of {', '.join(STUDIES)}")
    return importlib.import_module(f"savant_cli.studies.{name}")
