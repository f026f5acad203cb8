"""camdyn: nonlinear dynamics of cam-follower systems with combined rolling and sliding
contact: simulation, analysis and identification.

Quick start::

    import camdyn
    system = camdyn.load_system("sundar2014-friction")
    result = camdyn.simulate(system, speed=11.55, revolutions=30)
    result["alpha_ddot"].plot()
"""

from camdyn import compiled_cache
from camdyn.errors import (
    CamdynError,
    GeometryError,
    ParameterError,
    PresetError,
    SimulationError,
    UnitError,
    UnknownKeyError,
)

__version__ = "0.1.0"

# before anything compiled is loaded: numba's cache entries that a change of the sources
# made stale are removed (numba itself checks only a function's own file)
compiled_cache.refresh()

__all__ = [
    "load_system", "list_presets", "simulate", "static_equilibrium", "natural_frequency",
    "Cam", "Contact", "Follower", "Friction", "Motion", "Spring", "System",
    "Model", "Quantity",
    "CamdynError", "GeometryError", "ParameterError", "PresetError", "SimulationError", "UnitError",
    "UnknownKeyError",
]


_PARAMETERS = ("Cam", "Contact", "Follower", "Friction", "Motion", "Spring", "System")


def __getattr__(name):
    # lazy: importing camdyn (or a compiled submodule, as a sweep's worker process does)
    # neither compiles anything nor imports pint, xarray or SciPy; a Ctrl-C during the
    # import of a name waits for its end (camdyn.interrupts): a half-done import of numba
    # would break every later call
    from camdyn.interrupts import deferred

    with deferred():
        return _load(name)


def _load(name):
    if name == "load_system":
        from camdyn.io.system_config import load_system
        return load_system
    if name == "list_presets":
        from camdyn.params import config
        return config.list_presets
    if name in _PARAMETERS:
        from camdyn.params import system
        return getattr(system, name)
    if name in ("Model", "Quantity"):
        from camdyn.systems import protocol
        return getattr(protocol, name)
    if name == "simulate":   # every family: objects, and configurations by name or file
        from camdyn.io.sources import simulate
        return simulate
    if name in ("static_equilibrium", "natural_frequency"):
        from camdyn.model import equilibrium
        return getattr(equilibrium, name)
    raise AttributeError(name)
