"""Which open-loop mode makes a margin: each crossing of a broken loop labelled by the
pole(s) that dominate the loop near its frequency (issue 12 item 6).

The loop's states are named by where they come from (:func:`state_groups`): the plant's
``rigid`` (velocity, attitude, rate), ``actuator``, ``slosh_<tank>`` (one per sloshing tank) and
``flex_<n>`` states, the gyro filters (``sensor``), the loop delay (``delay``), and the
flight control's ``integrator`` and ``filter`` states. Each eigenvalue λ_j of the loop's
A is shared among the groups by its participation factors |v_kj w_jk| (right and left
eigenvectors), and contributes r_j / (z − λ_j) to L(z), r_j = (C v_j)(w_j B).
The group of a pole is the one it participates in most.

A crossing at f is labelled by

1. the lightly damped plant mode (slosh or flex, ζ < 0.1) nearest to f in units of its
   half-power half-width ζ f_n, when it is within :data:`RESONANCE_WIDTHS` of them and its
   contribution is at least :data:`RESONANCE_SHARE` of |L|: the loop's excursion around
   that resonance makes the crossing;
2. otherwise the physical group whose poles contribute most at f: the rigid body (its
   poles and the integrators', one nearly defective cluster at z = 1 summed as one), a
   slosh tank or a flex mode; each pole counts wholly for the group it participates in
   most, and the actuator, the filters, the gyros and the delay are in every path and
   label nothing. A rigid gain-reduction margin (< 0 dB) reads
   ``aero`` where the plant has an aerodynamically unstable rigid pole (the margin exists
   because of it) and ``integrator`` where it has none (in vacuum: the conditional
   stability of the PID's integrator on the rigid double integrator).

The band of the requirement (``rigid/aero``, ``slosh``, ``flex``) follows from the label.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import control as ct
import numpy as np

from savant_cli.linear.plant import PlantLinearization

#: A resonance labels crossings within this many half-power half-widths of it ...
RESONANCE_WIDTHS = 10.0
#: ... whose loop response it makes up at least this fraction of.
RESONANCE_SHARE = 0.25
#: An unstable real rigid pole faster than this (1/s) is the aerodynamic one; slower
#: ones are the frozen-time trajectory's drift (orbital and gravity-turn dynamics).
AERO_POLE_MIN = 0.05
#: Points of the grid on which a bending mode's peak loop gain is found.
PEAK_POINTS = 401
#: Groups in every loop path: they label no crossing.
PATH_GROUPS = ("actuator", "filter", "sensor", "delay")
#: The low-frequency groups: their poles form one cluster near z = 1.
LOW_GROUPS = ("rigid", "integrator")
#: Flight-control states per axis (``linear/loops.py::controller_lti``): the attitude
#: integrator, the rate-path filter (two 4th-order sections), the rate integrator and its
#: filter.
CONTROLLER_AXIS = ("integrator",) + ("filter",) * 8 + ("integrator",) + ("filter",) * 8
#: The roll law's states (roll by the engines' gimbals): the attitude integrator and the
#: roll-rate filter (two 4th-order sections).
CONTROLLER_ROLL = ("integrator",) + ("filter",) * 8


def plant_group(name: str) -> str:
    """Group of a linear plant state by its name (``linear/plant.py::linear_states``)."""
    if name.startswith("slosh_"):  # slosh_<tank>_{y,z,y_dot,z_dot}: the tank's group
        return name.removesuffix("_dot").rsplit("_", 1)[0]
    if name.startswith("flex_q"):
        return "flex_" + name[len("flex_q"):].split("_")[0]
    if re.fullmatch(r"d[py]\d*(_dot|_ddot|_piston)?", name) or name.startswith("valve"):
        return "actuator"  # every engine's channels (dp, dy, dp2 …), the simplex piston and valves
    return "rigid"


def band_of(mode: str) -> str:
    """The requirement band of a mode label."""
    if mode.startswith("slosh"):
        return "slosh"
    if mode.startswith("flex"):
        return "flex"
    return "rigid/aero"


def state_groups(lin: PlantLinearization, plant: ct.StateSpace, controller: ct.StateSpace) -> np.ndarray:
    """Group of every state of a loop built by ``linear/loops.py::assemble``: the sampled
    plant's (its linear states, then 2 gyro-filter states per gyro output, then the delay
    states), then the flight control's."""
    groups = [plant_group(s) for s in lin.sys.state_labels]
    n_gyro = 2 * sum(1 for o in lin.sys.output_labels if o.startswith("gyro_"))
    groups += ["sensor"] * n_gyro + ["delay"] * (plant.nstates - len(groups) - n_gyro)
    control = list(CONTROLLER_AXIS) * 2 + (list(CONTROLLER_ROLL) if controller.noutputs > 2 else [])
    if controller.nstates != len(control):
        raise ValueError(f"flight control with {controller.nstates} states; expected {len(control)}")
    return np.array(groups + control)


