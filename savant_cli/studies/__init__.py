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


def run_study(cfg, raw_cfg, out_dir, raise_errors: bool = False) -> int:
    """Run the configured study into ``out_dir``, then write its ``report.html``
    (:mod:`savant_cli.html_report`); the study's exit code. What ``savant run`` and
    :func:`savant_cli.run` both call.

    A report that cannot be written (no ``savant.h5`` with ``output.hdf5=false``, or an
    error while building it) is said on stderr and leaves the study's files and exit
    code as they are.

    An output that cannot be written (:class:`~savant_cli.errors.OutputWriteError`:
    disk full, folder not writable) or an earlier file of the folder that is damaged
    (:class:`~savant_cli.errors.DamagedFileError`, e.g. a batch journal's manifest) is
    said in one line on stderr and gives the error's exit code (1 and 2), after the
    study has printed its console summary; with ``raise_errors`` (the Python API) it is
    raised instead. A configuration error is always raised (the caller says it)."""
    from pathlib import Path

    from rich.console import Console

    from savant_cli import lifecycle
    from savant_cli.errors import DamagedFileError, OutputWriteError
    from savant_cli.io.console import print_quiet_lines
    from savant_cli.sim.compile_notice import silenced

    quiet = cfg.output.console == "quiet"
    if cfg.sim.progress and (quiet or not _progress_drawable()):
        cfg.sim.progress = False  # quiet: no bar; a notebook without ipywidgets: rich would warn per refresh
    err = Console(stderr=True)
    lifecycle.stage("study")
    try:
        with silenced(quiet):  # quiet: no compile line either
            code = get_study(cfg.study.name).run(cfg, raw_cfg, out_dir)
    except (OutputWriteError, DamagedFileError) as exc:
        if raise_errors:
            raise
        err.print(f"[bold red]error[/]: {exc}", highlight=False)
        return exc.exit_code
    lifecycle.stage("report")
    code = max(code, write_report_or_say(Path(out_dir), err, say_written=not quiet))
    if quiet:
        summary = _read_summary(Path(out_dir))
        summary.setdefault("status", "complete" if code == 0 else f"exit code {code}")
        print_quiet_lines(summary, out_dir)
    return code


_NOTEBOOK_NOTE = {"said": False}


def _progress_drawable() -> bool:
    """Whether progress bars can be drawn here; in a Jupyter kernel without ipywidgets
    they cannot (rich warns 'install "ipywidgets"' on every refresh): say so once per
    process and draw none."""
    from savant_cli.io.console import live_display_ok

    if live_display_ok():
        return True
    if not _NOTEBOOK_NOTE["said"]:
        _NOTEBOOK_NOTE["said"] = True
        import logging

        logging.getLogger("savant_cli").info("no progress bars in this notebook: install ipywidgets to see them")
    return False


def _read_summary(folder) -> dict:
    """The study's ``summary.json`` (empty when it wrote none or it cannot be read)."""
    import json

    try:
        data = json.loads((folder / "summary.json").read_text())
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def write_report_or_say(folder, console, raise_write_errors: bool = False, say_written: bool = True) -> int:
    """``report.html`` into ``folder``, or a line on ``console`` saying why not (and,
    with ``say_written``, where it was written); 1 when the page could not be written
    (:class:`~savant_cli.errors.OutputWriteError`: disk full, folder not writable; raised
    with ``raise_write_errors``), else 0 (a page that cannot be built leaves the exit
    status alone)."""
    from savant_cli.errors import OutputWriteError
    from savant_cli.html_report import write_report

    try:
        path = write_report(folder)
    except OutputWriteError as exc:
        if raise_write_errors:
            raise
        console.print(f"[red]report.html not written[/red]: {exc}", highlight=False)
        return exc.exit_code
    except FileNotFoundError as exc:
        console.print(f"no report.html: {exc}", highlight=False)
    except Exception as exc:  # noqa: BLE001 - the study's own outputs stand without the page
        console.print(f"[red]report.html not written[/red]: {type(exc).__name__}: {exc}", highlight=False)
    else:
        if say_written:
            console.print(f"report: {path}", highlight=False)
    return 0
