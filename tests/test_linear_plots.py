"""Charts of the frequency-domain stability study (``savant_cli.plots.linear``).

The loops are built here: a discretized (50 Hz, zero-order hold) aerodynamically unstable
rigid pitch plane θ̈ = μα θ + μc δ (μα = 0.4, μc = 1.2 1/s²) with a second-order actuator,
a lightly damped 1 Hz bending mode seen by the attitude and rate sensors, and a PID
attitude controller (Tustin) with a rate filter and one sample of computational delay.
The loop is open-loop unstable (one real pole outside the unit circle) and crosses
−180° several times (a gain-reduction margin, the rigid high-frequency margin, the
bending mode's phase crossings).
"""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import control as ct
import h5py
import numpy as np
import pytest

from conftest import PYPLOT_STUB, imported_names
from savant_cli.linear import charts as chart_data
from savant_cli.linear.store import read_charts, write_charts
from savant_cli.plots import linear
from savant_cli.plots.linear import MarginRow, plot_linear_point, plot_margin_envelope, point_tag

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
DT = 0.02
ROOT = Path(__file__).resolve().parents[1]
KINDS = ("bode", "nichols", "nyquist", "rootlocus", "pzmap", "response")


def axis_plant(name: str, mu_a: float = 0.4, mu_c: float = 1.2, flex_hz: float = 1.0, flex_zeta: float = 0.005,
               flex_gain: float = 2.0, slope: float = 0.02) -> ct.StateSpace:
    """Continuous plant of one axis: δ command (rad) → sensed attitude, sensed rate,
    attitude, gimbal (rad, rad/s, rad, rad). States θ, q, δ, δ̇, η, η̇."""
    wa, wf = 2 * np.pi * 8.0, 2 * np.pi * flex_hz
    a = np.zeros((6, 6))
    a[0, 1] = 1.0
    a[1, 0], a[1, 2] = mu_a, mu_c
    a[2, 3] = 1.0
    a[3, 2], a[3, 3] = -wa**2, -2 * 0.7 * wa
    a[4, 5] = 1.0
    a[5, 4], a[5, 5], a[5, 2] = -wf**2, -2 * flex_zeta * wf, flex_gain
    b = np.zeros((6, 1))
    b[3, 0] = wa**2
    c = np.zeros((4, 6))
    c[0, 0], c[0, 4] = 1.0, -slope  # attitude sensor sees the local slope of the mode
    c[1, 1], c[1, 5] = 1.0, slope
    c[2, 0] = 1.0
    c[3, 2] = 1.0
    return ct.ss(a, b, c, np.zeros((4, 1)), inputs=[f"{name}_delta_c"],
                 outputs=[f"{name}_theta_s", f"{name}_q_s", f"{name}_attitude", f"{name}_gimbal"])


def axis_controller(name: str, kp: float = 2.2, kd: float = 1.75, ki: float = 1.0) -> ct.StateSpace:
    """Discrete PID: δc = kp (θc − θs) + ki ∫(θc − θs) − kd F(s) qs, then one sample of delay."""
    wf = 2 * np.pi * 4.0
    f = ct.ss(ct.tf([wf**2], [1.0, 2 * 0.7 * wf, wf**2]))
    pd = ct.ss(f.A, np.hstack([np.zeros((2, 2)), f.B]), -kd * f.C, np.array([[kp, -kp, -kd * f.D[0, 0]]]))
    pid = ct.parallel(pd, ct.ss([[0.0]], [[1.0, -1.0, 0.0]], [[ki]], [[0.0, 0.0, 0.0]]))
    cd = ct.series(ct.c2d(pid, DT, "tustin"), ct.ss([[0.0]], [[1.0]], [[1.0]], [[0.0]], DT))
    return ct.ss(cd.A, cd.B, cd.C, cd.D, DT, inputs=[f"{name}_command", f"{name}_theta_s", f"{name}_q_s"],
                 outputs=[f"{name}_u"], name=f"{name}_fcs")


