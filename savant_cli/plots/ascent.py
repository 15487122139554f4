"""Ascent time-history figures of one run (the analogues of the paper's Figures 8–14).

Figures are drawn with matplotlib's object-oriented API on the Agg canvas
(``matplotlib.figure.Figure`` + ``FigureCanvasAgg``): no pyplot, no GUI backend, no
global state, so plotting works headless and never changes the backend of a caller's
interactive session. Each figure is made and written through the drawing base,
:mod:`savant_cli.plots.figure` (a 120-dpi PNG, written atomically).

Figures (file, paper figure, signals):

- ``body_rates.png`` (Fig. 8): ``body_rate`` in deg/s, roll/pitch/yaw
- ``alpha_beta.png`` (Fig. 9): ``alpha``, ``beta`` in deg, and the load indicators q·α (pitch
  plane, signed), q·β and the total q·α_total in kPa·deg (derived from ``dynamic_pressure``,
  ``alpha`` and ``beta``; cos α_total = cos α cos β)
- ``attitude_tracking.png`` (Fig. 10): ``attitude_euler`` vs ``attitude_euler_command`` (dashed)
- ``velocity_dynamic_pressure.png`` (Fig. 11): ``velocity_relative`` (m/s), ``dynamic_pressure`` (kPa)
- ``altitude_mach.png`` (Fig. 12): ``altitude`` (km), ``mach``
- ``gimbal_angles.png`` (Fig. 13): ``gimbal_angle`` vs ``gimbal_command`` (dashed), deg
- ``attitude_errors.png`` (Fig. 14): ``attitude_error`` in deg

Drawn when the model is on:

- ``flex_modes.png`` (flex): ``flex_q`` and ``flex_qdot`` of up to 8 modes
- ``gyro_rates.png`` (flex): pitch and yaw ``sensed_rate`` of each gyro vs the rigid ``body_rate``
- ``slosh.png`` (slosh): ``slosh_position`` per tank and ``slosh_frequency``
- ``guidance.png`` (closed-loop guidance): ``peg_time_to_go``,
  ``peg_velocity_to_go_magnitude``, ``peg_steering_angles`` and ``peg_converged``
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from savant_cli.io.record import RunRecord, Signal
from savant_cli.plots.figure import new_figure, save_figure

_WIDTH_IN = 8.0
#: Most points drawn per line; longer signals are strided.
MAX_POINTS = 5000

#: Display names of events on the plots; other events show their own name.
EVENT_LABELS = {
    "separation": "separation",
    "upper_stage_ignition": "ignition",
    "ignition": "ignition",
    "les_jettison": "LES jettison",
    "cutoff": "cutoff",
    "upper_stage_cutoff": "first cutoff",
    "upper_stage_restart": "restart",
}

#: (unit of a signal, unit to plot in) → scale factor.
_CONVERSIONS = {
    ("rad", "deg"): 180.0 / np.pi,
    ("rad/s", "deg/s"): 180.0 / np.pi,
    ("m", "km"): 1e-3,
    ("Pa", "kPa"): 1e-3,
    ("Pa*deg", "kPa*deg"): 1e-3,
    ("1", ""): 1.0,
    ("Hz", "Hz"): 1.0,
}


@dataclass(frozen=True)
class Line:
    """One curve: a column of a signal, converted to ``unit``."""

    signal: str
    column: int | None
    label: str
    dashed: bool = False


@dataclass(frozen=True)
class Panel:
    """One axes: a quantity with its unit; its first line's signal must be present."""

    quantity: str
    unit: str
    lines: tuple[Line, ...]
    wrap_degrees: bool = False  # angles: unwrap ±180° jumps for drawing


@dataclass(frozen=True)
class FigureSpec:
    """One PNG file."""

    filename: str
    title: str
    panels: tuple[Panel, ...]
    requires: str | None = None  # drawn only when this signal is in the run
    #: the panels of a run, for a figure whose panels follow the vehicle (one per tank);
    #: None: :attr:`panels`
    panels_of: Callable[[RunRecord], tuple[Panel, ...]] | None = None


