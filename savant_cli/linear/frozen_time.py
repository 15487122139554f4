"""Where frozen-time margins stop meaning anything: the first-stage tail-off window,
judged on physics (issue 26 item 6; docs/requirements.md, *The tail-off window*).

A frozen-time stability margin describes the loop of the plant frozen at one instant. It
says something about the flight only while that plant lasts long enough for the loop to
act on it, and changes slowly enough over one loop period. Near first-stage separation
neither holds. Two criteria, each evaluated on a scan of operating points over the last
``study.frozen_time.scan_s`` seconds before the flown separation:

``period``
    The loop's slowest rigid-body gain crossover (pitch or yaw) has a period
    ``T_c = 1 / f_c`` at least as long as the time left to separation,
    ``T_c ≥ t_sep − t``: the plant the margin describes ends before the loop completes one
    oscillation. (No rigid crossover at all: the margin describes no oscillation: fails.)
``control_power``
    The control power ``μc = |∂q̇/∂δ|`` (the plant's pitch or yaw angular acceleration per
    radian of gimbal, the smaller of the two, from the linearization) falls over one
    crossover period by at least the fraction the rigid gain margin requirement allows,
    ``1 − μc(t + T_c)/μc(t) ≥ 1 − 10^(−g/20)`` with ``g = requirements.rigid.gain_dB``
    (6 dB: half): within one oscillation the plant itself uses up the gain margin the
    requirement asks for. Past separation the first stage's control power is zero, so
    this criterion fails wherever ``period`` does (it starts no later, to within a scan
    step) and earlier where the thrust tail-off is steep.

Neither threshold depends on a design: the first is one period, the second the
requirement set's own gain margin. Each criterion's window starts at the beginning of the
final stretch of scan points at which it fails (linear between the last passing and the
first failing point, on the criterion's margin) and ends at separation; the window is the
union of the configured criteria's, from the earliest start.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from savant_cli.linear.loops import LinearPoint
from savant_cli.linear.margins import MarginRow

#: The criteria, in the order they are reported.
CRITERIA = ("period", "control_power")


@dataclass(frozen=True)
class ScanPoint:
    """One operating point of the scan.

    Attributes
    ----------
    time_s : float
        Mission time (s).
    crossover_axes_hz : dict
        Axis (``pitch``, ``yaw``) → its lowest rigid-body gain-crossover frequency (Hz;
        NaN: none).
    control_power_1_s2 : float
        Smaller of the pitch and yaw control powers ``|∂q̇/∂δ|`` (1/s²).
    """

    time_s: float
    crossover_axes_hz: dict
    control_power_1_s2: float

    @property
    def crossover_hz(self) -> float:
        """The lowest rigid crossover of both axes (Hz; NaN: no crossover)."""
        f = [v for v in self.crossover_axes_hz.values() if v > 0.0]
        return min(f) if f else float("nan")

    @property
    def period_s(self) -> float:
        """Crossover period (s; infinite without a crossover)."""
        return 1.0 / self.crossover_hz if self.crossover_hz > 0.0 else float("inf")


def scan_point(point: LinearPoint, rows: list[MarginRow]) -> ScanPoint:
    """The :class:`ScanPoint` of an analysed operating point: its rigid phase-margin
    crossings (``kind == "phase"``, mode ``rigid``) and the continuous plant's
    ``∂q̇/∂δp`` and ``∂ṙ/∂δy`` (states ``q``, ``dp``, ``r``, ``dy``)."""
    crossings = {}
    for axis in ("pitch", "yaw"):
        f = [r.frequency_hz for r in rows
             if r.axis == axis and r.kind == "phase" and r.mode == "rigid" and r.frequency_hz > 0.0]
        crossings[axis] = min(f) if f else float("nan")
    sys = point.plant_continuous
    names = list(sys.state_labels)
    a = np.asarray(sys.A)
    mu = min(abs(a[names.index("q"), names.index("dp")]), abs(a[names.index("r"), names.index("dy")]))
    return ScanPoint(point.time_s, crossings, float(mu))


def gain_fall_limit(gain_dB: float) -> float:
    """The fall of the control power over one period that uses up a gain margin of
    ``gain_dB``: ``1 − 10^(−gain_dB/20)`` (6 dB: 0.499)."""
    return 1.0 - 10.0 ** (-gain_dB / 20.0)


def period_margins(points: list[ScanPoint], separation_s: float) -> np.ndarray:
    """Per point, ``(t_sep − t) − T_c`` (s): the criterion ``period`` fails at ≤ 0."""
    return np.array([(separation_s - p.time_s) - p.period_s for p in points])


def control_power_margins(points: list[ScanPoint], separation_s: float, limit: float) -> np.ndarray:
    """Per point, ``limit − (1 − μc(t + T_c)/μc(t))``: the criterion ``control_power``
    fails at ≤ 0. ``μc`` is linear between scan points and zero past separation."""
    t = np.array([p.time_s for p in points])
    mu = np.array([p.control_power_1_s2 for p in points])
    out = np.empty(t.size)
    for i, p in enumerate(points):
        later = p.time_s + p.period_s
        mu_later = 0.0 if later >= separation_s else float(np.interp(later, t, mu))
        fall = 1.0 - mu_later / mu[i] if mu[i] > 0.0 else 1.0
        out[i] = limit - fall
    return out


def failing_start(times: np.ndarray, margins: np.ndarray) -> float | None:
    """Start (s) of the final stretch of failing points (margin ≤ 0, NaN fails): linear
    between the last passing point and the first failing one; the first scan time when
    every point fails; None when the last point passes."""
    fails = ~(margins > 0.0)
    if not fails.size or not fails[-1]:
        return None
    passing = np.flatnonzero(~fails)
    if not passing.size:
        return float(times[0])
    i = int(passing[-1])  # margins[i] > 0 ≥ margins[i + 1]
    m0, m1 = float(margins[i]), float(margins[i + 1])
    if not np.isfinite(m1):
        return float(times[i + 1])
    return float(times[i] + (times[i + 1] - times[i]) * m0 / (m0 - m1))


@dataclass
class FrozenTimeWindow:
    """The tail-off window of one flight: where frozen-time margins are not judged.

    Attributes
    ----------
    separation_s : float
        The flown separation (s): the window's end.
    starts : dict
        Criterion → its window start (s; None: it holds at every scan point).
    criteria : tuple of str
        The criteria that set the window (``study.frozen_time.criteria``).
    gain_fall_limit : float
        The ``control_power`` threshold (fraction).
    points : list of ScanPoint
        The scan.
    """

    separation_s: float
    starts: dict[str, float | None]
    criteria: tuple[str, ...]
    gain_fall_limit: float
    points: list[ScanPoint] = field(default_factory=list)

    @property
    def start_s(self) -> float | None:
        """The earliest start of the configured criteria (None: no window)."""
        s = [self.starts[c] for c in self.criteria if self.starts.get(c) is not None]
        return min(s) if s else None

    @property
    def bounds(self) -> tuple[float, float] | None:
        """``(start, separation)`` in s, or None."""
        return None if self.start_s is None else (self.start_s, self.separation_s)

    def contains(self, t: float) -> bool:
        return self.start_s is not None and self.start_s <= t < self.separation_s

    def describe(self) -> str:
        """E.g. ``"first-stage tail-off 123.05-130.47 s (frozen-time criteria: crossover
        period >= time to separation from 123.05 s; control power falls >= 49.9 % in one
        period from 124.10 s)"``."""
        parts = []
        for c in CRITERIA:
            text = {"period": "crossover period ≥ time to separation",
                    "control_power": f"control power falls ≥ {100 * self.gain_fall_limit:.1f} % in one period"}[c]
            start = self.starts.get(c)
            used = "" if c in self.criteria else " (not used)"
            parts.append(f"{text} from {start:.2f} s{used}" if start is not None else f"{text}: never{used}")
        head = (f"first-stage tail-off {self.start_s:.2f}-{self.separation_s:.2f} s" if self.start_s is not None
                else "no first-stage tail-off window")
        return f"{head} (frozen-time criteria: {'; '.join(parts)})"

    def as_dict(self) -> dict[str, Any]:
        return {"start_s": self.start_s, "end_s": self.separation_s, "criteria": list(self.criteria),
                "starts": dict(self.starts), "gain_fall_limit": self.gain_fall_limit, "line": self.describe(),
                "scan": [{"time_s": p.time_s, "crossover_pitch_hz": p.crossover_axes_hz.get("pitch"),
                          "crossover_yaw_hz": p.crossover_axes_hz.get("yaw"), "period_s": p.period_s,
                          "control_power_1_s2": p.control_power_1_s2} for p in self.points]}

    def crossover_at_start(self) -> dict[str, float]:
        """Each axis's rigid crossover (Hz) at the scan point nearest the window's start."""
        if self.start_s is None or not self.points:
            return {}
        p = min(self.points, key=lambda q: abs(q.time_s - self.start_s))
        return dict(p.crossover_axes_hz)


def window(points: list[ScanPoint], separation_s: float, criteria: tuple[str, ...], gain_dB: float) -> FrozenTimeWindow:
    """The :class:`FrozenTimeWindow` of a scan (points in time order, all before
    ``separation_s``)."""
    limit = gain_fall_limit(gain_dB)
    if not points:
        return FrozenTimeWindow(separation_s, dict.fromkeys(CRITERIA), tuple(criteria), limit, [])
    t = np.array([p.time_s for p in points])
    starts = {"period": failing_start(t, period_margins(points, separation_s)),
              "control_power": failing_start(t, control_power_margins(points, separation_s, limit))}
    return FrozenTimeWindow(separation_s, starts, tuple(criteria), limit, list(points))