def build_system(yaw_mu_a: float = 0.3) -> tuple[dict[str, ct.StateSpace], ct.StateSpace]:
    """Loops broken at each actuator command and the closed loop of both axes.

    The two axes are uncoupled here, so the loop of one axis with the other axis closed
    is that axis's plant and controller alone. (A loop that also carries the other axis's
    states, cancelled, has the same frequency response, but ``ct.stability_margins``
    returns spurious crossings for it: it is built from this minimal one.)
    """
    plants, controllers, loops = [], [], {}
    for name, mu_a in (("pitch", 0.4), ("yaw", yaw_mu_a)):
        p = ct.c2d(axis_plant(name, mu_a=mu_a), DT, "zoh")
        plant = ct.ss(p.A, p.B, p.C, p.D, DT, inputs=p.input_labels, outputs=p.output_labels, name=f"{name}_plant")
        controller = axis_controller(name)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # unused signals of the interconnection
            opened = ct.interconnect([plant, controller], inputs=[f"{name}_delta_c"], outputs=[f"{name}_u"])
        loops[name] = -opened  # δc = −L δ: the closed loop is L / (1 + L)
        plants.append(plant)
        controllers.append(controller)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        connections = []
        for n in ("pitch", "yaw"):
            connections += [[f"{n}_plant.{n}_delta_c", f"{n}_fcs.{n}_u"],
                            [f"{n}_fcs.{n}_theta_s", f"{n}_plant.{n}_theta_s"],
                            [f"{n}_fcs.{n}_q_s", f"{n}_plant.{n}_q_s"]]
        closed = ct.interconnect(plants + controllers, connections=connections,
                                 inplist=["pitch_fcs.pitch_command", "yaw_fcs.yaw_command"],
                                 inputs=["pitch_command", "yaw_command"],
                                 outlist=["pitch_plant.pitch_attitude", "yaw_plant.yaw_attitude",
                                          "pitch_plant.pitch_gimbal", "yaw_plant.yaw_gimbal"],
                                 outputs=["pitch_attitude", "yaw_attitude", "pitch_gimbal", "yaw_gimbal"])
    return loops, closed


def band(f_hz: float) -> str:
    return "flex" if abs(f_hz - 1.0) < 0.15 else "slosh" if 0.3 <= f_hz <= 0.8 else "rigid/aero"


def margin_rows(loops: dict[str, ct.StateSpace], time_s: float) -> list[MarginRow]:
    rows = []
    for axis, loop in loops.items():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # "falling back to 'frd' method"
            gm, pm, _, wpc, wgc, _ = ct.stability_margins(loop, returnall=True)
        for g, w in zip(gm, wpc):
            f = float(w / (2 * np.pi))
            rows.append(MarginRow(time_s, axis, "gain", float(20 * np.log10(g)), f, band(f)))
        for p, w in zip(pm, wgc):
            f = float(w / (2 * np.pi))
            rows.append(MarginRow(time_s, axis, "phase", float(p), f, band(f)))
    return rows


@pytest.fixture(scope="module")
def system():
    loops, closed = build_system()
    return loops, closed, margin_rows(loops, 55.0)


@pytest.fixture(scope="module")
def responses(system):
    loops, _, rows = system
    return [chart_data.loop_response(a, loops[a], (r.frequency_hz for r in rows if r.axis == a))
            for a in ("pitch", "yaw")]


@pytest.fixture(scope="module")
def point(system):
    loops, closed, rows = system
    return chart_data.point_charts(55.0, loops, closed, rows)


def test_test_loops_are_what_the_charts_expect(system):
    loops, closed, rows = system
    for loop in loops.values():
        assert loop.isdtime() and loop.dt == DT and loop.issiso()
        assert np.count_nonzero(np.abs(loop.poles()) > 1.0) == 1  # aerodynamically unstable
        assert np.all(np.abs(ct.feedback(loop, 1).poles()) < 1.0)  # stabilized by the loop
    assert set(closed.input_labels) == {"pitch_command", "yaw_command"}
    assert {"pitch_attitude", "yaw_attitude", "pitch_gimbal", "yaw_gimbal"} <= set(closed.output_labels)
    gains = [r.value for r in rows if r.axis == "pitch" and r.kind == "gain"]
    assert min(gains) < 0.0 < max(gains) and len(gains) >= 3  # gain-reduction and gain margins
    assert any(r.kind == "phase" for r in rows)


