"""``savant report RUN_DIR``: redraw a finished run's plots and summary from ``savant.h5``."""

from __future__ import annotations

from pathlib import Path

from rich.console import Console

from savant_cli.io.console import print_run_summary
from savant_cli.io.hdf5 import read_run

RUN_FILE = "savant.h5"
PLOTS_DIR = "plots"


def report(run_dir: Path | str, console: Console | None = None) -> list[Path]:
    """Redraw all plots of a run into ``run_dir/plots/`` and print its summary again.

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
    OSError
        If ``savant.h5`` is not a readable savant run file
        (:class:`savant_cli.io.hdf5.RunFileError` or an h5py error).
    """
    from savant_cli.plots.ascent import plot_ascent  # matplotlib only when drawing

    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise FileNotFoundError(f"run folder {run_dir} does not exist")
    h5 = run_dir / RUN_FILE
    if not h5.is_file():
        raise FileNotFoundError(
            f"no {RUN_FILE} in {run_dir}: not a savant run folder, or the run was made "
            f"with output.hdf5=false")
    record = read_run(h5)
    paths = plot_ascent(record, run_dir / PLOTS_DIR)
    print_run_summary(record.summary, record.status, record.message, console)
    return paths
