"""Reproducible generator of the upper-stage propellant-slosh tables of the default vehicle.

Run ``python -m savant_cli.datagen.ares_i_slosh [--out DIR]``; it writes
``slosh_lox.csv`` and ``slosh_lh2.csv`` into ``conf/vehicle/ares_i/`` of the source tree
(or ``DIR``). The output is a pure function of the constants below: tank radius and loads
are the public figures of ``shared/data/ares_i_public_data.md`` (taken from
:mod:`savant_cli.datagen.ares_i_tables`, the single place they are written), liquid
properties are estimates. Marks: **[P]** public, **[E]** estimate, **[D]** derived;
``conf/vehicle/ares_i/slosh_README.md`` cites each one.

Model — first antisymmetric mode of a flat-bottom upright circular cylinder
---------------------------------------------------------------------------
Linear potential-flow sloshing, spring-mass analogy of NASA SP-106 (Abramson ed., "The
Dynamic Behavior of Liquids in Moving Containers", 1966, ch. 2 and 6) and Dodge ("The New
Dynamic Behavior of Liquids in Moving Containers", SwRI 2000, ch. 1 and 3). Tank radius
``R``, liquid fill height ``h`` above the flat bottom, axial (settling) acceleration
``a``, liquid mass ``m_F = rho pi R^2 h``, ``xi = 1.8412`` the first root of
``J1'(xi) = 0``, ``lambda = xi h / R``:

* frequency ``omega1^2 = (xi a / R) tanh(lambda)``; it scales with ``sqrt(a)``;
* slosh mass ``m1 = m_F (2 R / (xi (xi^2 - 1) h)) tanh(lambda)``
  ``= 2 rho pi R^3 tanh(lambda) / (xi (xi^2 - 1))`` (no ``0/0`` at ``h = 0``);
  ``m1 / m_F -> 2 / (xi^2 - 1) = 0.837`` as ``h -> 0``, ``-> 0`` as ``h/R`` grows;
* spring-mass height above the tank bottom
  ``z1 = h - (2 R / xi) tanh(lambda / 2)``, i.e. ``h/2 - (2R/xi) tanh(xi h / (2R))``
  above the liquid's centre of mass (positive towards the free surface) — the
  spring-mass result of SP-106 ch. 6 (Table 6.1) and Dodge ch. 3 as it is usually quoted.
  Transcriptions of those tables differ (typos), so it is re-derived here by moment
  equivalence (below; checked by numerical quadrature in ``tests/test_slosh_tables.py``).
  ``0 <= z1 <= h`` for every ``h`` (``tanh y <= y``); ``z1 ~ xi^2 h^3 / (12 R^2)`` for a
  shallow fill; below the liquid CG while ``h/R < 2.08``; ``z1 -> h - 2R/xi`` (a fixed
  1.09 R below the free surface) for a deep one;
* smooth-wall viscous damping ratio (Mikishev and Dorozhkin, as quoted in SP-106 ch. 4
  and Dodge ch. 3; SP-106 gives the logarithmic decrement ``delta``, ``zeta = delta / 2 pi``):
  ``zeta = 4.98 nu^(1/2) R^(-3/4) a^(-1/4) [1 + 0.318 / sinh(1.84 h'/R)
  (1 + (1 - h'/R) / cosh(1.84 h'/R))] / (2 pi)`` with ``h' = max(h, 0.1 R)``: the
  bottom-boundary-layer term grows like ``R / h`` without bound as ``h -> 0``, where the
  formula (and the flat-bottom equivalent of a domed tank) is no longer meaningful; below
  ``h/R = 0.1`` the depth factor is held at its ``h/R = 0.1`` value (continuous, finite).

Spring-mass height — moment equivalence
---------------------------------------
With the tank held still, mode 1 is ``Phi = A(t) J1(k r) cos(theta) cosh(k z) / cosh(k h)``,
``k = xi / R``, ``z`` up from the bottom, and the free-surface condition gives
``omega1^2 = a k tanh(k h)``. Its pressure ``p ~ J1(k r) cos(theta) cosh(k z)`` acts on
the wall (lateral force ``F``, moment about the bottom centre ``M_w``) and on the bottom
(moment ``M_b``, using ``J2(xi) = J1(xi) / xi`` at the root of ``J1'``):
``F ~ sinh(kh) / k``, ``M_w ~ h sinh(kh)/k - (cosh(kh) - 1)/k^2``, ``M_b ~ 1/k^2``, so
the resultant acts at ``(M_w + M_b)/F = h - (cosh(kh) - 2) / (k sinh(kh))`` (the hinge
of the equivalent pendulum). The spring-mass model must reproduce ``F`` with its spring
force ``k1 u`` (``u`` the mass's displacement) and the moment ``M`` with the spring force
at the mass height ``z1`` *plus* the moment of the displaced mass's weight, ``m1 a u``:
``M = F (z1 + a / omega1^2)``, hence ``z1 = h - (cosh(kh) - 2)/(k sinh(kh)) -
coth(kh)/k = h - (2/k) tanh(kh/2)``. The pendulum of length ``L1 = a / omega1^2`` hung
from that hinge puts its bob at the same height, as it must.

Tables
------
One CSV per tank, 41 levels from 0 to the full fill height ``load / (rho pi R^2)``
inclusive (evenly spaced), columns ``level_m, frequency_hz, damping, slosh_mass_kg,
slosh_height_m``, frequency and damping at the reference acceleration
``a_ref = 9.80665 m/s^2`` (1 g). Level 0 is written exactly, with the limiting values
frequency 0, mass 0, height 0 and the (clamped, finite) damping.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from savant_cli.datagen.ares_i_tables import M_LH2, M_LOX, US_DIAMETER_M, write_csv

try:  # shared constants (savant_cli/constants.py), with a local fallback
    from savant_cli.constants import G0
except ImportError:  # pragma: no cover - only while constants.py is being written
    G0 = 9.80665

# ====================================================================== model constants
XI_1 = 1.8412                      # first root of J1'(x) = 0 (1.841184...), as SP-106 quotes it
A_REF_MPS2 = float(G0)             # reference acceleration of the tables, m/s^2 (1 g)
DAMPING_MIN_DEPTH_RATIO = 0.1      # [E] h/R below which the damping's depth factor is frozen
N_LEVELS = 41                      # table rows, level 0 .. the top level inclusive
TABLE_HEADROOM = 0.01              # [E] the tables reach 1 % above the nominal fill: a dispersed load
#                                    (±0.3 % at 3σ, conf/dispersions/ares_i.yaml) stays inside them

RING_MIN_DEPTH_RATIO = 0.1         # [E] d/R below which a ring's depth is held (ring near the surface)

# ====================================================================== public figures
TANK_RADIUS_M = US_DIAMETER_M / 2.0    # [P] 5.5 m upper-stage diameter -> R = 2.75 m, both tanks


@dataclass(frozen=True)
class RingBaffles:
    """Ring (annular) slosh baffles of one tank, evenly spaced up the barrel.

    Attributes
    ----------
    width_ratio : float
        Ring width over the tank radius, ``w/R``; the ring blocks the area fraction
        ``alpha = 1 - (1 - w/R)^2`` of the cross-section.
    spacing_m : float
        Distance between rings, m.
    lowest_m, highest_m : float
        Heights of the lowest and the highest ring above the flat bottom, m.
    design_amplitude_ratio : float
        Slosh wave amplitude at the wall over the radius, ``eta/R``, at which the
        amplitude-dependent ring damping is evaluated (small: the linear regime of the
        stability analysis, and the low, conservative end of the damping).
    """

    width_ratio: float
    spacing_m: float
    lowest_m: float
    highest_m: float
    design_amplitude_ratio: float

    def heights_m(self) -> np.ndarray:
        """Ring heights above the bottom, m."""
        n = int(np.floor((self.highest_m - self.lowest_m) / self.spacing_m + 1e-9)) + 1
        return self.lowest_m + self.spacing_m * np.arange(n)


# [E] both tanks: rings of 0.1 R width every 0.4 R (1.1 m) up the barrel, judged at a
# 2.75 cm wave (eta/R = 0.01); the resulting 0.4-1.5 % sits in the 0.001-0.01 order of
# baffled flight tanks of shared/data/ares_i_public_data.md
BAFFLE_WIDTH_RATIO = 0.1
BAFFLE_SPACING_M = 0.4 * TANK_RADIUS_M
BAFFLE_DESIGN_AMPLITUDE_RATIO = 0.01


@dataclass(frozen=True)
class Tank:
    """One upper-stage propellant tank (flat-bottom cylinder equivalent).

    Attributes
    ----------
    name : str
        Short name, used in the file name ``slosh_<name>.csv``.
    label : str
        Human-readable description for the CSV comments.
    load_kg : float
        Liquid load at ignition, kg.
    density_kg_m3 : float
        Liquid density, kg/m^3.
    kinematic_viscosity_m2_s : float
        Liquid kinematic viscosity, m^2/s.
    baffles : RingBaffles or None
        The tank's ring baffles (``None``: smooth wall).
    radius_m : float
        Tank radius, m.
    """

    name: str
    label: str
    load_kg: float
    density_kg_m3: float
    kinematic_viscosity_m2_s: float
    baffles: RingBaffles | None = None
    radius_m: float = TANK_RADIUS_M

    @property
    def full_height_m(self) -> float:
        """Fill height of the full load, m (``load / (rho pi R^2)``)."""
        return liquid_level_m(self.load_kg, self.density_kg_m3, self.radius_m)


def barrel_baffles(full_height_m: float) -> RingBaffles:
    """[E] Rings every :data:`BAFFLE_SPACING_M` from half a spacing above the bottom to
    the last one below the full level."""
    low = 0.5 * BAFFLE_SPACING_M
    n = int(np.floor((full_height_m - low) / BAFFLE_SPACING_M))
    return RingBaffles(BAFFLE_WIDTH_RATIO, BAFFLE_SPACING_M, low, low + n * BAFFLE_SPACING_M,
                       BAFFLE_DESIGN_AMPLITUDE_RATIO)


LOX = Tank("lox", "upper-stage LOX tank", load_kg=M_LOX,        # [D] 114,315 kg: 135.1 t [P] at MR 5.5
           density_kg_m3=1141.0,                                 # [E] saturated LOX at ~90 K
           kinematic_viscosity_m2_s=1.7e-7,                      # [E] ~1.9e-4 Pa s / 1141 kg/m^3
           baffles=barrel_baffles(M_LOX / (1141.0 * np.pi * TANK_RADIUS_M**2)))
LH2 = Tank("lh2", "upper-stage LH2 tank", load_kg=M_LH2,        # [D] 20,785 kg: 135.1 t [P] at MR 5.5
           density_kg_m3=70.85,                                  # [E] saturated LH2 at ~20 K
           kinematic_viscosity_m2_s=1.9e-7,                      # [E] ~1.35e-5 Pa s / 70.85 kg/m^3
           baffles=barrel_baffles(M_LH2 / (70.85 * np.pi * TANK_RADIUS_M**2)))
TANKS = (LOX, LH2)

HEADER = ["level_m", "frequency_hz", "damping", "slosh_mass_kg", "slosh_height_m"]


# ============================================================================ formulas
def _as_out(x: np.ndarray) -> float | np.ndarray:
    """A Python float for 0-d results, the array otherwise."""
    return float(x) if np.ndim(x) == 0 else x


def _check(radius_m, fill_height_m) -> tuple[np.ndarray, np.ndarray]:
    r = np.asarray(radius_m, dtype=float)
    h = np.asarray(fill_height_m, dtype=float)
    if np.any(~(r > 0.0)):
        raise ValueError(f"tank radius must be > 0 m, got {radius_m!r}")
    if np.any(~(h >= 0.0)) or np.any(~np.isfinite(h)):
        raise ValueError(f"fill height must be finite and >= 0 m, got {fill_height_m!r}")
    return r, h


def liquid_level_m(liquid_kg, density_kg_m3, radius_m):
    """Fill height of a flat-bottom cylinder holding a liquid mass.

    Parameters
    ----------
    liquid_kg : float or array_like
        Liquid mass, kg (>= 0).
    density_kg_m3 : float
        Liquid density, kg/m^3.
    radius_m : float
        Tank radius, m.

    Returns
    -------
    float or numpy.ndarray
        ``h = m / (rho pi R^2)``, m.
    """
    m = np.asarray(liquid_kg, dtype=float)
    return _as_out(m / (density_kg_m3 * np.pi * radius_m**2))


def slosh_frequency_rad_s(radius_m, fill_height_m, accel_mps2=A_REF_MPS2):
    """First-mode slosh natural frequency of a flat-bottom upright cylinder.

    ``omega1 = sqrt((xi a / R) tanh(xi h / R))``, ``xi = 1.8412`` (SP-106 ch. 2; Dodge
    ch. 1). Proportional to ``sqrt(a)``; 0 at ``h = 0``.

    Parameters
    ----------
    radius_m : float or array_like
        Tank radius ``R``, m.
    fill_height_m : float or array_like
        Liquid fill height ``h`` above the flat bottom, m (>= 0).
    accel_mps2 : float or array_like, optional
        Axial (settling) acceleration ``a``, m/s^2 (>= 0); 1 g by default.

    Returns
    -------
    float or numpy.ndarray
        ``omega1``, rad/s.

    Raises
    ------
    ValueError
        For ``R <= 0``, ``h < 0`` or ``a < 0``.
    """
    r, h = _check(radius_m, fill_height_m)
    a = np.asarray(accel_mps2, dtype=float)
    if np.any(~(a >= 0.0)):
        raise ValueError(f"axial acceleration must be >= 0 m/s^2, got {accel_mps2!r}")
    return _as_out(np.sqrt(XI_1 * a / r * np.tanh(XI_1 * h / r)))


def slosh_frequency_hz(radius_m, fill_height_m, accel_mps2=A_REF_MPS2):
    """First-mode slosh natural frequency in Hz, ``omega1 / (2 pi)``.

    Parameters
    ----------
    radius_m : float or array_like
        Tank radius, m.
    fill_height_m : float or array_like
        Liquid fill height above the flat bottom, m.
    accel_mps2 : float or array_like, optional
        Axial acceleration, m/s^2; 1 g by default.

    Returns
    -------
    float or numpy.ndarray
        Frequency, Hz.
    """
    return _as_out(np.asarray(slosh_frequency_rad_s(radius_m, fill_height_m, accel_mps2)) / (2.0 * np.pi))


def slosh_mass_ratio(radius_m, fill_height_m):
    """First-mode slosh mass as a fraction of the liquid mass, ``m1 / m_F``.

    ``m1 / m_F = 2 R tanh(xi h / R) / (xi (xi^2 - 1) h)`` (SP-106 Table 6.1; Dodge Table
    3.1), with its limit ``2 / (xi^2 - 1) = 0.8368`` at ``h = 0``.

    Parameters
    ----------
    radius_m : float or array_like
        Tank radius ``R``, m.
    fill_height_m : float or array_like
        Liquid fill height ``h``, m (>= 0).

    Returns
    -------
    float or numpy.ndarray
        ``m1 / m_F``, dimensionless, in ``(0, 0.837]``.
    """
    r, h = _check(radius_m, fill_height_m)
    x = XI_1 * h / r
    safe = np.where(x > 0.0, x, 1.0)
    tanh_over_x = np.where(x > 0.0, np.tanh(safe) / safe, 1.0)
    return _as_out(2.0 * tanh_over_x / (XI_1**2 - 1.0))


def slosh_mass_kg(radius_m, fill_height_m, density_kg_m3):
    """First-mode slosh (spring) mass.

    ``m1 = m_F 2 R tanh(xi h / R) / (xi (xi^2 - 1) h)`` with ``m_F = rho pi R^2 h``,
    evaluated as ``2 rho pi R^3 tanh(xi h / R) / (xi (xi^2 - 1))`` (0 at ``h = 0``,
    no ``0/0``).

    Parameters
    ----------
    radius_m : float or array_like
        Tank radius ``R``, m.
    fill_height_m : float or array_like
        Liquid fill height ``h``, m (>= 0).
    density_kg_m3 : float or array_like
        Liquid density ``rho``, kg/m^3.

    Returns
    -------
    float or numpy.ndarray
        ``m1``, kg; ``0 <= m1 <= m_F``.
    """
    r, h = _check(radius_m, fill_height_m)
    rho = np.asarray(density_kg_m3, dtype=float)
    return _as_out(2.0 * rho * np.pi * r**3 * np.tanh(XI_1 * h / r) / (XI_1 * (XI_1**2 - 1.0)))


def slosh_mass_height_m(radius_m, fill_height_m):
    """Height of the first-mode spring mass above the (flat) tank bottom.

    ``z1 = h - (2 R / xi) tanh(xi h / (2 R))``, i.e. ``h/2 - (2R/xi) tanh(xi h/(2R))``
    above the liquid's centre of mass (SP-106 Table 6.1, Dodge Table 3.1, spring-mass
    model; re-derived by moment equivalence in the module docstring). Evaluated as
    ``(2/k) (y - tanh y)``, ``k = xi/R``, ``y = k h / 2``, with its series
    ``y^3/3 - 2 y^5/15 + 17 y^7/315`` for ``y < 1e-3`` (no cancellation).

    Parameters
    ----------
    radius_m : float or array_like
        Tank radius ``R``, m.
    fill_height_m : float or array_like
        Liquid fill height ``h``, m (>= 0).

    Returns
    -------
    float or numpy.ndarray
        ``z1``, m; ``0 <= z1 <= h``; ``z1 -> h - 2R/xi`` for ``h >> R``.
    """
    r, h = _check(radius_m, fill_height_m)
    k = XI_1 / r
    y = 0.5 * k * h
    series = y**3 / 3.0 - 2.0 * y**5 / 15.0 + 17.0 * y**7 / 315.0
    z = (2.0 / k) * np.where(y < 1e-3, series, y - np.tanh(y))
    return _as_out(np.clip(z, 0.0, h))


def slosh_damping(radius_m, fill_height_m, kinematic_viscosity_m2_s, accel_mps2=A_REF_MPS2,
                  min_depth_ratio=DAMPING_MIN_DEPTH_RATIO):
    """First-mode viscous damping ratio of a smooth-wall (unbaffled) flat-bottom cylinder.

    Mikishev and Dorozhkin, as quoted in SP-106 ch. 4 (logarithmic decrement) and Dodge
    ch. 3 (``4.98 / 2 pi = 0.79``)::

        zeta = 4.98 nu^(1/2) R^(-3/4) a^(-1/4)
               [1 + 0.318 / sinh(1.84 h'/R) (1 + (1 - h'/R) / cosh(1.84 h'/R))] / (2 pi)

    with ``h' = max(h, min_depth_ratio R)``: the bottom term diverges like ``R / h`` as
    ``h -> 0``; below ``h/R = min_depth_ratio`` the depth factor is held constant.

    Parameters
    ----------
    radius_m : float or array_like
        Tank radius ``R``, m.
    fill_height_m : float or array_like
        Liquid fill height ``h``, m (>= 0).
    kinematic_viscosity_m2_s : float or array_like
        Liquid kinematic viscosity ``nu``, m^2/s (> 0).
    accel_mps2 : float or array_like, optional
        Axial acceleration ``a``, m/s^2 (> 0); 1 g by default.
    min_depth_ratio : float, optional
        ``h/R`` below which the depth factor is frozen (> 0), 0.1 by default.

    Returns
    -------
    float or numpy.ndarray
        Damping ratio ``zeta`` (fraction of critical), > 0 and finite.

    Raises
    ------
    ValueError
        For ``R <= 0``, ``h < 0``, ``nu <= 0``, ``a <= 0`` or ``min_depth_ratio <= 0``.
    """
    r, h = _check(radius_m, fill_height_m)
    nu = np.asarray(kinematic_viscosity_m2_s, dtype=float)
    a = np.asarray(accel_mps2, dtype=float)
    if np.any(~(nu > 0.0)) or np.any(~(a > 0.0)) or not min_depth_ratio > 0.0:
        raise ValueError("viscosity, acceleration and min_depth_ratio must be > 0")
    q = np.maximum(h / r, min_depth_ratio)
    depth = 1.0 + 0.318 / np.sinh(1.84 * q) * (1.0 + (1.0 - q) / np.cosh(1.84 * q))
    return _as_out(4.98 * np.sqrt(nu) * r**-0.75 * a**-0.25 * depth / (2.0 * np.pi))


def ring_baffle_damping(radius_m, fill_height_m, baffles: RingBaffles,
                        min_depth_ratio=RING_MIN_DEPTH_RATIO):
    """First-mode damping ratio added by submerged ring baffles.

    Miles (1958), "Ring damping of free surface oscillations in a circular tank", J. Appl.
    Mech. 25, as quoted in SP-106 ch. 4 and Dodge ch. 3, for one ring at depth ``d``
    below the free surface::

        zeta_ring = 2.83 exp(-4.60 d/R) alpha^(3/2) (eta/R)^(1/2)

    (``alpha`` the blocked area fraction, ``eta`` the wave amplitude at the wall), summed
    over the rings below the surface, each at ``d' = max(d, min_depth_ratio R)`` (the
    formula is for a ring well below the surface; one at the surface damps less, not
    more). Independent of the acceleration. A level below the lowest ring gets 0.

    Parameters
    ----------
    radius_m : float
        Tank radius ``R``, m.
    fill_height_m : float or array_like
        Liquid fill height ``h``, m (>= 0).
    baffles : RingBaffles
        Ring width, heights and the design wave amplitude.
    min_depth_ratio : float, optional
        ``d/R`` below which a ring's depth is held, 0.1 by default.

    Returns
    -------
    float or numpy.ndarray
        Damping ratio added by the rings (fraction of critical), >= 0.
    """
    r, h = _check(radius_m, fill_height_m)
    alpha = 1.0 - (1.0 - baffles.width_ratio) ** 2
    z = baffles.heights_m()
    depth = h[..., None] - z  # (levels, rings): > 0 for the submerged rings
    d = np.maximum(depth, min_depth_ratio * r)
    per_ring = 2.83 * np.exp(-4.60 * d / r) * alpha**1.5 * np.sqrt(baffles.design_amplitude_ratio)
    return _as_out(np.where(depth >= 0.0, per_ring, 0.0).sum(axis=-1))


def slosh_table(radius_m, density_kg_m3, kinematic_viscosity_m2_s, load_kg, n_levels=N_LEVELS,
                accel_mps2=A_REF_MPS2, baffles: RingBaffles | None = None) -> np.ndarray:
    """Slosh table of one tank from empty to full.

    Parameters
    ----------
    radius_m : float
        Tank radius, m.
    density_kg_m3 : float
        Liquid density, kg/m^3.
    kinematic_viscosity_m2_s : float
        Liquid kinematic viscosity, m^2/s.
    load_kg : float
        Full liquid load, kg; the last level is ``load / (rho pi R^2)``.
    n_levels : int, optional
        Number of evenly spaced levels from 0 to full inclusive (>= 2), 41 by default.
    accel_mps2 : float, optional
        Acceleration the frequency and damping are given at, m/s^2; 1 g by default.
    baffles : RingBaffles, optional
        Ring baffles, whose damping adds to the smooth wall's (none by default).

    Returns
    -------
    numpy.ndarray
        ``(n_levels, 5)``: level above the flat bottom (m), frequency (Hz), damping ratio,
        slosh mass (kg), slosh-mass height above the bottom (m); the columns of
        :data:`HEADER`. Row 0 is level 0 with its limiting values.
    """
    if int(n_levels) < 2:
        raise ValueError(f"n_levels must be >= 2, got {n_levels!r}")
    h_full = liquid_level_m(load_kg, density_kg_m3, radius_m)
    level = np.linspace(0.0, h_full, int(n_levels))
    level[-1] = h_full
    zeta = slosh_damping(radius_m, level, kinematic_viscosity_m2_s, accel_mps2)
    if baffles is not None:
        zeta = zeta + ring_baffle_damping(radius_m, level, baffles)
    return np.column_stack([
        level,
        slosh_frequency_hz(radius_m, level, accel_mps2),
        zeta,
        slosh_mass_kg(radius_m, level, density_kg_m3),
        slosh_mass_height_m(radius_m, level),
    ])


def tank_table(tank: Tank) -> np.ndarray:
    """:func:`slosh_table` of a :class:`Tank` at the reference acceleration."""
    return slosh_table(tank.radius_m, tank.density_kg_m3, tank.kinematic_viscosity_m2_s,
                       tank.load_kg * (1.0 + TABLE_HEADROOM), baffles=tank.baffles)


# ========================================================================== writing
def tank_comments(tank: Tank) -> list[str]:
    """The comment lines of one tank's CSV."""
    r = tank.radius_m
    return [
        "generated by `python -m savant_cli.datagen.ares_i_slosh`; sources, assumptions and marks in slosh_README.md",
        (f"tank: {tank.label}, first antisymmetric slosh mode, spring-mass analogy (NASA SP-106; Dodge 2000); "
         f"flat-bottom upright circular cylinder equivalent of the domed tank, radius R = {r:g} m [P], "
         + (f"ring baffles [E]: width {b.width_ratio:g} R every {b.spacing_m:g} m from {b.lowest_m:g} to "
            f"{b.highest_m:.4g} m above the bottom, damping judged at a wave of {b.design_amplitude_ratio:g} R"
            if (b := tank.baffles) is not None else "smooth wall, no baffles")),
        (f"liquid: load {tank.load_kg:g} kg [D] (135.1 t [P] at the J-2X mixture ratio 5.5), "
         f"density rho = {tank.density_kg_m3:g} kg/m3 [E], "
         f"kinematic viscosity nu = {tank.kinematic_viscosity_m2_s:g} m2/s [E]; "
         f"full fill height load/(rho pi R^2) = {tank.full_height_m:.6g} m [D]"),
        (f"level_m: liquid fill height above the flat tank bottom, m, {N_LEVELS} levels evenly spaced "
         f"from 0 to {100 * TABLE_HEADROOM:g} % above full inclusive (dispersed loads); "
         "level 0 holds the limiting values (frequency 0, mass 0, height 0)"),
        (f"frequency_hz and damping are given at the reference acceleration a_ref = {A_REF_MPS2:g} m/s2 (1 g); "
         "frequency scales as sqrt(a/a_ref), the smooth-wall damping formula as (a/a_ref)^-0.25 "
         "(the simulation uses the tabulated damping as it is)"),
        ("slosh_mass_kg: first-mode spring mass m1, kg; slosh_height_m: height of the spring mass above "
         "the tank bottom, m"),
        ("formulas (xi = 1.8412, h = level_m, m_F = rho pi R^2 h): omega1^2 = (xi a/R) tanh(xi h/R), "
         "frequency_hz = omega1/(2 pi); m1 = m_F 2R tanh(xi h/R)/(xi (xi^2 - 1) h); "
         "slosh_height_m = h - (2R/xi) tanh(xi h/(2R))"),
        ("damping: smooth wall (Mikishev, SP-106) zeta = 4.98 nu^0.5 R^-0.75 a^-0.25 [1 + 0.318/sinh(1.84 q) "
         f"(1 + (1 - q)/cosh(1.84 q))]/(2 pi), q = max(h/R, {DAMPING_MIN_DEPTH_RATIO:g})"
         + ("; plus ring baffles (Miles 1958, SP-106) sum over submerged rings of 2.83 exp(-4.6 d/R) "
            f"alpha^1.5 (eta/R)^0.5, d = max(depth below the surface, {RING_MIN_DEPTH_RATIO:g} R), "
            "alpha = 1 - (1 - w/R)^2, independent of a" if tank.baffles is not None else "")),
    ]


def write_all(out: Path) -> list[Path]:
    """Write ``slosh_lox.csv`` and ``slosh_lh2.csv`` into ``out``.

    Parameters
    ----------
    out : pathlib.Path
        Output folder (created if missing).

    Returns
    -------
    list of pathlib.Path
        The files written.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for tank in TANKS:
        path = out / f"slosh_{tank.name}.csv"
        write_csv(path, HEADER, tank_table(tank), tank_comments(tank))
        paths.append(path)
    return paths


def report() -> str:
    """Full-load and half-load values of each tank at 1 g."""
    lines = []
    for tank in TANKS:
        t = tank_table(tank)
        for label, row in (("full", t[-1]), ("half", t[(len(t) - 1) // 2])):
            lines.append(f"{tank.name} {label}: h {row[0]:.3f} m (h/R {row[0] / tank.radius_m:.3f}), "
                         f"f {row[1]:.4f} Hz @1 g, zeta {row[2]:.3e}, m1 {row[3]:.1f} kg "
                         f"({row[3] / (tank.density_kg_m3 * np.pi * tank.radius_m**2 * row[0]):.3f} m_F), "
                         f"z1 {row[4]:.3f} m")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    """Command line: write the two slosh tables and print their full/half-load values."""
    ap = argparse.ArgumentParser(description="Generate the ares_i upper-stage slosh tables (NASA SP-106).")
    ap.add_argument("--out", type=Path, default=None,
                    help="output folder (default: the shipped conf/vehicle/ares_i)")
    args = ap.parse_args(argv)
    if args.out is None:
        from savant_cli.paths import shipped_config_dir

        out = shipped_config_dir() / "vehicle" / "ares_i"
    else:
        out = args.out
    paths = write_all(out)
    print(report())
    print("wrote " + ", ".join(str(p) for p in paths))


__all__ = ["XI_1", "A_REF_MPS2", "DAMPING_MIN_DEPTH_RATIO", "N_LEVELS", "HEADER", "Tank", "LOX", "LH2", "TANKS",
           "liquid_level_m", "slosh_frequency_rad_s", "slosh_frequency_hz", "slosh_mass_ratio", "slosh_mass_kg",
           "slosh_mass_height_m", "slosh_damping", "RingBaffles", "ring_baffle_damping", "slosh_table", "tank_table", "write_all", "main"]

if __name__ == "__main__":
    main()
