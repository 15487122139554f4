"""One checked journal entry of a Monte Carlo batch (``runs/run_NNNNNN.npz``).

An entry is an ``.npz`` archive of named arrays (one run's outcome,
``montecarlo/batch.py::RunOutcome``) plus one more member, ``sha256``: the SHA-256
(:mod:`hashlib`) of the payload, taken over every other member in name order as its
name, dtype, shape and bytes. Reading an entry recomputes the digest; an archive that
cannot be opened (garbage, truncated, empty) or whose payload does not match its digest
is a :class:`~savant_cli.errors.DamagedFileError` naming the file and what is wrong.

The digest is inside the archive, so an entry is one file written at once
(:func:`savant_cli.io.atomic.atomic_path`: a temporary name, fsync, :func:`os.replace`;
the temporary file is removed when the write fails). It covers the payload rather than
the file's bytes so that it can live in the file it checks. Entries written before the
digest existed carry no ``sha256`` member; they are read as before, checked only by the
zip format's own CRC-32 of each member.
"""

from __future__ import annotations

import hashlib
import zipfile
import zlib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from savant_cli.errors import DamagedFileError
from savant_cli.io.atomic import atomic_path

#: The member holding the payload's SHA-256 (hex digits).
CHECKSUM_KEY = "sha256"

#: What reading a damaged archive raises (numpy, zipfile and zlib's errors).
_READ_ERRORS = (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile, zlib.error)


def payload_digest(arrays: Mapping[str, np.ndarray]) -> str:
    """SHA-256 of named arrays: per name in sorted order, the name, dtype, shape and
    C-order bytes.

    Parameters
    ----------
    arrays : mapping of str to numpy.ndarray
        The payload (no object arrays).

    Returns
    -------
    str
        64 hex digits.
    """
    h = hashlib.sha256()
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}\0{a.dtype.str}\0{a.shape}\0".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def write_entry(path: Path, arrays: Mapping[str, Any]) -> None:
    """Write the arrays and their digest to ``path``, atomically.

    Parameters
    ----------
    path : pathlib.Path
        The entry, ``<batch>/runs/run_NNNNNN.npz``.
    arrays : mapping of str to array-like
        The payload; ``sha256`` is reserved.

    Raises
    ------
    savant_cli.errors.OutputWriteError
        The entry could not be written (disk full, folder not writable); no temporary
        file is left and an earlier entry of that name is untouched.
    """
    payload = {k: np.asarray(v) for k, v in arrays.items()}
    if CHECKSUM_KEY in payload:
        raise ValueError(f"journal member name {CHECKSUM_KEY!r} is reserved")
    digest = payload_digest(payload)
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        np.savez(fh, **payload, **{CHECKSUM_KEY: np.array(digest)})


def _problem(path: Path, exc: BaseException) -> str:
    """What is wrong with an archive numpy could not read, in plain words."""
    try:
        size = path.stat().st_size
        with open(path, "rb") as fh:
            head = fh.read(8)
    except OSError as err:
        return f"unreadable: {err}"
    if size == 0:
        return "empty (0 bytes)"
    if not head.startswith(b"PK"):
        return f"not an npz archive ({size:,} bytes starting {head!r})"
    first = (str(exc).strip().splitlines() or [""])[0]
    return f"truncated or corrupt archive ({size:,} bytes; {type(exc).__name__}: {first})"


def read_entry(path: Path, rebuild: str) -> dict[str, np.ndarray]:
    """The payload of an entry, checked against its digest.

    Parameters
    ----------
    path : pathlib.Path
        The entry.
    rebuild : str
        What flies the run again, for the message of a damaged entry.

    Returns
    -------
    dict of str to numpy.ndarray
        Every member but the digest.

    Raises
    ------
    savant_cli.errors.DamagedFileError
        The archive cannot be read (garbage, truncated, empty) or its payload does not
        match its digest.
    """
    try:
        with np.load(path, allow_pickle=False) as z:
            if not hasattr(z, "files"):  # a bare .npy array, not an archive
                raise ValueError("a single .npy array, not an .npz archive")
            arrays = {k: z[k] for k in z.files}
    except _READ_ERRORS as exc:
        raise DamagedFileError(path, _problem(path, exc), rebuild) from None
    stored = arrays.pop(CHECKSUM_KEY, None)
    if stored is not None:
        actual = payload_digest(arrays)
        if str(stored) != actual:
            raise DamagedFileError(path, f"checksum mismatch: sha256 {actual[:12]}… of its content, "
                                         f"{str(stored)[:12]}… written", rebuild)
    return arrays
