"""The numeric CSV files of vehicle data, read one way: the vehicle tables
(:func:`savant_cli.vehicle.read_table`, also the slosh tables) and the modal data files
(:mod:`savant_cli.io.modal_data`).

Format: ``#`` comment lines anywhere (and ``#`` comments after a row), one header row of
column names, then rows of numbers, one per header column. Every refusal is a
:class:`~savant_cli.errors.ConfigError` keyed ``<folder>/<file>.csv`` (the file) or
``<folder>/<file>.csv:<column>`` (a cell), with the offending value and, for a cell,
its data row and file line. Units (the columns' suffixes) are the caller's:
:mod:`savant_cli.io.units`.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

import numpy as np

from savant_cli.errors import ConfigError
from savant_cli.io.table_order import data_line_numbers, row_text, table_key


class NumericCsv(NamedTuple):
    """A CSV's header, its numeric rows and the file line of each row.

    Attributes
    ----------
    header : list of str
        The column names as written (unit suffixes included), stripped.
    data : numpy.ndarray
        ``(n_rows, len(header))`` float64, every value finite, in the file's units.
    lines : list of int
        The 1-based file line of each data row (for messages).
    """

    header: list[str]
    data: np.ndarray
    lines: list[int]


def read_numeric_csv(path: Path, min_rows: int = 1,
                     check_header: Callable[[list[str]], None] | None = None) -> NumericCsv:
    """Read a numeric CSV with a header row.

    Parameters
    ----------
    path : pathlib.Path
        The file.
    min_rows : int, optional
        The fewest data rows accepted.
    check_header : callable, optional
        Called with the header before the rows are read (the caller's column checks, so
        a wrong header is reported as such, not as rows of the wrong length).

    Returns
    -------
    NumericCsv
        Header, finite data and the line of each row.

    Raises
    ------
    ConfigError
        A missing or unreadable file, no header, a row with another number of cells than
        the header (``<file>:line <n>``), a cell that is not a number or not finite
        (``<file>:<column>``, the cell, its line), fewer than ``min_rows`` rows.
    """
    key = table_key(path)
    if not path.is_file():
        raise ConfigError(key, str(path), "no such data file")
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(key, str(path), f"unreadable ({exc})") from None
    lines = text.splitlines()
    header_at = next((i for i, ln in enumerate(lines) if ln.strip() and not ln.lstrip().startswith("#")), None)
    if header_at is None:
        raise ConfigError(key, "empty", f"needs a header row of column names and at least {min_rows} data "
                          f"row{'s' if min_rows > 1 else ''}")
    header = [h.strip() for h in lines[header_at].split(",")]
    if check_header is not None:
        check_header(header)
    body = lines[header_at + 1:]
    rows = data_line_numbers(lines, header_at + 1)
    if not rows:
        data = np.zeros((0, len(header)))
    else:
        try:
            data = np.loadtxt(body, delimiter=",", comments="#", ndmin=2, dtype=np.float64)
        except ValueError:
            data = None
    if data is None or data.shape[1] != len(header):
        for i, ln in enumerate(body, start=header_at + 2):  # locate the culprit for the message
            s = ln.split("#", 1)[0].strip()
            if not s:
                continue
            cells = s.split(",")
            if len(cells) != len(header):
                raise ConfigError(f"{key}:line {i}", ln, f"has {len(cells)} cells; the header has {len(header)}")
            for c, name in zip(cells, header):
                try:
                    float(c)
                except ValueError:
                    raise ConfigError(f"{key}:{name}", c.strip(), f"line {i}: cells must be numbers") from None
        raise ConfigError(key, str(path), "malformed numeric table")
    if data.shape[0] < min_rows:
        raise ConfigError(key, data.shape[0], f"needs at least {min_rows} data row{'s' if min_rows > 1 else ''}")
    finite = np.isfinite(data)
    if not finite.all():
        i, j = (int(k[0]) for k in np.nonzero(~finite))
        raise ConfigError(f"{key}:{header[j]}", float(data[i, j]), f"{row_text(i, rows)}: all values must be finite")
    return NumericCsv(header, data, rows)
