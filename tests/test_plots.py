"""Ascent figures and ``savant report``."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from rich.console import Console

from savant_cli.io.hdf5 import write_run
from savant_cli.io.record import RunRecord, Signal
from savant_cli.plots import ascent
from savant_cli.plots.ascent import FIGURES, plot_ascent
from savant_cli.report import report

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
EXPECTED = {"body_rates.png", "alpha_beta.png", "attitude_tracking.png", "velocity_dynamic_pressure.png",
            "altitude_mach.png", "gimbal_angles.png", "attitude_errors.png"}
EVENTS = [("separation", 130.0), ("upper_stage_ignition", 131.0), ("les_jettison", 160.0), ("cutoff", 590.0)]


def ascent_record(n: int = 30_000, complete: bool = True, fidelity: bool = False) -> RunRecord:
    """All signals the seven figures use, shaped like a real ascent; with ``fidelity``
    also the flex, slosh and closed-loop guidance signals of their four figures."""
    rng = np.random.default_rng(3)
    t = np.linspace(0.0, 600.0, n)

    def walk(k: int, scale: float) -> np.ndarray:
        return np.cumsum(rng.normal(size=(n, k)), axis=0) * scale

    rpy = ("roll", "pitch", "yaw")
    euler_c = np.column_stack([np.radians(170.0) * np.minimum(t / 30.0, 1.0),
                               np.radians(90.0 - 80.0 * t / 600.0), np.radians(175.0 + 10.0 * t / 600.0)])
    euler_c = (euler_c + np.pi) % (2 * np.pi) - np.pi  # yaw crosses ±180°
    signals = {
        "time": Signal(t, "s", "time"),
        "body_rate": Signal(walk(3, 1e-4), "rad/s", "body rate", ("p", "q", "r"), "body"),
        "alpha": Signal(walk(1, 1e-4)[:, 0], "rad", "angle of attack"),
        "beta": Signal(walk(1, 1e-4)[:, 0], "rad", "sideslip"),
        "attitude_euler": Signal(euler_c + walk(3, 1e-4), "rad", "attitude", rpy, "launch"),
        "attitude_euler_command": Signal(euler_c, "rad", "command", rpy, "launch"),
        "velocity_relative": Signal(12.0 * t, "m/s", "air-relative speed"),
        "dynamic_pressure": Signal(3e4 * np.exp(-(((t - 60.0) / 30.0) ** 2)), "Pa", "dynamic pressure"),
        "altitude": Signal(0.5 * t**2, "m", "altitude"),
        "mach": Signal(t / 30.0, "1", "Mach"),
        "gimbal_angle": Signal(walk(2, 1e-4), "rad", "gimbal", ("pitch", "yaw"), "body"),
        "gimbal_command": Signal(walk(2, 1e-4), "rad", "gimbal command", ("pitch", "yaw"), "body"),
        "attitude_error": Signal(walk(3, 1e-5), "rad", "attitude error", rpy, "body"),
    }
    if fidelity:
        signals |= {
            "flex_q": Signal(walk(4, 1e-2), "kg^0.5*m", "modal coordinates", tuple(f"mode_{i + 1}" for i in range(4))),
            "flex_qdot": Signal(walk(4, 1e-1), "kg^0.5*m/s", "modal velocities", tuple(f"mode_{i + 1}" for i in range(4))),
            "sensed_rate": Signal(walk(9, 1e-4), "rad/s", "gyros"),
            "slosh_position": Signal(walk(4, 1e-3), "m", "slosh", ("lox_y", "lox_z", "lh2_y", "lh2_z"), "body"),
            "slosh_frequency": Signal(0.5 + walk(2, 1e-4), "Hz", "slosh frequency", ("lox", "lh2")),
            "peg_time_to_go": Signal(np.maximum(560.0 - t, 0.0) * (t > 170.0), "s", "time to go"),
            "peg_velocity_to_go_magnitude": Signal(np.maximum(560.0 - t, 0.0) * 15.0 * (t > 170.0), "m/s", "v_go"),
            "peg_steering_angles": Signal(walk(2, 1e-4), "rad", "steering", ("elevation", "out_of_plane")),
            "peg_converged": Signal((t > 170.0).astype(float), "1", "converged"),
            "peg_active": Signal((t > 170.0).astype(float), "1", "engaged"),
        }
    return RunRecord(
        signals=signals, events=list(EVENTS),
        summary={"status": "complete" if complete else "diverged", "max_dynamic_pressure_Pa": 30000.0,
                 "time_separation_s": 130.0, "perigee_altitude_km": None},
        config_yaml="a: 1\n", provenance={"host": "test"}, complete=complete,
        status="complete" if complete else "diverged",
        message="cutoff on target energy" if complete else "NaN in body_rate at t=590.000 s",
    )


def _check_pngs(paths: list[Path], folder: Path) -> None:
    assert {p.name for p in paths} == EXPECTED
    for p in paths:
        assert p.parent == folder and p.stat().st_size > 0
        assert p.read_bytes()[:8] == PNG_MAGIC
    assert not [p for p in folder.iterdir() if p.name.startswith(".")]  # no temp files left


def test_plot_ascent_writes_seven_pngs(tmp_path: Path) -> None:
    out = tmp_path / "plots"
    paths = plot_ascent(ascent_record(), out)
    _check_pngs(paths, out)
    assert [p.name for p in paths] == [spec.filename for spec in FIGURES if spec.requires is None]


def test_missing_signals_are_skipped(tmp_path: Path) -> None:
    rec = ascent_record(n=200)
    keep = {"time", "altitude", "mach", "alpha"}
    rec.signals = {k: v for k, v in rec.signals.items() if k in keep}
    paths = plot_ascent(rec, tmp_path)
    assert [p.name for p in paths] == ["alpha_beta.png", "altitude_mach.png"]
    rec.signals = {"time": rec.signals["time"]}
    assert plot_ascent(rec, tmp_path / "none") == []
    rec.signals = {}
    assert plot_ascent(rec, tmp_path / "none") == []


def _figure(rec: RunRecord, filename: str):
    spec = next(s for s in FIGURES if s.filename == filename)
    t = rec.signals["time"].data
    return ascent._draw(spec, rec, t, ascent._indices(t.size))


def test_fidelity_figures_drawn_only_with_their_signals(tmp_path: Path) -> None:
    extra = {"flex_modes.png", "gyro_rates.png", "slosh.png", "guidance.png"}
    paths = plot_ascent(ascent_record(n=400, fidelity=True), tmp_path / "a")
    assert {p.name for p in paths} == EXPECTED | extra
    fig = ascent._draw(next(s for s in FIGURES if s.filename == "flex_modes.png"), ascent_record(n=400, fidelity=True),
                       np.linspace(0.0, 600.0, 400), np.arange(400))
    assert [len(ax.get_lines()) for ax in fig.get_axes()][0] >= 4  # one line per retained mode (+ event lines)
    assert {p.name for p in plot_ascent(ascent_record(n=400), tmp_path / "b")} == EXPECTED


def test_incomplete_title_in_red() -> None:
    rec = ascent_record(n=300, complete=False, fidelity=True)
    for spec in FIGURES:
        fig = _figure(rec, spec.filename)
        title = fig._suptitle
        assert "INCOMPLETE: NaN in body_rate at t=590.000 s" in title.get_text()
        assert title.get_color() == "red"
    fig = _figure(ascent_record(n=300), "body_rates.png")
    assert "INCOMPLETE" not in fig._suptitle.get_text()


def test_axes_units_events_and_conversion() -> None:
    rec = ascent_record(n=300, fidelity=True)
    for spec in FIGURES:
        fig = _figure(rec, spec.filename)
        axes = fig.get_axes()
        assert len(axes) == len(spec.panels if spec.panels_of is None else spec.panels_of(rec))
        assert axes[-1].get_xlabel().endswith("(s)")
        for ax in axes:
            label = ax.get_ylabel()
            assert label.endswith(")") and "(" in label, label
            vlines = {ln.get_xdata()[0] for ln in ax.get_lines() if len(ln.get_xdata()) == 2
                      and ln.get_xdata()[0] == ln.get_xdata()[1]}
            assert vlines >= {t for _, t in EVENTS}, (spec.filename, vlines)
    fig = _figure(rec, "body_rates.png")
    ax = fig.get_axes()[0]
    assert "deg/s" in ax.get_ylabel()
    np.testing.assert_allclose(ax.get_lines()[0].get_ydata(), np.degrees(rec.signals["body_rate"].data[:, 0]))
    fig = _figure(rec, "velocity_dynamic_pressure.png")
    ax = fig.get_axes()[1]
    assert "kPa" in ax.get_ylabel()
    np.testing.assert_allclose(ax.get_lines()[0].get_ydata(), rec.signals["dynamic_pressure"].data / 1e3)
    fig = _figure(rec, "attitude_tracking.png")
    for ax in fig.get_axes():  # commanded dashed, no ±180° jumps drawn
        actual, command = ax.get_lines()[:2]
        assert command.get_linestyle() == "--"
        assert np.max(np.abs(np.diff(actual.get_ydata()))) < 90.0
        assert np.max(np.abs(actual.get_ydata() - command.get_ydata())) < 5.0


def test_long_signals_are_strided() -> None:
    rec = ascent_record(n=30_000)
    fig = _figure(rec, "alpha_beta.png")
    line = fig.get_axes()[0].get_lines()[0]
    assert len(line.get_xdata()) <= ascent.MAX_POINTS + 1
    assert line.get_xdata()[-1] == rec.signals["time"].data[-1]


HEADLESS_SCRIPT = """
import sys
from pathlib import Path
import numpy as np
from savant_cli.io.record import RunRecord, Signal
from savant_cli.plots.ascent import plot_ascent
t = np.linspace(0, 10, 50)
rec = RunRecord({"time": Signal(t, "s", ""), "altitude": Signal(t, "m", ""), "mach": Signal(t, "1", "")})
paths = plot_ascent(rec, Path(sys.argv[1]))
assert len(paths) == 1 and paths[0].stat().st_size > 0
assert "matplotlib.pyplot" not in sys.modules
"""


def test_headless_without_pyplot(tmp_path: Path) -> None:
    """No DISPLAY, no MPLBACKEND: plots still render, and pyplot is never imported."""
    env = {"PATH": "/usr/bin:/bin", "HOME": str(tmp_path),
           "PYTHONPATH": str(Path(__file__).resolve().parent.parent)}
    res = subprocess.run([sys.executable, "-c", HEADLESS_SCRIPT, str(tmp_path / "out")],
                         env=env, capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr


def test_report_redraws_from_savant_h5(tmp_path: Path) -> None:
    rec = ascent_record(n=3000)
    write_run(tmp_path / "savant.h5", rec)
    console = Console(record=True, width=120)
    paths = report(tmp_path, console=console)
    _check_pngs(paths, tmp_path / "plots")
    text = console.export_text()
    assert "max dynamic pressure" in text and "status: complete" in text


def test_report_without_savant_h5(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match="savant.h5"):
        report(tmp_path)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        report(tmp_path / "missing")


def test_captured_figures_are_kept_not_written(tmp_path):
    """Inside ``capture_figures`` both writers keep the figure by its path (nothing on
    disk, no folder made, the figure not cleared) and every sheet is new; outside, they
    write again."""
    from savant_cli.plots.figure import capture_figures, new_figure, save_figure, save_rendered, sheet

    def layout():
        fig = new_figure(3.0, 2.0)
        return fig, [fig.add_subplot(1, 1, 1)]

    with capture_figures() as kept:
        a, b = new_figure(3.0, 2.0), new_figure(3.0, 2.0)
        a.add_subplot(1, 1, 1).plot([0, 1], [1, 2])
        b.add_subplot(1, 1, 1)
        assert save_figure(a, tmp_path / "sub" / "a.png") == tmp_path / "sub" / "a.png"
        save_rendered(b, tmp_path / "b.png")
        first, _ = sheet(("capture-test",), layout)
        second, _ = sheet(("capture-test",), layout)
    assert kept == {tmp_path / "sub" / "a.png": a, tmp_path / "b.png": b}
    assert list(tmp_path.iterdir()) == [] and len(a.axes[0].lines) == 1 and first is not second
    save_figure(a, tmp_path / "a.png")
    assert (tmp_path / "a.png").read_bytes().startswith(b"\x89PNG") and not a.axes  # written, then cleared
