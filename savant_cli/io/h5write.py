"""Write an HDF5 file atomically, and survive a full disk.

HDF5 does not recover from a failed write: once the disk refuses a block (``ENOSPC``,
``EIO``), every later flush fails again, each of the file's open objects prints an
"Exception ignored" traceback when h5py frees it, and with several objects open the
library can crash at interpreter exit (h5py 3.16 / HDF5 2.0, seen on a 1 MB tmpfs). So
HDF5 never sees the failure here: it writes through :class:`GuardedFile`, a file object
(h5py's ``fileobj`` driver) that passes every operation to the real temporary file until
the operating system refuses one, then keeps the file's content in memory and goes on
there, remembering the refusal. When the block ends, :func:`atomic_h5` raises the
refusal as :class:`~savant_cli.errors.OutputWriteError` and the temporary file is removed
(:func:`savant_cli.io.atomic.atomic_path`); a file of the same name written before is
untouched.
"""

from __future__ import annotations

import io
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import h5py

from savant_cli.errors import OutputWriteError
from savant_cli.io.atomic import atomic_path


class GuardedFile(io.RawIOBase):
    """A binary file that never fails a write: the first ``OSError`` of the real file
    (``failure``) moves the content to memory, where the writing goes on.

    Parameters
    ----------
    path : pathlib.Path
        The file to create (truncated if it exists).
    """

    def __init__(self, path: Path) -> None:
        super().__init__()
        self.path = path
        self._fh: Any = open(path, "w+b", buffering=0)  # unbuffered: a refusal shows at its write
        self.failure: OSError | None = None

    def _to_memory(self, exc: OSError) -> None:
        """Go on in memory with what the real file holds (reads work on a full disk)."""
        self.failure = exc
        pos = self._fh.tell()
        self._fh.seek(0)
        mem = io.BytesIO(self._fh.read())
        mem.seek(pos)
        self._fh.close()
        self._fh = mem

    def _guard(self, op: str, *args: Any) -> Any:
        try:
            return getattr(self._fh, op)(*args)
        except OSError as exc:
            if self.failure is not None:
                raise  # memory refuses nothing: this is not the disk
            self._to_memory(exc)
            return getattr(self._fh, op)(*args)

    def readable(self) -> bool:
        return True

    def writable(self) -> bool:
        return True

    def seekable(self) -> bool:
        return True

    def readinto(self, buffer) -> int:
        return self._fh.readinto(buffer)

    def write(self, data) -> int:
        view = memoryview(data).cast("B")
        if self.failure is None:
            done = 0
            try:
                while done < len(view):  # a raw write may take part of the data
                    n = self._fh.write(view[done:])
                    if not n:
                        raise OSError(28, "No space left on device")
                    done += n
                return done
            except OSError as exc:
                self._fh.seek(self._fh.tell() - done)
                self._to_memory(exc)
        return self._fh.write(view)

    def seek(self, offset: int, whence: int = io.SEEK_SET) -> int:
        return self._fh.seek(offset, whence)

    def tell(self) -> int:
        return self._fh.tell()

    def truncate(self, size: int | None = None) -> int:
        return self._guard("truncate", self._fh.tell() if size is None else size)

    def flush(self) -> None:
        if not self._fh.closed:
            self._guard("flush")

    def close(self) -> None:
        if not self.closed:
            try:
                self.flush()
            finally:
                self._fh.close()
                super().close()  # RawIOBase.close flushes again: a no-op on the closed file


@contextmanager
def atomic_h5(final: Path | str, **file_kwargs: Any) -> Iterator[h5py.File]:
    """Yield a new :class:`h5py.File` that appears at ``final`` complete, or not at all.

    Parameters
    ----------
    final : pathlib.Path or str
        Destination (its folder is created if missing).
    **file_kwargs
        Passed to :class:`h5py.File` (``track_order`` …).

    Yields
    ------
    h5py.File
        The file, open for writing.

    Raises
    ------
    savant_cli.errors.OutputWriteError
        The disk refused a write (full, read-only, I/O error): named with the file, its
        folder and the reason, once the block has ended; nothing is left at ``final``'s
        temporary name and a previous ``final`` is untouched.
    """
    final = Path(final)
    with atomic_path(final) as tmp:
        guarded = GuardedFile(tmp)
        try:
            with h5py.File(guarded, "w", **file_kwargs) as f:
                yield f
        except Exception:
            if guarded.failure is None:
                raise
            # what went wrong after the disk refused a write follows from the refusal
        finally:
            try:
                guarded.close()
            except OSError as exc:
                guarded.failure = guarded.failure or exc
        if guarded.failure is not None:
            raise OutputWriteError(final, guarded.failure) from guarded.failure
