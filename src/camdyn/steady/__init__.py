"""Periodic steady states in the frequency domain: harmonic balance with the alternating
frequency-time scheme (:mod:`camdyn.steady.harmonic_balance`) and its frequency responses
(:mod:`camdyn.steady.response`), beside the shooting of
:mod:`camdyn.continuation`; parameters fitted to a steady-state record with the orbit as
the forward model (:mod:`camdyn.steady.record_fit`)."""

from camdyn.steady.harmonic_balance import HarmonicOrbit, harmonic_balance, hill_multipliers
from camdyn.steady.record_fit import RecordFit, fit_record
from camdyn.steady.response import HarmonicBranch, continue_harmonic

__all__ = ["HarmonicBranch", "HarmonicOrbit", "RecordFit", "continue_harmonic", "fit_record", "harmonic_balance",
           "hill_multipliers"]
