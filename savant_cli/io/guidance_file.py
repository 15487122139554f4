"""Read and write guidance command files (CSV or HDF5).

A command file holds, at (typically) 1 Hz, the inertial-to-commanded-body attitude as a
quaternion ``q_c2i`` (commanded body → ECI, Hamilton, scalar first; ECI X through
Greenwich at liftoff) and the commanded body rate (commanded-body axes).

CSV columns: ``time_s, q_w, q_x, q_y, q_z, rate_x_rad_s, rate_y_rad_s, rate_z_rad_s``
(``rate_*_deg_s`` also accepted), optionally ``v_rel_m_s``: the reference ascent's
Earth-relative speed at each sample, which ``guidance.first_stage_schedule =
relative_velocity`` indexes the first stage by. HDF5: datasets ``time_s`` (n),
``quaternion`` (n, 4), ``rate_rad_s`` (n, 3), optionally ``v_rel_m_s`` (n).
"""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

import h5py
import numpy as np

from savant_cli.errors import ConfigError
from savant_cli.io.atomic import atomic_path
from savant_cli.io.table_order import data_line_numbers, require_increasing, row_text, table_key

CSV_COLUMNS = ("time_s", "q_w", "q_x", "q_y", "q_z", "rate_x_rad_s", "rate_y_rad_s", "rate_z_rad_s")
SPEED_COLUMN = "v_rel_m_s"


class GuidanceTable(NamedTuple):
    """A command file's content as the engine flies it (SI).

    Attributes
    ----------
    time : ndarray, shape (n,)
        Sample times, s from liftoff, strictly increasing.
    quat : ndarray, shape (n, 4)
        Commanded attitude ``q_c2i`` (commanded body → ECI, Hamilton, scalar first), unit norm.
    rate : ndarray, shape (n, 3)
        Commanded body rate, rad/s, commanded-body axes.
    speed : ndarray, shape (m,)
        The reference ascent's Earth-relative speed at ``time[:m]``, m/s (the first-stage
        samples; empty when the file has none).
    """

    time: np.ndarray
    quat: np.ndarray
    rate: np.ndarray
    speed: np.ndarray


def _check(key: str, time: np.ndarray, quat: np.ndarray, rate: np.ndarray,
           speed: np.ndarray | None = None, lines: list[int] | None = None) -> GuidanceTable:
    """Refuse a malformed command table; ``key`` is ``<folder>/<file>`` and ``lines`` the
    file line of each row (CSV)."""
    if time.ndim != 1 or time.size < 2:
        raise ConfigError(f"{key}:time_s", time.shape, "needs at least 2 command samples")
    if not np.all(np.isfinite(time)):
        i = int(np.argmax(~np.isfinite(time)))
        raise ConfigError(f"{key}:time_s", float(time[i]), f"{row_text(i, lines)}: times must be finite")
    require_increasing(f"{key}:time_s", time, lines, what="the command time")
    if not (np.all(np.isfinite(quat)) and np.all(np.isfinite(rate))):
        raise ConfigError(key, "non-finite value", "all commands must be finite numbers")
    norms = np.linalg.norm(quat, axis=1)
    if np.any(np.abs(norms - 1.0) > 1e-3):
        i = int(np.argmax(np.abs(norms - 1.0)))
        raise ConfigError(f"{key}:q", float(norms[i]), f"{row_text(i, lines)}: quaternions must have unit norm")
    quat = quat / norms[:, None]
    if speed is not None and (speed.shape != time.shape or not np.all(np.isfinite(speed)) or np.any(speed < 0.0)):
        raise ConfigError(f"{key}:v_rel_m_s", "bad value", "one finite, non-negative speed per sample")
    return GuidanceTable(time=np.ascontiguousarray(time, float), quat=np.ascontiguousarray(quat, float),
                         rate=np.ascontiguousarray(rate, float),
                         speed=np.ascontiguousarray(speed if speed is not None else np.zeros(0), float))


def read_guidance(path: Path, key: str = "guidance.command_file") -> GuidanceTable:
    """Load a command file, refusing malformed content with a ConfigError.

    ``key`` names the config key in the errors about the file as a whole; errors about
    its content name ``<folder>/<file>:<column>`` and the row (and, in a CSV, its line).
    A time axis out of order is refused, never sorted."""
    path = Path(path)
    tkey = table_key(path)
    if path.suffix.lower() in (".h5", ".hdf5"):
        try:
            with h5py.File(path, "r") as f:
                return _check(tkey, f["time_s"][()], f["quaternion"][()], f["rate_rad_s"][()],
                              f["v_rel_m_s"][()] if "v_rel_m_s" in f else None)
        except (OSError, KeyError) as exc:
            raise ConfigError(key, str(path), f"unreadable HDF5 command file ({exc}); needs time_s, quaternion, rate_rad_s") from None
    try:
        with open(path) as f:
            text = f.read().splitlines()
        header_at = next((i for i, ln in enumerate(text) if ln.split("#", 1)[0].strip()), len(text))
        rows = data_line_numbers(text, header_at + 1)
        names = tuple(h.strip() for h in text[header_at].split(",")) if header_at < len(text) else ()
        table = (np.loadtxt([text[n - 1] for n in rows], delimiter=",", comments="#", ndmin=2) if rows
                 else np.zeros((0, len(names))))
    except (OSError, ValueError) as exc:
        raise ConfigError(key, str(path), f"unreadable CSV command file ({exc})") from None
    deg = all(f"rate_{a}_deg_s" in names for a in "xyz")
    need = CSV_COLUMNS[:5] + (tuple(f"rate_{a}_deg_s" for a in "xyz") if deg else CSV_COLUMNS[5:])
    missing = [c for c in need if c not in names]
    if missing or table.shape[1] != len(names):
        raise ConfigError(key, str(path), f"missing columns {missing}; expected {list(CSV_COLUMNS)}")
    col = {n: table[:, i] for i, n in enumerate(names)}
    quat = np.column_stack([col[c] for c in need[1:5]])
    rate = np.column_stack([col[c] for c in need[5:8]])
    if deg:
        rate = np.radians(rate)
    return _check(tkey, col["time_s"], quat, rate, col.get(SPEED_COLUMN), rows)


def write_guidance_csv(path: Path, time: np.ndarray, quat: np.ndarray, rate: np.ndarray, header: str = "",
                       speed: np.ndarray | None = None) -> None:
    """Write a command file in the CSV layout above (atomically); ``speed`` (m/s) adds
    the ``v_rel_m_s`` column."""
    columns = CSV_COLUMNS + ((SPEED_COLUMN,) if speed is not None else ())
    table = np.column_stack([time, quat, rate] + ([speed] if speed is not None else []))
    comment = "".join(f"# {line}\n" for line in header.splitlines())
    with atomic_path(Path(path)) as tmp:
        with open(tmp, "w") as f:
            f.write(comment)
            f.write(",".join(columns) + "\n")
            np.savetxt(f, table, delimiter=",", fmt="%.12g")
