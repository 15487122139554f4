"""Run outputs: HDF5 round trip and layout, atomic writes, JSON, provenance, console."""

from __future__ import annotations

import json
import math
from pathlib import Path

import h5py
import numpy as np
import pytest
from rich.console import Console

from savant_cli.io.atomic import atomic_path, to_jsonable, write_json_atomic, write_text_atomic
from savant_cli.io.console import loads_line, print_run_summary, split_unit
from savant_cli.io.hdf5 import FORMAT, FORMAT_VERSION, RunFileError, read_run, write_run
from savant_cli.io.provenance import collect_provenance
from savant_cli.io.record import RunRecord, Signal


def synthetic_record(n: int = 2500, complete: bool = True) -> RunRecord:
    rng = np.random.default_rng(7)
    t = np.arange(n) * 0.02
    rpy = ("roll", "pitch", "yaw")
    signals = {
        "time": Signal(t, "s", "mission time from liftoff"),
        "position_eci": Signal(rng.normal(size=(n, 3)) * 6.4e6, "m", "CG position", ("x", "y", "z"), "ECI"),
        "altitude": Signal(np.linspace(0.0, 1.2e5, n), "m", "geodetic altitude"),
        "body_rate": Signal(rng.normal(size=(n, 3)) * 1e-2, "rad/s", "body rate", ("p", "q", "r"), "body"),
        "attitude_error": Signal(rng.normal(size=(n, 3)) * 1e-3, "rad", "attitude error", rpy, "body"),
        "quaternion": Signal(rng.normal(size=(n, 4)), "1", "q_b2i", ("w", "x", "y", "z"), "ECI"),
        "rcs_command": Signal(rng.integers(-1, 2, size=n).astype(np.int8), "1", "roll jet command"),
        "configuration": Signal((t > 20.0).astype(np.int64), "1", "configuration flag"),
        "short": Signal(rng.normal(size=n), "Pa", "a 1-D float"),
    }
    summary = {
        "status": "complete" if complete else "diverged",
        "max_dynamic_pressure_Pa": 31234.5,
        "time_max_dynamic_pressure_s": 61.25,
        "time_separation_s": None,
        "apogee_altitude_km": math.inf,
        "eccentricity": math.nan,
        "n_steps": 12345,
        "note": "ünïcode ok",
        "flag": True,
    }
    return RunRecord(
        signals=signals,
        events=[("separation", 30.02), ("upper_stage_ignition", 31.0), ("cutoff", 49.98)],
        summary=summary,
        config_yaml="sim:\n  plant_rate_hz: 200.0\nvehicle:\n  name: ares_i  # ü\n",
        provenance={"savant_version": "0.1.0", "git_commit": "", "host": "test"},
        complete=complete,
        status="complete" if complete else "diverged",
        message="cutoff on target energy" if complete else "NaN in body_rate at t=12.340 s",
    )


# --------------------------------------------------------------------------- HDF5


def test_round_trip_exact(tmp_path: Path) -> None:
    rec = synthetic_record()
    path = tmp_path / "savant.h5"
    write_run(path, rec)
    back = read_run(path)
    assert list(back.signals) == list(rec.signals)  # order preserved
    for name, sig in rec.signals.items():
        got = back.signals[name]
        assert got.data.dtype == sig.data.dtype, name
        assert got.data.shape == sig.data.shape, name
        assert np.array_equal(got.data, sig.data), name
        assert (got.units, got.description, got.columns, got.frame) == (
            sig.units, sig.description, sig.columns, sig.frame), name
    assert back.events == rec.events
    assert back.config_yaml == rec.config_yaml
    assert back.provenance == rec.provenance
    assert (back.complete, back.status, back.message) == (rec.complete, rec.status, rec.message)
    assert list(back.summary) == list(rec.summary)
    s = back.summary
    assert s["time_separation_s"] is None
    assert s["apogee_altitude_km"] == math.inf
    assert isinstance(s["eccentricity"], float) and math.isnan(s["eccentricity"])
    assert s["n_steps"] == 12345 and isinstance(s["n_steps"], int)
    assert s["note"] == "ünïcode ok" and s["status"] == "complete" and s["flag"] is True
    assert s["max_dynamic_pressure_Pa"] == 31234.5


def test_incomplete_round_trip_and_empty_events(tmp_path: Path) -> None:
    rec = synthetic_record(n=10, complete=False)
    rec.events = []
    write_run(tmp_path / "r.h5", rec)
    back = read_run(tmp_path / "r.h5")
    assert back.complete is False and back.status == "diverged" and back.events == []
    assert back.message == "NaN in body_rate at t=12.340 s"


