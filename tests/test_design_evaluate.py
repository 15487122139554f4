"""Judging candidate flight controls on frozen operating points (``linear/evaluate.py``):
the same margins and verdict as ``study=linear`` for the shipped controller, and a
candidate's changes where they must be."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from conftest import linear_settings
from savant_cli.config import shipped_option
from savant_cli.linear.evaluate import freeze, judge_controller
from savant_cli.linear.point_analysis import analyse
from savant_cli.models.fcs import D_GAINS, FCS_STACK
from test_linear import _point

DT = 0.02
ARES_I = shipped_option("requirements", "ares_i")


@pytest.fixture(scope="module")
def max_q():
    model, snap = _point(["flex=on", "flex.n_modes=4", "slosh=on", "twd=on"], 55.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        point = freeze(model, snap, DT)
        reference = analyse(model, snap, linear_settings([55.0]), DT, ARES_I)
    return model, snap, point, reference


def test_a_frozen_point_judges_the_shipped_controller_as_the_linear_study(max_q):
    model, snap, point, ref = max_q
    assert point.phase == FCS_STACK and point.phase_name == "stack"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rows, peaks, v = judge_controller(point, model.fcs, DT, ARES_I, gains=snap.d[D_GAINS:D_GAINS + 8])
    # with the snapshot's gains: the very same loops, hence the same numbers
    assert [(r.axis, r.kind, r.mode) for r in rows] == [(r.axis, r.kind, r.mode) for r in ref.rows]
    np.testing.assert_allclose([r.value for r in rows], [r.value for r in ref.rows], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose([r.frequency_hz for r in rows], [r.frequency_hz for r in ref.rows], rtol=1e-9)
    assert [r.meets_requirement for r in rows] == [r.meets_requirement for r in ref.rows]
    assert v.passed == ref.verdict.passed and v.worst.text() == ref.verdict.worst.text()
    assert v.checks[-1].value == pytest.approx(ref.scalars["closed_loop_max_real_1_per_s"], rel=1e-9, abs=1e-12)
    assert [p.mode for p in peaks] == [p.mode for p in ref.peaks]
    # scheduled at the point's own altitude (the snapshot holds the previous cycle's
    # gains, 20 ms earlier): the same margins to well within their printed precision
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rows2, _, v2 = judge_controller(point, model.fcs, DT, ARES_I)
    assert [(r.axis, r.kind, r.mode) for r in rows2] == [(r.axis, r.kind, r.mode) for r in ref.rows]
    for a, b in zip(rows2, ref.rows):
        assert a.value == pytest.approx(b.value, abs=0.01 if a.kind == "gain" else 0.05)
    assert v2.passed == ref.verdict.passed


def test_a_candidate_changes_the_loop_it_should(max_q):
    """Doubling the attitude gain Kp of the stack schedule raises the loop gain at low
    frequency: the aerodynamic gain-reduction margin grows by 20 log10 of the ratio of the
    total attitude gains (Kp + Kir), within the share the rate path takes there."""
    model, snap, point, ref = max_q
    ft = model.fcs
    shipped = ft.gain_data.copy()
    data = ft.gain_data.copy()
    data[0, :, 0] *= 2.0  # Kp, pitch
    data[0, :, 4] *= 2.0  # Kp, yaw
    candidate = ft._replace(gain_data=data)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rows, _, _ = judge_controller(point, candidate, DT, ARES_I)
    base = [r for r in ref.rows if r.mode == "aero" and r.axis == "pitch"][0]
    new = [r for r in rows if r.mode == "aero" and r.axis == "pitch"][0]
    kp, kir = snap.d[D_GAINS], snap.d[D_GAINS + 3]
    expected = 20 * np.log10((2 * kp + kir) / (kp + kir))
    assert new.value - base.value == pytest.approx(-expected, abs=0.35 * expected)  # more negative: larger reduction margin
    assert np.array_equal(model.fcs.gain_data, shipped)  # the model's own tables untouched
