"""Periodic steady states in the frequency domain: harmonic balance with the alternating
frequency-time scheme (:mod:`camdyn.steady.harmonic_balance`), beside the shooting of
:mod:`camdyn.continuation`."""

from camdyn.steady.harmonic_balance import HarmonicOrbit, harmonic_balance, hill_multipliers

__all__ = ["HarmonicOrbit", "harmonic_balance", "hill_multipliers"]
