"""The Python API (savant_cli/api.py, savant_cli/result.py, docs/api.md): the same run
folder as the command line, configuration errors as ConfigError naming the key, the
history against the run file read with h5py directly, the linear points against
python-control's own margins, the Monte Carlo tables against the batch file, and
docs/api.md executed block by block."""

from __future__ import annotations

import json
import re
from pathlib import Path

import control as ct
import h5py
import numpy as np
import pytest

import savant_cli
from savant_cli.errors import ConfigError

ROOT = Path(__file__).resolve().parents[1]
#: a short flight: the first stage to 60 s (max-Q inside it)
SHORT = ["sim.max_time_s=60", "sim.progress=false"]
WALL = re.compile(r"wall|realtime_factor|compile_time")  # the machine, not the flight


@pytest.fixture(scope="module")
def short_run(tmp_path_factory):
    return savant_cli.run(SHORT, out_dir=tmp_path_factory.mktemp("api") / "short")


def test_run_returns_the_folder_it_wrote(short_run):
    r = short_run
    assert r.study == "nominal" and r.exit_code == 0 and r.complete
    for name in (".hydra/config.yaml", ".hydra/hydra.yaml", ".hydra/overrides.yaml", "savant.log", "savant.h5",
                 "summary.json", "plots/alpha_beta.png"):
        assert (r.run_dir / name).is_file(), name
    assert (r.run_dir / ".hydra/overrides.yaml").read_text().split() == ["-", SHORT[0], "-", SHORT[1]]
    assert r.summary == json.loads((r.run_dir / "summary.json").read_text())
    assert r.config.sim.max_time_s == 60 and r.config.study.name == "nominal"
    again = savant_cli.load(r.run_dir)
    assert again.summary == r.summary and again.status == r.status and again.exit_code == 0


def test_history_is_the_run_file(short_run):
    """Every logged signal with its units and component names, as h5py reads the file."""
    ds = short_run.history
    with h5py.File(short_run.h5) as f:
        th = f["time_history"]
        assert set(ds.data_vars) | {"time"} == set(th)
        np.testing.assert_array_equal(ds["time"].values, th["time"][()])
        for name in ("alpha", "body_rate", "quaternion", "dynamic_pressure"):
            np.testing.assert_array_equal(ds[name].values, th[name][()])
            assert ds[name].attrs["units"] == th[name].attrs["units"]
        assert list(ds["body_rate_axis"].values) == [str(c) for c in th["body_rate"].attrs["columns"]]
        names = [n.decode() if isinstance(n, bytes) else n for n in f["events/name"][()]]
    assert list(short_run.events) == names
    q = ds["dynamic_pressure"]
    assert float(q.max()) == pytest.approx(short_run.summary["max_dynamic_pressure_Pa"])


def test_plot_draws_figures_and_names_the_known_ones(short_run):
    fig = short_run.plot("alpha_beta")
    assert [ax.get_ylabel() for ax in fig.axes][:1] and len(fig.axes) == 3  # alpha, beta, q-alpha
    assert "gimbal_angles" in short_run.figure_names()
    with pytest.raises(KeyError, match="known: body_rates"):
        short_run.plot("bode")  # a nominal run has no linear points


@pytest.mark.parametrize("overrides, key, words", [
    (["winds.gust.amplitude_mps=80"], "winds.gust.amplitude_mps", "within ±50 m/s"),
    (["winds=no_such_wind"], "winds", "Could not find 'winds/no_such_wind'"),
    (["study.no_such_key=1"], "study.no_such_key", "Could not override"),
    (["study.times=1,2"], "study.times", "Ambiguous value"),
    (["flex.n_modes=4"], "flex.n_modes", "flex=on"),  # a key of another option: our hint
])
def test_configuration_errors_raise_config_error_naming_the_key(tmp_path, overrides, key, words):
    with pytest.raises(ConfigError) as info:
        savant_cli.run(overrides, out_dir=tmp_path / "run")
    assert info.value.key == key and words in str(info.value)
    assert not (tmp_path / "run").exists()  # nothing written


def test_a_string_or_a_flag_is_not_an_override_list(tmp_path):
    with pytest.raises(ConfigError, match="list of override strings"):
        savant_cli.run("study=linear", out_dir=tmp_path)
    with pytest.raises(ConfigError, match="runs one job"):
        savant_cli.run(["-m", "winds=none,ksc_mean_annual"], out_dir=tmp_path)


def test_a_user_config_dir_overrides_the_shipped_tree(tmp_path):
    """``config_dir`` replaces conf/ with the shipped groups behind it (``savant run -cd``).
    A user's wind takes the keys it leaves out (gust, shear) from a shipped option named
    in its defaults list; without one they are required, and refused naming the key."""
    conf = tmp_path / "conf" / "winds"
    conf.mkdir(parents=True)
    profile = "name: calm_test\nenabled: true\nscale: 1.0\n" \
              "profile: {altitude_m: [0, 100000], north_mps: [0, 0], east_mps: [3, 3]}\n"
    (conf / "calm_test.yaml").write_text("defaults: [none, _self_]\n" + profile)
    r = savant_cli.run(["winds=calm_test", "sim.max_time_s=5", "sim.progress=false", "output.plots=false",
                        "winds.gust.amplitude_mps=4"], config_dir=tmp_path / "conf", out_dir=tmp_path / "run")
    assert r.config.winds.name == "calm_test" and r.config.winds.enabled
    assert not r.config.winds.gust.enabled and r.config.winds.gust.amplitude_mps == 4.0  # none's gust, overridden
    assert r.config.winds.shear.direction_deg == 90.0  # none's shear
    east = r.history["wind_ned"].sel(wind_ned_axis=r.history["wind_ned_axis"].values[1])
    assert float(east.max()) == pytest.approx(3.0)
    (conf / "calm_test.yaml").write_text(profile)
    with pytest.raises(ConfigError) as err:
        savant_cli.run(["winds=calm_test", "sim.max_time_s=5"], config_dir=tmp_path / "conf", out_dir=tmp_path / "r2")
    assert err.value.key.startswith(("winds.gust.", "winds.shear.")) and "required" in err.value.allowed


