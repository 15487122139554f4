"""Damaged run files: say which file, what is wrong with it and what writes it again.

``savant report``, :func:`savant_cli.load` and ``savant collect`` read files that an
earlier command wrote. When one of them cannot be read back (truncated by a full disk or
a killed copy, overwritten, not HDF5 at all), they raise
:class:`~savant_cli.errors.DamagedFileError`, whose one line names the file, the problem
in plain words (``truncated: 1,024 of 88,310 bytes``) and the command that rebuilds it
(:func:`rebuild_hint`): the same ``savant run`` into the same folder for a run or a batch
(a batch then flies no run that its journal already holds), ``savant collect`` for a
multirun folder, ``savant rerun`` for a rerun folder.
"""

from __future__ import annotations

import re
import shlex
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import h5py
import yaml

from savant_cli.errors import DamagedFileError

#: What h5py raises on a damaged file (its error stack mapped to Python exceptions).
H5_ERRORS = (OSError, RuntimeError, KeyError, ValueError)


def _overrides(run_dir: Path) -> list[str] | None:
    """The command-line overrides of the run in ``run_dir`` (``.hydra/overrides.yaml``)
    without its output folder; None when unreadable."""
    try:
        items = yaml.safe_load((run_dir / ".hydra" / "overrides.yaml").read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return None
    if not isinstance(items, list):
        return None
    return [str(o) for o in items if not str(o).startswith(("hydra.run.dir=", "hydra.sweep.dir="))]


def rebuild_hint(run_dir: Path | str) -> str:
    """What writes the files of run folder ``run_dir`` again, as a clause.

    Parameters
    ----------
    run_dir : pathlib.Path or str
        A run folder (``savant run``), a batch folder, a multirun folder of shards, or a
        ``rerun_NNNNNN`` folder.

    Returns
    -------
    str
        For example ``run the same command again to rebuild it: savant run
        study=montecarlo study.n_runs=50 hydra.run.dir=DIR (the 49 runs in its journal
        runs/ are not flown again)``.
    """
    run_dir = Path(run_dir)
    m = re.fullmatch(r"rerun_(\d+)", run_dir.name)
    if m is not None:
        return f"rebuild it with: savant rerun {shlex.quote(str(run_dir.parent))} run={int(m.group(1))}"
    batch = (run_dir / "runs" / "manifest.json").is_file()
    if (run_dir / ".hydra").is_dir() or batch:
        overrides = _overrides(run_dir)
        where = f"hydra.run.dir={shlex.quote(str(run_dir))}"
        command = ("savant run " + " ".join([*map(shlex.quote, overrides), where]) if overrides is not None
                   else f"the command that made it, with {where}")
        tail = ""
        if batch:
            n = sum(1 for _ in (run_dir / "runs").glob("run_*.npz"))
            tail = f" (the {n} runs in its journal runs/ are not flown again)"
        return f"run the same command again to rebuild it: {command}{tail}"
    if any(run_dir.glob("*/runs/manifest.json")):
        return f"rebuild it from the shards' journals with: savant collect {shlex.quote(str(run_dir))}"
    return "run the command that wrote this folder again to rebuild it"


def h5_problem(path: Path, exc: BaseException) -> str:
    """What is wrong with an HDF5 file h5py refused, in plain words."""
    text = str(exc)
    try:
        size = path.stat().st_size
    except OSError:
        size = None
    if size == 0:
        return "empty (0 bytes)"
    trunc = re.search(r"truncated file: eof = (\d+).*?stored_eof = (\d+)", text)
    if trunc is not None:
        return f"truncated: {int(trunc.group(1)):,} of {int(trunc.group(2)):,} bytes"
    if "file signature not found" in text:
        return f"not an HDF5 file (no HDF5 signature in its {size:,} bytes)" if size is not None \
            else "not an HDF5 file (no HDF5 signature)"
    first = (text.strip().splitlines() or [type(exc).__name__])[0]
    return f"unreadable by HDF5: {first}"


@contextmanager
def read_h5(path: Path | str, rebuild: str | None = None) -> Iterator[h5py.File]:
    """Open an HDF5 file savant wrote, for reading; what h5py raises while it is open
    (on opening, or reading an object damaged inside) becomes a
    :class:`~savant_cli.errors.DamagedFileError` naming the file. Use it around reading
    only: an :class:`OSError` of the block's own is taken for the file's.

    Parameters
    ----------
    path : pathlib.Path or str
        The file (``<run_dir>/savant.h5``).
    rebuild : str, optional
        What writes it again; default :func:`rebuild_hint` of its folder.

    Yields
    ------
    h5py.File
        The open file.
    """
    path = Path(path)
    try:
        f = h5py.File(path, "r")
    except FileNotFoundError:
        raise
    except H5_ERRORS as exc:
        raise DamagedFileError(path, h5_problem(path, exc), rebuild or rebuild_hint(path.parent)) from None
    try:
        with f:
            yield f
    except (OSError, RuntimeError, KeyError) as exc:
        # h5py raises these very types; a subclass (FileNotFoundError, a savant error) or a
        # KeyError of a name the caller looked up is the caller's own
        if type(exc) not in (OSError, RuntimeError, KeyError) or (
                isinstance(exc, KeyError) and not any(w in str(exc) for w in ("Unable to", "Can't"))):
            raise
        raise DamagedFileError(path, h5_problem(path, exc), rebuild or rebuild_hint(path.parent)) from None


def verify_h5(path: Path | str, rebuild: str | None = None) -> None:
    """Read every attribute and every dataset of an HDF5 file once (chunk by chunk), so
    that damage anywhere in it is found before anything is drawn from it.

    Parameters
    ----------
    path : pathlib.Path or str
        The file.
    rebuild : str, optional
        What writes it again; default :func:`rebuild_hint` of its folder.

    Raises
    ------
    savant_cli.errors.DamagedFileError
        The file cannot be opened, or an object in it cannot be read (the message names
        the object).
    """
    path = Path(path)
    hint = rebuild or rebuild_hint(path.parent)
    with read_h5(path, hint) as f:
        def visit(name: str, obj) -> None:
            try:
                for key in obj.attrs:
                    obj.attrs[key]
                if isinstance(obj, h5py.Dataset) and obj.size:
                    if obj.chunks is None:
                        obj[()]
                    else:
                        for sel in obj.iter_chunks():
                            obj[sel]
            except H5_ERRORS as exc:
                first = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
                raise DamagedFileError(path, f"object /{name} unreadable: {first}", hint) from None

        visit("", f)
        f.visititems(visit)
