"""Test oracles: an independent SciPy implementation of the model."""
