"""Figures of a Monte Carlo dispersion study (``savant_cli.plots.montecarlo``).

The data are synthetic: normal samples for the scalar results, sinusoids of random
amplitude that end at random times (NaN tails) for the histories, and a margin table with
several linearization times, both axes, all three bands and a negative (gain-reduction)
aerodynamic gain margin. Every statistic drawn is checked against numpy on the inputs.
"""

from __future__ import annotations

import math
import os
import struct
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from conftest import PYPLOT_STUB, imported_names
from savant_cli.plots import figure, montecarlo
from savant_cli.plots.montecarlo import plot_envelopes, plot_histograms, plot_margin_spread, plot_montecarlo

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
ROOT = Path(__file__).resolve().parents[1]
N_RUNS = 300
REQ = {"rigid/aero": (6.0, 30.0), "slosh": (6.0, 30.0), "flex": (6.0, 30.0)}


def _png_size(path: Path) -> tuple[int, int]:
    """Width and height (pixels) of a PNG, from its IHDR chunk; checks the signature."""
    head = path.read_bytes()[:24]
    assert head[:8] == PNG_MAGIC and head[12:16] == b"IHDR", path
    return struct.unpack(">II", head[16:24])


def _check_pngs(paths: list[Path], folder: Path) -> None:
    for p in paths:
        assert p.parent == folder and p.is_file()
        w, h = _png_size(p)
        assert 400 <= w <= 3000 and 300 <= h <= 3000, (p.name, w, h)
        assert p.stat().st_size > 5_000
    assert not [p for p in folder.iterdir() if p.name.startswith(".")]  # no temp files left


def scalar_values(n_vars: int = 14, seed: int = 1) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    values = {f"var_{k:02d}": rng.normal(10.0 * k, 1.0 + k, N_RUNS) for k in range(n_vars)}
    values["var_00"][[5, 17]] = np.nan  # failed runs
    return values


def histories(n_t: int = 400, seed: int = 2) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Sinusoids of random amplitude, each run ending at a random time (NaN after it);
    run 0 (nominal) runs to the end; a few runs have a gap of missing samples."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 100.0, n_t)
    amp = rng.uniform(0.5, 2.0, (N_RUNS, 1))
    phase = rng.uniform(-0.3, 0.3, (N_RUNS, 1))
    alpha = amp * np.sin(2.0 * np.pi * t / 40.0 + phase)
    end = rng.uniform(50.0, 95.0, N_RUNS)
    end[0] = t[-1]
    alpha[t[None, :] > end[:, None]] = np.nan
    alpha[3, 100:120] = np.nan
    q = 30.0 * np.exp(-(((t - 60.0) / 20.0) ** 2)) * amp + 0.0 * alpha
    q[np.isnan(alpha)] = np.nan
    return t, {"alpha": alpha, "dynamic pressure/q": q}


def margin_table(seed: int = 3) -> dict[str, np.ndarray]:
    """Every run at 4 times: pitch has all bands (a negative aero gain margin); yaw has
    gain margins only, so its phase panel is empty."""
    rng = np.random.default_rng(seed)
    rows = []
    for run in range(40):
        for t in (20.0, 40.0, 60.0, 80.0):
            rows += [
                (run, t, "pitch", "gain", "rigid/aero", -8.0 + rng.normal(0, 1.5), 0.05),
                (run, t, "pitch", "gain", "rigid/aero", 10.0 + rng.normal(0, 1.0), 1.2),
                (run, t, "pitch", "phase", "rigid/aero", 40.0 + rng.normal(0, 5.0), 0.4),
                (run, t, "pitch", "phase", "slosh", 60.0 + rng.normal(0, 8.0), 0.8),
                (run, t, "pitch", "gain", "flex", 12.0 + rng.normal(0, 2.0), 2.5),
                (run, t, "yaw", "gain", "rigid/aero", -7.0 + rng.normal(0, 1.0), 0.06),
            ]
    rows.append((1, 80.0, "yaw", "gain", "flex", np.inf, np.nan))  # no finite margin: left out
    cols = list(zip(*rows))
    return {"run": np.array(cols[0], dtype=int), "time_s": np.array(cols[1]), "axis": np.array(cols[2]),
            "kind": np.array(cols[3]), "band": np.array(cols[4]), "value": np.array(cols[5]),
            "frequency_hz": np.array(cols[6])}


