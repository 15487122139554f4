"""``savant.h5``: one run's time histories, events, summary, config and provenance.

Layout (``format = "savant-run"``, ``format_version = 1``)::

    /                         attrs: format, format_version, complete (bool), status,
                                     message, and every provenance entry as a string
                                     attr (savant_version, git_commit, python, numba,
                                     host, created_utc, ...)
    /config                   scalar UTF-8 string dataset: the resolved config (YAML)
    /time_history/<name>      one dataset per signal, shape (n,) or (n, k), float64 (or
                              integer flags); attrs: units, description,
                              columns (string array, empty for 1-D), frame
                              ("ECI", "body", "NED", "launch", "structure" or "")
    /events/name              (m,) UTF-8 strings, in order of occurrence
    /events/time_s            (m,) float64
    /summary                  group; attrs hold the summary scalars (float, int, bool,
                              str). A value of None is stored as NaN and its key listed
                              in the string-array attr ``__none__``.

A study that has no single flight to store (``study=mode_retention``, ``study=flyoff``)
writes its ``savant.h5`` with :func:`write_study_file` instead: root attrs ``format =
"savant-study"``, ``format_version``, ``study`` and the provenance, ``/config``, and the
study's own group.

Signal order and summary order are preserved (groups are created with creation-order
tracking). Datasets that are 2-D or longer than 1,024 samples are chunked and compressed
with the shuffle filter and gzip level 4. The file is written through
:func:`savant_cli.io.h5write.atomic_h5`: it appears complete or not at all, and a full disk
is one :class:`~savant_cli.errors.OutputWriteError`.
"""

from __future__ import annotations

import math
import os
import zlib
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from savant_cli.io.h5write import atomic_h5
from savant_cli.io.integrity import read_h5
from savant_cli.io.record import RunRecord, Signal

FORMAT = "savant-run"
FORMAT_VERSION = 1
#: Format tag of a study file without a time history (:func:`write_study_file`).
STUDY_FORMAT = "savant-study"

#: Root attributes that are not provenance.
RESERVED_ROOT_ATTRS = ("format", "format_version", "complete", "status", "message")

#: Summary attribute listing the keys whose value is None.
NONE_MARKER = "__none__"

_STR = h5py.string_dtype(encoding="utf-8")
_COMPRESS_MIN_ROWS = 1024
_GZIP_LEVEL = 4
_CHUNK_BYTES = 1 << 18  # 256 KiB per chunk: large enough for speed, small for partial reads


class RunFileError(OSError):
    """A file that is not a readable savant run (wrong format tag or a newer version)."""


def _str_array(items: tuple[str, ...] | list[str]) -> np.ndarray:
    return np.array([str(s) for s in items], dtype=_STR)


def _check_signals(signals: dict[str, Signal]) -> int:
    if "time" not in signals:
        raise ValueError("RunRecord.signals must include 'time'")
    time_shape = np.shape(signals["time"].data)
    if len(time_shape) != 1:
        raise ValueError(f"signal 'time' must be 1-D, got shape {time_shape}")
    n = time_shape[0]
    for name, sig in signals.items():
        if not name or "/" in name:
            raise ValueError(f"invalid signal name {name!r}")
        shape = np.shape(sig.data)
        if len(shape) == 0 or shape[0] != n:
            raise ValueError(f"signal {name!r} has shape {shape}; expected {n} rows like 'time'")
        if sig.columns and (len(shape) < 2 or shape[1] != len(sig.columns)):
            raise ValueError(f"signal {name!r} has shape {shape} but {len(sig.columns)} column names")
    return n


