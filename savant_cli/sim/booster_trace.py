"""The strap-on boosters' nominal vacuum thrust and mass against mission time, before
any flight: what the first stage's nominal trace (``sim/build.py::first_stage_march``)
adds to the stage's own thrust and the stack's mass while the boosters are attached."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from savant_cli import constants
from savant_cli.models.propulsion import table_impulse
from savant_cli.sim import engine
from savant_cli.vehicle import Vehicle

#: Samples of the boosters' trace.
N_SAMPLES = 20001


class BoosterTrace(NamedTuple):
    """The boosters' nominal trace: summed vacuum thrust (N) and mass (kg) at
    ``time_s`` (s), their predicted jettison time (s), and each booster's vacuum thrust
    (N) and propellant left (kg), ``(n_boosters, n_samples)``."""

    time_s: np.ndarray
    thrust_vac_N: np.ndarray
    mass_kg: np.ndarray
    jettison_s: float
    each_thrust_vac_N: np.ndarray
    each_propellant_kg: np.ndarray

    def at(self, t: float) -> tuple[float, float]:
        """Their summed vacuum thrust (N) and mass (kg) at ``t`` (s): zero once jettisoned."""
        if t >= self.jettison_s:
            return 0.0, 0.0
        return float(np.interp(t, self.time_s, self.thrust_vac_N)), float(np.interp(t, self.time_s, self.mass_kg))

    def each_at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Each booster's vacuum thrust (N) and propellant left (kg) at ``t`` (s), while
        they are attached (before :attr:`jettison_s`)."""
        thrust = np.array([np.interp(t, self.time_s, f) for f in self.each_thrust_vac_N])
        return thrust, np.array([np.interp(t, self.time_s, m) for m in self.each_propellant_kg])


def booster_trace(vehicle: Vehicle) -> BoosterTrace | None:
    """Each booster burning ``k F(k t)`` of its table at its burn rate ``k`` (its load in
    the table's shape, as the plant burns it, ``models/boosters.py``), its mass its own
    table's at the propellant left, summed; the jettison predicted by its trigger: a
    booster's thrust fraction (the first sample after that booster's peak, once armed,
    below the fraction of it), or its delay alone; a trigger on another quantity, which
    no trace can place, at the end of the burn (None: no boosters)."""
    b = vehicle.boosters
    if b is None:
        return None
    rates = np.ones(b.count) if b.burn_rate is None else np.asarray(b.burn_rate, float)
    t = np.linspace(0.0, float(b.thrust_time_s[-1]) / float(rates.min()), N_SAMPLES)
    flow_per_thrust = b.propellant_kg / table_impulse(b.thrust_time_s, b.thrust_vac_N)
    thrusts, left, mass = [], [], np.zeros(t.size)
    for k, table in zip(rates, b.mass):
        flow = k * flow_per_thrust * np.interp(k * t, b.thrust_time_s, b.thrust_vac_N, left=0.0, right=0.0)
        burned = np.concatenate([[0.0], np.cumsum(0.5 * (flow[1:] + flow[:-1]) * np.diff(t))])
        left.append(np.maximum(b.propellant_kg - burned, 0.0))
        mass += np.interp(left[-1], table.propellant_kg, table.mass_kg)
        thrusts.append(constants.G0 * b.isp_vac_s * flow)
    trig = vehicle.events.trigger(engine.EV_BOOSTER_JETTISON)
    jettison = float(t[-1])
    if trig.booster is not None:
        f = thrusts[trig.booster]
        start = max(int(np.argmax(f)), int(np.searchsorted(t, trig.delay_s)))
        below = np.nonzero(f[start:] < trig.threshold * f.max())[0]
        jettison = float(t[start + below[0]]) if below.size else jettison
    elif trig.quantity is None:
        jettison = float(trig.delay_s)
    return BoosterTrace(t, np.sum(thrusts, axis=0), mass, jettison, np.array(thrusts), np.array(left))