def test_layout(tmp_path: Path) -> None:
    path = tmp_path / "savant.h5"
    write_run(path, synthetic_record())
    with h5py.File(path, "r") as f:
        assert f.attrs["format"] == FORMAT and int(f.attrs["format_version"]) == FORMAT_VERSION
        for key in ("complete", "status", "message", "savant_version", "git_commit", "host"):
            assert key in f.attrs
        assert f["config"].shape == () and f["config"].asstr()[()].startswith("sim:")
        assert list(f["events/name"].asstr()[()]) == ["separation", "upper_stage_ignition", "cutoff"]
        assert f["events/time_s"].dtype == np.float64
        assert "max_dynamic_pressure_Pa" in f["summary"].attrs
        assert list(f["summary"].attrs["__none__"]) == ["time_separation_s"]
        for name, ds in f["time_history"].items():
            for attr in ("units", "description", "columns", "frame"):
                assert attr in ds.attrs, (name, attr)
            assert ds.attrs["units"] != "", name
        pos = f["time_history/position_eci"]
        assert pos.compression == "gzip" and pos.compression_opts == 4 and pos.shuffle and pos.chunks
        assert list(pos.attrs["columns"]) == ["x", "y", "z"] and pos.attrs["frame"] == "ECI"
        assert f["time_history/time"].compression == "gzip"  # long 1-D is compressed too


def test_write_run_validates(tmp_path: Path) -> None:
    rec = synthetic_record(n=20)
    bad = RunRecord(signals={k: v for k, v in rec.signals.items() if k != "time"})
    with pytest.raises(ValueError, match="time"):
        write_run(tmp_path / "a.h5", bad)
    rec.signals["wrong"] = Signal(np.zeros(19), "m", "too short")
    with pytest.raises(ValueError, match="wrong"):
        write_run(tmp_path / "a.h5", rec)
    rec.signals["wrong"] = Signal(np.zeros((20, 2)), "m", "bad columns", ("a", "b", "c"))
    with pytest.raises(ValueError, match="wrong"):
        write_run(tmp_path / "a.h5", rec)
    assert list(tmp_path.iterdir()) == []


def test_failed_rewrite_keeps_previous_file(tmp_path: Path) -> None:
    path = tmp_path / "savant.h5"
    write_run(path, synthetic_record(n=50))
    before = path.read_bytes()
    rec = synthetic_record(n=60)
    rec.summary["bad"] = object()  # fails inside the atomic block, after the file was opened
    with pytest.raises(TypeError):
        write_run(path, rec)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["savant.h5"]
    assert read_run(path).signals["time"].data.size == 50


def test_read_run_rejects_foreign_files(tmp_path: Path) -> None:
    with h5py.File(tmp_path / "other.h5", "w") as f:
        f["x"] = 1.0
    with pytest.raises(RunFileError, match="not a savant run"):
        read_run(tmp_path / "other.h5")
    assert issubclass(RunFileError, OSError)
    with pytest.raises(FileNotFoundError):
        read_run(tmp_path / "missing.h5")


# --------------------------------------------------------------------------- atomic


def test_atomic_success_uses_hidden_sibling(tmp_path: Path) -> None:
    final = tmp_path / "sub" / "out.txt"
    with atomic_path(final) as tmp:
        assert tmp.parent == final.parent and tmp.name.startswith(".") and tmp.suffix == ".tmp"
        tmp.write_text("hello")
        assert not final.exists()
    assert final.read_text() == "hello"
    assert [p.name for p in final.parent.iterdir()] == ["out.txt"]


def test_atomic_exception_leaves_nothing(tmp_path: Path) -> None:
    final = tmp_path / "out.txt"
    with pytest.raises(RuntimeError, match="boom"):
        with atomic_path(final) as tmp:
            tmp.write_text("partial")
            raise RuntimeError("boom")
    assert not final.exists()
    assert list(tmp_path.iterdir()) == []


def test_atomic_failed_rewrite_keeps_existing(tmp_path: Path) -> None:
    final = tmp_path / "out.txt"
    write_text_atomic(final, "old")
    with pytest.raises(KeyError):
        with atomic_path(final) as tmp:
            tmp.write_text("new, half written")
            raise KeyError("interrupted")
    assert final.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["out.txt"]


def test_atomic_nothing_written_is_an_error(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError):
        with atomic_path(tmp_path / "x.txt"):
            pass
    assert list(tmp_path.iterdir()) == []


# --------------------------------------------------------------------------- JSON