@pytest.fixture(scope="module")
def linear_run(tmp_path_factory):
    return savant_cli.run(["study=linear", "study.times=[55]", "sim.progress=false"],
                          out_dir=tmp_path_factory.mktemp("api") / "linear")


def test_linear_points_are_python_control_systems_with_their_margins(linear_run):
    """The stored pitch loop's margins by python-control's own FRD routine on a fine grid
    equal the point's margin table."""
    point = linear_run.linear[55]  # an int finds the 55.0 s point
    loop = point["open_pitch"]
    assert isinstance(loop, ct.StateSpace) and loop.dt == pytest.approx(0.02)
    w = np.geomspace(2 * np.pi * 0.01, np.pi / loop.dt, 20000)[1:-1]
    gm, pm, _, wg, wp, _ = ct.stability_margins(ct.frd(loop, w), returnall=True, method="frd")
    table = point.margins[point.margins.axis == "pitch"]
    gains = table[table.kind == "gain"].sort_values("frequency_hz")
    ref = sorted((float(f) / (2 * np.pi), 20 * np.log10(g)) for g, f in zip(gm, wg) if np.isfinite(g) and g > 0)
    assert len(ref) == len(gains)
    for (f_ref, g_ref), (_, row) in zip(ref, gains.iterrows()):
        assert row.frequency_hz == pytest.approx(f_ref, rel=1e-3) and row.value == pytest.approx(g_ref, abs=0.01)
    phase = table[table.kind == "phase"]
    assert sorted(phase.value) == pytest.approx(sorted(float(p) for p in pm), abs=0.01)
    assert point.passed is True and point.judged is True
    assert {"pitch", "yaw"} <= set(point.checks.axis) and point.checks.passed.all()
    assert len(linear_run.margins) == len(point.margins)
    with pytest.raises(KeyError, match="stored: \\[55.0\\]"):
        linear_run.linear[56]
    assert len(linear_run.plot("nichols", time=55).axes) >= 1
    assert linear_run.plot("margin_envelope") is not None


def test_montecarlo_tables_are_the_batch_file(tmp_path):
    r = savant_cli.run(["study=montecarlo", "study.n_runs=3", "study.workers=1", "sim.progress=false",
                        "sim.max_time_s=60", "study.histories.signals=[]", "output.plots=false"],
                       out_dir=tmp_path / "mc")
    mc = r.montecarlo
    assert r.history is None and r.linear is None and r.exit_code == 0
    with h5py.File(r.h5) as f:
        g = f["montecarlo"]
        np.testing.assert_array_equal(mc.runs.index.to_numpy(), g["runs/run"][()])
        np.testing.assert_array_equal(mc.runs["max_qalpha_Pa_deg"].to_numpy(), g["summary/max_qalpha_Pa_deg"][()])
        np.testing.assert_array_equal(mc.dispersions["fs_burn_rate"].to_numpy(), g["dispersions/fs_burn_rate"][()])
        choices = json.loads(g["dispersions/wind_profile"].attrs["choices"])
        codes = g["dispersions/wind_profile"][()]
    assert list(mc.runs["status"]) == ["complete"] * 3
    assert [mc.dispersions["wind_profile"][k] for k in (1, 2)] == [choices[int(c)] for c in codes[1:]]
    assert mc.dispersions.attrs["items"]["fs_burn_rate"]["target"] == "tables.first_stage.burn_rate"
    assert mc.statistics.loc["max_qalpha_Pa_deg", "max"] == pytest.approx(mc.runs["max_qalpha_Pa_deg"].max())


def test_load_refuses_a_folder_without_a_run_file(tmp_path):
    with pytest.raises(FileNotFoundError, match="no savant.h5"):
        savant_cli.load(tmp_path)


@pytest.mark.slow
def test_api_and_command_line_write_the_same_run(tmp_path, short_run):
    """The command line's run of the same overrides: the same summary (wall-clock keys
    aside), the same history, the same resolved config."""
    from test_end_to_end import run

    proc = run(["run", *SHORT, f"hydra.run.dir={tmp_path / 'cli'}"], cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    cli = savant_cli.load(tmp_path / "cli")
    strip = lambda s: {k: v for k, v in s.items() if not WALL.search(k)}  # noqa: E731
    assert strip(cli.summary) == strip(short_run.summary)
    for name in cli.history.data_vars:
        np.testing.assert_array_equal(cli.history[name].values, short_run.history[name].values)
    assert sorted(p.name for p in (tmp_path / "cli").iterdir()) == sorted(p.name for p in short_run.run_dir.iterdir())
    assert (tmp_path / "cli/.hydra/config.yaml").read_text() == (short_run.run_dir / ".hydra/config.yaml").read_text()


def _python_blocks(text: str) -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)


@pytest.mark.slow
def test_docs_api_md_runs(tmp_path, monkeypatch):
    """Every ``python`` block of docs/api.md, in order, in one namespace."""
    blocks = _python_blocks((ROOT / "docs" / "api.md").read_text())
    assert len(blocks) >= 5
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    for i, block in enumerate(blocks):
        exec(compile(block, f"docs/api.md block {i + 1}", "exec"), namespace)  # noqa: S102
    from savant_cli.io.record import FLOWN

    assert namespace["r"].status in FLOWN
    assert (tmp_path / "outputs" / "alpha_beta.png").is_file()
