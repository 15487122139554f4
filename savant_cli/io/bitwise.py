"""Bitwise comparison of two ``savant.h5`` files: what "the same result" means.

Every dataset and every group attribute is compared (``numpy.array_equal`` with NaNs
equal, byte equality for strings) except what measures the machine rather than the
flight: provenance attributes (``provenance_*``), the stored config text (``/config``,
``config_yaml``), the wall-clock summary keys (:data:`WALL_CLOCK_KEYS`) and the
``*wall_time_s`` datasets; of the root attributes only a run's ``complete``, ``status``
and ``message`` (:data:`RUN_ATTRS`). Used by ``benchmarks/bitwise_regression.py`` (this
checkout against a reference commit) and by the tests that a sharded Monte Carlo,
collected, is the single-process batch.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import h5py
import numpy as np

#: Summary keys and root attributes that measure the machine, not the flight.
WALL_CLOCK_KEYS = ("study_wall_time_s", "process_wall_time_s", "sim_wall_time_s", "compile_time_s", "realtime_factor",
                   "wall_time_s", "wall_s", "simulation_wall_time_s", "elapsed_s", "runs_per_minute", "stage_wall_s")
#: Root attributes of a run file that describe the flight (the rest is provenance).
RUN_ATTRS = ("complete", "status", "message")


def equal(a: np.ndarray, b: np.ndarray) -> bool:
    """Same shape, same kind of dtype and the same values (NaNs equal)."""
    if a.shape != b.shape or a.dtype.kind != b.dtype.kind:
        return False
    if a.dtype.kind == "f":
        return bool(np.array_equal(a, b, equal_nan=True))
    return bool(np.array_equal(a, b))


def deviation(a: np.ndarray, b: np.ndarray) -> str:
    """How two unequal arrays differ: the largest absolute deviation, or shape and dtype."""
    if a.shape == b.shape and a.dtype.kind in "fiu" and b.dtype.kind in "fiu":
        with np.errstate(invalid="ignore"):
            d = np.abs(a.astype(float) - b.astype(float))
        return f"max |Δ| = {np.nanmax(d) if d.size else 0.0:.3e}"
    return f"shape {a.shape} vs {b.shape}, dtype {a.dtype} vs {b.dtype}"


def _attrs(obj: h5py.HLObject, skip: tuple[str, ...] = ()) -> dict[str, np.ndarray]:
    return {k: np.asarray(v) for k, v in obj.attrs.items() if k not in skip}


def compare_h5(a: Path, b: Path, addition: Callable[[str], bool] | None = None) -> list[str]:
    """Differences between two run files ``a`` (the reference) and ``b`` (the new one),
    each as ``location: what``; empty when they are bitwise identical.

    Parameters
    ----------
    a, b : Path
        The two ``savant.h5`` files.
    addition : callable, optional
        ``addition(key)`` is true for a summary key that only the new file may hold
        (a deliberate addition since the reference): such a key in the new file's list
        of null summary keys (``__none__``) is not a difference. None: no additions.
    """
    named = addition or (lambda key: False)
    diffs: list[str] = []
    with h5py.File(a, "r") as fa, h5py.File(b, "r") as fb:
        names_a, names_b = [], []
        fa.visit(names_a.append)
        fb.visit(names_b.append)
        for only, side in ((set(names_a) - set(names_b), "reference"), (set(names_b) - set(names_a), "new")):
            diffs += [f"{n}: only in the {side} file" for n in sorted(only)]
        for name in [n for n in names_a if n in set(names_b)]:
            oa, ob = fa[name], fb[name]
            if name == "config":
                continue  # the resolved config text (key order, new schema keys) is not an output
            skip = WALL_CLOCK_KEYS if name.endswith("summary") else ()
            at_a, at_b = _attrs(oa, skip), _attrs(ob, skip)
            for at in (at_a, at_b):  # provenance of a group (e.g. the Monte Carlo's): the machine, not the flight
                for k in [k for k in at if k.startswith("provenance_")]:
                    del at[k]
                at.pop("config_yaml", None)  # a batch's resolved config text, like /config: not an output
            if "__none__" in at_b:  # the summary's null keys: a named addition (not in the reference) may be null
                old_none = {str(x) for x in at_a.get("__none__", [])}
                at_b["__none__"] = np.array([x for x in at_b["__none__"] if str(x) in old_none or not named(str(x))],
                                            dtype=object)
            for k in sorted(set(at_a) | set(at_b)):
                if k not in at_a:
                    diffs.append(f"{name}@{k}: only in the new file")
                elif k not in at_b:
                    diffs.append(f"{name}@{k}: only in the reference file")
                elif not equal(at_a[k], at_b[k]):
                    diffs.append(f"{name}@{k}: {deviation(at_a[k], at_b[k])}")
            if isinstance(oa, h5py.Dataset):
                if name.endswith("wall_time_s"):
                    continue
                da, db = np.asarray(oa[()]), np.asarray(ob[()])
                if not equal(da, db):
                    diffs.append(f"{name}: {deviation(da, db)}")
        ra, rb = _attrs(fa), _attrs(fb)
        for k in RUN_ATTRS:  # (a Monte Carlo batch file has none of them)
            if (k in ra or k in rb) and (k not in ra or k not in rb or not equal(ra[k], rb[k])):
                diffs.append(f"/@{k}: {ra.get(k)} vs {rb.get(k)}")
    return diffs