def _by_gid(ax, gid: str):
    found = [a for a in ax.get_children() if a.get_gid() == gid]
    assert len(found) == 1, (gid, len(found))
    return found[0]


# --------------------------------------------------------------------------- histograms


@pytest.mark.parametrize(("n_vars", "per_page"), [(14, 12), (5, 2)])
def test_histogram_pages(tmp_path: Path, n_vars: int, per_page: int) -> None:
    values = scalar_values(n_vars)
    out = tmp_path / "mc"
    paths = plot_histograms(values, out, units={"var_01": "m/s"}, nominal={k: float(v[0]) for k, v in values.items()},
                            per_page=per_page)
    pages = math.ceil(n_vars / per_page)
    assert [p.name for p in paths] == [f"histograms_{k:02d}.png" for k in range(1, pages + 1)]
    assert sorted(out.iterdir()) == paths
    _check_pngs(paths, out)


def test_histogram_panel_contents() -> None:
    values = scalar_values(3)
    nominal = {"var_01": 11.5}
    fig = montecarlo._histogram_page(list(values), values, {"var_01": "m/s"}, nominal, 1, 1)
    axes = fig.axes
    assert len(axes) == 3
    assert axes[1].get_title() == "var_01 [m/s]" and axes[0].get_title() == "var_00"
    for ax, (name, v) in zip(axes, values.items()):
        finite = v[np.isfinite(v)]
        counts, edges = _by_gid(ax, "histogram").get_data()[:2]
        assert counts.sum() == finite.size  # every finite value counted, NaN ignored
        assert 5 <= counts.size <= figure.MAX_BINS
        np.testing.assert_array_equal(counts, np.histogram(finite, bins=edges)[0])
        assert edges[0] == finite.min() and edges[-1] == finite.max()
        pct = sorted(float(line.get_xdata()[0]) for line in ax.lines if line.get_gid() == "percentile")
        np.testing.assert_allclose(pct, np.percentile(finite, [0.135, 99.865]))
        nom = [float(line.get_xdata()[0]) for line in ax.lines if line.get_gid() == "nominal"]
        assert nom == ([11.5] if name in nominal else [])
        text = " ".join(t.get_text() for t in ax.texts)
        assert f"N {finite.size}" in text and f"σ {np.std(finite, ddof=1):.3g}" in text
        assert f"mean {np.mean(finite):.4g}" in text


def test_bin_count_is_numpy_auto_capped() -> None:
    rng = np.random.default_rng(4)
    for x in (rng.normal(size=300), rng.uniform(size=50), rng.exponential(size=1000)):
        assert figure.bin_count(x) == min(len(np.histogram_bin_edges(x, "auto")) - 1, 60)
    outlier = np.append(rng.normal(size=1000), 1e12)  # 'auto' would ask for ~10^12 bins
    assert figure.bin_count(outlier) == 60
    assert figure.bin_count(np.full(10, 3.0)) == 1 and figure.bin_count(np.array([1.0])) == 1


def test_histogram_degenerate_values(tmp_path: Path) -> None:
    values = {"all_nan": np.full(10, np.nan), "single": np.array([np.nan, 4.2]), "constant": np.full(20, 7.0),
              "zero": np.zeros(5), "empty": np.zeros(0)}
    paths = plot_histograms(values, tmp_path, nominal={"all_nan": np.nan, "constant": 7.0})
    assert len(paths) == 1
    _check_pngs(paths, tmp_path)
    fig = montecarlo._histogram_page(list(values), values, None, None, 1, 1)
    ax_nan, ax_single, ax_const = fig.axes[:3]
    assert not ax_nan.patches and [t.get_text() for t in ax_nan.texts] == ["no finite values"]
    assert _by_gid(ax_single, "histogram").get_data()[0].tolist() == [1]
    counts, edges = _by_gid(ax_const, "histogram").get_data()[:2]
    assert counts.tolist() == [20] and edges[0] < 7.0 < edges[1]
    assert plot_histograms({}, tmp_path / "none") == []
    with pytest.raises(ValueError):
        plot_histograms(values, tmp_path, per_page=0)


