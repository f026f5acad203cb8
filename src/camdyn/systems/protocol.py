"""The model protocol: one descriptor per model, from which camdyn builds the model's
driver and runs it.

A model is a hybrid system: a state ``y`` (``len(states)`` components), a mode vector
(``len(modes)`` slots: which contacts are closed, which way a friction force acts, ...),
guards whose sign change is an event, and a parameter vector ``p`` (``len(parameters)``
numbers, in SI units, in the order of :attr:`Model.parameters`). Its functions are numba
functions (``@numba.njit``) defined at the top level of a module file:

``rhs(t, y, mode, p, dydt)``
    the state's rates into ``dydt``;
``guards(t, y, f, known, p, values, rates)``
    each guard's value and its time derivative (NaN where unknown) into ``values`` and
    ``rates``; ``f = dy/dt`` at ``(t, y)`` when ``known`` is true;
``expected_sign(k, mode, p)``
    +1.0 or -1.0 for guard ``k`` active in ``mode``, 0.0 for an inactive one; an event is
    an active guard crossing against its expected sign;
``transition(k, t, y, values, mode, p)``
    the new mode after guard ``k`` crossed, in place, and the state's reset (an impact's
    velocity jump) where there is one;
``initial_mode(t, y, p, mode)``
    the mode of a state at the start;
``jacobian(t, y, f0, mode, p, jac)`` (optional)
    ``d f / d y`` into the ``n x n`` array ``jac``; central differences without it;
``monitor(t, y, mode, p)`` (optional)
    a scalar whose largest value between events is logged (an impact's peak force);
``outputs(t, y, mode, p, out)`` (optional)
    derived channels (:attr:`Model.outputs`) of one state into ``out``;
``regime(mode, p)`` (optional)
    0 or 1, the dynamic regime of a mode (free flight, contact): the driver starts the
    step after an event at the last step size of the new mode's regime; 0 without it.

:func:`adapter_source` writes the module through which the integrator calls them;
:mod:`camdyn.integrator.instances` compiles the integrator for the model, and
:func:`camdyn.simulate` runs it. The tutorial is
docs/user-models.md.
"""

from __future__ import annotations

import importlib
import inspect
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from camdyn.errors import ParameterError
from camdyn.params.units import parse_quantity, parse_speed

#: The id under which a model's own driver knows it (below the registry's
#: ``VARIATIONAL``; its variational system is ``VARIATIONAL + MODEL_ID``). The adapter
#: ignores it; it keeps the bundled models' id-keyed traits off protocol models.
MODEL_ID = 99

__all__ = ["Model", "BoundModel", "Quantity", "MODEL_ID", "adapter_source", "read_value", "REQUIRED", "OPTIONAL"]

#: The functions a model must give, and those it may give.
REQUIRED = ("rhs", "guards", "expected_sign", "transition", "initial_mode")
OPTIONAL = ("jacobian", "monitor", "outputs", "regime")
#: Stepper codes of the driver (``camdyn.integrator.driver.METHOD_*``) a model may prefer.
_METHODS = {"dop853": 3, "dormand-prince": 1, "rodas4": 2}


@dataclass(frozen=True)
class Quantity:
    """A named quantity of a model: a parameter, a state component, an output channel.

    Attributes
    ----------
    name : str
        Its key (a parameter's key in ``parameters={...}``; a variable's name in the
        Dataset).
    unit : str
        Its SI unit, as pint writes it (``"m"``, ``"N/m"``, ``"kg"``, ``"Hz"``, ``""``
        for a number).
    description : str
        What it is, for the Dataset's ``long_name`` and for error messages.
    default : float or None
        A parameter's value [unit] when none is given; None: it must be given.
    """

    name: str
    unit: str = ""
    description: str = ""
    default: float | None = None


def _quantities(items, what: str) -> tuple[Quantity, ...]:
    out = []
    for item in items:
        if isinstance(item, Quantity):
            out.append(item)
        elif isinstance(item, str):
            out.append(Quantity(item))
        elif isinstance(item, tuple) and 1 <= len(item) <= 4:
            out.append(Quantity(*item))
        else:
            raise ParameterError(f"a model's {what} are Quantity objects, names or (name, unit, description) "
                                 f"tuples; got {item!r}")
    names = [q.name for q in out]
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise ParameterError(f"a model's {what} repeat the names {duplicates}")
    return tuple(out)


def _is_jitted(function) -> bool:
    return hasattr(function, "py_func") and hasattr(function, "signatures")


