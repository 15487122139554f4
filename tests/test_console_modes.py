"""Quiet where asked (issue 27 item 11): ``output.console=full|summary|quiet`` and
``savant_cli.run(..., quiet=True)``, no progress bar (and so no repeated rich
"install ipywidgets" warning) in a notebook without ipywidgets, and Monte Carlo tables
that read at 80 columns."""

from __future__ import annotations

import io
import logging
import subprocess
import sys
from pathlib import Path

import pytest
from rich.console import Console

import savant_cli
from conftest import compose_config
from savant_cli.config import validate
from savant_cli.errors import ConfigError
from savant_cli.io.console import (
    CONSOLE_MODES, HEADLINE_KEYS, format_sig, live_display_ok, print_quiet_lines, print_run_summary, readable_name,
    study_console
)
from savant_cli.montecarlo.console_summary import print_tables

ROOT = Path(__file__).resolve().parents[1]
INSERTION = ["insertion_radius_error_m", "insertion_speed_error_mps", "insertion_flight_path_angle_error_deg",
             "insertion_velocity_error_mps", "insertion_perigee_error_km", "insertion_apogee_error_km",
             "insertion_inclination_error_deg", "insertion_node_error_deg"]


def _render(fn, width: int = 80) -> str:
    console = Console(width=width, record=True, file=io.StringIO(), color_system=None)
    fn(console)
    return console.export_text()


def _first_column(text: str) -> list[str]:
    """The first column's cells of a rich table (a cell's wrapped lines joined): a new
    cell starts where the second column has text."""
    cells: list[str] = []
    for line in text.splitlines():
        if not line.startswith("│"):
            continue
        parts = line.split("│")
        first, second = parts[1].strip(), parts[2].strip()
        if second:
            cells.append(first)
        elif cells and first:
            cells[-1] += " " + first
    return cells


def _stats(names: list[str]) -> list[dict]:
    return [dict(variable=n, max=168769.8129200502, max_run=26, min=-0.0201, min_run=3,
                 **{"p0.135": 7.47999999999997, "p50": 12.5, "p99.865": 123456.7}) for n in names]


def test_monte_carlo_table_names_are_distinguishable_at_80_columns():
    """The eight insertion variables (and a long one) keep their whole names at 80
    columns, wrapped at spaces, so no two look alike (before: all cut to 'insertion…')."""
    names = INSERTION + ["usable_propellant_remaining_kg"]
    text = _render(lambda c: print_tables(c, _stats(names), [], {"complete": 8}, []))
    assert max(len(line) for line in text.splitlines()) <= 80
    cells = _first_column(text)
    assert cells == [readable_name(n) for n in names]
    assert len(set(cells)) == len(names) and "…" not in text
    assert "168,800 [26]" in text and "7.48" in text and "7.4799" not in text  # 4 significant digits
    assert "max [run]" in text


def test_format_sig_rounds_to_significant_digits():
    assert [format_sig(v) for v in (168769.8129200502, 7.47999999999997, 0.000123456, 9.99996, -0.0201, 0.0)] == \
        ["168,800", "7.48", "0.0001235", "10", "-0.0201", "0"]
    assert format_sig(130.46, 5) == "130.46" and format_sig(1.2e12) == "1.200e+12" and format_sig(26) == "26"
    assert format_sig(None) == "—" and format_sig(float("nan")) == "nan" and format_sig(True) == "yes"


SUMMARY = {"status": "complete", "message": "cutoff: PEG time to go elapsed", "max_dynamic_pressure_Pa": 39075.5,
           "max_alpha_deg": 6.64, "sim_wall_time_s": 3.2, "realtime_factor": 170.0, "rms_attitude_error_deg": 0.13,
           "mission_success": 1, "mission_verdict": "mission: SUCCESS"}


@pytest.mark.parametrize("mode", CONSOLE_MODES)
def test_run_summary_per_console_mode(mode):
    text = _render(lambda c: print_run_summary(SUMMARY, "complete", SUMMARY["message"], c, mode))
    if mode == "quiet":
        assert text == ""
        return
    assert "max dynamic pressure" in text and "status: complete" in text and "mission: SUCCESS" in text
    full = mode == "full"
    assert ("sim wall time" in text) is full and ("rms attitude error" in text) is full
    assert "max dynamic pressure" in HEADLINE_KEYS[0].replace("_", " ")


