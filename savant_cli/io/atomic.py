"""Atomic file writes: a file either appears complete under its final name or not at all.

Every output of a run (``savant.h5``, ``summary.json``, plots, generated data files) is
written to a hidden temporary file in the destination directory, flushed to disk, then
renamed onto its final name with :func:`os.replace` (atomic on POSIX and Windows within
one file system). An exception while writing removes the temporary file and leaves any
previous file of that name untouched. A write the operating system refuses (disk full,
folder not writable, read-only file system) is raised as
:class:`~savant_cli.errors.OutputWriteError`, which names the file, its folder and the
reason in one line.
"""

from __future__ import annotations

import json
import math
import os
import secrets
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path, PurePath
from typing import Any

import numpy as np

from savant_cli.errors import OutputWriteError, SavantError


def _temp_name(final: Path) -> Path:
    """Hidden sibling of ``final`` with a unique ``.tmp`` name."""
    return final.with_name(f".{final.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp")


def _fsync_file(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _fsync_dir(directory: Path) -> None:
    """Persist a rename (best effort; not possible on every platform)."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


class _NothingWritten(FileNotFoundError):
    """The block of :func:`atomic_path` created no file (a programming error, not I/O)."""


@contextmanager
def atomic_path(final: Path | str) -> Iterator[Path]:
    """Yield a temporary path to write; move it onto ``final`` when the block succeeds.

    The temporary file is ``.<name>.<pid>.<random>.tmp`` in the directory of ``final``
    (created if missing), so the rename never crosses file systems. The block must create
    the file at the yielded path (any writer: ``open``, ``h5py.File``, ``savefig`` with an
    explicit ``format``). On success the file is fsynced and renamed with
    :func:`os.replace`; on any exception (including ``KeyboardInterrupt``) the temporary
    file is deleted, ``final`` is left as it was, and the exception propagates; an
    :class:`OSError` of the write (h5py's included) propagates as
    :class:`~savant_cli.errors.OutputWriteError` naming ``final``.

    Parameters
    ----------
    final : pathlib.Path or str
        Destination file name.

    Yields
    ------
    pathlib.Path
        The temporary path to write to.

    Raises
    ------
    FileNotFoundError
        If the block finished without creating the temporary file.
    savant_cli.errors.OutputWriteError
        If the folder or the file could not be written (disk full, not writable).

    Examples
    --------
    >>> with atomic_path(out_dir / "flex_sweep.csv") as tmp:  # doctest: +SKIP
    ...     with open(tmp, "w") as fh:
    ...         fh.write(text)

    HDF5 files go through :func:`savant_cli.io.h5write.atomic_h5`, which keeps a full
    disk away from the HDF5 library.
    """
    final = Path(final)
    try:
        final.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputWriteError(final, exc) from exc
    tmp = _temp_name(final)
    try:
        yield tmp
        if not tmp.exists():
            raise _NothingWritten(f"atomic write of {final}: nothing was written to {tmp}")
        _fsync_file(tmp)
        os.replace(tmp, final)
    except BaseException as exc:
        try:
            tmp.unlink()
        except OSError:
            pass  # never created, or the folder cannot be written: nothing to remove
        if isinstance(exc, OSError) and not isinstance(exc, (SavantError, _NothingWritten)):
            raise OutputWriteError(final, exc) from exc
        raise
    _fsync_dir(final.parent)


def write_text_atomic(path: Path | str, text: str, encoding: str = "utf-8") -> None:
    """Write ``text`` to ``path`` atomically.

    Parameters
    ----------
    path : pathlib.Path or str
        Destination file (its directory is created if missing).
    text : str
        Content.
    encoding : str, optional
        Text encoding, UTF-8 by default.
    """
    with atomic_path(Path(path)) as tmp:
        with open(tmp, "w", encoding=encoding, newline="") as fh:
            fh.write(text)


def to_jsonable(obj: Any) -> Any:
    """Convert ``obj`` to plain JSON types.

    numpy scalars become Python scalars, arrays and tuples become lists, paths become
    strings, and non-finite floats (NaN, ±inf) become ``None`` (JSON ``null``).

    Parameters
    ----------
    obj : Any
        A dict, list, tuple, numpy array or scalar, str, bool, int, float, None or path.

    Returns
    -------
    Any
        The same structure made of dict, list, str, int, float, bool and None only.

    Raises
    ------
    TypeError
        For any other type.
    """
    if obj is None or isinstance(obj, (bool, str)):
        return obj
    if isinstance(obj, np.generic):
        obj = obj.item()
        if isinstance(obj, (bytes, complex)):
            raise TypeError(f"cannot write {type(obj).__name__} value {obj!r} as JSON")
        return to_jsonable(obj)
    if isinstance(obj, int):
        return int(obj)
    if isinstance(obj, float):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, Mapping):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, PurePath):
        return str(obj)
    raise TypeError(f"cannot write {type(obj).__name__} value {obj!r} as JSON")


def write_json_atomic(path: Path | str, obj: Any) -> None:
    """Write ``obj`` as JSON (indent 2, trailing newline) to ``path`` atomically.

    NaN and ±inf are written as ``null`` (strict JSON has no non-finite numbers); numpy
    scalars and arrays are converted to Python numbers and lists (see
    :func:`to_jsonable`).

    Parameters
    ----------
    path : pathlib.Path or str
        Destination file (its directory is created if missing).
    obj : Any
        JSON-like structure.

    Raises
    ------
    TypeError
        If ``obj`` holds a value with no JSON form; nothing is written then.
    """
    text = json.dumps(to_jsonable(obj), indent=2, allow_nan=False, ensure_ascii=False) + "\n"
    write_text_atomic(path, text)
