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


def run_study(cfg, raw_cfg, out_dir) -> int:
    """Run the configured study into ``out_dir``, then write its ``report.html``
    (:mod:`savant_cli.html_report`); the study's exit code. What ``savant run`` and
    :func:`savant_cli.run` both call.

    A report that cannot be written (no ``savant.h5`` with ``output.hdf5=false``, or an
    error while building it) is said on stderr and leaves the study's files and exit
    code as they are."""
    from pathlib import Path

    from rich.console import Console

    from savant_cli.io.console import print_quiet_lines

    quiet = cfg.output.console == "quiet"
    if cfg.sim.progress and (quiet or not _progress_drawable()):
        cfg.sim.progress = False  # quiet: no bar; a notebook without ipywidgets: rich would warn per refresh
    code = get_study(cfg.study.name).run(cfg, raw_cfg, out_dir)
    write_report_or_say(Path(out_dir), Console(stderr=True), say_written=not quiet)
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


def write_report_or_say(folder, console, say_written: bool = True) -> None:
    """``report.html`` into ``folder``, or a line on ``console`` saying why not (and,
    with ``say_written``, where it was written)."""
    from savant_cli.html_report import write_report

    try:
        path = write_report(folder)
    except FileNotFoundError as exc:
        console.print(f"no report.html: {exc}", highlight=False)
    except Exception as exc:  # noqa: BLE001 - the study's own outputs stand without the page
        console.print(f"[red]report.html not written[/red]: {type(exc).__name__}: {exc}", highlight=False)
    else:
        if say_written:
            console.print(f"report: {path}", highlight=False)
