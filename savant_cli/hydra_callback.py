"""The Hydra callback that checks and locks a run folder before Hydra writes into it.

Hydra's ``run_job`` creates the run folder, opens the job log in it and writes
``.hydra/`` (config, hydra config, overrides) before it calls our task, so a command
refused inside the task has already rewritten an existing folder's record and left a new
folder behind. ``conf/config.yaml`` therefore registers :class:`RunFolderCallback`
(``hydra.callbacks.savant_run_folder``), whose ``on_run_start`` runs after Hydra composed
the config and before ``run_job``:

1. the config is validated (:func:`savant_cli.config.validate`), as the task will again;
2. the run folder (``hydra.run.dir``, made absolute and written back, so that the
   folder locked is the one Hydra writes into even when ``${now:…}`` would tick) is
   refused when another process holds it (:func:`savant_cli.run_lock.refuse_if_busy`);
3. the study's own checks of an existing folder run
   (:func:`savant_cli.studies.check_folder`: a Monte Carlo folder holding another
   configuration's runs);
4. the folder is locked (:func:`savant_cli.run_lock.acquire`), held to the end of the
   process.

A refusal prints one line and exits with status 2 before anything is created or
written. In a multirun, ``on_multirun_start`` locks the sweep folder (``hydra.sweep.dir``)
for the life of the sweep, so a second sweep into it is refused before any job starts;
each job then validates and locks its own folder inside the task, after Hydra has made
it (the sweep's launcher creates job folders, and their configs exist only per job).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from hydra.experimental.callback import Callback
from omegaconf import DictConfig, OmegaConf, open_dict, read_write

from savant_cli.errors import ConfigError


def refuse(exc: ConfigError) -> None:
    """Print a refusal the way the task does and exit with status 2."""
    from rich.console import Console

    Console(stderr=True).print(f"[bold red]configuration error[/]: {exc}", highlight=False)
    raise SystemExit(ConfigError.exit_code)


def _absolute(config: DictConfig, key: str) -> Path:
    """The folder at ``key`` (``hydra.run.dir``, ``hydra.sweep.dir``) resolved against
    the working directory, and written back into ``config`` as that absolute path."""
    folder = Path(str(OmegaConf.select(config, key))).expanduser().resolve()
    parent_key, leaf = key.rsplit(".", 1)
    parent = OmegaConf.select(config, parent_key)
    with read_write(parent), open_dict(parent):
        parent[leaf] = str(folder)
    return folder


class RunFolderCallback(Callback):
    """Validate and lock the run folder before Hydra writes into it (module notes)."""

    def on_run_start(self, config: DictConfig, **kwargs: Any) -> None:
        from hydra.core.hydra_config import HydraConfig

        from savant_cli import run_lock
        from savant_cli.config import validate
        from savant_cli.hydra_compose import register_schema, task_config
        from savant_cli.studies import check_folder

        register_schema()  # as savant run does; for a Hydra app of its own using this callback
        HydraConfig.instance().set_config(config)  # what run_job does first; data paths read it
        try:
            typed = validate(task_config(config))  # what the task gets: the config without its hydra node
            folder = _absolute(config, "hydra.run.dir")
            run_lock.refuse_if_busy(folder)
            check_folder(typed, folder)
            run_lock.acquire(folder)
        except ConfigError as exc:
            refuse(exc)

    def on_run_end(self, config: DictConfig, **kwargs: Any) -> None:
        from savant_cli import run_lock

        for lock in run_lock.held():
            lock.release()

    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        from savant_cli import run_lock

        try:
            run_lock.acquire(_absolute(config, "hydra.sweep.dir"), key="hydra.sweep.dir")
        except ConfigError as exc:
            refuse(exc)

    def on_multirun_end(self, config: DictConfig, **kwargs: Any) -> None:
        self.on_run_end(config)

