"""Time-domain stability margins of the nonlinear, time-varying simulation
(``study=time_margins``): a gain or delay inserted at a gimbal command, the verdict on
the response (stable only when it decays per period at least as a mode of the stated
damping ratio), and the bisection for the smallest change that is not stable."""