def test_json_nan_and_numpy(tmp_path: Path) -> None:
    obj = {
        "nan": math.nan, "inf": math.inf, "ninf": -math.inf,
        "np_nan": np.float64("nan"), "np_float": np.float32(1.5), "np_int": np.int64(3),
        "np_bool": np.bool_(True), "array": np.array([1.0, np.nan, 2.0]), "none": None,
        "nested": {"t": (1, np.float64(2.5))}, "path": Path("a/b"), "s": "x",
    }
    path = tmp_path / "summary.json"
    write_json_atomic(path, obj)
    text = path.read_text()
    assert "NaN" not in text and "Infinity" not in text
    assert text.startswith("{\n  \"nan\": null")  # indent=2
    back = json.loads(text, parse_constant=lambda c: pytest.fail(f"non-standard JSON constant {c}"))
    assert back == {
        "nan": None, "inf": None, "ninf": None, "np_nan": None, "np_float": 1.5, "np_int": 3,
        "np_bool": True, "array": [1.0, None, 2.0], "none": None, "nested": {"t": [1, 2.5]},
        "path": "a/b", "s": "x",
    }
    assert type(back["np_int"]) is int


def test_json_unserialisable_writes_nothing(tmp_path: Path) -> None:
    with pytest.raises(TypeError):
        write_json_atomic(tmp_path / "x.json", {"bad": object()})
    assert list(tmp_path.iterdir()) == []
    assert to_jsonable([np.int32(1)]) == [1]


# --------------------------------------------------------------------------- provenance


def test_provenance_fields(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)  # not a git repository
    prov = collect_provenance(wall_time_s=12.5)
    for key in ("savant_version", "git_commit", "git_dirty", "source_git_commit", "python", "numpy",
                "numba", "platform", "host", "created_utc", "wall_time_s"):
        assert key in prov, key
    assert all(isinstance(v, str) for v in prov.values())
    assert prov["git_commit"] == "" and prov["git_dirty"] == ""
    assert prov["wall_time_s"] == "12.500"
    assert prov["created_utc"].endswith("+00:00")
    assert "wall_time_s" not in collect_provenance()


# --------------------------------------------------------------------------- console


def test_split_unit() -> None:
    assert split_unit("max_dynamic_pressure_Pa") == ("max dynamic pressure", "Pa", "{:,.0f}")
    assert split_unit("cutoff_inertial_velocity_mps")[1] == "m/s"
    assert split_unit("perigee_altitude_km")[1] == "km"
    assert split_unit("cutoff_altitude_m")[1] == "m"
    assert split_unit("time_cutoff_s")[1] == "s"
    assert split_unit("max_alpha_deg")[1] == "deg"
    assert split_unit("realtime_factor") == ("realtime factor", "", None)


def test_print_run_summary() -> None:
    console = Console(record=True, width=120, color_system="truecolor", force_terminal=True)
    summary = synthetic_record().summary
    print_run_summary(summary, "complete", "cutoff on target energy", console)
    text = console.export_text()
    assert "max dynamic pressure" in text and "31,234" in text and "Pa" in text
    assert "time separation" in text and "—" in text and "inf" in text
    assert "status: complete" in text and "cutoff on target energy" in text
    console = Console(record=True, width=120, color_system="truecolor", force_terminal=True)
    print_run_summary({"max_alpha_deg": 2.0}, "diverged", "NaN in body_rate", console)
    assert "status: diverged" in console.export_text(clear=False)
    html = console.export_html(inline_styles=True)
    assert "color: #800000" in html  # status in red


def test_loads_line_on_the_console() -> None:
    """A run above its q·α allowable keeps its status but the console says so, in red,
    with the ratio and the time above; without an allowable no loads line is printed."""
    base = {"max_qalpha_Pa_deg": 236000.0, "time_max_qalpha_s": 58.1, "qalpha_limit_Pa_deg": 160000.0,
            "qalpha_limit_ratio": 236000.0 / 160000.0, "time_above_qalpha_limit_s": 2.54,
            "qalpha_limit_exceeded": 1}
    console = Console(record=True, width=200, color_system="truecolor", force_terminal=True)
    print_run_summary(base, "complete", "cutoff", console)
    text = console.export_text(clear=False)
    assert "status: complete" in text
    assert "1.475 of the limit 160,000 Pa·deg: EXCEEDED for 2.54 s" in text
    assert "color: #800000" in console.export_html(inline_styles=True)
    under = {**base, "max_qalpha_Pa_deg": 64000.0, "qalpha_limit_ratio": 0.4, "time_above_qalpha_limit_s": 0.0,
             "qalpha_limit_exceeded": 0}
    assert loads_line(under) == ("loads: max q·α_total 64,000 Pa·deg at 58.10 s is 0.400 of the limit "
                                 "160,000 Pa·deg", False)
    assert loads_line({**base, "qalpha_limit_Pa_deg": None}) is None