def _chunk_rows(data: np.ndarray) -> int:
    row_bytes = max(1, data.itemsize * int(np.prod(data.shape[1:])))
    return int(min(data.shape[0], max(1, _CHUNK_BYTES // row_bytes)))


def _compress_chunk(data: np.ndarray, start: int, rows: int) -> bytes:
    """One chunk exactly as HDF5's shuffle + deflate pipeline stores it.

    Edge chunks are padded to the full chunk shape with zeros (HDF5 stores edge chunks
    whole; the padding is never read back).
    """
    block = data[start:start + rows]
    if block.shape[0] < rows:
        pad = np.zeros((rows - block.shape[0], *data.shape[1:]), dtype=data.dtype)
        block = np.concatenate([block, pad])
    raw = np.ascontiguousarray(block).view(np.uint8).reshape(-1, data.itemsize)
    return zlib.compress(np.ascontiguousarray(raw.T).tobytes(), _GZIP_LEVEL)


def _write_signals(group: h5py.Group, signals: dict[str, Signal]) -> None:
    """Create one dataset per signal; compress the chunks of all of them in parallel.

    HDF5 runs its filters under h5py's global lock, one chunk at a time; deflate is the
    whole cost of writing a run. The chunks are therefore shuffled and deflated here on
    a thread pool (zlib releases the GIL) and stored with ``write_direct_chunk``; the
    result is byte-for-byte the standard shuffle + gzip layout any HDF5 reader decodes.
    """
    jobs = []
    for name, sig in signals.items():
        data = np.ascontiguousarray(sig.data)
        compress = data.size > 0 and (data.ndim >= 2 or data.shape[0] > _COMPRESS_MIN_ROWS)
        if compress:
            rows = _chunk_rows(data)
            ds = group.create_dataset(name, shape=data.shape, dtype=data.dtype, chunks=(rows, *data.shape[1:]),
                                      compression="gzip", compression_opts=_GZIP_LEVEL, shuffle=True)
            if data.dtype.kind in "fiu" and data.dtype.byteorder in "=|<":
                jobs.extend((ds, data, start, rows) for start in range(0, data.shape[0], rows))
            else:
                ds[...] = data
        else:
            ds = group.create_dataset(name, data=data)
        ds.attrs["units"] = str(sig.units)
        ds.attrs["description"] = str(sig.description)
        ds.attrs["columns"] = _str_array(tuple(sig.columns))
        ds.attrs["frame"] = str(sig.frame)
    if not jobs:
        return
    workers = max(1, min(len(jobs), os.cpu_count() or 1, 8))
    with ThreadPoolExecutor(max_workers=workers) as pool:
        chunks = pool.map(lambda job: _compress_chunk(job[1], job[2], job[3]), jobs)
        for (ds, data, start, _rows), payload in zip(jobs, chunks):
            ds.id.write_direct_chunk((start,) + (0,) * (data.ndim - 1), payload, filter_mask=0)


def _write_summary(group: h5py.Group, summary: dict[str, Any]) -> None:
    none_keys: list[str] = []
    for key, value in summary.items():
        if key == NONE_MARKER:
            raise ValueError(f"summary key {NONE_MARKER!r} is reserved")
        if value is None:
            group.attrs[key] = np.nan
            none_keys.append(key)
        elif isinstance(value, (str, np.str_)):
            group.attrs.create(key, str(value), dtype=_STR)
        elif isinstance(value, (bool, np.bool_, int, np.integer, float, np.floating)):
            group.attrs[key] = value
        else:
            raise TypeError(f"summary[{key!r}] = {value!r}: only float, int, bool, str or None")
    group.attrs[NONE_MARKER] = _str_array(none_keys)


def write_run(path: Path | str, record: RunRecord, extra=None) -> None:
    """Write a run to an HDF5 file, atomically.

    Parameters
    ----------
    path : pathlib.Path or str
        Destination, normally ``<run_dir>/savant.h5`` (directory created if missing).
    record : RunRecord
        The run. Every signal must have as many rows as ``record.signals["time"]``.
    extra : callable, optional
        ``extra(h5py.File)`` writes a study's own groups inside the same atomic write.

    Raises
    ------
    ValueError
        If ``time`` is missing, a signal's row count differs from ``time``, column names
        do not match the data, or a provenance key collides with a reserved root attr.
    TypeError
        If a summary value is not float, int, bool, str or None.

    Notes
    -----
    Layout in the module docstring and in ``docs/outputs.md``. Nothing is left at
    ``path`` (and a previous file there is untouched) when writing fails.
    """
    _check_signals(record.signals)
    for key in record.provenance:
        if key in RESERVED_ROOT_ATTRS:
            raise ValueError(f"provenance key {key!r} collides with a reserved root attribute")
    with atomic_h5(Path(path), track_order=True) as f:
        f.attrs["format"] = FORMAT
        f.attrs["format_version"] = np.int64(FORMAT_VERSION)
        f.attrs["complete"] = bool(record.complete)
        f.attrs["status"] = str(record.status)
        f.attrs["message"] = str(record.message)
        for key, value in record.provenance.items():
            f.attrs[key] = "" if value is None else str(value)
        f.create_dataset("config", data=str(record.config_yaml), dtype=_STR)
        _write_signals(f.create_group("time_history", track_order=True), record.signals)
        ev = f.create_group("events", track_order=True)
        ev.create_dataset("name", data=_str_array([e[0] for e in record.events]), dtype=_STR)
        ev.create_dataset("time_s", data=np.array([float(e[1]) for e in record.events], dtype=np.float64))
        _write_summary(f.create_group("summary", track_order=True), record.summary)
        if extra is not None:
            extra(f)


def write_study_file(path: Path | str, study: str, config_yaml: str, provenance: dict[str, Any], fill) -> None:
    """Write a study's ``savant.h5`` that holds no time history, atomically.

    Parameters
    ----------
    path : pathlib.Path or str
        Destination (directory created if missing).
    study : str
        The study's name (root attribute ``study``).
    config_yaml : str
        The resolved config (dataset ``/config``).
    provenance : dict
        Provenance entries, one string root attribute each.
    fill : callable
        ``fill(h5py.File)`` writes the study's own groups inside the same atomic write.
    """
    with atomic_h5(Path(path), track_order=True) as f:
        f.attrs["format"] = STUDY_FORMAT
        f.attrs["format_version"] = np.int64(FORMAT_VERSION)
        f.attrs["study"] = study
        for key, value in provenance.items():
            if key not in RESERVED_ROOT_ATTRS:
                f.attrs[key] = "" if value is None else str(value)
        f.create_dataset("config", data=str(config_yaml), dtype=_STR)
        fill(f)


def as_str(value: Any) -> str:
    """A string attribute or dataset value as ``str`` (bytes decoded as UTF-8, 0-d arrays unwrapped)."""
    if isinstance(value, bytes):
        return value.decode("utf-8")
    if isinstance(value, np.ndarray) and value.shape == ():
        return as_str(value[()])
    return str(value)


def _as_python(value: Any) -> Any:
    if isinstance(value, (bytes, str)):
        return as_str(value)
    if isinstance(value, np.generic):
        return value.item()
    return value


def _read_signal(ds: h5py.Dataset) -> Signal:
    cols = ds.attrs.get("columns", np.array([], dtype=object))
    return Signal(
        data=ds[()],
        units=as_str(ds.attrs.get("units", "")),
        description=as_str(ds.attrs.get("description", "")),
        columns=tuple(as_str(c) for c in np.atleast_1d(cols)),
        frame=as_str(ds.attrs.get("frame", "")),
    )


def read_run(path: Path | str) -> RunRecord:
    """Read a run written by :func:`write_run`.

    Parameters
    ----------
    path : pathlib.Path or str
        A ``savant.h5`` file.

    Returns
    -------
    RunRecord
        Arrays exactly as written (same dtype and values); summary values as Python
        ``float``/``int``/``bool``/``str``/``None``; provenance as strings.

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    RunFileError
        If the file is not a savant run or was written by a newer format version.
    savant_cli.errors.DamagedFileError
        If the file cannot be read back (truncated, not HDF5, damaged inside); the
        message names it, the problem and what writes it again.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no such run file: {path}")
    with read_h5(path) as f:
        fmt = as_str(f.attrs.get("format", ""))
        if fmt != FORMAT:
            raise RunFileError(f"{path} is not a savant run file (format attribute {fmt!r}, expected {FORMAT!r})")
        version = int(f.attrs.get("format_version", 0))
        if version > FORMAT_VERSION:
            raise RunFileError(
                f"{path} has format_version {version}; this savant reads up to {FORMAT_VERSION} (upgrade savant)")
        provenance = {k: as_str(v) for k, v in f.attrs.items() if k not in RESERVED_ROOT_ATTRS}
        signals = {name: _read_signal(ds) for name, ds in f["time_history"].items()}
        names = [as_str(s) for s in f["events/name"][()]]
        times = [float(t) for t in f["events/time_s"][()]]
        sg = f["summary"]
        none_keys = {as_str(k) for k in np.atleast_1d(sg.attrs.get(NONE_MARKER, np.array([], dtype=object)))}
        summary: dict[str, Any] = {}
        for key, value in sg.attrs.items():
            if key == NONE_MARKER:
                continue
            v = _as_python(value)
            if key in none_keys and isinstance(v, float) and math.isnan(v):
                v = None
            summary[key] = v
        return RunRecord(
            signals=signals,
            events=list(zip(names, times)),
            summary=summary,
            config_yaml=as_str(f["config"][()]),
            provenance=provenance,
            complete=bool(f.attrs.get("complete", False)),
            status=as_str(f.attrs.get("status", "")),
            message=as_str(f.attrs.get("message", "")),
        )
