"""Exception types of camdyn.

Every error a user can cause by bad input is a subclass of :class:`CamdynError`,
with a message a mechanical engineer can act on. The command-line interface prints
each in one line, without a traceback, and exits with status 2 for bad input and 1 for
a failure at run time (:data:`RUNTIME_ERRORS`: the solver stopped, the disk filled up).
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


class OutputError(CamdynError, OSError):
    """An output file cannot be written: its folder is missing or read-only, or the disk
    lacks the space the result needs (refused before the work starts)."""


class StorageError(CamdynError, OSError):
    """Writing a file failed at run time (the disk filled up, an I/O error); nothing was
    written under the final name."""


class SweepInterrupted(KeyboardInterrupt):
    """A sweep was interrupted (Ctrl-C, SIGTERM); its finished chunks are saved and the
    message says how to resume."""


#: Errors that happen at run time on valid input (exit status 1 in the command line).
RUNTIME_ERRORS = (SimulationError, StorageError)
