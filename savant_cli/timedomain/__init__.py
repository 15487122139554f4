"""Time-domain stability margins of the nonlinear, time-varying simulation
(``study=time_margins``): a gain or delay inserted at a gimbal command, the response's
growth, and the bisection for the smallest change that makes it grow."""