# --------------------------------------------------------------------------- envelopes


def test_envelope_stats_match_numpy() -> None:
    _, hist = histories()
    data = hist["alpha"]
    env = montecarlo._envelope_stats(data)
    count = np.isfinite(data).sum(axis=0)
    assert count.min() == 1 and count.max() == N_RUNS  # late samples: only the nominal run
    np.testing.assert_array_equal(env.count, count)
    np.testing.assert_array_equal(env.minimum, np.nanmin(data, axis=0))
    np.testing.assert_array_equal(env.maximum, np.nanmax(data, axis=0))
    np.testing.assert_allclose(env.median, np.nanmedian(data, axis=0))
    two = count >= 2
    lo, hi = np.nanpercentile(data[:, two], [0.135, 99.865], axis=0)
    np.testing.assert_allclose(env.low[two], lo)
    np.testing.assert_allclose(env.high[two], hi)
    assert np.isnan(env.low[~two]).all() and np.isnan(env.high[~two]).all()
    # a hand-checkable column: 0.135 % of the way from the smallest to the next value
    col = np.array([[1.0], [np.nan], [3.0], [2.0]])
    e = montecarlo._envelope_stats(col)
    np.testing.assert_allclose([e.low[0], e.median[0], e.high[0]], [1.0 + 0.0027, 2.0, 3.0 - 0.0027])


