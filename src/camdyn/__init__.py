"""camdyn: nonlinear dynamics of cam-follower systems with combined rolling and sliding
contact: simulation, analysis and identification.

Quick start::

    import camdyn
    system = camdyn.load_system("sundar2014-friction")
    result = camdyn.simulate(system, speed=11.55, revolutions=30)
    result["alpha_ddot"].plot()
"""

from camdyn.config import list_presets, load_system
from camdyn.errors import (
    CamdynError, GeometryError, ParameterError, PresetError, SimulationError, UnitError, UnknownKeyError,
)
from camdyn.parameters import Cam, Contact, Follower, Friction, Motion, Spring, System

__version__ = "0.1.0"

__all__ = [
    "load_system", "list_presets", "simulate", "static_equilibrium", "natural_frequency",
    "Cam", "Contact", "Follower", "Friction", "Motion", "Spring", "System",
    "CamdynError", "GeometryError", "ParameterError", "PresetError", "SimulationError", "UnitError",
    "UnknownKeyError",
]


def __getattr__(name):  # lazy: importing camdyn does not compile anything
    if name == "simulate":
        from camdyn.simulation import simulate
        return simulate
    if name in ("static_equilibrium", "natural_frequency"):
        from camdyn.model import equilibrium
        return getattr(equilibrium, name)
    raise AttributeError(name)
