"""Estimators of model parameters from measured vibration (thesis chapters 3 and 4)."""