def test_plot_linear_point_writes_six_pngs(system, point, tmp_path):
    _, _, rows = system
    out = tmp_path / "charts"
    paths = plot_linear_point(point, rows, out)
    assert [p.name for p in paths] == [f"{k}_t0055.0.png" for k in KINDS]
    for p in paths:
        assert p.parent == out and p.read_bytes()[:8] == PNG_MAGIC
    assert sorted(f.name for f in out.iterdir()) == sorted(p.name for p in paths)  # no temporary files left


def test_figures_reused_between_points_carry_nothing_over(system, point, tmp_path):
    """Charts keep their figure from one point to the next: drawing point A, then a
    different point B, then A again gives the same pixels as the first A."""
    _, _, rows = system
    first = plot_linear_point(point, rows, tmp_path / "a1")
    other_loops, other_closed = build_system(yaw_mu_a=0.6)
    other_rows = margin_rows(other_loops, 80.0)[:2]
    other = chart_data.point_charts(80.0, other_loops, other_closed, other_rows)
    # B's closed-loop poles sit 230 1/s farther left in the s-plane than A's (z/100 ↔
    # s − ln(100)/dt): limits that B widened must not stay wide for A
    pz = point.pzmap
    other = dataclasses.replace(other, pzmap=chart_data.PoleZeroMap(pz.poles / 100.0, pz.zeros, pz.dt))
    plot_linear_point(other, other_rows, tmp_path / "b", exclusion_zones=False)
    again = plot_linear_point(point, rows, tmp_path / "a2")
    for p, q in zip(first, again):
        assert p.read_bytes() == q.read_bytes(), p.name


def test_chart_data_survives_the_run_file(system, point, tmp_path):
    """What ``savant report`` draws: the chart data written into HDF5 and read back is
    the same data, and draws the same pixels."""
    _, _, rows = system
    with h5py.File(tmp_path / "c.h5", "w") as f:
        write_charts(f.create_group("charts", track_order=True), point)
    with h5py.File(tmp_path / "c.h5", "r") as f:
        back = read_charts(f["charts"])
    assert back.time_s == point.time_s
    assert [lp.label for lp in back.loops] == ["pitch", "yaw"]
    for a, b in zip(point.loops + point.root_loci, back.loops + back.root_loci):
        for name in a.__dataclass_fields__:
            x, y = getattr(a, name), getattr(b, name)
            assert (np.array_equal(x, y) if isinstance(x, np.ndarray) else x == y), name
    assert np.array_equal(back.pzmap.poles, point.pzmap.poles) and back.pzmap.dt == DT
    assert back.responses.outputs == point.responses.outputs and np.array_equal(back.responses.ramp,
                                                                                 point.responses.ramp)
    first = plot_linear_point(point, rows, tmp_path / "direct")
    again = plot_linear_point(back, rows, tmp_path / "reread")
    for p, q in zip(first, again):
        assert p.read_bytes() == q.read_bytes(), p.name


def test_command_responses_against_a_hand_simulation(system, point):
    """The step response against x[k+1] = A x[k] + B u[k] stepped by hand; the unit-area
    pulse response is (s[k] − s[k−1]) / dt and the ramp response dt Σ_{i<k} s[i], both
    consequences of linearity and time invariance."""
    _, closed, _ = system
    rs = point.responses
    assert rs.commands == ("pitch_command", "yaw_command")
    assert set(rs.outputs) == {"pitch_attitude", "yaw_attitude", "pitch_gimbal", "yaw_gimbal"}
    n = rs.time_s.size
    assert rs.time_s[1] == pytest.approx(DT) and rs.time_s[-1] == pytest.approx(chart_data.RESPONSE_DURATION_S)
    for i, cmd in enumerate(rs.commands):
        sub = closed[[closed.find_output(o) for o in rs.outputs], [closed.find_input(cmd)]]
        x = np.zeros(sub.nstates)
        y = np.empty((len(rs.outputs), n))
        for k in range(n):
            y[:, k] = sub.C @ x + sub.D[:, 0]
            x = sub.A @ x + sub.B[:, 0]
        np.testing.assert_allclose(rs.step[:, i], y, atol=1e-9)
        pulse = np.diff(np.concatenate([np.zeros((len(rs.outputs), 1)), y], axis=1), axis=1) / DT
        np.testing.assert_allclose(rs.impulse[:, i], pulse, atol=1e-7)
        ramp = DT * np.concatenate([np.zeros((len(rs.outputs), 1)), np.cumsum(y, axis=1)[:, :-1]], axis=1)
        np.testing.assert_allclose(rs.ramp[:, i], ramp, atol=1e-9)
    j = rs.outputs.index("pitch_attitude")
    assert rs.step[j, 0, -1] == pytest.approx(1.0, abs=0.1)  # tracks the step


