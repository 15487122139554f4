"""From the journal of a batch (one or many shard folders) to the batch's outputs:
``savant.h5`` (group ``montecarlo``), ``minmax.csv``, ``percentiles.csv``,
``dispersion_statistics.csv``, ``margin_spread.csv``, ``insertion_accuracy.csv``,
``summary.json``, plots and the console summary, in one call (:func:`write_outputs`).
The figures are drawn by the function the caller hands in
(:func:`savant_cli.plots.montecarlo_batch.draw_figures`, a floor above this one)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console

from savant_cli.config import ReliabilitySpec, RequirementSet
from savant_cli.errors import OutputWriteError
from savant_cli.io.atomic import write_json_atomic
from savant_cli.io.h5write import atomic_h5
from savant_cli.montecarlo.analysis import analyse
from savant_cli.montecarlo.console_summary import print_analysis
from savant_cli.montecarlo.inventory import Inventory
from savant_cli.montecarlo.results import Tables
from savant_cli.montecarlo.storage import write_csv, write_group, write_tables

DrawFigures = Callable[[Path, Tables, list[dict[str, Any]], dict[str, tuple[float, float]] | None], list[Path]]
"""The batch's figure drawer: (folder, tables, dispersions, band requirements) → PNGs."""


def write_outputs(out_dir: Path, inv: Inventory, expected: list[int], dispersions: list[dict[str, Any]],
                  config_yaml: str, provenance: dict[str, str], history_names: list[str],
                  history_time: np.ndarray, requirements: RequirementSet | None,
                  draw: DrawFigures | None, console: Console | None = None, *,
                  reliability_spec: ReliabilitySpec) -> dict[str, Any]:
    """Write every batch output into ``out_dir``; returns the ``summary.json`` content.
    ``requirements``: the set the runs' margins were judged against (its band values
    mark the margin-spread plot); ``draw``: draws the figures into ``out_dir/plots``
    after the files are written (None: no plots); ``reliability_spec``: the demonstrated success's
    confidence, target and success statuses (``study.reliability``).

    An output that cannot be written (disk full, folder not writable) raises
    :class:`~savant_cli.errors.OutputWriteError` after the console summary has been
    printed (from the journal, when ``savant.h5`` itself failed); every file written
    before it stays whole, and the failed one keeps its previous content or does not
    exist (atomic writes)."""
    runs = sorted(r for r in expected if r in inv.files)
    missing = inv.missing(expected)
    bands = requirements.by_band() if requirements is not None else {}
    done: dict[str, Any] = {}
    try:
        try:
            out_dir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise OutputWriteError(out_dir / "savant.h5", exc) from exc
        with atomic_h5(out_dir / "savant.h5") as f:
            g = f.create_group("montecarlo")
            tb = done["tb"] = write_tables(g, inv, runs, history_names, history_time)
            an = done["an"] = analyse(tb, expected, missing, dispersions, requirements, reliability_spec)
            write_group(g, tb, an, inv, expected, dispersions, config_yaml, provenance, requirements)
        write_csv(out_dir / "minmax.csv", [{k: r[k] for k in ("variable", "max", "max_run", "min", "min_run")}
                                           for r in an.stats])
        write_csv(out_dir / "percentiles.csv", an.stats)
        write_csv(out_dir / "dispersion_statistics.csv", an.disp_stats)
        if an.spread:
            write_csv(out_dir / "margin_spread.csv", an.spread)
        if an.insertion["accuracy"]:
            # with navigation=inertial, the navigation errors' rows follow
            write_csv(out_dir / "insertion_accuracy.csv",
                      an.insertion["accuracy"] + an.insertion.get("navigation_errors", []))
        write_json_atomic(out_dir / "summary.json", an.summary)
        if draw is not None:
            draw(out_dir, tb, dispersions, bands or None)
    except OutputWriteError:
        if console is not None:  # the summary still reaches the console
            tb = done.get("tb") or write_tables(None, inv, runs, [], history_time)
            an = done.get("an") or analyse(tb, expected, missing, dispersions, requirements, reliability_spec)
            print_analysis(console, tb, an)
        raise
    if console is not None:
        print_analysis(console, tb, an)
    return an.summary