@dataclass(frozen=True)
class ModePeak:
    """The peak loop gain at one bending mode of one loop at one point.

    Attributes
    ----------
    time_s : float
        Flight time of the point (s).
    axis : str
        Loop: ``"pitch"`` or ``"yaw"``.
    mode : str
        ``flex_<n>``.
    peak_dB : float
        Largest |L| near the mode's resonance (dB); its attenuation is ``-peak_dB``.
    frequency_hz : float
        Where the peak is (Hz).
    """

    time_s: float
    axis: str
    mode: str
    peak_dB: float
    frequency_hz: float


class MarginLabeler:
    """Labels the crossings of one discrete SISO loop (see the module notes).

    Parameters
    ----------
    loop : control.StateSpace
        The broken loop (discrete).
    groups : numpy.ndarray
        Group name of each of its states (:func:`state_groups`).
    aero_unstable : bool
        Whether the plant has an aerodynamically unstable rigid pole at this point.
    """

    def __init__(self, loop: ct.StateSpace, groups: np.ndarray, aero_unstable: bool) -> None:
        if groups.size != loop.nstates:
            raise ValueError(f"{groups.size} state groups for a loop of {loop.nstates} states")
        self.dt = float(loop.dt)
        self.aero_unstable = aero_unstable
        lam, v = np.linalg.eig(np.asarray(loop.A))
        w = np.linalg.inv(v)
        self.poles = lam
        self.residues = (np.asarray(loop.C) @ v).ravel() * (w @ np.asarray(loop.B)).ravel()
        self.d = float(np.asarray(loop.D).ravel()[0])
        part = np.abs(v * w.T)
        part /= np.maximum(part.sum(axis=0, keepdims=True), 1e-300)
        self.names = [g for g in dict.fromkeys(groups) if g not in PATH_GROUPS]
        share = np.array([part[groups == g].sum(axis=0) for g in self.names])  # (groups, poles)
        path = np.array([part[groups == g].sum(axis=0) for g in PATH_GROUPS if g in groups]).sum(axis=0)
        # the group each pole belongs to most (−1: a path group's)
        self.owner = np.where(share.max(axis=0) >= path, np.argmax(share, axis=0), -1)
        with np.errstate(divide="ignore", invalid="ignore"):  # a pole at z = 0 (a pure delay): s = −∞
            s = np.log(lam.astype(complex)) / self.dt
            self.zeta = -s.real / np.maximum(np.abs(s), 1e-300)
        self.freq_hz = np.abs(s.imag) / (2 * np.pi)
        self.half_width_hz = np.abs(s.real) / (2 * np.pi)

    def _by_group(self, f_hz: float) -> tuple[np.ndarray, float]:
        """|contribution| of every group's poles to L at f, and |L| there."""
        z = np.exp(2j * np.pi * f_hz * self.dt)
        contrib = self.residues / (z - self.poles)
        total = abs(contrib.sum() + self.d)
        owner = self.owner
        # each pole wholly to its group; the rigid and integrator poles, a nearly defective
        # cluster at z = 1 whose single contributions are ill-conditioned, as one sum
        low = [g for g, name in enumerate(self.names) if name in LOW_GROUPS]
        by_group = np.array([abs(contrib[np.isin(owner, low) if g in low else owner == g].sum())
                             for g in range(len(self.names))])
        return by_group, total

    def _resonant(self, g: int) -> np.ndarray:
        """Indices of the lightly damped (0 < ζ < 0.1) oscillatory poles of group g."""
        return np.flatnonzero((self.owner == g) & (self.zeta < 0.1) & (self.zeta > 0) & (self.freq_hz > 0))

    def label(self, f_hz: float, kind: str, value: float) -> tuple[str, str]:
        """``(mode, band)`` of a ``kind`` (gain/phase) crossing of margin ``value`` at f."""
        by_group, total = self._by_group(f_hz)
        best, best_dist = None, np.inf
        for g, name in enumerate(self.names):
            if not name.startswith(("slosh", "flex")):
                continue
            for j in self._resonant(g):
                dist = abs(f_hz - self.freq_hz[j]) / max(self.half_width_hz[j], 1e-9)
                if dist <= RESONANCE_WIDTHS and by_group[g] >= RESONANCE_SHARE * total and dist < best_dist:
                    best, best_dist = name, dist
        if best is None:
            best = self.names[int(np.argmax(by_group))]
            if best in LOW_GROUPS:
                best = "rigid"
        mode = best
        if mode == "rigid" and kind == "gain" and value < 0.0:
            # a gain-reduction margin of the rigid body: the aerodynamic divergence pole's
            # where it exists; without it (in vacuum) the integrator's phase lag's, the
            # conditional stability of a PID on a double integrator
            mode = "aero" if self.aero_unstable else "integrator"
        return str(mode), band_of(str(mode))


    def flex_peaks(self, response, time_s: float, axis: str) -> list[ModePeak]:
        """The loop's peak gain at each bending mode it carries: for every ``flex_<n>``
        group with a lightly damped pole whose contribution is at least
        :data:`RESONANCE_SHARE` of |L| at its frequency, the largest |L| within
        :data:`RESONANCE_WIDTHS` half-power half-widths of it (the mode's attenuation is
        its negative). ``response``: the loop's
        :class:`savant_cli.linear.response.FastResponse`."""
        out = []
        for g, name in enumerate(self.names):
            if not name.startswith("flex"):
                continue
            carried = {}
            for j in self._resonant(g):
                by_group, total = self._by_group(self.freq_hz[j])
                if by_group[g] >= RESONANCE_SHARE * total:
                    carried[j] = by_group[g]
            if not carried:
                continue
            j = max(carried, key=carried.get)
            f = self.freq_hz[j] + np.linspace(-RESONANCE_WIDTHS, RESONANCE_WIDTHS, PEAK_POINTS) * self.half_width_hz[j]
            f = f[(f > 0.0) & (f < 0.5 / self.dt)]
            mag = np.abs(response.siso(2 * np.pi * f))
            k = int(np.argmax(mag))
            out.append(ModePeak(time_s, axis, str(name), float(20 * np.log10(mag[k])), float(f[k])))
        return out


def aero_unstable(lin: PlantLinearization) -> bool:
    """Whether the plant has an unstable real pole carried by its rigid states (the
    aerodynamic divergence of a vehicle whose centre of pressure is ahead of its CG;
    real to 1 %: the pitch and yaw poles of a symmetric vehicle are a double pole that
    the eigenvalue solver splits into a pair ±1e-4 j)."""
    a = np.asarray(lin.sys.A)
    lam, v = np.linalg.eig(a)
    w = np.linalg.inv(v)
    part = np.abs(v * w.T)
    rigid = np.array([plant_group(s) == "rigid" for s in lin.sys.state_labels])
    for j, p in enumerate(lam):  # faster than the frozen-time trajectory drift (0.05 1/s)
        if p.real > AERO_POLE_MIN and abs(p.imag) < 1e-2 * abs(p) and part[rigid, j].sum() > 0.5 * part[:, j].sum():
            return True
    return False
