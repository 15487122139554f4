"""Table look-ups for the compiled hot path.

Two families: functions on separate arrays (``locate``, ``interp1``, ``trilinear``) and
``*_at`` functions that read one flat array at given offsets. The plant keeps all its
tables in one flat array because numba reference-counts every array argument on every
call; with two dozen table arrays those atomic operations were a quarter of the run time
(measured with perf, ``docs/architecture.md``).

``np.interp`` serves single 1-D columns. Where one breakpoint search feeds many columns
(mass properties) or three axes (aerodynamic coefficients), these kernels find the cell
once and blend, because no library offers a multi-column or trilinear look-up callable
from numba-compiled code. Outside a table the value is held at the end point (clamped),
which is the usual convention for flight-simulation data tables.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy")
def locate(axis: np.ndarray, n: int, x: float) -> tuple[int, float]:
    """Cell index ``i`` and weight ``w`` with ``x ≈ (1-w)·axis[i] + w·axis[i+1]``.

    Parameters
    ----------
    axis : ndarray
        Strictly increasing breakpoints; only the first ``n`` are used.
    n : int
        Number of valid breakpoints (≥ 2).
    x : float
        Query point; clamped to ``[axis[0], axis[n-1]]``.
    """
    if x <= axis[0]:
        return 0, 0.0
    if x >= axis[n - 1]:
        return n - 2, 1.0
    lo, hi = 0, n - 1  # bisection: axis[lo] <= x < axis[hi] (no array view, no allocation)
    while hi - lo > 1:
        mid = (lo + hi) >> 1
        if axis[mid] <= x:
            lo = mid
        else:
            hi = mid
    return lo, (x - axis[lo]) / (axis[lo + 1] - axis[lo])


@njit(cache=True, error_model="numpy")
def trilinear(grid: np.ndarray, i: int, wi: float, j: int, wj: float, k: int, wk: float) -> float:
    """Trilinear blend of ``grid[i:i+2, j:j+2, k:k+2]`` with cell weights."""
    c00 = grid[i, j, k] * (1.0 - wi) + grid[i + 1, j, k] * wi
    c01 = grid[i, j, k + 1] * (1.0 - wi) + grid[i + 1, j, k + 1] * wi
    c10 = grid[i, j + 1, k] * (1.0 - wi) + grid[i + 1, j + 1, k] * wi
    c11 = grid[i, j + 1, k + 1] * (1.0 - wi) + grid[i + 1, j + 1, k + 1] * wi
    c0 = c00 * (1.0 - wj) + c10 * wj
    c1 = c01 * (1.0 - wj) + c11 * wj
    return c0 * (1.0 - wk) + c1 * wk


@njit(cache=True, error_model="numpy")
def interp1(axis: np.ndarray, values: np.ndarray, x: float) -> float:
    """Linear interpolation of one column, clamped at the ends.

    Same result as ``np.interp`` for a strictly increasing axis; ``np.interp`` under numba
    re-validates its arguments on every call (measured ~320 ns against ~30 ns here), which
    matters four times per plant step.
    """
    i, w = locate(axis, axis.size, x)
    return (1.0 - w) * values[i] + w * values[i + 1]


@njit(cache=True, error_model="numpy")
def locate_at(a: np.ndarray, off: int, n: int, x: float) -> tuple[int, float]:
    """:func:`locate` on the axis ``a[off:off+n]`` of a flat array, without a view.

    Returns the cell index relative to ``off`` and the weight.
    """
    if x <= a[off]:
        return 0, 0.0
    if x >= a[off + n - 1]:
        return n - 2, 1.0
    lo, hi = 0, n - 1
    while hi - lo > 1:
        mid = (lo + hi) >> 1
        if a[off + mid] <= x:
            lo = mid
        else:
            hi = mid
    x0 = a[off + lo]
    return lo, (x - x0) / (a[off + lo + 1] - x0)


@njit(cache=True, error_model="numpy")
def interp1_at(a: np.ndarray, off_x: int, off_y: int, n: int, x: float) -> float:
    """:func:`interp1` of the column ``a[off_y:off_y+n]`` against ``a[off_x:off_x+n]``."""
    i, w = locate_at(a, off_x, n, x)
    return (1.0 - w) * a[off_y + i] + w * a[off_y + i + 1]


@njit(cache=True, error_model="numpy")
def trilinear_at(a: np.ndarray, base: int, si: int, sj: int, i: int, wi: float, j: int, wj: float,
                 k: int, wk: float) -> float:
    """:func:`trilinear` of a C-ordered 3-D block of a flat array.

    Element ``(i, j, k)`` of the block is ``a[base + i·si + j·sj + k]``.
    """
    p = base + i * si + j * sj + k
    c00 = a[p] * (1.0 - wi) + a[p + si] * wi
    c01 = a[p + 1] * (1.0 - wi) + a[p + si + 1] * wi
    c10 = a[p + sj] * (1.0 - wi) + a[p + si + sj] * wi
    c11 = a[p + sj + 1] * (1.0 - wi) + a[p + si + sj + 1] * wi
    c0 = c00 * (1.0 - wj) + c10 * wj
    c1 = c01 * (1.0 - wj) + c11 * wj
    return c0 * (1.0 - wk) + c1 * wk


@njit(cache=True, error_model="numpy", inline="always")
def tab(tb: np.ndarray, field: int) -> tuple[int, int]:
    """Offset and element count of field number ``field`` of a packed table array
    (:func:`savant_cli.models.blocks.pack`)."""
    return int(tb[2 * field]), int(tb[2 * field + 1])


@njit(cache=True, error_model="numpy", inline="always")
def tab_offset(tb: np.ndarray, field: int) -> int:
    """Offset of field number ``field``'s data in a packed table array."""
    return int(tb[2 * field])