def test_pole_zero_map_of_the_closed_loop(system, point):
    _, closed, _ = system
    pz = point.pzmap
    assert pz.dt == DT
    np.testing.assert_allclose(np.sort_complex(pz.poles), np.sort_complex(np.linalg.eigvals(closed.A)), atol=1e-9)
    np.testing.assert_allclose(pz.s_poles, np.log(pz.poles) / DT)
    assert pz.zeros.size >= 4  # the PID and flex-filter zeros of both axes
    for z in pz.zeros:  # transmission zeros of commands → attitudes: the system matrix loses rank
        sub = closed[[closed.find_output("pitch_attitude"), closed.find_output("yaw_attitude")], [0, 1]]
        rosenbrock = np.block([[z * np.eye(sub.nstates) - sub.A, -sub.B], [sub.C, sub.D]])
        assert np.linalg.svd(rosenbrock, compute_uv=False)[-1] < 1e-6 * max(1.0, abs(z))


def test_point_tag_and_margin_row():
    assert point_tag(55.0) == "t0055.0" and point_tag(123.45) == "t0123.5"
    row = MarginRow(10.0, "pitch", "gain", -8.46, 0.125, "rigid/aero")
    assert row.unit == "dB" and row.label() == "pitch GM -8.5 dB @ 0.125 Hz"
    with pytest.raises(ValueError, match="kind"):
        MarginRow(10.0, "pitch", "delay", 1.0, 1.0, "flex")


def test_nichols_annotates_every_margin(system, responses):
    _, _, rows = system
    fig = linear._nichols_figure(55.0, responses, rows, exclusion_zones=True)
    ax = fig.axes[0]
    texts = " | ".join(t.get_text() for t in ax.texts)
    for row in rows:
        assert f"{row.value:.1f}" in texts, row
    assert "55.0 s" in fig._suptitle.get_text()
    assert "deg" in ax.get_xlabel() and "dB" in ax.get_ylabel()
    assert ax.get_legend() is not None
    zones = [p for p in ax.patches if p.get_width() == pytest.approx(2 * linear.EXCLUSION_PHASE_DEG)]
    assert zones and all(p.get_height() == pytest.approx(2 * linear.EXCLUSION_GAIN_DB) for p in zones)
    assert any(z.get_x() == pytest.approx(-180.0 - linear.EXCLUSION_PHASE_DEG) for z in zones)
    plain = linear._nichols_figure(55.0, responses, rows, exclusion_zones=False).axes[0]
    assert not [p for p in plain.patches if p.get_width() == pytest.approx(2 * linear.EXCLUSION_PHASE_DEG)]


def test_phase_convention_puts_the_rigid_crossover_critical_point_at_minus_180(system, responses):
    _, _, rows = system
    for lp in responses:
        pm = min((r for r in rows if r.axis == lp.axis and r.kind == "phase"), key=lambda r: r.frequency_hz)
        i = int(np.argmin(np.abs(lp.f_hz - pm.frequency_hz)))
        assert lp.f_hz[i] == pytest.approx(pm.frequency_hz)  # margin frequencies are on the grid
        assert -360.0 < lp.phase_deg[i] <= 0.0
        assert lp.phase_deg[i] == pytest.approx(-180.0 + pm.value, abs=0.5)
        assert np.max(np.abs(np.diff(lp.phase_deg))) < 90.0  # unwrapped


def test_bode_axes_units(system, responses):
    _, _, rows = system
    fig = linear._bode_figure(55.0, responses, rows)
    ax_m, ax_p = fig.axes
    assert "dB" in ax_m.get_ylabel()
    assert "deg" in ax_p.get_ylabel() and "Hz" in ax_p.get_xlabel()
    assert ax_p.get_xscale() == "log"
    lo, hi = ax_p.get_xlim()
    assert lo == pytest.approx(0.01) and hi == pytest.approx(25.0)  # 0.01 Hz to Nyquist
    assert "55.0 s" in fig._suptitle.get_text() and fig.legends
    # the phase is drawn in degrees: it spans several multiples of 180, not of π
    phase = np.concatenate([line.get_ydata() for line in ax_p.lines if len(line.get_ydata()) > 100])
    assert np.ptp(phase) > 180.0