def _rpy_panels(actual: str, command: str | None, unit: str, what: str, wrap: bool = False) -> tuple[Panel, ...]:
    panels = []
    for i, axis in enumerate(("roll", "pitch", "yaw")):
        lines = [Line(actual, i, f"{axis}" if command is None else f"{axis} actual")]
        if command is not None:
            lines.append(Line(command, i, f"{axis} commanded", dashed=True))
        panels.append(Panel(f"{axis} {what}", unit, tuple(lines), wrap_degrees=wrap))
    return tuple(panels)


def _slosh_panels(record: RunRecord) -> tuple[Panel, ...]:
    """A panel per sloshing tank (its mass's displacement, the columns ``<tank>_y``,
    ``<tank>_z`` of ``slosh_position``), then every tank's slosh frequency."""
    tanks = record.signals["slosh_frequency"].columns
    return tuple(Panel(f"{tank.upper()} slosh mass", "m", (Line("slosh_position", 2 * j, "y"),
                                                           Line("slosh_position", 2 * j + 1, "z")))
                 for j, tank in enumerate(tanks)) + (
        Panel("slosh frequency", "Hz",
              tuple(Line("slosh_frequency", j, tank.upper()) for j, tank in enumerate(tanks))),)


#: The seven ascent figures, in the paper's order.
FIGURES: tuple[FigureSpec, ...] = (
    FigureSpec("body_rates.png", "Body angular rates (cf. Fig. 8)",
               _rpy_panels("body_rate", None, "deg/s", "rate")),
    FigureSpec("alpha_beta.png", "Angle of attack and sideslip (cf. Fig. 9)", (
        Panel("angle of attack α", "deg", (Line("alpha", None, "α"),)),
        Panel("sideslip β", "deg", (Line("beta", None, "β"),)),
        Panel("load indicator", "kPa*deg", (Line("q_alpha_total", None, "q·α total"), Line("q_alpha", None, "q·α"),
                                             Line("q_beta", None, "q·β"))),
    )),
    FigureSpec("attitude_tracking.png", "Attitude command tracking, 3-2-1 Euler angles (cf. Fig. 10)",
               _rpy_panels("attitude_euler", "attitude_euler_command", "deg", "angle", wrap=True)),
    FigureSpec("velocity_dynamic_pressure.png", "Relative velocity and dynamic pressure (cf. Fig. 11)", (
        Panel("air-relative velocity", "m/s", (Line("velocity_relative", None, "velocity"),)),
        Panel("dynamic pressure", "kPa", (Line("dynamic_pressure", None, "q̄"),)),
    )),
    FigureSpec("altitude_mach.png", "Altitude and Mach number (cf. Fig. 12)", (
        Panel("altitude", "km", (Line("altitude", None, "altitude"),)),
        Panel("Mach number", "", (Line("mach", None, "Mach"),)),
    )),
    FigureSpec("gimbal_angles.png", "Pitch and yaw gimbal angles (cf. Fig. 13)", (
        Panel("pitch gimbal δp", "deg", (Line("gimbal_angle", 0, "pitch actual"),
                                          Line("gimbal_command", 0, "pitch commanded", dashed=True))),
        Panel("yaw gimbal δy", "deg", (Line("gimbal_angle", 1, "yaw actual"),
                                        Line("gimbal_command", 1, "yaw commanded", dashed=True))),
    )),
    FigureSpec("attitude_errors.png", "Attitude errors (cf. Fig. 14)",
               _rpy_panels("attitude_error", None, "deg", "error")),
    FigureSpec("flex_modes.png", "Flexible-body modal coordinates", (
        Panel("modal displacement q", "kg^0.5*m", tuple(Line("flex_q", i, f"mode {i + 1}") for i in range(8))),
        Panel("modal velocity q̇", "kg^0.5*m/s", tuple(Line("flex_qdot", i, f"mode {i + 1}") for i in range(8))),
    ), requires="flex_q"),
    FigureSpec("gyro_rates.png", "Sensed (rigid + flex) vs rigid body rate at each gyro", tuple(
        Panel(f"{axis} rate", "deg/s", (Line("body_rate", k, "rigid"),
                                        Line("sensed_rate", 3 * g + k, f"{name} gyro")))
        for k, axis in ((1, "pitch"), (2, "yaw"))
        for g, name in ((0, "upper-stage"), (1, "IMU"), (2, "first-stage"))
    ), requires="flex_q"),
    FigureSpec("slosh.png", "Propellant slosh", (), requires="slosh_frequency", panels_of=_slosh_panels),
    FigureSpec("guidance.png", "Powered Explicit Guidance", (
        Panel("time to go", "s", (Line("peg_time_to_go", None, "t_go"),)),
        Panel("velocity to go", "m/s", (Line("peg_velocity_to_go_magnitude", None, "|v_go|"),)),
        Panel("thrust direction", "deg", (Line("peg_steering_angles", 0, "elevation above horizontal"),
                                          Line("peg_steering_angles", 1, "out of the target plane"))),
        Panel("converged", "", (Line("peg_converged", None, "converged"), Line("peg_active", None, "engaged",
                                                                              dashed=True))),
    ), requires="peg_time_to_go"),
)