@dataclass(frozen=True)
class Model:
    """A hybrid model that camdyn can simulate: its quantities and its numba functions.

    Parameters
    ----------
    name : str
        The model's name, for messages and the Dataset's attributes.
    states : sequence
        The state's components in order (``Quantity``, or ``(name, unit, description)``).
    parameters : sequence
        The parameter vector's entries in order, in SI units.
    guards : sequence of str
        The guards' names, in order (the event table's ``guard`` names).
    modes : sequence of str
        The mode vector's slots, in order.
    functions : dict
        The numba functions by role (:data:`REQUIRED` and any of :data:`OPTIONAL`).
    outputs : sequence, optional
        Derived channels that ``functions["outputs"]`` fills, in order.
    speed : str, optional
        The parameter [Hz] that ``camdyn.simulate(..., speed=...)`` sets: the cam's speed
        in revolutions per second, one revolution being the model's period.
    controlled : int, optional
        How many leading state components the error control watches; all by default.
    method : str
        The stepper: ``"dop853"`` (default), ``"dormand-prince"`` or ``"rodas4"``.
    max_step_fraction : float
        The largest step as a fraction of the period (1 / ``speed``) [-].
    plain_error_estimate : bool
        Control DOP853's steps by their 5th-order error estimate alone, not Hairer's
        combination with the 3rd-order one (for a force with a branch point at
        separation, such as Hertz's; docs/integrator.md).
    initial_state : callable, optional
        ``initial_state(p) -> y0``: the state at rest for the parameter vector ``p``
        (SI units); zeros without it.
    """

    name: str
    states: tuple
    parameters: tuple
    guards: tuple
    modes: tuple
    functions: dict = field(repr=False)
    outputs: tuple = ()
    speed: str | None = None
    controlled: int | None = None
    method: str = "dop853"
    max_step_fraction: float = 1.0 / 32.0
    plain_error_estimate: bool = False
    initial_state: object = field(default=None, repr=False)

    def __post_init__(self):
        set_ = object.__setattr__
        set_(self, "states", _quantities(self.states, "states"))
        set_(self, "parameters", _quantities(self.parameters, "parameters"))
        set_(self, "outputs", _quantities(self.outputs, "outputs"))
        set_(self, "guards", tuple(str(g) for g in self.guards))
        set_(self, "modes", tuple(str(m) for m in self.modes))
        set_(self, "functions", dict(self.functions))
        if not self.states or not self.modes:
            raise ParameterError(f"model {self.name!r}: a model needs at least one state and one mode slot")
        missing = [role for role in REQUIRED if role not in self.functions]
        unknown = sorted(set(self.functions) - set(REQUIRED) - set(OPTIONAL))
        if missing or unknown:
            raise ParameterError(f"model {self.name!r}: functions missing {missing}" if missing else
                                 f"model {self.name!r}: unknown function roles {unknown}; "
                                 f"known: {list(REQUIRED + OPTIONAL)}")
        if self.outputs and "outputs" not in self.functions:
            raise ParameterError(f"model {self.name!r} names output channels but gives no 'outputs' function")
        for role, function in self.functions.items():
            _source_of(self.name, role, function)
        if self.speed is not None and self.speed not in self.parameter_names:
            raise ParameterError(f"model {self.name!r}: its speed parameter {self.speed!r} is not one of its "
                                 f"parameters {list(self.parameter_names)}")
        n = len(self.states)
        if self.controlled is not None and not 1 <= int(self.controlled) <= n:
            raise ParameterError(f"model {self.name!r}: controlled must be 1 to {n}, got {self.controlled}")
        if self.method not in _METHODS:
            raise ParameterError(f"model {self.name!r}: method must be one of {sorted(_METHODS)}, got {self.method!r}")
        if not (math.isfinite(self.max_step_fraction) and 0.0 < self.max_step_fraction <= 1.0):
            raise ParameterError(f"model {self.name!r}: max_step_fraction must be in (0, 1], "
                                 f"got {self.max_step_fraction}")

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return tuple(q.name for q in self.parameters)

    @property
    def state_names(self) -> tuple[str, ...]:
        return tuple(q.name for q in self.states)

    def bind(self, parameters: dict | None = None) -> BoundModel:
        """The model with its parameter values: ``parameters`` maps keys of
        :attr:`parameters` to numbers in SI units or to text with units (``"0.2 mm"``,
        ``"2400 rpm"``); the others keep their defaults.

        Raises
        ------
        ParameterError
            An unknown key, or a parameter without a value or default.
        UnitError
            A value whose unit does not fit.
        """
        given = dict(parameters or {})
        unknown = sorted(set(given) - set(self.parameter_names))
        if unknown:
            raise ParameterError(f"model {self.name!r} has no parameter {unknown[0]!r}; "
                                 f"its parameters: {', '.join(self.parameter_names)}")
        values = []
        for q in self.parameters:
            value = given.get(q.name, q.default)
            if value is None:
                raise ParameterError(f"model {self.name!r}: parameter {q.name!r} [{q.unit}] ({q.description}) "
                                     "has no default; give it a value")
            values.append(read_value(value, q))
        return BoundModel(self, tuple(values))

    def dependencies(self) -> tuple[str, ...]:
        """The source files of the modules that define the model's functions."""
        files = {_source_of(self.name, role, f)[2] for role, f in self.functions.items()}
        package = Path(__file__).resolve().parents[1]
        if any(Path(f).resolve().is_relative_to(package) for f in files):
            # a bundled model: its functions call camdyn's physics, which numba's cache
            # does not follow
            files |= {str(f) for folder in ("model", "systems") for f in (package / folder).glob("*.py")}
        return tuple(sorted(files))


