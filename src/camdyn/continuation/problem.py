"""The periodic problem a shooting method solves: a registered hybrid model, its parameter
vector as a function of one scalar parameter, the forcing period, and the state
components that are shooting unknowns.

Two builders: :func:`model_problem` for the test models of :mod:`camdyn.systems.registry`
(the scalar parameter is one entry of ``p``), and :func:`system_problem` for the
cam-follower (the scalar parameter is a dotted key of a :class:`~camdyn.params.system.System`
such as ``motion.speed``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from types import ModuleType

import numpy as np

from camdyn.errors import ParameterError
from camdyn.integrator import driver as bundled_driver
from camdyn.model.geometry import cam_angle, contact_point, pressed_angles
from camdyn.params.schema import parameter_index
from camdyn.params.system import System
from camdyn.simulation import limits
from camdyn.simulation.models import model_driver
from camdyn.simulation.runner import prepare
from camdyn.systems import registry as systems
from camdyn.systems.protocol import MODEL_ID, BoundModel

__all__ = ["Problem", "model_problem", "system_problem", "bound_problem", "parameter_unit", "FORCING_INDEX"]

#: Index of the forcing frequency W [rad/s] in each test model's parameter vector.
FORCING_INDEX = {systems.OSCILLATOR: 3, systems.RIGID_IMPACT: 3, systems.COUPLED_OSCILLATORS: 4}


@dataclass(frozen=True)
class Problem:
    """A forced hybrid system whose periodic orbits are sought.

    Attributes
    ----------
    system_id : int
        Registered model (:mod:`camdyn.systems.registry`).
    build : callable
        ``build(value) -> (p, period)``: the parameter vector and the forcing period [s] at
        the scalar parameter ``value`` (its unit is that of the parameter named ``name``).
    value : float
        The scalar parameter's starting value.
    template : ndarray (n,)
        A full initial state: its first ``unknowns`` components are replaced by the
        shooting unknowns, the others (quadratures) are kept.
    unknowns : int
        Number of leading state components that are shooting unknowns.
    name : str
        Name of the scalar parameter (an index ``p[i]`` or a dotted key).
    unit : str
        Unit of the scalar parameter.
    t_start : float
        Phase of the orbit's start [s]: the orbit is sought at ``t_start + j k T``.
    rtol, atol : float
        Integration tolerances of every shooting run.
    system : System or None
        The cam-follower system at ``value`` (None for a test model).
    impact_sign : float
        An event on guard 0 counts as an impact when its new sign equals this (0: every
        event on guard 0 counts).
    impacts : bool
        False for a model without impacts (the forced oscillator, whose guard 0 marks
        zero crossings): no event counts as one.
    key : str or None
        The dotted key of the cam-follower's scalar parameter.
    matrix_rtol, matrix_atol : float or None
        Tolerances of the variational runs, which give the monodromy matrix only (every
        residual comes from a plain run at ``rtol, atol``); None: ``rtol, atol``. The
        cam-follower's are ten times looser (:func:`system_problem`).
    template_at : callable or None
        ``template_at(value) -> ndarray (n,)``: the template at the scalar parameter
        ``value``, for a model whose kept components depend on it (the cam's speed as a
        state of two followers on a cam held at that speed); None: ``template``.
    driver : module or None
        The driver that integrates the model: a protocol model's own
        (:func:`bound_problem`); None: the bundled one (:mod:`camdyn.integrator.driver`).
    step_fraction : float or None
        Largest step and scan interval as fractions of the period [-]; None: those of
        :func:`~camdyn.simulation.limits.step_limits`.
    orbit_guess : callable or None
        ``orbit_guess(value, times) -> ndarray (N, unknowns)``: a guess of the periodic
        orbit at ``times`` [s] (one forcing period on a uniform grid, end excluded), from
        which harmonic balance starts when given no guess (the cam-follower's: the
        follower riding the cam rigidly); None: the constant ``template``.
    """

    system_id: int
    build: Callable[[float], tuple[np.ndarray, float]]
    value: float
    template: np.ndarray
    unknowns: int
    name: str = "parameter"
    unit: str = ""
    t_start: float = 0.0
    rtol: float = 1e-10
    atol: float = 1e-12
    system: System | None = field(default=None, compare=False)
    impact_sign: float = 0.0
    impacts: bool = True
    key: str | None = None
    matrix_rtol: float | None = None
    matrix_atol: float | None = None
    template_at: Callable[[float], np.ndarray] | None = field(default=None, compare=False)
    clock: int | None = None
    driver: ModuleType | None = field(default=None, compare=False)
    step_fraction: float | None = None
    orbit_guess: Callable[[float, np.ndarray], np.ndarray] | None = field(default=None, compare=False)

    def engine(self) -> ModuleType:
        """The driver module that integrates this problem's model."""
        return bundled_driver if self.driver is None else self.driver

    def run(self, *args):
        """``engine().integrate(*args)``: one run of the problem's model."""
        return self.engine().integrate(*args)

    def full_state(self, x, value: float) -> np.ndarray:
        """The full state (n,) from the unknowns ``x`` at the scalar parameter ``value``:
        the template there with its first ``unknowns`` components replaced."""
        y = (self.template if self.template_at is None else self.template_at(float(value))).copy()
        y[:self.unknowns] = np.asarray(x, dtype=float)
        return y

    def matrix_tolerances(self) -> tuple[float, float]:
        """``(rtol, atol)`` of the variational runs."""
        return (self.rtol if self.matrix_rtol is None else self.matrix_rtol,
                self.atol if self.matrix_atol is None else self.matrix_atol)


