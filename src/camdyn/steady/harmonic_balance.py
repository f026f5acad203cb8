"""Harmonic balance with the alternating frequency-time scheme (AFT) for a periodic
problem whose dynamics is smooth over the orbit (one mode, no event on it).

Method (Krack & Gross, *Harmonic Balance for Nonlinear Vibration Problems*, ch. 2-3):
the unknowns ``y`` (first ``problem.unknowns`` state components, first-order form
``y' = f(t, y)``) are written as the truncated real Fourier series

    y(t) = a_0 + sum_{k=1..H} a_k cos(k w s) + b_k sin(k w s),   s = t - t_start,  w = 2 pi / T  [rad/s]

with coefficients in the unit of each state component. The residual in the frequency
domain is ``R(X) = nabla X - P f(t_j, E X)``: ``nabla`` the derivative in the basis
(``a'_k = k w b_k``, ``b'_k = -k w a_k``), ``E`` the synthesis on the N grid times
``t_j = t_start + j T / N`` and ``P`` the discrete Fourier projection (AFT). Its exact
Jacobian is ``nabla - P J E`` with ``J = df/dy`` the model's own Jacobian at the grid
times.

Grid (anti-aliasing rule): a nonlinearity of polynomial degree ``q`` maps H harmonics to
``qH``; the projection onto harmonics ``<= H`` is exact when ``N >= (q + 1) H + 1``. The
default ``N`` is ``8 H + 2`` (exact up to degree 7; the contact law's
3/2 power and the friction law are not polynomial, so their aliasing error falls as their
Fourier tail, which the convergence measure bounds).

Stability by Hill's method: the Hill matrix is ``-dR/dX`` (the real-basis form of the
complex Hill matrix); of its ``n (2H + 1)`` eigenvalues the ``n`` with the smallest
imaginary parts are kept (NLvib's sorting) and the multipliers are ``exp(lambda T)``.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from camdyn.continuation.problem import Problem
from camdyn.errors import ParameterError, SimulationError
from camdyn.simulation import limits
from camdyn.systems.traits import contact_mode_slot

__all__ = ["HarmonicOrbit", "GridModel", "harmonic_balance", "harmonic_residual", "hill_multipliers", "grid_size",
           "tail_measure", "resize"]


@dataclass(frozen=True)
class HarmonicOrbit:
    """A periodic orbit by harmonic balance.

    Attributes
    ----------
    coefficients : ndarray (n, 2H + 1)
        Per unknown component: ``[a_0, a_1, b_1, ..., a_H, b_H]`` in that component's unit.
    times : ndarray (N,)
        Grid times ``t_start + j T / N`` [s].
    samples : ndarray (N, n)
        The unknowns at the grid times (their units).
    period : float
        The forcing period T [s].
    harmonics : int
        H, the highest harmonic kept.
    residual : float
        Max-norm of the frequency-domain residual (unit of the state rates).
    iterations : int
        Newton iterations taken.
    tail : float
        Convergence measure [-] (:func:`tail_measure`): the largest amplitude
        ``sqrt(a_k^2 + b_k^2)`` of the top harmonics ``k > 3H/4``, and of the top two at
        least, over the largest amplitude of harmonics ``k >= 1``, taken over the
        components, each in its own unit (1 at H <= 2, 0 at H = 0).
    multipliers : ndarray (n,)
        Floquet multipliers by Hill's method [-], largest magnitude first.
    exponents : ndarray (n,)
        The kept Floquet exponents lambda [1/s].
    """

    coefficients: np.ndarray
    times: np.ndarray
    samples: np.ndarray
    period: float
    harmonics: int
    residual: float
    iterations: int
    tail: float
    multipliers: np.ndarray
    exponents: np.ndarray

    @property
    def stable(self) -> bool:
        """All multipliers inside the unit circle."""
        return bool(np.all(np.abs(self.multipliers) < 1.0))

    def amplitudes(self) -> np.ndarray:
        """``(n, H)``: amplitude ``sqrt(a_k^2 + b_k^2)`` of harmonics 1..H (state units)."""
        c = self.coefficients
        return np.hypot(c[:, 1::2], c[:, 2::2])


#: The harmonics of a problem's orbit guess that ``"auto"`` looks at to choose its first H [-].
PROBE_HARMONICS = 8


def grid_size(harmonics: int) -> int:
    """N = 8 H + 2: the anti-aliasing rule ``N >= (q + 1) H + 1`` with q = 7, made even (the
    transforms are matrix products, so N need not be a power of two)."""
    return 8 * harmonics + 2


@functools.lru_cache(maxsize=16)
def _transforms(harmonics: int, count: int):
    """Synthesis E (N, 2H+1) and projection P (2H+1, N), read-only (kept between calls)."""
    phase = 2.0 * math.pi * np.arange(count) / count
    k = np.arange(1, harmonics + 1)
    synth = np.empty((count, 2 * harmonics + 1))
    synth[:, 0] = 1.0
    synth[:, 1::2] = np.cos(np.outer(phase, k))
    synth[:, 2::2] = np.sin(np.outer(phase, k))
    project = synth.T * (2.0 / count)
    project[0] *= 0.5
    synth.flags.writeable = project.flags.writeable = False
    return synth, project


@functools.lru_cache(maxsize=16)
def _bases(harmonics: int, count: int, omega: float):
    """Synthesis E (N, 2H+1), projection P (2H+1, N) and derivative nabla (2H+1, 2H+1),
    read-only (kept between calls: a Newton solve asks for the same ones each iteration)."""
    synth, project = _transforms(harmonics, count)
    k = np.arange(1, harmonics + 1)
    nabla = np.zeros((2 * harmonics + 1, 2 * harmonics + 1))
    nabla[2 * k - 1, 2 * k] = k * omega                           # a'_k = k w b_k
    nabla[2 * k, 2 * k - 1] = -k * omega                          # b'_k = -k w a_k
    nabla.flags.writeable = False
    return synth, project, nabla


class GridModel:
    """The problem's rhs and Jacobian at every grid time, through its driver's compiled
    registry (``problem.engine().systems``), at the scalar parameter ``value`` [its unit].

    ``parameters``, if given, maps the parameter vector ``p`` built at ``value`` to the one
    evaluated (the continuation's unclipped contact law)."""

    def __init__(self, problem: Problem, value: float, parameters=None):
        self.problem, self.value = problem, value
        self.p, self.period = problem.build(value)
        if parameters is not None:
            self.p = parameters(self.p)
        self.systems = problem.engine().systems
        self.system = problem.system_id
        self.n = problem.template.size
        self.u = problem.unknowns

    def full_states(self, samples: np.ndarray) -> np.ndarray:
        """The full states (N, n) of the unknowns ``samples`` (N, u): the problem's template
        with its first ``u`` components replaced."""
        states = np.tile(self.problem.full_state(samples[0], self.value), (samples.shape[0], 1))
        states[:, :self.u] = samples
        return states

    def mode(self, time: float, state: np.ndarray) -> np.ndarray:
        """The hybrid mode the model starts in at ``time`` [s] and full state ``state``."""
        sys = self.systems
        mode = np.zeros(int(sys.mode_size(self.system)))
        sys.initial_mode(self.system, float(time), state, self.p, mode)
        return mode

    def balanced_modes(self, times: np.ndarray, samples: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The full states (N, n) and the mode at every sample (N, mode size) of an orbit
        balanced in one mode: the first sample's, in contact throughout where the model
        has a contact slot."""
        states = self.full_states(samples)
        modes = np.tile(self.mode(times[0], states[0]), (times.size, 1))
        slot = contact_mode_slot(self.system)
        if slot is not None:
            modes[:, slot] = 1.0
        return states, modes

    def evaluate(self, times: np.ndarray, samples: np.ndarray):
        """rates (N, u) and Jacobians (N, u, u) at the unknowns ``samples`` (N, u)."""
        sys, u = self.systems, self.u
        states = self.full_states(samples)
        mode = self.mode(times[0], states[0])
        rates = np.empty_like(states)
        jacs = np.empty((times.size, self.n, self.n))
        sys.grid_values(self.system, times, states, mode, self.p, rates, jacs)
        rates, jacs = rates[:, :u], jacs[:, :u, :u]
        return rates, jacs, mode

    def guard_changes(self, times: np.ndarray, samples: np.ndarray, mode: np.ndarray) -> list[int]:
        """Active guards (expected sign not 0 in ``mode``) whose sign differs from the
        expected one somewhere on the sampled orbit (none for a problem without impacts,
        whose guards only mark crossings: the forced oscillator's)."""
        sys = self.systems
        if not self.problem.impacts:
            return []
        states = self.full_states(samples)
        out, changed = np.empty(times.size), []
        for k in range(int(sys.guard_count(self.system))):
            sign = float(sys.expected_sign(self.system, k, mode, self.p))
            if sign == 0.0:
                continue
            sys.guard_samples(self.system, self.p, times, states, k, out)
            if np.any(out * sign < 0.0):
                changed.append(k)
        return changed


def harmonic_residual(model: GridModel, x: np.ndarray, harmonics: int, jacobian: bool = True):
    """The frequency-domain residual and its exact Jacobian (None unless ``jacobian``) at the
    coefficients ``x`` (u, 2H + 1) on the grid of :func:`grid_size` times.

    Returns
    -------
    residual : ndarray (u (2H + 1),)
        ``R = nabla X - P f(t_j, E X)`` (units of the state rates).
    jacobian : ndarray (u (2H + 1), u (2H + 1))
        ``dR/dX = nabla - P J E`` (rates per state unit).
    times : ndarray (N,)
        The grid times [s].
    samples : ndarray (N, u)
        The unknowns there (their units).
    mode : ndarray
        The hybrid mode at the first grid time.
    """
    count = grid_size(harmonics)
    omega = 2.0 * math.pi / model.period
    synth, project, nabla = _bases(harmonics, count, omega)
    times = model.problem.t_start + model.period * np.arange(count) / count
    u, m = model.u, 2 * harmonics + 1
    samples = (synth @ x.T)                                       # (N, u)
    rates, jacs, mode = model.evaluate(times, samples)
    residual = (x @ nabla.T - (project @ rates).T).ravel()        # R = nabla X - P f
    if not jacobian:
        return residual, None, times, samples, mode
    # dR/dX[c j, d i] = nabla[j, i] delta_cd - sum_k P[j, k] J_k[c, d] E[k, i], block by block;
    # an entry J_cd that is the same at every grid time gives J_cd P E = J_cd I (P E = I, N > 2H)
    jac = np.zeros((u * m, u * m))
    first = jacs[0]
    varying = (jacs != first).any(axis=0)
    for c in range(u):
        rows = slice(c * m, (c + 1) * m)
        for d in range(u):
            cols = slice(d * m, (d + 1) * m)
            if varying[c, d]:
                jac[rows, cols] = -(project @ (jacs[:, c, d][:, None] * synth))
            elif first[c, d] != 0.0:
                jac[rows, cols] = -first[c, d] * np.eye(m)
        jac[rows, rows] += nabla
    return residual, jac, times, samples, mode


def _newton(model: GridModel, coefficients: np.ndarray, harmonics: int, tolerance: float, max_iterations: int):
    omega = 2.0 * math.pi / model.period
    u, m = model.u, 2 * harmonics + 1
    x = coefficients.copy()
    step_norm = math.inf
    for iteration in range(max_iterations + 1):
        residual, jac, times, samples, mode = harmonic_residual(model, x, harmonics)
        norm = float(np.max(np.abs(residual)))
        scale = max(float(np.max(np.abs(x))) * omega, 1e-300)
        if iteration > 0 and (norm <= tolerance * scale or step_norm <= 1e-14 * scale / omega):
            return x, times, samples, norm, iteration, jac, mode
        if iteration == max_iterations:
            break
        step = np.linalg.solve(jac, -residual).reshape(u, m)
        step_norm = float(np.max(np.abs(step)))
        x = x + step
    raise SimulationError(f"harmonic balance did not converge in {max_iterations} Newton iterations "
                          f"(residual {norm:.3g}); try a better guess or shooting (continuation.orbits.find_orbit)")


def hill_multipliers(jacobian: np.ndarray, unknowns: int, period: float) -> tuple[np.ndarray, np.ndarray]:
    """Floquet exponents [1/s] and multipliers [-] by Hill's method: eigenvalues of the
    Hill matrix ``-dR/dX``, the ``unknowns`` with the smallest absolute imaginary part kept,
    ``mu = exp(lambda T)``; multipliers largest magnitude first."""
    values = np.linalg.eigvals(-jacobian)
    kept = values[np.argsort(np.abs(values.imag), kind="stable")[:unknowns]]
    multipliers = np.exp(kept * period)
    order = np.argsort(-np.abs(multipliers), kind="stable")
    return kept[order], multipliers[order]


def tail_measure(x: np.ndarray, harmonics: int) -> float:
    """The convergence measure of coefficients ``x`` (u, 2H + 1) [-]: the largest amplitude of
    the harmonics ``k > 3H/4``, and at least of the top two, over the largest amplitude of
    harmonics ``k >= 1``. (Two at least: a symmetric nonlinearity, a cubic spring's,
    makes every even harmonic zero, so the top one alone would say H = 2 or 4 is enough
    where the third harmonic is not small.)"""
    if harmonics == 0:
        return 0.0
    amp = np.hypot(x[:, 1::2], x[:, 2::2])
    top = amp[:, min(int(math.floor(0.75 * harmonics)), max(harmonics - 2, 0)):]   # k > 3H/4, k >= H - 1
    largest = float(np.max(amp))
    return float(np.max(top)) / largest if largest > 0 else 0.0


def resize(x: np.ndarray, harmonics: int) -> np.ndarray:
    """Coefficients ``x`` (u, 2H' + 1) padded with zeros or cut to ``harmonics`` (their units)."""
    out = np.zeros((x.shape[0], 2 * harmonics + 1))
    m = min(x.shape[1], out.shape[1])
    out[:, :m] = x[:, :m]
    return out


def _guess(model: GridModel, harmonics: int, guess) -> np.ndarray:
    if guess is not None:
        g = np.asarray(guess, float)
        if g.ndim == 2:
            return resize(g, harmonics)
        return resize(g.reshape(model.u, 1), harmonics)         # a constant state
    problem = model.problem
    if problem.orbit_guess is not None:                          # the problem's own orbit guess, projected
        count = grid_size(harmonics)
        times = problem.t_start + model.period * np.arange(count) / count
        samples = np.asarray(problem.orbit_guess(model.value, times), float)
        return (_transforms(harmonics, count)[1] @ samples).T
    return resize(problem.template[:model.u].reshape(model.u, 1).astype(float), harmonics)


def _first_harmonics(model: GridModel, guess, tail_tolerance: float) -> tuple[int, np.ndarray]:
    """``"auto"``'s first H and guess: H = 4 from a given or constant guess (at H = 2
    the tail, read from the top two harmonics, is always 1); from the problem's orbit
    guess, the smallest of 4 and 8 whose tail (:func:`tail_measure`)
    the guess already meets (the guess's spectrum says how many harmonics the orbit needs,
    which spares Newton the solves at the smaller H)."""
    if guess is not None or model.problem.orbit_guess is None:
        return 4, _guess(model, 4, guess)
    x = _guess(model, PROBE_HARMONICS, None)
    h = 4
    while h < PROBE_HARMONICS and tail_measure(resize(x, h), h) > tail_tolerance:
        h *= 2
    return h, resize(x, h)


def harmonic_balance(problem: Problem, harmonics: int | str = "auto", guess=None, value: float | None = None,
                     tolerance: float = 1e-11, tail_tolerance: float = 1e-8, max_harmonics: int = 128,
                     max_iterations: int = 40) -> HarmonicOrbit:
    """The periodic orbit of ``problem`` at its parameter ``value`` by harmonic balance (AFT).

    Parameters
    ----------
    harmonics : int or "auto"
        H. "auto": H = 4, 8, 16, ... until the convergence measure ``tail`` is below
        ``tail_tolerance`` [-] (each solve starts from the last).
    guess : array or None
        Coefficients (n, 2H'+1) (any H', padded or cut) or a constant state (n,); None:
        the problem's template state.
    tolerance : float
        Newton stops when ``max|R| <= tolerance * w max|X|`` [-], or the step is below
        1e-14 of the largest coefficient.

    Raises
    ------
    SimulationError
        Newton fails, or an active guard changes sign on the orbit (contact lost, an
        impact): the dynamics is not smooth over it; use shooting
        (:func:`camdyn.continuation.orbits.find_orbit`).
    """
    limits.check_number("tolerance", tolerance)
    model = GridModel(problem, problem.value if value is None else float(value))
    auto = harmonics == "auto"
    if not auto and (not isinstance(harmonics, int) or harmonics < 0):
        raise ParameterError(f"harmonics must be a non-negative integer or 'auto', got {harmonics!r}")
    if auto:
        h, x = _first_harmonics(model, guess, tail_tolerance)
    else:
        h = int(harmonics)
        x = _guess(model, h, guess)
    while True:
        x, times, samples, norm, iterations, jac, mode = _newton(model, x, h, tolerance, max_iterations)
        tail = tail_measure(x, h)
        if not auto or tail <= tail_tolerance or 2 * h > max_harmonics:
            break
        h *= 2
        x = resize(x, h)
    changed = model.guard_changes(times, samples, mode)
    if changed:
        raise SimulationError(f"guard(s) {changed} change sign on the harmonic-balance orbit (contact lost or an "
                              "impact): the dynamics is not smooth over the orbit; use shooting "
                              "(camdyn.continuation.orbits.find_orbit)")
    exponents, multipliers = hill_multipliers(jac, model.u, model.period)
    return HarmonicOrbit(x, times, samples, model.period, h, norm, iterations, tail, multipliers, exponents)