def read_value(value, q: Quantity) -> float:
    """``value`` of the quantity ``q`` as a number in its SI unit: a number as it is, text
    with units converted (``"0.2 mm"``, ``"2400 rpm"`` for a speed in Hz)."""
    if isinstance(value, bool):
        raise ParameterError(f"parameter {q.name!r} [{q.unit}]: expected a number or text with units, got {value!r}")
    if isinstance(value, (int, float, np.floating, np.integer)):
        number = float(value)
    elif q.unit == "Hz":
        number = parse_speed(value, key=q.name)
    else:
        number = parse_quantity(value, q.unit or "dimensionless", key=q.name)
    if not math.isfinite(number):
        raise ParameterError(f"parameter {q.name!r} [{q.unit}] must be finite, got {value!r}")
    return number


@dataclass(frozen=True)
class BoundModel:
    """A :class:`Model` with its parameter vector (SI units, in the order of
    ``model.parameters``): what :func:`camdyn.simulate` runs."""

    model: Model
    values: tuple

    @property
    def p(self) -> np.ndarray:
        return np.array(self.values, dtype=float)

    def __getitem__(self, key: str) -> float:
        """A parameter's value [its unit]."""
        try:
            return self.values[self.model.parameter_names.index(key)]
        except ValueError:
            raise ParameterError(f"model {self.model.name!r} has no parameter {key!r}") from None

    def replace(self, parameters: dict) -> BoundModel:
        """The same model with some parameters changed (numbers in SI units or text)."""
        current = dict(zip(self.model.parameter_names, self.values))
        current.update(parameters)
        return self.model.bind(current)

    def initial_state(self) -> np.ndarray:
        """The model's state at rest for these parameters."""
        n = len(self.model.states)
        if self.model.initial_state is None:
            return np.zeros(n)
        y0 = np.asarray(self.model.initial_state(self.p), dtype=float)
        if y0.shape != (n,) or not np.all(np.isfinite(y0)):
            raise ParameterError(f"model {self.model.name!r}: initial_state gave {y0!r}, not {n} finite numbers")
        return y0


def _source_of(model: str, role: str, function) -> tuple[str, str, str]:
    """(module, name, file) of a model's function, refused unless it is a numba function
    at the top level of an importable module file."""
    if not _is_jitted(function):
        raise ParameterError(f"model {model!r}: its {role!r} function must be compiled with @numba.njit, "
                             f"got {function!r}")
    py = function.py_func
    module_name, name = py.__module__, py.__qualname__
    if "<" in name or "." in name:
        raise ParameterError(f"model {model!r}: its {role!r} function {name} must be defined at the top level of a "
                             "module (not inside a function or class), so that its compiled code can be cached")
    module = importlib.import_module(module_name) if module_name != "__main__" else importlib.import_module("__main__")
    path = getattr(module, "__file__", None)
    if path is None or getattr(module, name, None) is not function:
        raise ParameterError(f"model {model!r}: its {role!r} function {name} must be importable from a module file "
                             f"(module {module_name!r} {'has no file' if path is None else 'does not hold it'}); "
                             "define the model's functions in a .py file")
    return module_name, name, inspect.getfile(module)


