"""Order checks of table axes: a table out of order is refused, never repaired.

Every data table savant reads (vehicle tables, modal data, slosh tables, guidance
command files, comparison references) is interpolated or indexed along one or more
axes that must be strictly increasing *as written*. A table whose rows are out of
order is refused with a :class:`~savant_cli.errors.ConfigError` naming
``<folder>/<file>.csv:<column>``, the row and its line in the file, the value and the
one it follows; savant never sorts a table for the user (a silently re-sorted table
flies a different vehicle than the file reads, issue 27 item 7).

Rows are counted as the data rows below the header, from 1; the line is the file's own
line number (comment and blank lines counted), so an editor jumps to it.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from savant_cli.errors import ConfigError

#: What every refusal of this module ends with.
NEVER_SORTED = "put the rows in order (savant refuses a table out of order; it never sorts one)"


def table_key(path: Path) -> str:
    """``<folder>/<file>`` of a table, the prefix of its error keys (``ares_i/aero_stack.csv``)."""
    path = Path(path)
    return f"{path.parent.name}/{path.name}"


def data_line_numbers(lines: Sequence[str], start: int) -> list[int]:
    """1-based file line numbers of the data rows of a CSV.

    Parameters
    ----------
    lines : sequence of str
        The file's lines.
    start : int
        Index in ``lines`` of the first line after the header.

    Returns
    -------
    list of int
        The line number of each data row: lines that hold something other than a ``#``
        comment (the rule of ``numpy.loadtxt(comments="#")``).
    """
    return [i + 1 for i in range(start, len(lines)) if lines[i].split("#", 1)[0].strip()]


def row_text(row: int, line_numbers: Sequence[int] | None = None) -> str:
    """``row 5 (line 9)`` for the 0-based data row ``row``."""
    where = f"row {row + 1}"
    if line_numbers is not None and row < len(line_numbers):
        where += f" (line {line_numbers[row]})"
    return where


def require_increasing(key: str, values: np.ndarray, line_numbers: Sequence[int] | None = None,
                       strict: bool = True, what: str = "the table axis") -> None:
    """Refuse a column that is not (strictly) increasing.

    Parameters
    ----------
    key : str
        ``<folder>/<file>.csv:<column>`` (or a config key) named in the error.
    values : numpy.ndarray
        The column as written in the file (before any unit conversion).
    line_numbers : sequence of int, optional
        The file line of each row (:func:`data_line_numbers`).
    strict : bool
        True: each value must exceed the one before; False: must not fall below it.
    what : str
        What the column is, for the message.

    Raises
    ------
    ConfigError
        At the first row out of order, with its value.
    """
    x = np.asarray(values, dtype=float)
    d = np.diff(x)
    bad = d <= 0.0 if strict else d < 0.0
    if np.any(bad):
        i = int(np.argmax(bad)) + 1
        order = "strictly increasing" if strict else "non-decreasing"
        raise ConfigError(key, float(x[i]), f"{row_text(i, line_numbers)}: {what} must be {order}, and "
                                            f"{x[i]:.9g} follows {x[i - 1]:.9g} in {row_text(i - 1, line_numbers)}; "
                                            + NEVER_SORTED)


def require_grid_order(keys: Sequence[str], columns: Sequence[np.ndarray],
                       line_numbers: Sequence[int] | None = None) -> None:
    """Refuse grid rows that are not listed in order: the first column varies slowest,
    the last fastest, and each is strictly increasing within the block of rows that
    share the columns before it (so no row repeats).

    Parameters
    ----------
    keys : sequence of str
        ``<folder>/<file>.csv:<column>`` of each grid column, slowest first.
    columns : sequence of numpy.ndarray
        The columns as written in the file, same order.
    line_numbers : sequence of int, optional
        The file line of each row.

    Raises
    ------
    ConfigError
        At the first row out of order, keyed by the column that breaks the order.
    """
    grid = np.column_stack([np.asarray(c, dtype=float) for c in columns])
    if grid.shape[0] < 2:
        return
    d = np.diff(grid, axis=0)
    differs = d != 0.0
    first = np.argmax(differs, axis=1)  # the slowest column that changes between two rows
    step = d[np.arange(d.shape[0]), first]
    bad = ~differs.any(axis=1) | (step < 0.0)
    if not np.any(bad):
        return
    i = int(np.argmax(bad)) + 1
    names = [k.rpartition(":")[2] for k in keys]
    layout = (f"the grid's rows must list {names[0]} slowest and {names[-1]} fastest, each strictly increasing "
              f"within the rows that share the columns before it")
    if not differs[i - 1].any():
        raise ConfigError(keys[-1], grid[i].tolist(), f"{row_text(i, line_numbers)} repeats "
                                                      f"{row_text(i - 1, line_numbers)}; {layout}")
    k = int(first[i - 1])
    within = ", ".join(f"{n} = {v:.9g}" for n, v in zip(names[:k], grid[i, :k]))
    raise ConfigError(keys[k], float(grid[i, k]),
                      f"{row_text(i, line_numbers)}: {layout}, and {grid[i, k]:.9g} follows {grid[i - 1, k]:.9g} in "
                      f"{row_text(i - 1, line_numbers)}{f' (at {within})' if within else ''}; " + NEVER_SORTED)
