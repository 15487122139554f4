"""Margins labelled by the mode that makes them (issue 12 item 6): on a loop assembled
from known parts, and on the default vehicle at full fidelity against the model's own
slosh and bending frequencies."""

from __future__ import annotations

import warnings

import control as ct
import numpy as np
import pytest

from savant_cli.linear.margins import Bands, loop_margins
from savant_cli.linear.modes import MarginLabeler, band_of
from savant_cli.models import layout, slosh as slosh_model
from savant_cli.sim.plant import derivative

DT = 0.02


def _synthetic_loop() -> tuple[ct.StateSpace, np.ndarray]:
    """A rigid PD loop k (1 + 0.6 s) / s² with a lightly damped 2 Hz mode added on (ζ =
    0.005, |L| = 3 at its resonance, so the loop crosses the unit circle on either side
    of it), sampled at 50 Hz; the state groups are known by construction."""
    rigid = ct.ss(ct.tf([0.8 * 0.6, 0.8], [1.0, 0.0, 0.0]))  # crossover near 0.08 Hz
    wf, zf = 2 * np.pi * 2.0, 0.005
    mode = ct.ss(ct.tf([2 * zf * wf * 3.0 * wf], [1.0, 2 * zf * wf, wf * wf]))
    lag = ct.ss(ct.tf([1.0], [1.0 / (2 * np.pi * 8.0), 1.0]))  # an 8 Hz filter in the path
    loop = ct.c2d(ct.series(ct.parallel(rigid, mode), lag), DT, "zoh")
    # parallel() stacks rigid then mode states; series() puts the lag's state after them
    groups = np.array(["rigid"] * rigid.nstates + ["flex_1"] * mode.nstates + ["filter"] * lag.nstates)
    return loop, groups


def test_crossings_of_a_loop_built_from_known_parts():
    loop, groups = _synthetic_loop()
    labeler = MarginLabeler(loop, groups, aero_unstable=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rows = loop_margins(loop, 0.0, "pitch", Bands(), labeler=labeler)
    near_mode = [r for r in rows if abs(r.frequency_hz - 2.0) < 0.1]
    assert near_mode and all(r.mode == "flex_1" and r.band == "flex" for r in near_mode)
    low = [r for r in rows if r.kind == "phase" and r.frequency_hz < 0.5]
    assert low and all(r.mode == "rigid" and r.band == "rigid/aero" for r in low)
    assert not [r for r in rows if r.mode == "filter"]  # a path group labels nothing


def test_band_of_each_label():
    assert [band_of(m) for m in ("rigid", "aero", "integrator", "slosh_lox", "slosh_lh2", "flex_3")] == \
        ["rigid/aero"] * 3 + ["slosh", "slosh", "flex"]


@pytest.fixture(scope="module")
def full_fidelity_margins():
    from conftest import linear_settings
    from savant_cli.linear.point_analysis import analyse
    from test_linear import _point

    out = {}
    for t in (55.0, 180.0):
        model, snap = _point(["flex=on", "flex.n_modes=4", "slosh=on", "twd=on"], t)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            a = analyse(model, snap, linear_settings([t]), DT)
        rows, extra = a.rows, a.scalars
        aux = np.zeros(layout.N_AUX)
        derivative(snap.t, snap.x, snap.u, model.p, model.packed_tables, aux, np.zeros(snap.x.size))
        slosh_hz = aux[slosh_model.A_FREQUENCY:slosh_model.A_FREQUENCY + 2] / (2 * np.pi)
        stage = 0 if t < 130.0 else 2
        flex_hz = model.tables.flex_freq[stage, :4] / (2 * np.pi)
        out[t] = (rows, extra, slosh_hz, flex_hz)
    return out


def test_default_vehicle_margins_are_labelled_by_their_modes(full_fidelity_margins):
    """At max-Q the phase crossing near the closed-loop bandwidth is the rigid-body one
    (it was labelled slosh by the frequency window), the −9.7 dB gain reduction is the
    aerodynamic pole's; in vacuum (180 s) the gain reduction is the integrator's. Every
    phase crossing labelled by a bending mode (its resonance's phase swing) lies within
    10 % of that mode's frequency in the modal data, a gain crossing within a factor 2
    (off the resonance a mode labels the phase crossover where its skirt dominates |L|:
    at 180 s the upper stage's 5.3 and 12.0 Hz crossovers either side of its 9.5 Hz mode,
    shaped by the notch there), and every one labelled by a slosh tank within a factor 1.5 of that tank's
    spring-mass frequency (the slosh model's own, uncoupled: on the vehicle the coupled
    LOX pole sits 19 % above it at 180 s, 0.444 against 0.373 Hz, and the tank's loop
    excursion reaches beyond it) and below the first bending mode."""
    rows55, extra55, _, _ = full_fidelity_margins[55.0]
    pitch = [r for r in rows55 if r.axis == "pitch"]
    bandwidth = extra55["pitch_bandwidth_hz"]
    rigid_pm = min((r for r in pitch if r.kind == "phase"), key=lambda r: abs(r.frequency_hz - bandwidth))
    assert rigid_pm.mode == "rigid" and rigid_pm.band == "rigid/aero" and rigid_pm.frequency_hz < 0.4
    assert [r.mode for r in pitch if r.kind == "gain" and r.value < 0] == ["aero"]
    rows180 = full_fidelity_margins[180.0][0]
    assert [r.mode for r in rows180 if r.axis == "pitch" and r.kind == "gain" and r.value < 0] == ["integrator"]
    for t, (rows, _, slosh_hz, flex_hz) in full_fidelity_margins.items():
        for r in rows:
            if r.mode.startswith("slosh"):
                f = slosh_hz[0 if r.mode == "slosh_lox" else 1]
                assert f / 1.5 < r.frequency_hz < min(1.5 * f, flex_hz.min()), (t, r)
            elif r.mode.startswith("flex"):
                f = flex_hz[int(r.mode.split("_")[1]) - 1]
                assert f / 2.0 < r.frequency_hz < 2.0 * f, (t, r)
                # a crossing on the resonance itself (its phase swing) lies within 10 %
                if r.kind == "phase":
                    assert abs(r.frequency_hz - f) < 0.1 * f, (t, r)
        assert {r.band for r in rows} <= {"rigid/aero", "slosh", "flex"}
    # the baffled tanks still make crossings in vacuum (the LOX mode at 180 s): the slosh
    # check above is not empty
    assert any(r.mode.startswith("slosh") for r in rows180)