def adapter_source(model: Model) -> str:
    """The source of the module through which the integrator calls ``model``: the
    registry's functions (:mod:`camdyn.systems.registry`) for this one model, whose
    system id they ignore."""
    imports = []
    for role, function in sorted(model.functions.items()):
        module_name, name, _ = _source_of(model.name, role, function)
        imports.append(f"from {module_name} import {name} as _{role}")
    n = len(model.states)
    controlled = n if model.controlled is None else int(model.controlled)
    jacobian = ("    _jacobian(t, y, f0, mode, p, jac)\n" if "jacobian" in model.functions else _DIFFERENCE_JACOBIAN)
    monitor = ("    return _monitor(t, y, mode, p)\n" if "monitor" in model.functions else "    return 0.0\n")
    regime = ("    return _regime(mode, p)\n" if "regime" in model.functions else "    return 0\n")
    text = _ADAPTER.format(name=model.name, imports="\n".join(imports), n=n, controlled=controlled,
                           m=len(model.guards), modes=len(model.modes), method=_METHODS[model.method],
                           jacobian=jacobian, monitor=monitor, regime=regime,
                           model_id=MODEL_ID,
                           plain_id=MODEL_ID if model.plain_error_estimate else -1)
    return text + (_OUTPUT_SAMPLES if "outputs" in model.functions else "")


_DIFFERENCE_JACOBIAN = """\
    # central differences: their noise is far below forward differences', which the
    # variational system's error control on the state-transition matrix would chase
    n = y.shape[0]
    yh = y.copy()
    fp = np.empty(n)
    fm = np.empty(n)
    for j in range(n):
        h = 6.0554544523933395e-06 * max(abs(y[j]), 1e-6)   # cube root of the machine epsilon
        yh[j] = y[j] + h
        _rhs(t, yh, mode, p, fp)
        yh[j] = y[j] - h
        _rhs(t, yh, mode, p, fm)
        for i in range(n):
            jac[i, j] = (fp[i] - fm[i]) / (2.0 * h)
        yh[j] = y[j]
"""

_OUTPUT_SAMPLES = """

@numba.njit(cache=True)
def output_samples(t, y, modes, p, out):
    for i in range(t.shape[0]):
        if y[i, 0] == y[i, 0]:   # a sample the run reached (not NaN)
            _outputs(t[i], y[i], modes[i], p, out[i])
"""

_ADAPTER = '''"""The integrator's view of the model {name!r} (generated by camdyn.systems.protocol)."""
import numba
import numpy as np

{imports}

# the registry's model ids: this model is {model_id}; CAM_FOLLOWER marks whether DOP853's
# steps are controlled by their 5th-order estimate alone (registry.plain_error_estimate)
CAM_FOLLOWER = {plain_id}
OSCILLATOR = RIGID_IMPACT = COUPLED_OSCILLATORS = TRANSLATING_FOLLOWER = STICK_SLIP = DRIVEN_CAM = -2
FLEXIBLE_PIVOT = TWO_FOLLOWERS = SLIDING_FOLLOWER = DRIVEN_CAM_ANGLE = TWO_FOLLOWERS_ANGLE = -2


@numba.njit(cache=True)
def state_size(system):
    return {n}


@numba.njit(cache=True)
def controlled_size(system):
    return {controlled}


@numba.njit(cache=True)
def guard_count(system):
    return {m}


@numba.njit(cache=True)
def mode_size(system):
    return {modes}


@numba.njit(cache=True)
def rhs(system, t, y, mode, p, dydt):
    _rhs(t, y, mode, p, dydt)


@numba.njit(cache=True, inline="always")
def rhs_inline(system, t, y, mode, p, dydt):
    _rhs(t, y, mode, p, dydt)


@numba.njit(cache=True)
def jacobian(system, t, y, f0, mode, p, jac):
{jacobian}

@numba.njit(cache=True)
def variational_jacobian(system, t, y, f0, mode, p, jac):
    jacobian(system, t, y, f0, mode, p, jac)


@numba.njit(cache=True)
def carried_slot(system, p):
    return -1


@numba.njit(cache=True)
def carries(system):
    return False


@numba.njit(cache=True)
def guards(system, t, y, f, known, p, values, rates):
    _guards(t, y, f, known, p, values, rates)


@numba.njit(cache=True)
def expected_sign(system, k, mode, p):
    return _expected_sign(k, mode, p)


@numba.njit(cache=True)
def transition(system, k, t, y, values, mode, p):
    _transition(k, t, y, values, mode, p)


@numba.njit(cache=True)
def initial_mode(system, t, y, p, mode):
    _initial_mode(t, y, p, mode)


@numba.njit(cache=True)
def regime(system, mode, p):
{regime}

@numba.njit(cache=True)
def preferred_method(system, mode, p):
    return {method}


@numba.njit(cache=True)
def monitor(system, t, y, mode, p):
{monitor}'''