def test_resonance_is_resolved(system, responses):
    loops, _, _ = system
    lp = responses[0]
    f = np.linspace(0.9, 1.1, 20001)  # around the 1 Hz bending mode
    dense = 20 * np.log10(np.abs(np.asarray(ct.frequency_response(loops["pitch"], 2 * np.pi * f).complex).ravel()))
    near = (lp.f_hz > 0.9) & (lp.f_hz < 1.1)
    assert lp.mag_db[near].max() == pytest.approx(dense.max(), abs=0.2)
    assert lp.mag_db[near].min() == pytest.approx(dense.min(), abs=0.5)


def test_root_locus_closed_loop_poles_at_nominal_gain(system, point):
    loops, closed, _ = system
    loop = loops["pitch"]
    gains = chart_data.ROOT_LOCUS_GAINS
    rl = point.root_loci[0]
    assert rl.label == "pitch" and np.array_equal(rl.gains, gains)
    assert rl.branches.shape == (gains.size, loop.nstates) and 1.0 in gains
    # the closed loop of 1 + k L = 0 at every gain: eigenvalues of A − k B C / (1 + k D)
    for i in (0, gains.size // 2, gains.size - 1):
        k = gains[i]
        a_cl = loop.A - k * loop.B @ loop.C / (1.0 + k * loop.D[0, 0])
        exact = np.linalg.eigvals(a_cl)
        assert max(np.min(np.abs(rl.branches[i] - p)) for p in exact) < 1e-8
    assert np.max(np.abs(rl.nominal)) < 1.0  # and the closed loop is stable, as closed.poles() says
    assert np.max(np.abs(closed.poles())) < 1.0
    # branches are continuous: each pole moves less between successive gains than to any other
    steps = np.abs(np.diff(rl.branches, axis=0))
    assert np.all(steps.max(axis=0) < 0.5)


def test_response_and_pzmap_figures(point):
    fig = linear._response_figure(55.0, point.responses)
    assert len(fig.axes) == 6 and fig.legends and "55.0 s" in fig._suptitle.get_text()
    lefts, rights = fig.axes[:3], fig.axes[3:]  # attitude, and gimbal on twin axes
    assert all("attitude (deg)" in ax.get_ylabel() for ax in lefts)
    assert all("gimbal (deg)" in ax.get_ylabel() for ax in rights)
    assert "(s)" in lefts[-1].get_xlabel()
    step_attitude = lefts[0].lines[1].get_ydata()  # after the dashed command
    assert step_attitude[-1] == pytest.approx(1.0, abs=0.1)  # tracks the 1° step
    fig = linear._pzmap_figure(55.0, point.pzmap)
    assert fig.legends and "Re z" in fig.axes[0].get_xlabel() and "Hz" in fig.axes[1].get_ylabel()


def test_bad_loops_are_refused(system, tmp_path):
    _, closed, rows = system
    with pytest.raises(ValueError, match="at least one loop"):
        chart_data.point_charts(1.0, {}, closed, rows)
    with pytest.raises(ValueError, match="SISO"):
        chart_data.point_charts(1.0, {"pitch": closed}, closed, rows)
    assert not list(tmp_path.iterdir())


def test_margin_envelope(system, tmp_path):
    loops, _, _ = system
    rows = []
    for t in (10.0, 40.0, 70.0):
        rows += margin_rows(loops, t)
    rows.append(MarginRow(70.0, "yaw", "gain", float("inf"), float("nan"), "flex"))  # skipped
    req = {"rigid/aero": (6.0, 30.0), "slosh": (6.0, 30.0), "flex": (6.0, 30.0)}
    out = plot_margin_envelope(rows, tmp_path / "env" / "margin_envelope.png", requirements=req)
    assert out == tmp_path / "env" / "margin_envelope.png" and out.read_bytes()[:8] == PNG_MAGIC
    assert [f.name for f in out.parent.iterdir()] == ["margin_envelope.png"]
    fig = linear._envelope_figure(rows, req)
    ax_g, ax_p = fig.axes
    assert "dB" in ax_g.get_ylabel() and "deg" in ax_p.get_ylabel() and "(s)" in ax_p.get_xlabel()
    levels = {round(float(line.get_ydata()[0]), 6) for line in ax_g.lines}
    assert {6.0, -6.0} <= levels and 30.0 in {round(float(line.get_ydata()[0]), 6) for line in ax_p.lines}
    assert plot_margin_envelope(rows[:3], tmp_path / "plain.png").read_bytes()[:8] == PNG_MAGIC


def test_margin_envelope_marks_the_verdicts_it_is_given():
    """Judged rows get a black edge by their own verdict, not by the band values; failing
    points get a red line across both panels."""
    from dataclasses import replace

    rows = [MarginRow(10.0, "pitch", "gain", 12.0, 1.0, "rigid/aero", "rigid", False),
            MarginRow(10.0, "pitch", "gain", 3.0, 1.0, "flex", "flex_1", True),
            MarginRow(40.0, "pitch", "phase", 45.0, 0.3, "rigid/aero", "rigid", True)]
    req = {"rigid/aero": (6.0, 30.0), "flex": (6.0, 30.0)}
    fig = linear._envelope_figure(rows, req, failed_times=[10.0])
    ax_g, ax_p = fig.axes
    edges = {}
    for coll in ax_g.collections:
        (x, y), = coll.get_offsets()
        edges[float(y)] = tuple(coll.get_edgecolors()[0][:3])
    assert edges[12.0] == (0.0, 0.0, 0.0) and edges[3.0] != (0.0, 0.0, 0.0)
    for ax in (ax_g, ax_p):
        assert any(np.allclose(line.get_xdata(), [10.0, 10.0]) for line in ax.lines)
    unjudged = linear._envelope_figure([replace(r, meets_requirement=None) for r in rows], req)
    edges = {float(c.get_offsets()[0][1]): tuple(c.get_edgecolors()[0][:3]) for c in unjudged.axes[0].collections}
    assert edges[3.0] == (0.0, 0.0, 0.0) and edges[12.0] != (0.0, 0.0, 0.0)  # by the band's 6 dB


def test_no_pyplot(tmp_path):
    """The module never imports or uses pyplot.

    ``"matplotlib.pyplot" not in sys.modules`` cannot be the test: python-control imports
    pyplot when it is imported. Instead the module's source must not import it, and in a
    fresh interpreter where ``matplotlib.pyplot`` is a stub whose every attribute raises,
    importing the module and drawing every chart must still work.
    """
    assert not [name for name in imported_names(linear.__file__) if "pyplot" in name]

    code = PYPLOT_STUB + textwrap.dedent(f"""
        import warnings
        from pathlib import Path
        import control as ct
        from savant_cli.linear.charts import point_charts
        from savant_cli.plots.linear import MarginRow, plot_linear_point, plot_margin_envelope
        warnings.simplefilter("ignore")
        plant = ct.c2d(ct.ss([[0, 1], [0.4, 0]], [[0], [1.2]], [[1, 0], [0, 1]], [[0], [0]]), 0.02, "zoh")
        loop = ct.series(plant, ct.ss([], [], [], [[2.2, 1.75]], dt=0.02))
        cl = ct.feedback(loop, 1)
        closed = ct.ss(cl.A, cl.B, cl.C, cl.D, 0.02, inputs=["pitch_command"], outputs=["pitch_attitude"])
        rows = [MarginRow(1.0, "pitch", "phase", 45.0, 0.3, "rigid/aero")]
        out = Path({str(tmp_path)!r})
        plot_linear_point(point_charts(1.0, {{"pitch": loop}}, closed, rows), rows, out)
        plot_margin_envelope(rows, out / "env.png")
        print(len(list(out.glob("*.png"))))
    """)
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    res = subprocess.run([sys.executable, "-c", code], check=False, capture_output=True, text=True, env=env,
                         timeout=120)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == "7"


def test_plot_modules_only_draw():
    """Physics out of the plots: no plot module imports python-control, scipy or the
    simulation; what they draw is computed elsewhere (linear/, the studies)."""
    for path in sorted((ROOT / "savant_cli" / "plots").glob("*.py")):
        names = imported_names(path)
        bad = [n for n in names if n.split(".")[0] in ("control", "scipy", "numba")
               or n.startswith(("savant_cli.sim", "savant_cli.models", "savant_cli.studies"))]
        assert not bad, (path.name, bad)
