"""Fast frequency response of a state-space system on many frequencies.

``control``'s state-space frequency response solves one Hessenberg system per frequency
(slycot ``tb05ad``, ~30 µs each on the 85-state loops), and its FRD margin routine then
evaluates a spline point by point; margins of a batch of points need tens of thousands
of evaluations. Here ``A`` is brought once to complex Schur form ``A = Z T Zᴴ`` (a
backward-stable reduction: no eigenvector conditioning, so the integrators' and the
drift's repeated eigenvalues near z = 1 are harmless) and

    H(s) = D + (C Z) (s I − T)⁻¹ (Zᴴ B),     s = e^{jωT} (discrete) or jω,

is one triangular back substitution, vectorized over all frequencies of a grid, or one
LAPACK triangular solve at a single frequency. The tests check it against
:meth:`control.StateSpace.frequency_response`.
"""

from __future__ import annotations

import control as ct
import numpy as np
from scipy.linalg import rsf2csf, schur, solve_triangular


class FastResponse:
    """Frequency response evaluator of one state-space system.

    Parameters
    ----------
    sys : control.StateSpace
        Continuous or discrete system (``dt`` in s for a discrete one).
    """

    def __init__(self, sys: ct.StateSpace) -> None:
        self.sys = sys
        self._discrete = bool(sys.isdtime(strict=True))
        self._d = np.asarray(sys.D, dtype=complex)
        if sys.nstates:
            t, z = rsf2csf(*schur(np.asarray(sys.A, dtype=float), output="real"))  # faster than complex
        else:
            t, z = np.zeros((0, 0), dtype=complex), np.zeros((0, 0), dtype=complex)
        self._t = t
        self._zb = z.conj().T @ sys.B
        self._cz = sys.C @ z

    @property
    def poles(self) -> np.ndarray:
        """Eigenvalues of ``A`` (the z-plane poles of a discrete system)."""
        return np.diag(self._t).copy()

    def _point(self, w: np.ndarray) -> np.ndarray:
        return np.exp(1j * w * self.sys.dt) if self._discrete else 1j * w

    def __call__(self, w: np.ndarray | float) -> np.ndarray:
        """Complex response, shape (n_outputs, n_inputs, n_w), at ``w`` (rad/s)."""
        w = np.atleast_1d(np.asarray(w, dtype=float))
        s = self._point(w)
        n = self._t.shape[0]
        if w.size == 1 and n:
            x = solve_triangular(s[0] * np.eye(n) - self._t, self._zb, check_finite=False)
            return (self._cz @ x + self._d)[:, :, None]
        m = self._zb.shape[1]
        x = np.empty((n, m * w.size), dtype=complex)  # column j * n_w + k: input j, frequency k
        rhs = np.repeat(self._zb, w.size, axis=1)
        den = np.tile(s, m)
        t = self._t
        for i in range(n - 1, -1, -1):  # back substitution, all frequencies at once
            x[i] = (rhs[i] + t[i, i + 1:] @ x[i + 1:]) / (den - t[i, i])
        return (self._cz @ x).reshape(-1, m, w.size) + self._d[:, :, None]

    def siso(self, w: np.ndarray | float) -> np.ndarray:
        """Complex response of a SISO system, shape (n_w,)."""
        return self(w)[0, 0]
