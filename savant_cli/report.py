"""``savant report RUN_DIR``: redraw every figure of a finished run from its ``savant.h5``
alone, write its ``report.html`` again (:mod:`savant_cli.html_report`) and print its
summary again.

What is drawn depends on what the file holds:

* a time history (``study=nominal``, ``linear``, ``flex_sweep``): the ascent plots, and
  the console summary of the flight;
* group ``linear``: the six charts of every point that has chart data and the margin
  envelope (``plots/linear/``);
* group ``flex_sweep``: the Nichols overlays (``plots/flex_sweep/``);
* group ``montecarlo`` (a Monte Carlo batch, or the folder of one fly-off controller):
  histograms, dispersion histograms, envelopes and the margin spread;
* group ``flyoff``: the nominal-history overlays and the metric histograms;
* group ``mode_retention``: the step-response overlays and the margins against the count;
* group ``time_margins``: one figure per search (``plots/time_margins/``).

The figures have the names, and show the data, of the ones the study drew itself.
"""

from __future__ import annotations

from pathlib import Path

import h5py
from rich.console import Console

from savant_cli.io.console import print_run_summary
from savant_cli.io.hdf5 import FORMAT, STUDY_FORMAT, RunFileError, read_run
from savant_cli.io.integrity import verify_h5

RUN_FILE = "savant.h5"
PLOTS_DIR = "plots"


def _contents(h5: Path) -> tuple[str, set[str]]:
    """The file's format tag and top-level groups (a Monte Carlo batch file has no tag)."""
    with h5py.File(h5, "r") as f:
        fmt = f.attrs.get("format", "")
        return (fmt.decode() if isinstance(fmt, bytes) else str(fmt)), set(f)


def report(run_dir: Path | str, console: Console | None = None) -> list[Path]:
    """Redraw all figures of a run into ``run_dir/plots/``, write ``run_dir/report.html``
    and print its summary again.

    Parameters
    ----------
    run_dir : pathlib.Path or str
        A run folder written by ``savant run`` (it holds ``savant.h5``).
    console : rich.console.Console, optional
        Where to print the summary; a new stdout console by default.

    Returns
    -------
    list of pathlib.Path
        The PNG files written.

    Raises
    ------
    FileNotFoundError
        If ``run_dir`` does not exist or holds no ``savant.h5``.
    savant_cli.io.hdf5.RunFileError
        If ``savant.h5`` is an HDF5 file but not a savant one.
    savant_cli.errors.DamagedFileError
        If ``savant.h5`` cannot be read back whole (truncated, not HDF5, an object
        damaged inside): the message names the file, the problem and the command that
        writes it again (:func:`savant_cli.io.integrity.rebuild_hint`).
    savant_cli.errors.OutputWriteError
        If a figure or ``report.html`` cannot be written (disk full, folder not
        writable); the summary has been printed and the files written before stay whole.
    """
    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise FileNotFoundError(f"run folder {run_dir} does not exist")
    h5 = run_dir / RUN_FILE
    if not h5.is_file():
        raise FileNotFoundError(
            f"no {RUN_FILE} in {run_dir}: not a savant run folder, or the run was made "
            f"with output.hdf5=false")
    console = console or Console()
    verify_h5(h5)  # damage anywhere is named before anything is drawn
    fmt, groups = _contents(h5)
    folder = run_dir / PLOTS_DIR
    paths: list[Path] = []
    if fmt == FORMAT:
        from savant_cli.plots.ascent import plot_ascent  # matplotlib only when drawing

        record = read_run(h5)
        print_run_summary(record.summary, record.status, record.message, console)  # even if no plot can be written
        paths += plot_ascent(record, folder)
    elif fmt != STUDY_FORMAT and "montecarlo" not in groups:
        raise RunFileError(f"{h5} is not a savant run file (format attribute {fmt!r})")
    from savant_cli.studies.redraw import STUDY_GROUPS, draw_groups

    paths += draw_groups(h5, groups, folder)
    studies = sorted(groups & set(STUDY_GROUPS))
    if studies:
        console.print(f"redrawn from {RUN_FILE}: {', '.join(studies)}")
    from savant_cli.html_report import write_report_or_say

    write_report_or_say(run_dir, console, raise_write_errors=True)  # report.html, with the figures just drawn
    return paths