def _check_tolerances(rtol: float, atol: float) -> None:
    limits.check_tolerances(rtol, atol)


def model_problem(system_id: int, p, initial_state, index: int | None = None, t_start: float = 0.0,
                  rtol: float = 1e-10, atol: float = 1e-12) -> Problem:
    """A test model's periodic problem; the scalar parameter is ``p[index]`` (default the
    forcing frequency W [rad/s]). The forcing period is ``2 pi / W`` [s].

    Parameters
    ----------
    system_id : int
        :data:`~camdyn.systems.registry.OSCILLATOR`, ``RIGID_IMPACT`` or ``COUPLED_OSCILLATORS``.
    p : array_like
        The model's parameter vector (units in its module's docstring).
    initial_state : array_like (n,)
        A full state; its controlled components start the search.
    index : int, optional
        Entry of ``p`` that is the scalar parameter.
    """
    if system_id not in FORCING_INDEX:
        raise ParameterError(f"system {system_id} is not a forced test model; use system_problem for the cam-follower")
    base = np.asarray(p, dtype=float).copy()
    forcing = FORCING_INDEX[system_id]
    index = forcing if index is None else int(index)
    if not 0 <= index < base.size:
        raise ParameterError(f"parameter index {index} outside the parameter vector of {base.size} entries")
    state = np.asarray(initial_state, dtype=float).copy()
    if state.size != systems.state_size(system_id) or not np.all(np.isfinite(state)):
        raise ParameterError(f"the initial state must be {systems.state_size(system_id)} finite numbers")
    _check_tolerances(rtol, atol)

    def build(value: float) -> tuple[np.ndarray, float]:
        q = base.copy()
        q[index] = value
        if not q[forcing] > 0:
            raise ParameterError(f"the forcing frequency must be positive, got {q[forcing]} rad/s")
        return q, 2.0 * math.pi / q[forcing]

    build(base[index])
    return Problem(system_id, build, float(base[index]), state, int(systems.controlled_size(system_id)),
                   name=f"p[{index}]", t_start=float(t_start), rtol=rtol, atol=atol,
                   impacts=system_id != systems.OSCILLATOR)


def parameter_unit(system: System, key: str) -> str:
    """The SI unit of the continuous parameter ``key`` of ``system`` (``Hz`` for a cam
    speed); a :class:`ParameterError` for an unknown or non-numeric key."""
    known = parameter_index(type(system))
    if key not in known:
        raise ParameterError(f"unknown parameter {key!r}; `camdyn presets keys` lists them")
    unit = known[key].unit
    if unit in ("str", "bool", "int", "law"):
        raise ParameterError(f"{key} is not a continuous parameter (its kind is {unit})")
    return "Hz" if unit == "speed" else unit


def _check_periodic_motion(system: System, key: str) -> None:
    """Refuse a cam motion whose forcing is not periodic (a ramp), or a parameter that
    does not enter the motion that runs (the speed of an oscillating cam, which moves at
    ``motion.frequency``): shooting would find a fixed point of a map that is not the
    system's period map, or a branch that does not move."""
    kind = system.motion.kind
    if kind == "ramp":
        raise ParameterError("periodic orbits need a periodic cam motion: a ramp (motion.kind = 'ramp') is not; "
                             "use motion.kind = 'constant'")
    if kind == "oscillating" and key == "motion.speed":
        raise ParameterError("an oscillating cam moves at motion.frequency, not motion.speed: continue in "
                             "motion.frequency")
    if kind == "constant" and key in ("motion.frequency", "motion.amplitude", "motion.start_speed", "motion.ramp_time"):
        raise ParameterError(f"{key} does not enter a cam turning at constant speed (motion.kind = 'constant')")


