"""Running a study: the configured study into its run folder, then its ``report.html``.

What ``savant run`` (:mod:`savant_cli.cli`) and the Python API (:func:`savant_cli.run`)
both call once the config is validated and the folder locked. At the top floor beside
them: it reaches down to the study registry (:mod:`savant_cli.studies`) and to
:mod:`savant_cli.html_report`, and nothing below imports it.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from omegaconf import DictConfig

    from savant_cli.config import SavantConfig


def run_study(cfg: SavantConfig, raw_cfg: DictConfig, out_dir: str | Path, raise_errors: bool = False) -> int:
    """Run the configured study into ``out_dir``, then write its ``report.html``
    (:func:`savant_cli.html_report.write_report_or_say`). What ``savant run`` and
    :func:`savant_cli.run` both call.

    A report that cannot be written (no ``savant.h5`` with ``output.hdf5=false``, or an
    error while building it) is said on stderr and leaves the study's files and exit
    code as they are.

    An output that cannot be written (:class:`~savant_cli.errors.OutputWriteError`:
    disk full, folder not writable) or an earlier file of the folder that is damaged
    (:class:`~savant_cli.errors.DamagedFileError`, e.g. a batch journal's manifest) is
    said in one line on stderr and gives the error's exit code (1 and 2), after the
    study has printed its console summary; with ``raise_errors`` (the Python API) it is
    raised instead. A configuration error is always raised (the caller says it).

    Parameters
    ----------
    cfg : savant_cli.config.SavantConfig
        The validated config; ``cfg.sim.progress`` is switched off when no progress bar
        can be drawn (``output.console=quiet``, a notebook without ipywidgets).
    raw_cfg : omegaconf.DictConfig
        The composed task config (without its ``hydra`` node), as the study records it.
    out_dir : str or pathlib.Path
        The run folder.
    raise_errors : bool
        Raise an output or damaged-file error instead of saying it.

    Returns
    -------
    int
        The exit code: the study's, or the report's when that is worse, or the error's.
    """
    from rich.console import Console

    from savant_cli import lifecycle
    from savant_cli.errors import DamagedFileError, OutputWriteError
    from savant_cli.html_report import write_report_or_say
    from savant_cli.io.console import print_quiet_lines
    from savant_cli.sim.compile_notice import silenced
    from savant_cli.studies import get_study

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


def _read_summary(folder: Path) -> dict:
    """The study's ``summary.json`` (empty when it wrote none or it cannot be read)."""
    import json

    try:
        data = json.loads((folder / "summary.json").read_text())
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}
