"""The compiled integrator: Runge-Kutta and Rosenbrock steppers, event location, and a
driver that runs a whole hybrid simulation per call.

The integrator knows nothing of cams. It calls the systems registered in
:mod:`camdyn.systems.registry` through four functions: the right-hand side, the guard
(event) functions, the mode transition at a guard crossing, and the stiffness flag
that picks the stepper.
"""