def system_problem(system: System, key: str = "motion.speed", initial_state=None, rtol: float = 1e-10,
                   atol: float = 1e-12) -> Problem:
    """The cam-follower's periodic problem over one cam period ``1 / speed`` [s], the
    scalar parameter being the dotted key ``key`` of ``system`` in SI units (``motion.speed``
    in [Hz], ``cam.runout`` in [m], ...).

    ``initial_state`` is ``(alpha [rad], alpha_dot [rad/s])`` (default the static
    equilibrium). The shooting unknowns are alpha and alpha_dot; the friction-work
    quadrature is not one.

    The variational runs (the monodromy matrix) use ``100 rtol, 100 atol``: the matrix
    follows the contact resonance (about 1 kHz) at full amplitude where the orbit itself
    barely carries it, so at ``rtol`` its error control takes more than ten times the
    plain run's steps (15 000 against 1 200 per revolution of the chapter 4 rig at
    ``rtol = 1e-10``), at ``100 rtol`` fewer (840); against the multipliers at ``rtol``
    they move by 4e-11 on the chapter 4 rig (11.55 Hz, ``|mu| = 5e-5``) and 5e-6 next to
    the chapter 3 rig's period doubling (16 Hz, ``mu = -0.986``), measured.
    """
    limits.check_system(system)
    _check_tolerances(rtol, atol)
    _check_periodic_motion(system, key)
    unit = parameter_unit(system, key)
    value = parameter_index(type(system))[key].getter(system)
    if value is None or not math.isfinite(float(value)):
        raise ParameterError(f"{key} has no finite value to start from")
    value = float(value)

    last = {}   # the last value built: harmonic balance asks for it twice per orbit

    def build(value: float) -> tuple[np.ndarray, float]:
        if last.get("value") != value:
            moved = system.with_values(**{key: value})
            limits.check_system(moved)
            period = moved.motion.period
            if not (math.isfinite(period) and period > 0):
                raise ParameterError(f"the cam must turn to have a period; {key} = {value} gives none")
            last.update(value=value, p=prepare(moved).p, period=period)
        return last["p"].copy(), last["period"]

    p, _ = build(value)
    prep = prepare(system)
    template = prep.y0.copy()
    if initial_state is not None:
        if len(initial_state) != 2:
            raise ParameterError(f"initial_state is (alpha [rad], alpha_dot [rad/s]), got {len(initial_state)} values")
        template[0], template[1] = float(initial_state[0]), float(initial_state[1])
        if not np.all(np.isfinite(template)):
            raise ParameterError("initial_state must be finite")
    def orbit_guess(value: float, times: np.ndarray) -> np.ndarray:
        # the follower riding the cam pressed in by the template's (static) penetration,
        # where Hertz's law has a stiffness (at rigid contact, delta = 0, it has none and
        # Newton starts off far); alpha_dot by spectral differentiation over the period
        p, period = build(value)
        pressed = max(contact_point(float(template[0]), cam_angle(float(times[0]), p)[0], p)[0], 0.0)
        alpha = pressed_angles(np.ascontiguousarray(times, dtype=float), p, float(template[0]), pressed)
        spectrum = np.fft.rfft(alpha) * (2j * math.pi / period) * np.arange(alpha.size // 2 + 1)
        if alpha.size % 2 == 0:
            spectrum[-1] = 0.0                                       # the Nyquist bin has no derivative
        return np.column_stack([alpha, np.fft.irfft(spectrum, n=alpha.size)])

    return Problem(systems.CAM_FOLLOWER, build, value, template, int(systems.controlled_size(systems.CAM_FOLLOWER)),
                   name=key, unit=str(unit), rtol=rtol, atol=atol, system=system, impact_sign=1.0, key=key,
                   matrix_rtol=100.0 * rtol, matrix_atol=100.0 * atol, orbit_guess=orbit_guess)


def bound_problem(bound, key: str | None = None, t_start: float = 0.0, rtol: float = 1e-10,
                  atol: float = 1e-12) -> Problem:
    """A protocol model's periodic problem (:mod:`camdyn.systems.protocol`); the scalar
    parameter is the model's parameter ``key`` (default its speed [Hz]), in its unit. The
    forcing period is one over the speed; every state component is a shooting unknown,
    the start the model's state at rest.

    Raises
    ------
    ParameterError
        A model without a speed parameter, or an unknown ``key``.
    """
    if not isinstance(bound, BoundModel):
        raise ParameterError(f"expected a model with its parameters (Model.bind()), got {type(bound).__name__}")
    model = bound.model
    if model.speed is None:
        raise ParameterError(f"model {model.name!r} has no speed parameter, so no forcing period to shoot over")
    key = model.speed if key is None else key
    if key not in model.parameter_names:
        raise ParameterError(f"model {model.name!r} has no parameter {key!r}; its parameters: "
                             f"{', '.join(model.parameter_names)}")
    _check_tolerances(rtol, atol)
    unit = model.parameters[model.parameter_names.index(key)].unit

    def build(value: float) -> tuple[np.ndarray, float]:
        moved = bound.replace({key: float(value)})
        return moved.p, 1.0 / moved[model.speed]

    unknowns = len(model.states) if model.controlled is None else int(model.controlled)
    return Problem(MODEL_ID, build, float(bound[key]), bound.initial_state(), unknowns, name=key, unit=unit,
                   t_start=float(t_start), rtol=rtol, atol=atol, impacts=False, key=key, driver=model_driver(model),
                   step_fraction=model.max_step_fraction, matrix_rtol=10 * rtol, matrix_atol=10 * atol)
