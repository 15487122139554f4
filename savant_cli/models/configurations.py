"""Vehicle configurations and engine phases: the discrete modes the plant switches on.

The aerodynamic and mass tables are stacked over the three configurations; the thrust
model reads the engine phase. Both arrive as held plant inputs set by the event logic
(``sim/engine.py``): separation, J-2X ignition and LES jettison.
"""

from __future__ import annotations

from savant_cli.vehicle import CONFIG_NAMES

CONFIG_STACK = 0  # first stage + upper stage + LES (liftoff to separation)
CONFIG_UPPER_LES = 1  # upper stage with the launch-escape system (separation to jettison)
CONFIG_UPPER = 2  # upper stage alone
N_CONFIG = len(CONFIG_NAMES)

ENGINE_FIRST = 0  # first-stage motor burning
ENGINE_OFF = 1  # coast between separation and ignition
ENGINE_UPPER = 2  # upper-stage engine burning
