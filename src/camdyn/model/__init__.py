"""The assembled cam-follower model: parameter layout, equations of motion, equilibrium."""

from camdyn.interrupts import guard_numba

guard_numba()   # before anything here is compiled or loaded: Ctrl-C waits for the end of a load
