"""The fast frequency response and the margin routines against python-control's own:
``StateSpace.frequency_response``, ``stability_margins`` (FRD method on a very fine grid)
and ``disk_margins``."""

from __future__ import annotations

import control as ct
import numpy as np
import pytest

from savant_cli.linear.margins import Bands, disk_margins, frequency_grid, loop_margins
from savant_cli.linear.response import FastResponse

DT = 0.02


def _flex_loop() -> ct.StateSpace:
    """PD on an unstable rigid plant times a lightly damped 1 Hz mode, with an integrator
    and its repeated pole at z = 1 (a defective A), discretized at 50 Hz."""
    s = ct.tf("s")
    rigid = 1.2 * (1.5 * s + 1.0) / (s * s - 0.4)
    mode = 1.0 + 0.2 * s * (2 * np.pi) / (s * s + 2 * 0.01 * (2 * np.pi) * s + (2 * np.pi) ** 2)
    integ = (s + 0.3) / s
    return ct.ss(ct.c2d(ct.ss(rigid * mode * integ), DT, "zoh"))


def _mimo_loop() -> ct.StateSpace:
    """2x2 coupled loop: two copies of the flex loop mixed by a constant coupling."""
    g = _flex_loop()
    couple = ct.ss([], [], [], [[1.0, 0.3], [-0.2, 1.0]], DT)
    return ct.append(g, ct.ss(ct.c2d(ct.ss(ct.tf(2.0, [1.0, 2.0])), DT, "zoh"))) * couple


@pytest.mark.parametrize("system", ["siso", "mimo", "continuous", "defective"])
def test_fast_response_equals_control(system):
    if system == "siso":
        sys = _flex_loop()
    elif system == "mimo":
        sys = _mimo_loop()
    elif system == "continuous":
        sys = ct.rss(12, 2, 3, strictly_proper=False)
    else:  # a Jordan block: triple pole at z = 1, which an eigenvector form cannot take
        a = np.eye(3) + np.diag([1.0, 1.0], 1)
        sys = ct.ss(a, [[0.0], [0.0], [1.0]], [[1.0, 0.5, 0.2]], [[0.1]], DT)
    w = np.geomspace(0.05, np.pi / DT * 0.99 if sys.isdtime() else 500.0, 400)
    fr = FastResponse(sys)
    ref = sys.frequency_response(w).complex.reshape(sys.noutputs, sys.ninputs, -1)
    got = fr(w)
    assert got.shape == ref.shape
    assert np.abs(got - ref).max() <= 1e-8 * np.abs(ref).max()
    one = fr(w[123])  # the single-frequency path
    assert np.allclose(one[:, :, 0], ref[:, :, 123], rtol=1e-9, atol=1e-12 * np.abs(ref).max())
    ref_poles = np.linalg.eigvals(sys.A)
    assert all(np.abs(ref_poles - p).min() < 1e-5 * max(1.0, abs(p)) for p in fr.poles)


def test_loop_margins_equal_control_stability_margins():
    """Every crossing python-control finds on a very fine FRD grid, with the same value."""
    loop = _flex_loop()
    rows = loop_margins(loop, 0.0, "pitch", Bands(flex_from_hz=0.7))
    w = np.geomspace(2 * np.pi * 0.01, np.pi / DT, 8000)[1:-1]
    gm, pm, _, wg, wp, _ = ct.stability_margins(ct.frd(loop, w), returnall=True, method="frd")
    ref_gain = sorted((float(f) / (2 * np.pi), 20 * np.log10(g)) for g, f in zip(gm, wg) if np.isfinite(g) and g > 0)
    ref_phase = sorted((float(f) / (2 * np.pi), float(p)) for p, f in zip(pm, wp))
    gain = [(r.frequency_hz, r.value) for r in rows if r.kind == "gain"]
    phase = [(r.frequency_hz, r.value) for r in rows if r.kind == "phase"]
    assert len(gain) == len(ref_gain) >= 1 and len(phase) == len(ref_phase) >= 3
    for (f, v), (fr_, vr) in zip(gain, ref_gain):
        assert f == pytest.approx(fr_, rel=1e-5) and v == pytest.approx(vr, abs=1e-4)
    for (f, v), (fr_, vr) in zip(phase, ref_phase):
        assert f == pytest.approx(fr_, rel=1e-5) and v == pytest.approx(vr, abs=1e-3)
    assert {r.band for r in rows} == {"rigid/aero", "flex"}


@pytest.mark.parametrize("system", ["siso", "mimo"])
def test_disk_margins_equal_control_disk_margins(system):
    """Same grid, same numbers as control.disk_margins (μ bound for the MIMO loop)."""
    loop = _flex_loop() if system == "siso" else _mimo_loop()
    got = disk_margins(loop)
    w = frequency_grid(loop)
    dm, dgm, dpm = ct.disk_margins(loop, w, skew=0.0)
    assert got["disk_margin"] == pytest.approx(dm, rel=1e-6)
    assert got["disk_gain_margin_dB"] == pytest.approx(dgm, rel=1e-6)  # control returns dB
    assert got["disk_phase_margin_deg"] == pytest.approx(dpm, rel=1e-6)
    assert 0.0 < got["disk_margin"] < 2.0
