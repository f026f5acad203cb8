"""Simulations: time histories as xarray Datasets, and the instantaneous-impact map."""
