"""Vehicle configurations and engine phases: the discrete modes the plant switches on.

The aerodynamic and mass tables are stacked over the vehicle's configurations, in the
order its events reach them (each jettison moves to the next, ``sim/engine.py``); the
thrust model reads the engine phase. Both arrive as held plant inputs set by the event
logic. The numbers below are the shipped two-stage vehicles' (no boosters), which the
reference-ascent generators in ``savant_cli/datagen/`` fly.
"""

from __future__ import annotations

CONFIG_STACK = 0  # first stage + upper stage + LES (liftoff to separation)
CONFIG_UPPER_LES = 1  # upper stage with the launch-escape system (separation to jettison)
CONFIG_UPPER = 2  # upper stage alone

ENGINE_FIRST = 0  # first-stage motor burning
ENGINE_OFF = 1  # coast between separation and ignition
ENGINE_UPPER = 2  # upper-stage engine burning
