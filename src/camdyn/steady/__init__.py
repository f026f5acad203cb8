"""Periodic steady states in the frequency domain: harmonic balance with the alternating
frequency-time scheme (:mod:`camdyn.steady.harmonic_balance`) and its frequency responses
(:mod:`camdyn.steady.response`), beside the shooting of
:mod:`camdyn.continuation`."""

from camdyn.steady.harmonic_balance import HarmonicOrbit, harmonic_balance, hill_multipliers
from camdyn.steady.response import HarmonicBranch, continue_harmonic

__all__ = ["HarmonicBranch", "HarmonicOrbit", "continue_harmonic", "harmonic_balance", "hill_multipliers"]