def test_envelope_figure_draws_the_statistics() -> None:
    t, hist = histories()
    data = hist["alpha"]
    fig = montecarlo._envelope_figure(t, data, "alpha", {"alpha": "deg"}, max_lines=50)
    ax = fig.axes[0]
    assert ax.get_xlabel() == "time (s)" and ax.get_ylabel() == "alpha [deg]"
    assert ax.get_legend() is not None
    lo_line, hi_line = _by_gid(ax, "minimum"), _by_gid(ax, "maximum")
    np.testing.assert_array_equal(lo_line.get_xdata(), t)
    np.testing.assert_array_equal(lo_line.get_ydata(), np.nanmin(data, axis=0))
    np.testing.assert_array_equal(hi_line.get_ydata(), np.nanmax(data, axis=0))
    np.testing.assert_allclose(_by_gid(ax, "median").get_ydata(), np.nanmedian(data, axis=0))
    np.testing.assert_array_equal(_by_gid(ax, "nominal").get_ydata(), data[0])
    # band: the filled polygon spans the percentiles where at least 2 runs have data
    verts = np.vstack([p.vertices for p in _by_gid(ax, "band").get_paths()])
    two = np.isfinite(data).sum(axis=0) >= 2
    lo, hi = np.nanpercentile(data[:, two], [0.135, 99.865], axis=0)
    assert verts[:, 1].min() == pytest.approx(lo.min()) and verts[:, 1].max() == pytest.approx(hi.max())
    assert verts[:, 0].max() <= t[two].max() + 1e-9
    # individual runs: 50 of 300, NaN-separated in one line, values taken from the input rows
    runs = _by_gid(ax, "runs")
    y = np.asarray(runs.get_ydata(), dtype=float).reshape(50, t.size + 1)
    rows = [int(np.flatnonzero(np.all((data == r[:-1]) | (np.isnan(data) & np.isnan(r[:-1])), axis=1))[0])
            for r in y]
    assert rows[0] == 0 and rows[-1] == N_RUNS - 1 and len(set(rows)) == 50
    assert np.all(np.diff(rows) >= N_RUNS // 50 - 1)  # evenly spread


def test_plot_envelopes_files(tmp_path: Path) -> None:
    t, hist = histories()
    paths = plot_envelopes(t, hist, tmp_path / "env", units={"alpha": "deg"})
    assert [p.name for p in paths] == ["envelope_alpha.png", "envelope_dynamic_pressure_q.png"]
    _check_pngs(paths, tmp_path / "env")


def test_envelope_degenerate_inputs(tmp_path: Path) -> None:
    t = np.linspace(0.0, 10.0, 50)
    rng = np.random.default_rng(5)
    cases = {
        "all_nan": np.full((20, 50), np.nan),
        "single_run": np.sin(t)[None, :],
        "one_dim": np.cos(t),  # a 1-D history is one run
        "constant": np.full((30, 50), 2.0),
        "failed_nominal": np.vstack([np.full(50, np.nan), rng.normal(size=(5, 50))]),
    }
    paths = plot_envelopes(t, cases, tmp_path)
    assert len(paths) == len(cases)
    _check_pngs(paths, tmp_path)
    env = montecarlo._envelope_stats(cases["single_run"])
    np.testing.assert_array_equal(env.minimum, np.sin(t))
    assert np.isnan(env.low).all()
    assert np.isnan(montecarlo._envelope_stats(cases["all_nan"]).maximum).all()
    with pytest.raises(ValueError):
        plot_envelopes(t, {"bad": np.zeros((3, 49))}, tmp_path)


def test_run_rows() -> None:
    assert montecarlo._run_rows(5, 200).tolist() == [0, 1, 2, 3, 4]
    assert montecarlo._run_rows(300, 0).size == 0
    rows = montecarlo._run_rows(1001, 11)
    assert rows.tolist() == list(range(0, 1001, 100))


# --------------------------------------------------------------------------- margins


def test_margin_spread_figure() -> None:
    table = margin_table()
    fig = montecarlo._margin_figure(table, REQ)
    axes = np.array(fig.axes).reshape(2, 2)
    assert [ax.get_title() for ax in axes[0]] == ["pitch", "yaw"]
    assert "dB" in axes[0, 0].get_ylabel() and "deg" in axes[1, 0].get_ylabel()
    assert "(s)" in axes[1, 0].get_xlabel()
    finite = np.isfinite(table["value"])
    for r, kind in enumerate(("gain", "phase")):
        for c, axis in enumerate(("pitch", "yaw")):
            ax = axes[r, c]
            req = sorted(float(line.get_ydata()[0]) for line in ax.lines if line.get_gid() == "requirement")
            assert req == ([-6.0, 6.0] if kind == "gain" else [30.0])
            sel = finite & (table["kind"] == kind) & (table["axis"] == axis)
            texts = [t.get_text() for t in ax.texts]
            assert ("no crossings" in texts) == (not sel.any())
            for band in ("rigid/aero", "slosh", "flex"):
                m = sel & (table["band"] == band)
                pts = [a for a in ax.collections if a.get_gid() == f"points/{band}"]
                if not m.any():
                    assert not pts
                    continue
                # every run's margin drawn, jittered only in time
                drawn = np.asarray(pts[0].get_offsets())
                np.testing.assert_array_equal(drawn[:, 1], table["value"][m])
                times = table["time_s"][m]
                assert np.abs(drawn[:, 0] - times).max() < 0.5 * 20.0  # within half the time step
                # min–max bar per time (gain margins: one per sign)
                bars = next(a for a in ax.collections if a.get_gid() == f"range/{band}")
                drawn_bars = sorted((float(s[0, 1]), float(s[1, 1])) for s in bars.get_segments())
                expected = []
                for tt in np.unique(times):
                    v = table["value"][m & (table["time_s"] == tt)]
                    groups = [v[v < 0], v[v >= 0]] if kind == "gain" else [v]
                    expected += [(float(g.min()), float(g.max())) for g in groups if g.size]
                assert drawn_bars == sorted(expected)
                # nominal run
                nom = next(a for a in ax.collections if a.get_gid() == f"nominal/{band}")
                np.testing.assert_allclose(np.sort(nom.get_offsets()[:, 1]),
                                           np.sort(table["value"][m & (table["run"] == 0)]))
    gain_pitch = _by_gid(axes[0, 0], "points/rigid/aero")
    assert gain_pitch.get_offsets()[:, 1].min() < 0.0  # the negative aero margin is drawn
    bars = _by_gid(axes[0, 0], "range/rigid/aero")
    assert len(bars.get_segments()) == 8  # 4 times × (gain reduction, gain increase)


def test_plot_margin_spread_file(tmp_path: Path) -> None:
    out = plot_margin_spread(margin_table(), tmp_path / "m" / "margin_spread.png", requirements=REQ)
    assert out == tmp_path / "m" / "margin_spread.png"
    _check_pngs([out], tmp_path / "m")
    # no requirements, one time, one run only, an empty table: no crash
    small = {k: v[:6] for k, v in margin_table().items()}
    assert plot_margin_spread(small, tmp_path / "small.png").is_file()
    empty = {k: v[:0] for k, v in margin_table().items()}
    fig = montecarlo._margin_figure(empty, None)
    assert all("no crossings" in [t.get_text() for t in ax.texts] for ax in fig.axes)
    bad = dict(margin_table())
    bad["value"] = bad["value"][:-1]
    with pytest.raises(ValueError):
        plot_margin_spread(bad, tmp_path / "bad.png")
    with pytest.raises(ValueError):
        plot_margin_spread({k: v for k, v in margin_table().items() if k != "band"}, tmp_path / "bad.png")
    assert not (tmp_path / "bad.png").exists()


# --------------------------------------------------------------------------- all


def test_plot_montecarlo(tmp_path: Path) -> None:
    values = scalar_values(5)
    t, hist = histories(n_t=200)
    paths = plot_montecarlo(tmp_path, values=values, time_s=t, histories=hist, margins=margin_table(),
                            units={"alpha": "deg"}, nominal={"var_00": 0.0}, requirements=REQ)
    assert [p.name for p in paths] == ["histograms_01.png", "envelope_alpha.png",
                                       "envelope_dynamic_pressure_q.png", "margin_spread.png"]
    _check_pngs(paths, tmp_path)
    only = plot_montecarlo(tmp_path / "only", values=scalar_values(2), time_s=t, histories={}, margins={})
    assert [p.name for p in only] == ["histograms_01.png"]
    with pytest.raises(ValueError):
        plot_montecarlo(tmp_path, values={}, time_s=None, histories=hist, margins=None)


def test_no_pyplot(tmp_path: Path) -> None:
    """The module never imports or uses pyplot: its source does not import it, and in a
    fresh interpreter where ``matplotlib.pyplot`` is a stub whose every attribute raises,
    drawing every figure still works (and pyplot is never imported for real)."""
    assert not [name for name in imported_names(montecarlo.__file__) if "pyplot" in name]

    code = PYPLOT_STUB + textwrap.dedent(f"""
        from pathlib import Path
        import numpy as np
        from savant_cli.plots.montecarlo import plot_montecarlo
        rng = np.random.default_rng(0)
        t = np.linspace(0, 10, 30)
        margins = {{"run": np.array([0, 1]), "time_s": np.array([5.0, 5.0]), "axis": np.array(["pitch", "yaw"]),
                   "kind": np.array(["gain", "phase"]), "band": np.array(["rigid/aero", "flex"]),
                   "value": np.array([-6.5, 35.0]), "frequency_hz": np.array([0.05, 2.0])}}
        paths = plot_montecarlo(Path({str(tmp_path)!r}), values={{"x": rng.normal(size=50)}}, time_s=t,
                                histories={{"y": rng.normal(size=(4, 30))}}, margins=margins)
        print(len(paths))
    """)
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": str(tmp_path),
           "PYTHONPATH": str(ROOT)}
    res = subprocess.run([sys.executable, "-c", code], check=False, capture_output=True, text=True, env=env,
                         timeout=120)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == "3"
