"""A finished run's study figures, drawn again from its ``savant.h5`` alone by each study's
own drawing code: what ``savant report`` writes (:mod:`savant_cli.report`) and what
``savant_cli.Result.plot`` returns (inside :func:`savant_cli.plots.figure.capture_figures`)."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

#: The groups of ``savant.h5`` that hold a study's figures, in drawing order.
STUDY_GROUPS = ("linear", "flex_sweep", "montecarlo", "flyoff", "mode_retention", "fcs_design", "time_margins")


def draw_groups(h5: Path, groups: Iterable[str], folder: Path) -> list[Path]:
    """Draw the figures of the study groups among ``groups`` into ``folder``.

    Parameters
    ----------
    h5 : Path
        The run file (``<run folder>/savant.h5``).
    groups : iterable of str
        Top-level groups of the file; those in :data:`STUDY_GROUPS` are drawn.
    folder : Path
        The run's ``plots/`` folder (a Monte Carlo batch draws into
        ``<run folder>/plots`` whatever it is).

    Returns
    -------
    list of Path
        The PNG files written (or, inside ``capture_figures``, kept).
    """
    present = set(groups)
    paths: list[Path] = []
    if "linear" in present:
        from savant_cli.linear.store import read_linear_group
        from savant_cli.studies.linear import draw_linear

        charts, rows, requirements, zones, failed = read_linear_group(h5)
        paths += draw_linear(charts, rows, requirements, zones, folder, failed)
    if "flex_sweep" in present:
        from savant_cli.studies import flex_sweep

        paths += flex_sweep.draw(*flex_sweep.read_group(h5), folder)
    if "montecarlo" in present:
        from savant_cli.plots.montecarlo_batch import redraw

        paths += redraw(h5.parent)
    if "flyoff" in present:
        from savant_cli.studies import flyoff

        paths += flyoff.draw(*flyoff.read_group(h5), folder)
    if "mode_retention" in present:
        from savant_cli.studies import mode_retention

        paths += mode_retention.draw(mode_retention.read_group(h5), folder)
    if "fcs_design" in present:
        from savant_cli.studies import fcs_design

        paths += fcs_design.draw(*fcs_design.read_group(h5), folder)
    if "time_margins" in present:
        from savant_cli.studies import time_margins

        paths += time_margins.draw(time_margins.read_group(h5), folder)
    return paths