def _convert(sig: Signal, unit: str) -> tuple[float, str]:
    """Scale factor from the signal's units to ``unit``, and the unit label to show."""
    if sig.units == unit:
        return 1.0, unit
    factor = _CONVERSIONS.get((sig.units, unit))
    if factor is None:  # unknown pairing: plot as stored, say so on the axis
        return 1.0, sig.units
    return factor, unit


def _column(sig: Signal, column: int | None) -> np.ndarray | None:
    data = np.asarray(sig.data)
    if column is None:
        return data if data.ndim == 1 else None
    if data.ndim != 2 or data.shape[1] <= column:
        return None
    return data[:, column]


def _stride(n: int) -> slice:
    step = max(1, -(-n // MAX_POINTS))
    return slice(None, None, step)


def _indices(n: int) -> np.ndarray:
    """Strided sample indices, always including the last sample."""
    idx = np.arange(n)[_stride(n)]
    if n and idx[-1] != n - 1:
        idx = np.append(idx, n - 1)
    return idx


def _wrap_deg(x: np.ndarray) -> np.ndarray:
    return (x + 180.0) % 360.0 - 180.0


def _event_groups(events: list[tuple[str, float]], t0: float, t1: float) -> list[tuple[float, str]]:
    """Events inside [t0, t1] as (time, label); events closer than 1.5 % of the span share
    one label ("separation / ignition")."""
    inside = sorted((float(t), EVENT_LABELS.get(name, name)) for name, t in events
                    if np.isfinite(t) and t0 <= t <= t1)
    gap = 0.015 * max(t1 - t0, 1e-9)
    groups: list[tuple[float, str]] = []
    for t, label in inside:
        if groups and t - groups[-1][0] < gap:
            groups[-1] = (groups[-1][0], f"{groups[-1][1]} / {label}")
        else:
            groups.append((t, label))
    return groups


def _event_lines(ax, events: list[tuple[str, float]], t0: float, t1: float, label: bool) -> None:
    for name, t in events:
        if np.isfinite(t) and t0 <= t <= t1:
            ax.axvline(t, color="0.45", lw=0.7, ls=":", zorder=1)
    if label:
        for t, text in _event_groups(events, t0, t1):
            ax.text(t, 0.97, text, transform=ax.get_xaxis_transform(), rotation=90, fontsize=7,
                    color="0.3", ha="right", va="top",
                    bbox={"facecolor": "white", "alpha": 0.75, "edgecolor": "none", "pad": 1.0})


#: the signals :func:`load_signals` derives
LOAD_SIGNALS = ("q_alpha", "q_beta", "q_alpha_total")


def _panels(spec: FigureSpec, record: RunRecord) -> tuple[RunRecord, list[Panel]]:
    """The record (with the derived load signals when the figure draws them) and the
    panels of ``spec`` it has the signals for (none: the figure is not drawn)."""
    if spec.requires is not None and spec.requires not in record.signals:
        return record, []
    all_panels = spec.panels if spec.panels_of is None else spec.panels_of(record)
    if any(line.signal in LOAD_SIGNALS for p in all_panels for line in p.lines):
        derived = load_signals(record.signals)
        if derived:
            record = dataclasses.replace(record, signals={**record.signals, **derived})
    return record, [p for p in all_panels if p.lines[0].signal in record.signals
                    and _column(record.signals[p.lines[0].signal], p.lines[0].column) is not None]


def _draw(spec: FigureSpec, record: RunRecord, t: np.ndarray, idx: np.ndarray) -> Figure | None:
    record, panels = _panels(spec, record)
    if not panels:
        return None
    # fixed margins in inches instead of a layout engine (which would draw every figure
    # twice): the figure is 8 in wide, 1.75 in per panel
    clean = record.complete and record.status == "complete"
    top_in = 0.5 if clean else 0.72
    height = top_in + 0.55 + 1.75 * len(panels)
    fig = new_figure(_WIDTH_IN, height, left=0.95, right=0.25, bottom=0.55, top=top_in, hspace=0.15)
    axes = fig.subplots(len(panels), 1, sharex=True, squeeze=False)[:, 0]
    tt = t[idx]
    for k, (ax, panel) in enumerate(zip(axes, panels)):
        unit_label = panel.unit
        reference = None
        for j, line in enumerate(panel.lines):
            sig = record.signals.get(line.signal)
            col = None if sig is None else _column(sig, line.column)
            if col is None:
                continue
            factor, unit_label_j = _convert(sig, panel.unit)
            if j == 0:
                unit_label = unit_label_j
            y = col.astype(np.float64, copy=False) * factor
            if panel.wrap_degrees and unit_label_j == "deg":
                if reference is None:  # first line: remove ±180° jumps
                    y = np.degrees(np.unwrap(np.radians(y)))
                    reference = y
                else:  # later lines: the branch closest to the first line
                    y = reference + _wrap_deg(y - reference)
            ax.plot(tt, y[idx], lw=1.0, ls="--" if line.dashed else "-", color=f"C{j}", label=line.label)
        ax.set_ylabel(f"{panel.quantity} ({unit_label})" if unit_label else f"{panel.quantity} (–)", fontsize=9)
        ax.grid(True, lw=0.4, alpha=0.6)
        if len(ax.get_lines()) > 1:
            ax.legend(loc="best", fontsize=7, framealpha=0.8, ncol=2 if len(ax.get_lines()) > 4 else 1)
        _event_lines(ax, record.events, float(t[0]), float(t[-1]), label=(k == 0))
    axes[-1].set_xlabel("time from liftoff (s)")
    axes[-1].set_xlim(float(t[0]), float(t[-1]) if t[-1] > t[0] else float(t[0]) + 1.0)
    if clean:
        fig.suptitle(spec.title, fontsize=11, y=1.0 - 0.2 / height, va="top")
    else:  # a run that did not fly to its end, or flew to it unhealthy (limit cycle, saturated)
        msg = record.message if len(record.message) <= 90 else record.message[:87] + "..."
        verdict = "INCOMPLETE" if not record.complete else record.status.replace("_", " ").upper()
        fig.suptitle(f"{spec.title}\n{verdict}: {msg}", fontsize=11, color="red", y=1.0 - 0.15 / height, va="top")
    return fig


def load_signals(signals: dict[str, Signal]) -> dict[str, Signal]:
    """The derived load-indicator signals (Pa·deg) of a run's ``dynamic_pressure``,
    ``alpha`` and ``beta``: ``q_alpha`` = q·α and ``q_beta`` = q·β (signed, deg), and
    ``q_alpha_total`` = q·α_total with cos α_total = cos α cos β, as the run summary
    computes them (empty when a signal is missing)."""
    if not all(k in signals for k in ("dynamic_pressure", "alpha", "beta")):
        return {}
    q = np.asarray(signals["dynamic_pressure"].data, dtype=np.float64)
    a = np.asarray(signals["alpha"].data, dtype=np.float64)
    b = np.asarray(signals["beta"].data, dtype=np.float64)
    if q.ndim != 1 or a.shape != q.shape or b.shape != q.shape:
        return {}
    total = np.degrees(np.arccos(np.clip(np.cos(a) * np.cos(b), -1.0, 1.0)))
    return {"q_alpha": Signal(q * np.degrees(a), "Pa*deg", "dynamic pressure times angle of attack"),
            "q_beta": Signal(q * np.degrees(b), "Pa*deg", "dynamic pressure times sideslip"),
            "q_alpha_total": Signal(q * total, "Pa*deg", "dynamic pressure times total angle of attack")}


def _time_base(record: RunRecord | None) -> tuple[np.ndarray, np.ndarray] | None:
    time_sig = record.signals.get("time") if record is not None else None
    if time_sig is None or np.ndim(time_sig.data) != 1 or np.size(time_sig.data) == 0:
        return None
    t = np.asarray(time_sig.data, dtype=np.float64)
    return t, _indices(t.size)


def figure_names(record: RunRecord | None) -> list[str]:
    """The ascent figures a run has the signals for (file names without ``.png``)."""
    if _time_base(record) is None:
        return []
    return [spec.filename.removesuffix(".png") for spec in FIGURES if _panels(spec, record)[1]]


def figure(record: RunRecord, name: str) -> Figure:
    """One ascent figure of a run, by its file name without ``.png`` (``alpha_beta`` …),
    as a new matplotlib ``Figure`` (what ``savant_cli.Result.plot`` returns).

    Raises
    ------
    KeyError
        No such figure, or the run lacks its signals.
    """
    base = _time_base(record)
    spec = next((s for s in FIGURES if s.filename == f"{name}.png"), None)
    fig = _draw(spec, record, *base) if spec is not None and base is not None else None
    if fig is None:
        raise KeyError(f"no ascent figure {name!r} for this run; known: {', '.join(figure_names(record))}")
    return fig


def plot_ascent(record: RunRecord, out_dir: Path) -> list[Path]:
    """Draw the ascent figures of a run as PNG files.

    Parameters
    ----------
    record : RunRecord
        The run (from the simulation or :func:`savant_cli.io.hdf5.read_run`).
    out_dir : pathlib.Path
        Folder for the PNGs (created if missing), normally ``<run_dir>/plots``.

    Returns
    -------
    list of pathlib.Path
        The files written, in the order of :data:`FIGURES`. A figure whose signals are
        all missing is skipped silently; a panel whose signal is missing is left out.
        The figures are drawn by forked worker processes in parallel, one per core
        (serially where processes cannot fork): the same files either way.

    Notes
    -----
    Angles are drawn in degrees, rates in deg/s, altitude in km and dynamic pressure in
    kPa; events (separation, ignition, LES jettison, cutoff) are thin dotted vertical
    lines on every axes. Lines longer than :data:`MAX_POINTS` samples are strided. When
    ``record.complete`` is False every title carries ``INCOMPLETE: <message>`` in red; a
    run that flew to its end unhealthy carries its status (``LIMIT CYCLE: <message>``,
    ``SATURATED: <message>``).
    """
    out_dir = Path(out_dir)
    base = _time_base(record)
    if base is None:
        return []
    _JOB["args"] = (record, base, out_dir)
    try:
        workers = min(len(FIGURES), _draw_workers())
        if workers > 1:  # forked children inherit the record: nothing pickled but the paths back
            from concurrent.futures import ProcessPoolExecutor

            from savant_cli.processes import process_context, worker_initializer

            with ProcessPoolExecutor(workers, mp_context=process_context(), **worker_initializer()) as pool:
                drawn = list(pool.map(_draw_file, range(len(FIGURES))))
        else:
            drawn = [_draw_file(i) for i in range(len(FIGURES))]
    finally:
        _JOB.clear()
    return [path for path in drawn if path is not None]


#: The figures' job for :func:`_draw_file`, set by :func:`plot_ascent` (forked workers inherit it).
_JOB: dict = {}


def _draw_workers() -> int:
    """Processes that draw the figures at once: the cores, in a main process where
    ``fork`` is how processes start (a spawned worker would pay matplotlib's import and
    the record's pickling; a worker of a study's pool has the other cores busy); else one."""
    import multiprocessing

    from savant_cli.processes import default_workers, process_context

    if multiprocessing.parent_process() is not None or process_context().get_start_method() != "fork":
        return 1
    return default_workers()


def _draw_file(i: int) -> Path | None:
    """Draw figure ``FIGURES[i]`` of the job into its PNG; its path (None: nothing to draw)."""
    record, (t, idx), out_dir = _JOB["args"]
    spec = FIGURES[i]
    fig = _draw(spec, record, t, idx)
    if fig is None:
        return None
    return save_figure(fig, out_dir / spec.filename)
