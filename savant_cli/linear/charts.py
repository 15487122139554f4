"""The data behind the linear study's charts: frequency responses, root loci, pole-zero
maps and closed-loop time responses of one operating point, as plain data objects (the
way python-control's ``*_response()`` functions return data, not drawings).

:func:`point_charts` computes everything the six charts of an operating point draw;
:mod:`savant_cli.linear.store` writes it into ``savant.h5`` (``linear/<point>/charts``)
and reads it back, and :mod:`savant_cli.plots.linear` only draws it. Every control
computation is python-control's: frequency responses (:func:`control.frequency_response`),
poles and zeros (``sys.poles()``, ``sys.zeros()``), closed loops (:func:`control.feedback`)
and time responses (:func:`control.step_response`, :func:`control.impulse_response`,
:func:`control.forced_response`).

Conventions
-----------
*Open loop.* ``L`` is the SISO loop broken at one axis's actuator command with the other
axis closed; the closed loop is ``L / (1 + L)`` (negative unity feedback), so the critical
point is L = −1: 0 dB and −180° (mod 360°).

*Frequency grid.* From :data:`F_MIN_HZ` to the Nyquist frequency ``1 / (2 dt)`` (25 Hz at
50 Hz; :data:`F_MAX_CONTINUOUS_HZ` for a continuous loop): :data:`N_FREQUENCIES` log-spaced
points, plus :data:`N_RESONANCE` points spread over ±8 half-power half-widths around the
damped frequency of every pole and zero of L with damping ratio below
:data:`RESONANCE_DAMPING` (a 0.5 % damped flex mode is 1 % wide; the log grid alone is
0.4 % per point), plus the exact frequencies of the margin table, so the markers sit on
the curves.

*Phase.* The phase is unwrapped along the grid (continuous curve, no ±180° jumps), then
shifted by a whole number of turns so that at the lowest-frequency gain crossover
(|L| = 0 dB, the rigid-body crossover; the lowest grid frequency when |L| never crosses
0 dB) it lies in (−360°, 0°]. The rigid-body phase margin is then the distance to the
critical point drawn at −180°.

*Root locus.* The closed-loop poles for each gain k are ``control.feedback(L, k).poles()``
(eigenvalues of the state-space closed loop L / (1 + k L)), joined into branches by
nearest assignment between successive gains. :func:`control.root_locus_map` is not used:
it roots the transfer-function polynomial of L, whose coefficients cannot represent the
20–80 poles clustered near z = 1 of a 50-Hz loop: for k = 1 it put closed-loop poles at
|z| = 2.1 on a 58-state test loop whose eigenvalues are all inside |z| < 0.9997, and at
|z| = 2.6 on the study's 85-state loops (eigenvalues within |z| ≤ 1 + 5e-6), with or
without slycot. A loop whose closed-loop poles equal another's at the first and last
gain shares its locus.

*Pole-zero map.* The zeros are the transmission zeros of the square block commands →
attitudes.

*Time responses.* Commands in rad and outputs in rad (the system is linear, so also deg
per deg). The discrete impulse is python-control's unit-area pulse (one sample of 1/dt);
the ramp is u = t. Only the command inputs and the attitude and gimbal outputs are
simulated (not the gust inputs).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import control as ct
import numpy as np
from scipy.optimize import linear_sum_assignment

from savant_cli.linear.margins import MarginRow

#: Lowest frequency of a chart's grid (Hz).
F_MIN_HZ = 0.01
#: Highest frequency of a continuous-time loop (Hz); a discrete loop stops at 1/(2 dt).
F_MAX_CONTINUOUS_HZ = 25.0
#: Log-spaced points of the base frequency grid.
N_FREQUENCIES = 600
#: Extra points around each lightly damped pole or zero of the loop.
N_RESONANCE = 31
#: Poles and zeros with a damping ratio below this get the extra points.
RESONANCE_DAMPING = 0.1
#: Gains k of the root locus 1 + k L = 0 (k = 1 is the nominal loop and is always included).
ROOT_LOCUS_GAINS = np.unique(np.concatenate([np.logspace(-2.0, 1.0, 25), [1.0]]))
#: Duration of the closed-loop time responses (s).
RESPONSE_DURATION_S = 10.0

AXIS_ORDER = ("pitch", "yaw", "roll")
#: Names of the closed loop's command inputs and of the outputs the responses keep.
COMMAND_INPUTS = ("pitch_command", "yaw_command", "roll_command")
RESPONSE_SUFFIXES = ("_attitude", "_gimbal")


@dataclass(frozen=True)
class LoopResponse:
    """Frequency response of one open loop on its chart grid.

    Attributes
    ----------
    label : str
        The loop's name: its axis (``"pitch"``, ``"yaw"``) or, in a parameter study, the
        variant's legend label.
    f_hz : numpy.ndarray
        Frequencies (Hz), increasing.
    response : numpy.ndarray
        Complex L(e^{jωT}) (–).
    mag_db : numpy.ndarray
        20 log10 |L| (dB).
    phase_deg : numpy.ndarray
        ∠L (deg), unwrapped and shifted (module notes, *Phase*).
    """

    label: str
    f_hz: np.ndarray
    response: np.ndarray
    mag_db: np.ndarray
    phase_deg: np.ndarray

    @property
    def axis(self) -> str:
        return self.label


@dataclass(frozen=True)
class RootLocus:
    """Closed-loop poles of 1 + k L = 0 of one loop over the gains.

    Attributes
    ----------
    label : str
        The loop's axis.
    gains : numpy.ndarray
        Loop gains k (–), increasing; 1 is among them.
    branches : numpy.ndarray
        Complex closed-loop poles, shape (gains, states); each column is one continuous
        branch (z-plane for a discrete loop, 1/s for a continuous one).
    poles, zeros : numpy.ndarray
        Open-loop poles and zeros of L.
    dt : float or None
        Sample time of L (s); None for a continuous loop.
    """

    label: str
    gains: np.ndarray
    branches: np.ndarray
    poles: np.ndarray
    zeros: np.ndarray
    dt: float | None

    @property
    def nominal(self) -> np.ndarray:
        """The closed-loop poles at k = 1."""
        return self.branches[int(np.argmin(np.abs(self.gains - 1.0)))]


@dataclass(frozen=True)
class PoleZeroMap:
    """Poles and zeros of the closed loop.

    Attributes
    ----------
    poles : numpy.ndarray
        Closed-loop poles (z-plane when ``dt``, else s-plane in 1/s).
    zeros : numpy.ndarray
        Transmission zeros of commands → attitudes (finite ones).
    dt : float or None
        Sample time (s); None for a continuous system.
    """

    poles: np.ndarray
    zeros: np.ndarray
    dt: float | None

    @property
    def s_poles(self) -> np.ndarray:
        """Equivalent s-plane poles ln(z)/dt (1/s); NaN for poles at z = 0."""
        return s_plane(self.poles, self.dt)

    @property
    def s_zeros(self) -> np.ndarray:
        return s_plane(self.zeros, self.dt)


@dataclass(frozen=True)
class CommandResponses:
    """Closed-loop step, impulse and ramp responses to each attitude command.

    Attributes
    ----------
    time_s : numpy.ndarray
        Time after the command (s).
    commands : tuple of str
        Input names (``pitch_command``, ``yaw_command``; rad).
    outputs : tuple of str
        Output names (``pitch_attitude``, ``pitch_gimbal`` …; rad).
    step, impulse, ramp : numpy.ndarray
        Responses, shape (outputs, commands, time): to a unit step (rad per rad), a
        unit-area pulse (rad per rad·s) and a unit ramp u = t (rad per rad/s).
    """

    time_s: np.ndarray
    commands: tuple[str, ...]
    outputs: tuple[str, ...]
    step: np.ndarray
    impulse: np.ndarray
    ramp: np.ndarray

    def of(self, kind: str) -> np.ndarray:
        """The ``"step"``, ``"impulse"`` or ``"ramp"`` responses."""
        return {"step": self.step, "impulse": self.impulse, "ramp": self.ramp}[kind]


@dataclass(frozen=True)
class PointCharts:
    """Everything the six charts of one operating point draw.

    Attributes
    ----------
    time_s : float
        Flight time of the point (s).
    loops : tuple of LoopResponse
        Open-loop frequency responses, pitch first.
    root_loci : tuple of RootLocus
        Root locus of each loop, same order.
    pzmap : PoleZeroMap
        Closed-loop poles and zeros.
    responses : CommandResponses
        Closed-loop time responses to the attitude commands.
    """

    time_s: float
    loops: tuple[LoopResponse, ...]
    root_loci: tuple[RootLocus, ...]
    pzmap: PoleZeroMap
    responses: CommandResponses


def sorted_axes(names: Iterable[str]) -> list[str]:
    """Pitch, yaw, then any other names alphabetically."""
    names = list(names)
    return [a for a in AXIS_ORDER if a in names] + sorted(a for a in names if a not in AXIS_ORDER)


def sample_time(sys: ct.LTI) -> float | None:
    """dt of a discrete system with a numeric sample time, else None."""
    dt = sys.dt
    if dt is None or dt is True or dt is False or not sys.isdtime():
        return None
    return float(dt)


def s_plane(roots: np.ndarray, dt: float | None) -> np.ndarray:
    """Equivalent s-plane roots ln(z)/dt (1/s) of z-plane roots; roots at z = 0 become NaN.
    Continuous roots (``dt`` None) are returned as they are."""
    roots = np.asarray(roots, dtype=complex)
    if dt is None:
        return roots
    out = np.full(roots.shape, np.nan + 0j)
    ok = np.isfinite(roots) & (np.abs(roots) > 1e-6)
    out[ok] = np.log(roots[ok]) / dt
    return out


def chart_frequency_grid(sys: ct.LTI, extra_hz: Iterable[float] = ()) -> np.ndarray:
    """Log grid from :data:`F_MIN_HZ` to the Nyquist frequency, refined at resonances and
    holding ``extra_hz`` exactly (Hz)."""
    dt = sample_time(sys)
    f_hi = 0.5 / dt if dt else F_MAX_CONTINUOUS_HZ
    parts = [np.geomspace(F_MIN_HZ, f_hi, N_FREQUENCIES)]
    s = s_plane(np.concatenate([sys.poles(), sys.zeros()]), dt)
    s = s[np.isfinite(s) & (s.imag > 0)]  # one of each conjugate pair
    wn = np.abs(s)
    zeta = -s.real / np.maximum(wn, 1e-300)
    light = np.abs(zeta) < RESONANCE_DAMPING
    # u = tan(θ/2) spacing: equal steps of the angle θ around the resonance circle that the
    # mode draws in the Nyquist plane, out to ±8 half-widths (ζ f_n) on either side
    u = np.tan(np.linspace(-np.arctan(8.0), np.arctan(8.0), N_RESONANCE))
    for w, z, wd in zip(wn[light], zeta[light], s.imag[light]):
        fd, half = wd / (2 * np.pi), max(abs(z), 1e-4) * w / (2 * np.pi)
        parts.append(fd + half * u)
    parts.append(np.asarray([f for f in extra_hz if np.isfinite(f)], dtype=float))
    f = np.concatenate(parts)
    f = np.clip(f, F_MIN_HZ, f_hi)
    return np.unique(f)


def _require_siso(label: str, sys: ct.LTI) -> None:
    if not sys.issiso():
        raise ValueError(f"loop {label!r} must be SISO, got {sys.ninputs} inputs and {sys.noutputs} outputs")


def loop_response(label: str, sys: ct.LTI, margin_frequencies_hz: Iterable[float] = ()) -> LoopResponse:
    """Frequency response of a SISO open loop on its chart grid (module notes).

    Parameters
    ----------
    label : str
        The loop's name (its axis, or a variant's legend label).
    sys : control.LTI
        SISO open loop, negative-feedback convention (closed loop L / (1 + L)).
    margin_frequencies_hz : iterable of float
        Frequencies (Hz) to hold exactly on the grid: the loop's margin crossings.

    Raises
    ------
    ValueError
        If ``sys`` is not SISO.
    """
    _require_siso(label, sys)
    f = chart_frequency_grid(sys, margin_frequencies_hz)
    resp = ct.frequency_response(sys, 2 * np.pi * f)
    f = np.asarray(resp.omega, dtype=float) / (2 * np.pi)
    h = np.asarray(resp.complex, dtype=complex).reshape(-1)
    with np.errstate(divide="ignore"):
        mag_db = 20.0 * np.log10(np.abs(h))
    phase = np.degrees(np.unwrap(np.angle(h)))
    sign = np.signbit(mag_db)
    cross = np.flatnonzero(sign[1:] != sign[:-1])
    anchor = int(cross[0]) if cross.size else 0
    # the whole number of turns putting the anchor phase in (−360°, 0°]
    phase = phase - 360.0 * math.ceil(phase[anchor] / 360.0)
    return LoopResponse(label, f, h, mag_db, phase)


def _locus_branches(sys: ct.LTI, gains: np.ndarray) -> np.ndarray:
    """Closed-loop poles of 1 + k L = 0, shape (gains, n), columns continuous branches."""
    loci = np.empty((len(gains), sys.nstates), dtype=complex)
    for i, k in enumerate(gains):
        # feedback(L, k) = L / (1 + k L): the poles of 1 + k L, without building k L
        p = np.asarray(ct.feedback(sys, float(k)).poles(), dtype=complex)
        if i == 0:
            loci[0] = np.sort_complex(p)
            continue
        prev = loci[i - 1]
        _, col = linear_sum_assignment(np.abs(prev[:, None] - p[None, :]))
        loci[i] = p[col]
    return loci


def same_poles(a: np.ndarray, b: np.ndarray, tol: float = 1e-4) -> bool:
    """Whether two sets of poles are equal to ``tol`` (relative to max(1, |p|)): to drawing
    accuracy (the zoom of the root-locus chart is 0.22 wide), and loose enough for the
    eigenvalue error of the clustered poles near z = 1 (ε^(1/m) for an m-fold cluster,
    about 3e-5 on the study's 85-state loops)."""
    if a.shape != b.shape or not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        return False
    cost = np.abs(a[:, None] - b[None, :])
    rows, cols = linear_sum_assignment(cost)
    return bool(np.all(cost[rows, cols] <= tol * np.maximum(1.0, np.abs(a[rows]))))


def _shared_branches(sys: ct.LTI, known: Sequence[np.ndarray], gains: np.ndarray) -> np.ndarray | None:
    """A root locus of ``known`` that is also that of ``sys``, if any.

    For a SISO loop the closed-loop characteristic polynomial is den(z) + k num(z) (up to a
    factor when D ≠ 0), fixed by its roots at two gains: loops whose closed-loop poles
    agree at the first and last gain have the same locus at every gain, to the accuracy
    of :func:`same_poles` (the pitch and yaw loops of an axisymmetric vehicle). Two
    eigenvalue problems instead of one per gain.
    """
    if not known:
        return None
    ends = [np.asarray(ct.feedback(sys, float(k)).poles(), dtype=complex) for k in (gains[0], gains[-1])]
    for loci in known:
        if loci.shape[1] == sys.nstates and same_poles(ends[0], loci[0]) and same_poles(ends[1], loci[-1]):
            return loci
    return None


def root_loci(loops: Mapping[str, ct.LTI], gains: np.ndarray = ROOT_LOCUS_GAINS) -> tuple[RootLocus, ...]:
    """Root loci of 1 + k L = 0 of every loop (pitch first); loops with the same locus
    share one computation (module notes, *Root locus*)."""
    gains = np.asarray(gains, dtype=float)
    out, computed = [], []
    for name in sorted_axes(loops):
        sys = loops[name]
        _require_siso(name, sys)
        branches = _shared_branches(sys, computed, gains)
        if branches is None:
            branches = _locus_branches(sys, gains)
            computed.append(branches)
        out.append(RootLocus(name, gains, branches, np.asarray(sys.poles(), dtype=complex),
                             np.asarray(sys.zeros(), dtype=complex), sample_time(sys)))
    return tuple(out)


def _commands(closed: ct.LTI) -> list[str]:
    found = [c for c in COMMAND_INPUTS if c in closed.input_labels]
    return found or list(closed.input_labels)


def _transmission_zeros(closed: ct.StateSpace, outputs: Sequence[str], inputs: Sequence[str]) -> np.ndarray:
    """Transmission zeros of the square block commands → attitudes (python-control without
    slycot computes zeros of square systems only), else of the whole system."""
    oi = [k for k in (closed.find_output(o) for o in outputs) if k is not None]
    ii = [k for k in (closed.find_input(i) for i in inputs) if k is not None]
    systems = [closed[oi, ii]] if oi and len(oi) == len(ii) else []
    for sys in systems + [closed]:
        try:
            z = np.asarray(sys.zeros(), dtype=complex)
        except (NotImplementedError, ValueError, np.linalg.LinAlgError):
            continue
        return z[np.isfinite(z)]
    return np.zeros(0, dtype=complex)


def pole_zero_map(closed: ct.StateSpace) -> PoleZeroMap:
    """Closed-loop poles and the zeros of commands → attitudes."""
    commands = _commands(closed)
    zeros = _transmission_zeros(closed, [c.replace("_command", "_attitude") for c in commands], commands)
    return PoleZeroMap(np.asarray(closed.poles(), dtype=complex), zeros, sample_time(closed))


def command_responses(closed: ct.StateSpace, duration_s: float = RESPONSE_DURATION_S) -> CommandResponses:
    """Step, impulse and ramp responses of the attitude and gimbal outputs to each command.

    Parameters
    ----------
    closed : control.StateSpace
        Closed loop with inputs ``pitch_command``, ``yaw_command`` (rad) and outputs
        including ``<axis>_attitude`` and ``<axis>_gimbal`` (rad). Without such names, every
        input and output is kept.
    duration_s : float
        Length of the responses (s); sampled at the system's dt (1000 points when
        continuous).
    """
    dt = sample_time(closed)
    h = dt or duration_s / 1000.0
    t = np.arange(0.0, duration_s + 0.5 * h, h)
    commands = _commands(closed)
    outputs = [o for o in closed.output_labels if o.endswith(RESPONSE_SUFFIXES)] or list(closed.output_labels)
    sub = closed[[closed.find_output(o) for o in outputs], [closed.find_input(c) for c in commands]]
    shape = (sub.noutputs, sub.ninputs, t.size)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        step = np.asarray(ct.step_response(sub, t).outputs).reshape(shape)
        impulse = np.asarray(ct.impulse_response(sub, t).outputs).reshape(shape)
        ramp = np.zeros(shape)
        for i in range(sub.ninputs):
            u = np.zeros((sub.ninputs, t.size))
            u[i] = t
            ramp[:, i, :] = np.asarray(ct.forced_response(sub, t, u).outputs).reshape(shape[0], -1)
    return CommandResponses(t, tuple(commands), tuple(outputs), step, impulse, ramp)


def point_charts(time_s: float, loops: Mapping[str, ct.LTI], closed: ct.StateSpace,
                 margins: Sequence[MarginRow]) -> PointCharts:
    """The data of the six charts of one operating point.

    Parameters
    ----------
    time_s : float
        Flight time of the point (s).
    loops : mapping of str to control.LTI
        SISO open loop of each axis, broken at that axis's actuator command (rad → rad)
        with the other axis closed, negative-feedback convention.
    closed : control.StateSpace
        Closed loop, inputs ``<axis>_command`` and outputs ``<axis>_attitude``,
        ``<axis>_gimbal`` (rad).
    margins : sequence of MarginRow
        The point's margins: their frequencies are held exactly on each loop's grid.

    Raises
    ------
    ValueError
        If ``loops`` is empty or a loop is not SISO.
    """
    if not loops:
        raise ValueError("the charts of a point need at least one loop")
    names = sorted_axes(loops)
    for a in names:
        _require_siso(a, loops[a])
    responses = tuple(loop_response(a, loops[a], (r.frequency_hz for r in margins if r.axis == a)) for a in names)
    return PointCharts(float(time_s), responses, root_loci({a: loops[a] for a in names}), pole_zero_map(closed),
                       command_responses(closed))
