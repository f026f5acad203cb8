"""The registry of hybrid systems the compiled integrator can run."""
