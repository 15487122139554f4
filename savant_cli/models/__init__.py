"""Physical models of the plant and the flight software, one per module.

Importing this package imports every model in the fixed order below. That order hands
out the indices of the fields the models declare in the plant's shared vectors
(:mod:`savant_cli.models.blocks`): the compile-time state is the rigid body's (the
vehicle's tanks, gimbal channels and roll jets follow at run time,
:mod:`savant_cli.models.layout`); the discrete state is guidance, sensors, flight control. Never import a
model elsewhere in a way that bypasses this package (a plain ``import
savant_cli.models.x`` always runs this file first).
"""

from savant_cli.models import blocks, configurations, interp, quaternion  # noqa: F401  (infrastructure)
from savant_cli.models import earth, gravity, atmosphere, winds  # noqa: F401  (environment)
from savant_cli.models import rigid_body, propulsion, actuator, rcs  # noqa: F401  (parameters in this order)
from savant_cli.models import mass, aero, twd, slosh, flex  # noqa: F401
from savant_cli.models import cluster  # noqa: F401  (a table only: after the models whose kernels it calls)
from savant_cli.models import guidance, sensors, fcs  # noqa: F401  (flight software, discrete state in order)
from savant_cli.models import command_schedule, peg  # noqa: F401  (appended: older staging states stay valid)
from savant_cli.models import navigation  # noqa: F401  (appended likewise)
from savant_cli.models import roll_gimbal  # noqa: F401  (appended likewise)
from savant_cli.models import throttle  # noqa: F401  (appended likewise)
from savant_cli.models import boosters  # noqa: F401  (appended likewise)

#: The models that build plant parameters and tables, in build order.
PLANT_MODELS = (earth, gravity, atmosphere, winds, propulsion, actuator, rcs, mass, aero, twd, slosh, flex, cluster,
                sensors, peg, navigation, throttle, boosters)
