"""The Python API (docs/api.md): run a study from a notebook or a script, the way
``savant run`` does, and get its results back as Python objects.

:func:`run` composes the config with Hydra's compose API from the same tree and search
path as the command line (the shipped ``conf/``, or ``config_dir`` in its place with the
shipped tree behind it), applies the same overrides and validation, and writes the same
run folder: ``.hydra/`` (``config.yaml``, ``hydra.yaml``, ``overrides.yaml``),
``savant.log`` and the study's files. A configuration problem raises
:class:`~savant_cli.errors.ConfigError` naming the key (the command line prints it and
exits 2); a run that does not fly to its end returns its result with ``exit_code`` 1
and its status, as the command line exits 1. :func:`load` reads a finished folder back.
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Sequence
from pathlib import Path

from savant_cli.errors import ConfigError
from savant_cli.hydra_compose import compose_config, task_config
from savant_cli.result import Result, load

__all__ = ["run", "load", "Result", "ConfigError"]

#: The log format of Hydra's job logging (what ``savant run`` writes to ``savant.log``).
LOG_FORMAT = "[%(asctime)s][%(name)s][%(levelname)s] - %(message)s"


def _write_hydra_files(out_dir: Path, cfg, task_cfg, overrides: list[str]) -> None:
    """``.hydra/config.yaml``, ``hydra.yaml`` and ``overrides.yaml``, as Hydra writes them."""
    from omegaconf import OmegaConf

    from savant_cli.io.atomic import write_text_atomic

    folder = out_dir / ".hydra"
    folder.mkdir(parents=True, exist_ok=True)
    write_text_atomic(folder / "config.yaml", OmegaConf.to_yaml(task_cfg))
    write_text_atomic(folder / "hydra.yaml", OmegaConf.to_yaml(OmegaConf.create({"hydra": cfg.hydra})))
    write_text_atomic(folder / "overrides.yaml", OmegaConf.to_yaml(OmegaConf.create(list(overrides))))


def run(overrides: Sequence[str] | None = None, config_dir: str | Path | None = None,
        out_dir: str | Path | None = None, quiet: bool = False) -> Result:
    """Run the configured study, as ``savant run OVERRIDES`` does, and return its result.

    Parameters
    ----------
    overrides : sequence of str, optional
        Hydra overrides, as on the command line (``["study=linear", "flex=on",
        "study.times=[55]"]``). A sweep (``a=1,2``, ``-m``) is refused: run one job per
        call, or use ``savant run -m``.
    config_dir : str or pathlib.Path, optional
        A config tree used in place of the shipped ``conf/`` (``savant run -cd DIR``);
        the shipped groups stay on the search path behind it.
    out_dir : str or pathlib.Path, optional
        The run folder; default ``hydra.run.dir`` of the config
        (``outputs/<date>/<time>_<study>`` below the working directory).
    quiet : bool
        Print only the status line and the study's verdict line (no table, no progress
        bar): the override ``output.console=quiet``, recorded in the run folder like
        any other. Errors are raised (and a report that cannot be written is said on
        stderr) all the same.

    Returns
    -------
    Result
        The run folder read back (:func:`savant_cli.load`), ``exit_code`` the command
        line's: 0 when the study's flight flew to its end, 1 when not.

    Raises
    ------
    ConfigError
        An override Hydra refuses (unknown key or option, bad syntax) or a value the
        validation refuses, naming the key, the value and what is allowed; or
        ``out_dir`` held by another writer (:class:`savant_cli.run_lock.FolderBusy`,
        naming the holder's PID and host). Nothing is written then.
    savant_cli.errors.OutputWriteError
        An output could not be written (disk full, folder not writable): it names the
        file and its folder; the files written before it are whole.
    savant_cli.errors.DamagedFileError
        A file of an earlier run in ``out_dir`` cannot be read back (a batch journal's
        manifest): it names the file and what writes it again.
    KeyboardInterrupt
        After the run folder is settled as ``savant run`` settles it (removed when
        nothing was written, else marked ``interrupted.json``; one line on stderr).
    """
    from hydra.core.hydra_config import HydraConfig
    from omegaconf import OmegaConf, open_dict

    from savant_cli import lifecycle, run_lock
    from savant_cli.config import validate
    from savant_cli.runner import run_study
    from savant_cli.studies import check_folder

    if isinstance(overrides, (str, bytes)):
        raise ConfigError("overrides", overrides, "must be a list of override strings, e.g. ['study=linear']")
    overrides = [str(o) for o in (overrides or [])]
    for o in overrides:
        if o.startswith("-"):
            raise ConfigError("overrides", o, "must be Hydra overrides; savant_cli.run runs one job (no flags)")
    if quiet:
        given = [o for o in overrides if o.lstrip("+~").split("=", 1)[0] == "output.console"]
        if any(o.split("=", 1)[-1] != "quiet" for o in given):
            raise ConfigError("quiet", True, f"conflicts with the override {given[0]!r}: pass one or the other")
        if not given:
            overrides.append("output.console=quiet")
    cdir = None if config_dir is None else Path(config_dir).expanduser().resolve()
    if cdir is not None and not cdir.is_dir():
        raise ConfigError("config_dir", str(config_dir), "must be an existing config folder")
    cfg = compose_config(overrides, cdir)
    target = Path(out_dir) if out_dir is not None else Path(OmegaConf.select(cfg, "hydra.run.dir"))
    target = target.expanduser().resolve()
    with open_dict(cfg):
        cfg.hydra.runtime.output_dir = str(target)
        cfg.hydra.run.dir = str(target)
    task_cfg = task_config(cfg)
    hydra_config = HydraConfig.instance()
    previous = hydra_config.cfg
    hydra_config.set_config(cfg)  # paths.hydra_search_dirs reads the config sources from it
    handler = None
    root = logging.getLogger()
    level = root.level
    lock = None
    try:
        typed = validate(task_cfg)  # before anything is written: a bad value leaves no folder
        run_lock.refuse_if_busy(target, key="out_dir")  # one writer per folder (docs/outputs.md)
        check_folder(typed, target)
        lock = run_lock.acquire(target, key="out_dir")
        _write_hydra_files(target, cfg, task_cfg, overrides)
        handler = logging.FileHandler(target / "savant.log")
        handler.setFormatter(logging.Formatter(LOG_FORMAT))
        root.addHandler(handler)
        root.setLevel(logging.INFO if level in (logging.NOTSET, logging.WARNING) else min(level, logging.INFO))
        code = run_study(typed, task_cfg, target, raise_errors=True)
        lifecycle.clear_marker(target)
    except ConfigError:
        if lock is not None:
            _detach(handler, root, level)  # the log file goes with a discarded folder
            handler = None
            lifecycle.discard_if_untouched(lock)
        raise
    except KeyboardInterrupt as exc:  # the folder settled as on the command line, then the interrupt goes on
        sys.stderr.write(lifecycle.settle_interrupt(exc) + "\n")
        raise
    finally:
        if lock is not None:
            lock.release()
        hydra_config.cfg = previous
        _detach(handler, root, level)
    return load(target, exit_code=code)


def _detach(handler: logging.Handler | None, root: logging.Logger, level: int) -> None:
    """Remove and close the run's log handler (``None``: nothing to do); give the root
    logger its level back."""
    if handler is not None:
        root.removeHandler(handler)
        root.setLevel(level)
        handler.close()
