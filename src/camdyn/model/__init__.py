"""The assembled cam-follower model: parameter layout, equations of motion, equilibrium."""