def test_quiet_lines_are_the_status_and_the_verdict():
    text = _render(lambda c: print_quiet_lines(SUMMARY, "/runs/x", c), width=200)
    assert text.splitlines() == ["status: complete — cutoff: PEG time to go elapsed (outputs: /runs/x)",
                                 "mission: SUCCESS"]
    batch = {"status": "complete", "reliability": {"line": "success 8 of 8 runs: 74.989 % demonstrated",
                                                   "target_met": False}}
    assert _render(lambda c: print_quiet_lines(batch, "/b", c), width=200).splitlines()[1].startswith("success 8 of 8")
    assert len(_render(lambda c: print_quiet_lines({"status": "complete"}, "/c", c)).splitlines()) == 1
    linear = {**SUMMARY, "requirements_verdict": "requirements ares_i: PASS, 4 of 4 points pass",
              "requirements_met": True}  # the study's judgement before its flight's mission line
    assert _render(lambda c: print_quiet_lines(linear, "/l", c), width=200).splitlines()[1].startswith("requirements")


def test_study_console_is_silent_only_when_quiet():
    assert study_console("quiet").quiet and not study_console("summary").quiet and not study_console("full").quiet
    with pytest.raises(ValueError):
        study_console("loud")


@pytest.mark.parametrize("mode", CONSOLE_MODES)
def test_every_console_mode_is_a_valid_config(mode):
    assert validate(compose_config([f"output.console={mode}"])).output.console == mode


def test_unknown_console_mode_is_refused():
    with pytest.raises(ConfigError) as info:
        validate(compose_config(["output.console=loud"]))
    assert info.value.key == "output.console" and "full, summary, quiet" in info.value.allowed


def test_no_progress_bar_in_a_notebook_without_ipywidgets(monkeypatch, caplog):
    """In a Jupyter kernel without ipywidgets rich's progress bars draw nothing and warn
    'install "ipywidgets"' at every refresh: the study runs without them, and savant
    says so once per process, not once per call."""
    pytest.importorskip("rich")
    try:
        import ipywidgets  # noqa: F401
        has_widgets = True
    except ImportError:
        has_widgets = False
    assert live_display_ok(Console(force_jupyter=True)) is has_widgets
    assert live_display_ok(Console(force_jupyter=False, file=io.StringIO()))
    import savant_cli.runner as runner

    monkeypatch.setattr("savant_cli.io.console.live_display_ok", lambda console=None: False)
    monkeypatch.setitem(runner._NOTEBOOK_NOTE, "said", False)
    with caplog.at_level(logging.INFO, logger="savant_cli"):
        assert runner._progress_drawable() is False
        assert runner._progress_drawable() is False
    assert [r.getMessage() for r in caplog.records].count(
        "no progress bars in this notebook: install ipywidgets to see them") == 1


def test_api_quiet_prints_two_lines_and_records_the_override(tmp_path, capsys):
    out = tmp_path / "quiet"
    r = savant_cli.run(["sim.max_time_s=20"], out_dir=out, quiet=True)
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) in (1, 2), lines
    assert lines[0].startswith(f"status: {r.status}") and f"(outputs: {out.resolve()}" in lines[0]
    assert "output.console=quiet" in (out / ".hydra" / "overrides.yaml").read_text()
    assert (out / "report.html").is_file()  # written, only not announced


def test_api_quiet_conflicting_with_an_override_is_refused(tmp_path):
    with pytest.raises(ConfigError) as info:
        savant_cli.run(["output.console=full"], out_dir=tmp_path / "x", quiet=True)
    assert info.value.key == "quiet" and not (tmp_path / "x").exists()


def test_command_line_console_summary_and_quiet(tmp_path):
    """``savant run output.console=summary`` prints the headline rows only;
    ``output.console=quiet`` the status line and the mission line."""
    def run(mode: str) -> str:
        proc = subprocess.run([sys.executable, "-m", "savant_cli.cli", "run", "sim.max_time_s=20", "output.plots=false",
                               f"output.console={mode}", f"hydra.run.dir={tmp_path / mode}"],
                              cwd=tmp_path, capture_output=True, text=True, env={**__import__("os").environ,
                                                                                  "PYTHONPATH": str(ROOT),
                                                                                  "COLUMNS": "120"})
        assert proc.returncode in (0, 1), proc.stderr
        return proc.stdout
    summary = run("summary")
    assert "max dynamic pressure" in summary and "sim wall time" not in summary and "status: " in summary
    quiet = run("quiet").splitlines()
    assert 1 <= len(quiet) <= 2 and quiet[0].startswith("status: ")
