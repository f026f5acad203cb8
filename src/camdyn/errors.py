"""Exception types of camdyn.

Every error a user can cause by bad input is a subclass of :class:`CamdynError`,
with a message a mechanical engineer can act on. The command-line interface
prints these in one line and exits with status 2.
"""


class CamdynError(Exception):
    """Base class of all camdyn input and modelling errors."""


class ParameterError(CamdynError, ValueError):
    """A parameter value is missing, not finite, or outside its physical range."""


class UnitError(ParameterError):
    """A quantity has a unit that cannot be read or has the wrong dimension."""


class UnknownKeyError(ParameterError, KeyError):
    """A parameter key does not exist."""

    def __str__(self) -> str:  # KeyError quotes its message; keep it plain
        return str(self.args[0]) if self.args else ""


class GeometryError(ParameterError):
    """The cam and follower geometry is impossible (for example, they can never touch)."""


class PresetError(CamdynError, LookupError):
    """A named preset does not exist or a configuration file cannot be read."""


class SimulationError(CamdynError, RuntimeError):
    """The integrator could not complete a simulation (step-size underflow, too many steps)."""


class DataError(CamdynError, ValueError):
    """A measurement file cannot be read or its samples are unusable (gaps, NaN, clipping)."""


class IdentificationError(CamdynError, RuntimeError):
    """An estimator refuses a record: its assumptions fail, or it has too little information."""
